"""``frontier_detector`` node: frontier cells and groups (with cPoints) of the map.

Callbacks store the newest ``map`` and ``object_costmap``; a timer on the ROS clock
(``rate_hz``) recomputes the frontiers when either changed since the last run (so at most
once per map update) with :func:`explore_seg.core.frontiers.find_frontiers`, and
publishes every frontier cell (``frontiers``), one point per group at its cPoint
(``frontiers/groups``), RViz markers and the processing time (``~/timing``).
"""

from __future__ import annotations

import time
from enum import Enum

import numpy as np
from geometry_msgs.msg import Point
from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import ColorRGBA, Float64MultiArray, MultiArrayDimension
from visualization_msgs.msg import Marker, MarkerArray

from explore_seg import convert
from explore_seg.core.frontiers import Frontier, FrontierParams, find_frontiers, object_obstacles, \
    traversable_mask
from explore_seg.core.grid import GridMap
from explore_seg.node_util import WarnThrottle, failsafe, run
from explore_seg.params import ParamBinding
from explore_seg.qos import map_qos

#: Seconds between repeated warnings of one kind.
_WARN_PERIOD_S = 5.0
#: Marker sizes (m): frontier cell points, cPoint spheres, text height.
_CELL_MARKER_M = 0.05
_SPHERE_MARKER_M = 0.25
_TEXT_MARKER_M = 0.3


class State(Enum):
    """What the node is doing."""

    WAITING_FOR_MAP = 0
    RUNNING = 1


def frontier_clouds(frontiers: list[Frontier], grid: GridMap, z_m: float = 0.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Structured float32 clouds (x, y, z, group_id, group_size) of all frontier cells and
    of the cPoints (one per group)."""
    if frontiers:
        cells = np.concatenate([f.cells for f in frontiers])
        gid = np.concatenate([np.full(len(f.cells), f.id) for f in frontiers])
        gsize = np.concatenate([np.full(len(f.cells), f.size_cells) for f in frontiers])
        x, y = grid.cells_to_world(cells[:, 0], cells[:, 1])
    else:
        x = y = gid = gsize = np.zeros(0)
    all_pts = convert.xyz_cloud(np.stack([x, y, np.full_like(x, z_m)], axis=1),
                                {"group_id": gid, "group_size": gsize})
    px = np.asarray([f.point_xy_m[0] for f in frontiers], dtype=np.float64)
    py = np.asarray([f.point_xy_m[1] for f in frontiers], dtype=np.float64)
    groups = convert.xyz_cloud(np.stack([px, py, np.full_like(px, z_m)], axis=1),
                               {"group_id": [f.id for f in frontiers],
                                "group_size": [f.size_cells for f in frontiers]})
    return all_pts, groups


def frontier_markers(frontiers: list[Frontier], grid: GridMap, header) -> MarkerArray:
    """DELETEALL, then one POINTS marker (cells), one SPHERE_LIST (cPoints, red when not
    passable) and a size text per group."""
    out = MarkerArray()
    clear = Marker()
    clear.header = header
    clear.action = Marker.DELETEALL
    out.markers.append(clear)
    if not frontiers:
        return out
    cells = Marker()
    cells.header, cells.ns, cells.id = header, "frontier_cells", 0
    cells.type, cells.action = Marker.POINTS, Marker.ADD
    cells.pose.orientation.w = 1.0
    cells.scale.x = cells.scale.y = _CELL_MARKER_M
    cells.color = ColorRGBA(r=1.0, g=0.5, b=0.0, a=1.0)
    allc = np.concatenate([f.cells for f in frontiers])
    x, y = grid.cells_to_world(allc[:, 0], allc[:, 1])
    cells.points = [Point(x=float(a), y=float(b), z=0.0) for a, b in zip(x, y)]
    out.markers.append(cells)
    spheres = Marker()
    spheres.header, spheres.ns, spheres.id = header, "cpoints", 0
    spheres.type, spheres.action = Marker.SPHERE_LIST, Marker.ADD
    spheres.pose.orientation.w = 1.0
    spheres.scale.x = spheres.scale.y = spheres.scale.z = _SPHERE_MARKER_M
    for f in frontiers:
        spheres.points.append(Point(x=f.point_xy_m[0], y=f.point_xy_m[1], z=0.0))
        spheres.colors.append(ColorRGBA(r=0.1, g=0.4, b=1.0, a=1.0) if f.point_passable
                              else ColorRGBA(r=1.0, g=0.1, b=0.1, a=1.0))
    out.markers.append(spheres)
    for f in frontiers:
        text = Marker()
        text.header, text.ns, text.id = header, "sizes", f.id
        text.type, text.action = Marker.TEXT_VIEW_FACING, Marker.ADD
        text.pose.position = Point(x=f.point_xy_m[0], y=f.point_xy_m[1], z=_TEXT_MARKER_M)
        text.pose.orientation.w = 1.0
        text.scale.z = _TEXT_MARKER_M
        text.color = ColorRGBA(r=1.0, g=1.0, b=1.0, a=1.0)
        text.text = str(f.size_cells)
        out.markers.append(text)
    return out


class FrontierDetectorNode(Node):
    """Frontier detection node (see module docstring)."""

    def __init__(self, *, context=None, parameter_overrides=None,
                 node_name: str = "frontier_detector", namespace: str = "") -> None:
        super().__init__(node_name, context=context,
                         parameter_overrides=parameter_overrides or [], namespace=namespace)
        self._p = ParamBinding(self, FrontierParams())
        p = self._p.params
        self._grid: GridMap | None = None
        self._layer: GridMap | None = None
        self._dirty = False
        self._state = State.WAITING_FOR_MAP
        self.frontiers: list[Frontier] = []
        self.runs = 0
        self._warn = WarnThrottle(self, _WARN_PERIOD_S)
        self.failures = 0          # cycles lost to an exception (node_util.failsafe)

        self._pub_cells = self.create_publisher(PointCloud2, "frontiers", 1)
        self._pub_groups = self.create_publisher(PointCloud2, "frontiers/groups", 1)
        self._pub_markers = self.create_publisher(MarkerArray, "frontiers/markers", 1)
        self._pub_timing = self.create_publisher(Float64MultiArray, "~/timing", 10)
        qos = map_qos(p.map_transient_local)
        self.create_subscription(OccupancyGrid, "map", self._on_map, qos)
        self.create_subscription(OccupancyGrid, "object_costmap", self._on_layer, qos)
        self._timer = self.create_timer(1.0 / p.rate_hz, self._tick)
        self._p.on_change(self._params_changed)

    @property
    def params(self) -> FrontierParams:
        """Current parameters."""
        return self._p.params

    @property
    def state(self) -> State:
        """Current state."""
        return self._state


    def _params_changed(self, old: FrontierParams, new: FrontierParams) -> None:
        self._dirty = True
        if new.rate_hz != old.rate_hz:
            self._timer.cancel()
            self.destroy_timer(self._timer)
            self._timer = self.create_timer(1.0 / new.rate_hz, self._tick)

    def _on_map(self, msg: OccupancyGrid) -> None:
        try:
            self._grid = convert.grid_from_msg(msg)
            self._dirty = True
        except ValueError as err:
            self._warn("map", f"dropped map: {err}")

    def _on_layer(self, msg: OccupancyGrid) -> None:
        try:
            self._layer = convert.grid_from_msg(msg)
            self._dirty = True
        except ValueError as err:
            self._warn("object_costmap", f"dropped object_costmap: {err}")

    @failsafe("frontier detection")
    def _tick(self) -> None:
        if self._grid is None:
            self._state = State.WAITING_FOR_MAP
            return
        self._state = State.RUNNING
        if not self._dirty:
            return
        self._dirty = False
        p = self.params
        grid = self._grid
        t0 = time.perf_counter()
        extra = None
        if p.use_object_costmap and self._layer is not None:
            if self._layer.frame_id != grid.frame_id:
                self._warn("layer_frame", f"object_costmap frame {self._layer.frame_id!r} "
                                          f"differs from map frame {grid.frame_id!r}: ignored")
            else:
                extra = object_obstacles(self._layer, grid, p.object_occupied_threshold)
        passable = traversable_mask(grid, extra, p)
        self.frontiers = find_frontiers(grid, extra, p, passable=passable)
        t1 = time.perf_counter()
        self.runs += 1
        header = convert.make_header(grid.frame_id, grid.stamp_ns)
        cells, groups = frontier_clouds(self.frontiers, grid)
        self._pub_cells.publish(convert.cloud_to_msg(cells, header))
        self._pub_groups.publish(convert.cloud_to_msg(groups, header))
        self._pub_markers.publish(frontier_markers(self.frontiers, grid, header))
        timing = Float64MultiArray()
        timing.layout.dim = [MultiArrayDimension(label="detect_cluster_ms,groups,cells",
                                                 size=3, stride=3)]
        timing.data = [(t1 - t0) * 1e3, float(len(self.frontiers)),
                       float(sum(f.size_cells for f in self.frontiers))]
        self._pub_timing.publish(timing)


def main(args: list[str] | None = None) -> int:
    """Console script ``frontier_detector``."""
    return run(FrontierDetectorNode, args)


if __name__ == "__main__":
    main()
