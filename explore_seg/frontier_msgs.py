"""Frontiers as messages: point clouds of the cells and cPoints, and RViz markers.

Published by ``frontier_detector`` and by ``target_selector`` (which detects frontiers
itself) on ``frontiers``, ``frontiers/groups`` and ``frontiers/markers``.
"""

from __future__ import annotations

import numpy as np
from geometry_msgs.msg import Point
from rclpy.node import Node
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from explore_seg import convert
from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import GridMap

#: Marker sizes (m): frontier cell points, cPoint spheres, text height.
_CELL_MARKER_M = 0.05
_SPHERE_MARKER_M = 0.25
_TEXT_MARKER_M = 0.3


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


class FrontierPublisher:
    """The three frontier topics of a node (``frontiers``, ``frontiers/groups``,
    ``frontiers/markers``), published together for one map."""

    def __init__(self, node: Node) -> None:
        self._cells = node.create_publisher(PointCloud2, "frontiers", 1)
        self._groups = node.create_publisher(PointCloud2, "frontiers/groups", 1)
        self._markers = node.create_publisher(MarkerArray, "frontiers/markers", 1)

    def publish(self, frontiers: list[Frontier], grid: GridMap) -> None:
        """Publish the frontiers of ``grid`` (stamped with the map's stamp)."""
        header = convert.make_header(grid.frame_id, grid.stamp_ns)
        cells, groups = frontier_clouds(frontiers, grid)
        self._cells.publish(convert.cloud_to_msg(cells, header))
        self._groups.publish(convert.cloud_to_msg(groups, header))
        self._markers.publish(frontier_markers(frontiers, grid, header))
