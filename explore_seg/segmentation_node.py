"""``segmentation`` node: DuDe room segmentation of the map, with persistent region ids.

The ``map`` callback only stores the newest message; a timer on the ROS clock
(``process_period_s``) processes the newest one not yet processed, so when maps arrive
faster than they can be segmented the stale ones are skipped and at most one result is
published per map update. Each result is published as

* ``regions`` (sensor_msgs/Image, 32SC1): region id per map cell, aligned cell-for-cell
  with the map (row = y, not flipped), header = the map's frame and stamp;
* ``regions/info`` (nav_msgs/MapMetaData): the map geometry, ``map_load_time`` = the map
  stamp (pairs the two);
* ``regions/color`` (nav_msgs/OccupancyGrid): a visualisation for RViz (``costmap``
  colour scheme): every region id hashed to 1..99, -1 where there is no region; only
  while it has a subscriber;
* ``~/timing`` (std_msgs/Float64): wall time of the update in milliseconds.

While ``exploration_done`` is true (and ``idle_when_done``), the timer is paused
(:class:`~explore_seg.done_gate.DoneGate`); the newest map is kept and segmented when the
flag turns false.

Ids of regions that did not change stay the same between updates (DuDe spec shared/docs/dude.md §12).
When the map stamps or the node clock jump back by more than ``input.clock_jump_s`` (a
simulator restart, a new SLAM session) the incremental state is dropped: the next map is
segmented from scratch (:class:`~explore_seg.time_guard.TimeGuard`; logged once).
"""

from __future__ import annotations

import time
from enum import Enum

import numpy as np
import numpy.typing as npt
from nav_msgs.msg import MapMetaData, OccupancyGrid
from rclpy.node import Node
from sensor_msgs.msg import Image
from std_msgs.msg import Float64

from explore_seg import convert
from explore_seg.core.grid import GridMap
from explore_seg.core.limits import InputLimits
from explore_seg.core.segmentation import (IncrementalSegmenter, SegmentationNodeParams,
                                           SegmentationParams)
from explore_seg.done_gate import DoneGate
from explore_seg.node_util import WarnThrottle, failsafe, run
from explore_seg.params import ParamBinding
from explore_seg.qos import MAP_QOS, map_qos
from explore_seg.time_guard import TimeGuard

#: Seconds between repeated warnings of one kind.
_WARN_PERIOD_S = 5.0
#: Colour grid: ids are hashed to 1..COLOR_LEVELS; the multiplier spreads neighbours.
COLOR_LEVELS = 99
_COLOR_STRIDE = 37


class State(Enum):
    """What the node is doing."""

    WAITING_FOR_MAP = 0
    RUNNING = 1


def color_grid(labels: npt.NDArray[np.int32], grid: GridMap) -> GridMap:
    """Visualisation grid of region labels: id hashed to 1..99, -1 where no region."""
    data = np.where(labels > 0, (labels.astype(np.int64) * _COLOR_STRIDE) % COLOR_LEVELS + 1,
                    -1).astype(np.int8)
    return grid.with_data(data)


class SegmentationNode(Node):
    """Room segmentation node (see module docstring)."""

    def __init__(self, *, context=None, parameter_overrides=None,
                 node_name: str = "segmentation", namespace: str = "") -> None:
        super().__init__(node_name, context=context,
                         parameter_overrides=parameter_overrides or [], namespace=namespace)
        self._p = ParamBinding(self, SegmentationNodeParams())
        self._lp = ParamBinding(self, InputLimits(), prefix="input.")
        p = self._p.params
        self._seg = IncrementalSegmenter(self._algo_params(p))
        self._latest: OccupancyGrid | None = None
        self._state = State.WAITING_FOR_MAP
        self._warn = WarnThrottle(self, _WARN_PERIOD_S)
        self.failures = 0          # cycles lost to an exception (node_util.failsafe)
        #: Number of maps segmented and of maps skipped as stale.
        self.processed = 0
        self.skipped = 0
        self.last_labels: npt.NDArray[np.int32] | None = None
        self._time = TimeGuard(self._lp.params.clock_jump_s,
                               clock=lambda: self.get_clock().now().nanoseconds)
        self._lp.on_change(lambda old, new: setattr(self._time, "jump_s", new.clock_jump_s))

        self._pub_regions = self.create_publisher(Image, "regions", MAP_QOS)
        self._pub_info = self.create_publisher(MapMetaData, "regions/info", MAP_QOS)
        self._pub_color = self.create_publisher(OccupancyGrid, "regions/color", MAP_QOS)
        self._pub_timing = self.create_publisher(Float64, "~/timing", 10)
        self.create_subscription(OccupancyGrid, "map", self._on_map,
                                 map_qos(p.map_transient_local))
        self._timer = self.create_timer(p.process_period_s, self._tick)
        # After a pause the clock has moved on: no jump (the map stamps are kept).
        self._done_gate = DoneGate(self, "segmentation", lambda: [self._timer],
                                   lambda: self.params.idle_when_done,
                                   lambda: self._time.forget("clock"))
        self._p.on_change(self._params_changed)

    @staticmethod
    def _algo_params(p: SegmentationNodeParams) -> SegmentationParams:
        names = SegmentationParams.__dataclass_fields__
        return SegmentationParams(**{k: getattr(p, k) for k in names})

    @property
    def params(self) -> SegmentationNodeParams:
        """Current parameters."""
        return self._p.params

    @property
    def state(self) -> State:
        """Current state."""
        return self._state

    @property
    def paused(self) -> bool:
        """True while idle after exploration_done (see :class:`DoneGate`)."""
        return self._done_gate.paused

    @property
    def segmenter(self) -> IncrementalSegmenter:
        """The segmenter (its ``last_update_info`` tells what the last update did)."""
        return self._seg


    def _params_changed(self, old: SegmentationNodeParams,
                        new: SegmentationNodeParams) -> None:
        algo_old, algo_new = self._algo_params(old), self._algo_params(new)
        if algo_new != algo_old:
            self._seg.set_params(algo_new)
        if new.process_period_s != old.process_period_s:
            self._timer.cancel()
            self.destroy_timer(self._timer)
            self._timer = self._done_gate.adopt(
                self.create_timer(new.process_period_s, self._tick))
        self._done_gate.update()                # idle_when_done

    def _restart_segmenter(self) -> None:
        """After a failed update: the next one is a full run (no half-updated state)."""
        self._seg.set_params(self._seg.params)

    def _on_map(self, msg: OccupancyGrid) -> None:
        if self._latest is not None:
            self.skipped += 1
        self._latest = msg

    def _observe(self, stream: str, t_ns: int, expected_gap_ns: int = 0) -> None:
        """Feed the time model; a jump back restarts the segmenter (a new time line)."""
        def restart() -> str:
            self._restart_segmenter()
            return "the next map is segmented from scratch"
        self._time.track(stream, t_ns, self._warn, restart, expected_gap_ns)

    @property
    def time_jumps(self) -> int:
        """Clock jumps seen (map stamps or node clock)."""
        return self._time.jumps

    @failsafe("segmentation update", on_error="_restart_segmenter")
    def _tick(self) -> None:
        self._observe("clock", self.get_clock().now().nanoseconds,
                      int(self.params.process_period_s * 1e9))
        msg, self._latest = self._latest, None
        if msg is None:
            return
        try:
            grid = convert.grid_from_msg(msg, self._lp.params)
        except ValueError as err:
            self._warn("map", f"dropped map: {err}")
            return
        if grid.stamp_ns > 0:                   # 0: an unstamped map, no time line
            self._observe("map", grid.stamp_ns)
        self._state = State.RUNNING
        t0 = time.perf_counter()
        if not self.params.incremental:
            self._seg.set_params(self._seg.params)      # next update is a full run
        labels = self._seg.update(grid)
        elapsed_ms = (time.perf_counter() - t0) * 1000.0
        self.last_labels = labels
        self.processed += 1
        img, info = convert.labels_to_msgs(labels, grid, msg.header.stamp)
        self._pub_regions.publish(img)
        self._pub_info.publish(info)
        if self._pub_color.get_subscription_count() > 0:
            # Only for display (RViz); colouring every update costs the other nodes
            # sharing this process their time.
            self._pub_color.publish(convert.grid_to_msg(color_grid(labels, grid),
                                                        msg.header.stamp))
        self._pub_timing.publish(Float64(data=elapsed_ms))


def main(args: list[str] | None = None) -> int:
    """Console script ``segmentation``."""
    return run(SegmentationNode, args)


if __name__ == "__main__":
    raise SystemExit(main())
