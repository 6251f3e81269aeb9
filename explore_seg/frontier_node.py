"""``frontier_detector`` node: frontier cells and groups (with cPoints) of the map.

Callbacks store the newest ``map`` and ``object_costmap``; a timer on the ROS clock
(``rate_hz``) recomputes the frontiers when either changed since the last run (so at most
once per map update) with :func:`explore_seg.core.explorer.detect_frontiers`, and
publishes every frontier cell (``frontiers``), one point per group at its cPoint
(``frontiers/groups``), RViz markers (``frontiers/markers``) and the processing time
(``~/timing``). Detection parameters are bound under ``frontier.`` (shared with
``target_selector``, which detects frontiers itself: the ``explorer`` process does not
run this node). Time model (:class:`~explore_seg.time_guard.TimeGuard`): when the map stamps
jump back by more than ``input.clock_jump_s`` (a simulator restart, a new SLAM session) the
object layer of the old time line is dropped until a new one arrives; jumps of the map,
layer or clock and a layer whose stamps lie far from the map's are logged once.
"""

from __future__ import annotations

import time
from enum import Enum

from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from explore_seg import convert
from explore_seg.core.explorer import detect_frontiers
from explore_seg.core.frontiers import (Frontier, FrontierCache, FrontierNodeParams,
                                        FrontierParams)
from explore_seg.core.grid import GridMap
from explore_seg.core.limits import InputLimits
from explore_seg.frontier_msgs import FrontierPublisher
from explore_seg.node_util import WarnThrottle, failsafe, run
from explore_seg.params import ParamBinding
from explore_seg.qos import map_qos
from explore_seg.time_guard import TimeGuard

#: Seconds between repeated warnings of one kind.
_WARN_PERIOD_S = 5.0
#: Prefix of the detection parameters (shared with target_selector).
FRONTIER_PREFIX = "frontier."


class State(Enum):
    """What the node is doing."""

    WAITING_FOR_MAP = 0
    RUNNING = 1


class FrontierDetectorNode(Node):
    """Frontier detection node (see module docstring)."""

    def __init__(self, *, context=None, parameter_overrides=None,
                 node_name: str = "frontier_detector", namespace: str = "") -> None:
        super().__init__(node_name, context=context,
                         parameter_overrides=parameter_overrides or [], namespace=namespace)
        self._node_p = ParamBinding(self, FrontierNodeParams())
        self._p = ParamBinding(self, FrontierParams(), prefix=FRONTIER_PREFIX)
        self._lp = ParamBinding(self, InputLimits(), prefix="input.")
        node_p = self._node_p.params
        self._grid: GridMap | None = None
        self._layer: GridMap | None = None
        self._dirty = False
        self._state = State.WAITING_FOR_MAP
        self._fcache = FrontierCache()   # exact: reused only where the map is unchanged
        self.frontiers: list[Frontier] = []
        self.runs = 0
        self._warn = WarnThrottle(self, _WARN_PERIOD_S)
        self.failures = 0          # cycles lost to an exception (node_util.failsafe)
        self._time = TimeGuard(self._lp.params.clock_jump_s,
                               clock=lambda: self.get_clock().now().nanoseconds)
        self._lp.on_change(lambda old, new: setattr(self._time, "jump_s", new.clock_jump_s))

        self._pub_frontiers = FrontierPublisher(self)
        self._pub_timing = self.create_publisher(Float64MultiArray, "~/timing", 10)
        qos = map_qos(node_p.map_transient_local)
        self.create_subscription(OccupancyGrid, "map", self._on_map, qos)
        self.create_subscription(OccupancyGrid, "object_costmap", self._on_layer, qos)
        self._timer = self.create_timer(1.0 / node_p.rate_hz, self._tick)
        self._p.on_change(self._params_changed)
        self._node_p.on_change(self._node_params_changed)

    @property
    def params(self) -> FrontierParams:
        """Current detection parameters."""
        return self._p.params

    @property
    def node_params(self) -> FrontierNodeParams:
        """Current node settings."""
        return self._node_p.params

    @property
    def state(self) -> State:
        """Current state."""
        return self._state

    def _params_changed(self, old: FrontierParams, new: FrontierParams) -> None:
        self._dirty = True

    def _node_params_changed(self, old: FrontierNodeParams, new: FrontierNodeParams) -> None:
        if new.rate_hz != old.rate_hz:
            self._timer.cancel()
            self.destroy_timer(self._timer)
            self._timer = self.create_timer(1.0 / new.rate_hz, self._tick)

    def _observe(self, stream: str, t_ns: int, expected_gap_ns: int = 0) -> None:
        """Feed the time model; map stamps going back drop the layer of the old time line."""
        if t_ns == 0 and stream != "clock":
            return                              # an unstamped map: no time line
        def drop_layer() -> str:
            if stream != "map" or self._layer is None:
                return ""
            self._layer = None
            return "object layer of the old time line dropped"
        self._time.track(stream, t_ns, self._warn, drop_layer, expected_gap_ns)

    @property
    def time_jumps(self) -> int:
        """Clock jumps seen (map, layer or clock)."""
        return self._time.jumps

    def _on_map(self, msg: OccupancyGrid) -> None:
        try:
            self._grid = convert.grid_from_msg(msg, self._lp.params)
            self._dirty = True
        except ValueError as err:
            self._warn("map", f"dropped map: {err}")
            return
        self._observe("map", self._grid.stamp_ns)

    def _on_layer(self, msg: OccupancyGrid) -> None:
        try:
            self._layer = convert.grid_from_msg(msg, self._lp.params)
            self._dirty = True
        except ValueError as err:
            self._warn("object_costmap", f"dropped object_costmap: {err}")
            return
        self._observe("object_costmap", self._layer.stamp_ns)

    @failsafe("frontier detection")
    def _tick(self) -> None:
        self._observe("clock", self.get_clock().now().nanoseconds,
                      int(1e9 / self.node_params.rate_hz))
        if self._grid is None:
            self._state = State.WAITING_FOR_MAP
            return
        self._state = State.RUNNING
        if not self._dirty:
            return
        self._dirty = False
        grid = self._grid
        t0 = time.perf_counter()
        self._fcache.start(grid)
        det = detect_frontiers(grid, self._layer, self.params, cache=self._fcache)
        if det.layer_warning:
            self._warn("layer_frame", det.layer_warning)
        skew = self._time.disagreement("map", "object_costmap") if self._layer else None
        if skew:
            self._warn("layer_time", f"object_costmap used, but {skew}")
        self.frontiers = det.frontiers
        t1 = time.perf_counter()
        self.runs += 1
        self._pub_frontiers.publish(self.frontiers, grid)
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
