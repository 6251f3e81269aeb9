"""``target_selector`` node: picks the next frontier goal and sends it as ``goal_pose``.

Thin wiring around the ROS-free decision core :class:`explore_seg.core.explorer.Explorer`:
it detects frontiers from ``map`` (+ ``object_costmap``) itself (no ``frontier_detector``
needed; it publishes the same ``frontiers`` topics), computes path lengths robot ->
cPoints in one sweep, scores them (``strategy``: the paper's eq. 1-3 with region labels
from ``regions``, nearest, explore_lite, or rrt_exploration, whose candidates come from
RRTs) and keeps, switches, blacklists and finishes. Its parameters:
:class:`~explore_seg.core.selection.SelectorNodeParams`, the detection parameters
:class:`~explore_seg.core.frontiers.FrontierParams` under ``frontier.`` and the RRT
detector's :class:`~explore_seg.core.rrt.RrtParams` under ``rrt.``. It subscribes ``scan``
too: with ``scan_overlay.enabled`` the scans since the last maps fill the map's unknown
cells for the decisions (:mod:`explore_seg.core.scan_overlay`, :mod:`explore_seg.scan_input`).
A SLAM correction (a loop closure), found in the map-frame poses or in ``map``
(``scan_overlay.correction_*``, :mod:`explore_seg.core.corrections`), makes the overlay
forget the scans taken before it: they were laid at the uncorrected poses.

One timer ``_tick`` on the ROS clock (``rate_hz``) runs the state machine::

    WAITING_FOR_MAP -> WAITING_FOR_POSE -> SELECTING <-> NAVIGATING -> DONE
    (any) -> STOPPED via ~/stop; STOPPED/DONE -> running via ~/resume or ~/start

In DONE the node idles: the tick returns at once and the pose subscription is dropped
until ``exploration_done`` turns false again (:class:`~explore_seg.done_gate.DoneGate`).

Bad input never raises out of a callback: malformed messages are dropped (throttled
warning), the last good map/pose/labels are kept; labels whose geometry differs from the
map are ignored; a robot outside the map or walled in gets no new goal (the current one
is kept and its progress still checked).
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np
from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import MapMetaData, OccupancyGrid
from rclpy.node import Node
from sensor_msgs.msg import Image, LaserScan
from std_msgs.msg import Bool, ColorRGBA, Float64MultiArray, MultiArrayDimension
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker, MarkerArray

from explore_seg import convert
from explore_seg.core.corrections import CorrectionDetector
from explore_seg.core.explorer import Explorer, ExplorerStep
from explore_seg.core.frontiers import Frontier, FrontierParams
from explore_seg.core.grid import GridMap, resample_array
from explore_seg.core.limits import InputLimits
from explore_seg.core.pose_fusion import PoseFusionParams
from explore_seg.core.rrt import RrtParams
from explore_seg.core.scan_overlay import ScanOverlayParams
from explore_seg.core.selection import Action, Goal, NavOutcome, SelectorNodeParams
from explore_seg.done_gate import DoneGate
from explore_seg.frontier_msgs import FrontierPublisher
from explore_seg.frontier_node import FRONTIER_PREFIX
from explore_seg.nav_client import NavClient
from explore_seg.node_util import WarnThrottle, failsafe, run
from explore_seg.params import ParamBinding
from explore_seg.pose_input import PoseHooks, PoseInput
from explore_seg.qos import MAP_QOS, POSE_QOS, RELIABLE_QOS, SENSOR_QOS, map_qos
from explore_seg.scan_input import ScanInput
from explore_seg.time_guard import StallWatchdog, TimeGuard

#: Seconds between repeated warnings of one kind.
_WARN_PERIOD_S = 5.0
#: Marker sizes (m): goal arrow length / width, blacklist spheres.
_ARROW_M = (0.5, 0.08)
_BLACKLIST_MARKER_M = 0.2


class State(Enum):
    """State of the decision loop."""

    WAITING_FOR_MAP = "waiting_for_map"
    WAITING_FOR_POSE = "waiting_for_pose"
    SELECTING = "selecting"
    NAVIGATING = "navigating"
    DONE = "done"
    STOPPED = "stopped"


class TargetSelectorNode(Node):
    """Frontier goal selection node (see module docstring)."""

    def __init__(self, *, context=None, parameter_overrides=None,
                 node_name: str = "target_selector", namespace: str = "") -> None:
        super().__init__(node_name, context=context,
                         parameter_overrides=parameter_overrides or [], namespace=namespace)
        self._p = ParamBinding(self, SelectorNodeParams())
        self._fp = ParamBinding(self, FrontierParams(), prefix=FRONTIER_PREFIX)
        self._lp = ParamBinding(self, InputLimits(), prefix="input.")
        self._pfp = ParamBinding(self, PoseFusionParams(), prefix="pose_fusion.")
        self._rp = ParamBinding(self, RrtParams(), prefix="rrt.")
        self._op = ParamBinding(self, ScanOverlayParams(), prefix="scan_overlay.")
        p = self._p.params
        self._explorer = Explorer(self._fp.params, p, self._rp.params, self._op.params)
        self._corrections = CorrectionDetector(self._op.params)
        self._grid: GridMap | None = None
        self._layer: GridMap | None = None
        self._regions_img: Image | None = None
        self._regions_info: MapMetaData | None = None
        self._labels: np.ndarray | None = None
        self._labels_dirty = False
        self._pose: tuple[float, float, float] | None = None
        self._pose_time_ns = 0
        self.frontiers: list[Frontier] = []
        self._state = State.STOPPED if not p.autostart else State.WAITING_FOR_MAP
        self._done_published: bool | None = None
        self._last_goal_pub_s = -math.inf
        self._region_warned = False
        self._warn = WarnThrottle(self, _WARN_PERIOD_S)
        self.failures = 0          # cycles lost to an exception (node_util.failsafe)
        self.last_reason = ""
        self.goals_sent = 0
        self._time = TimeGuard(self._lp.params.clock_jump_s)
        self._stall = StallWatchdog(self._lp.params.stall_periods)
        self._pose_stamp_ns: int | None = None

        self._pub_goal = self.create_publisher(PoseStamped, "goal_pose", RELIABLE_QOS)
        self._pub_done = self.create_publisher(Bool, "exploration_done", MAP_QOS)
        self._pub_markers = self.create_publisher(MarkerArray, "~/markers", 1)
        self._pub_timing = self.create_publisher(Float64MultiArray, "~/timing", 10)
        self._pub_frontiers = FrontierPublisher(self)
        qos = map_qos(p.map_transient_local)
        self.create_subscription(OccupancyGrid, "map", self._on_map, qos)
        self.create_subscription(OccupancyGrid, "object_costmap", self._on_layer, qos)
        self.create_subscription(Image, "regions", self._on_regions, qos)
        self.create_subscription(MapMetaData, "regions/info", self._on_regions_info, qos)
        self._scans = ScanInput(lambda: self._op.params, self._explorer.add_scan, self._warn)
        self.create_subscription(LaserScan, "scan", self._scans.on_scan, SENSOR_QOS)
        # The pose stream is unsubscribed while exploration_done is true (idle after done;
        # ~/start or ~/resume publish false, which subscribes again).
        self._done_gate = DoneGate(self, "pose subscription", lambda: [], lambda: True)
        self._pose_in = PoseInput(
            self, p.pose_topic_type, self._pfp.params, POSE_QOS, PoseHooks(
                map_frame=lambda: None if self._grid is None else self._grid.frame_id,
                limits=lambda: self._lp.params, warn=self._warn,
                drop=lambda text: self._warn("pose", f"dropped {text}"),
                on_pose=self._set_pose, grid=lambda: self._grid),
            subscribe=self._done_gate.subscribe)
        self._pfp.on_change(lambda old, new: self._pose_in.set_params(new))
        self._nav = (NavClient(self, p.nav_action, p.nav_accept_timeout_s, p.cancel_timeout_s,
                               self._warn) if p.nav_action else None)
        self.create_service(Trigger, "~/start", self._srv_start)
        self.create_service(Trigger, "~/stop", self._srv_stop)
        self.create_service(Trigger, "~/resume", self._srv_resume)
        self._timer = self.create_timer(1.0 / p.rate_hz, self._tick)
        self._p.on_change(self._params_changed)
        self._fp.on_change(lambda old, new: self._explorer.set_params(frontier=new))
        self._rp.on_change(lambda old, new: self._explorer.set_params(rrt=new))
        self._op.on_change(self._overlay_params_changed)
        self._publish_done(False)

    # ---------------------------------------------------------------- helpers
    @property
    def params(self) -> SelectorNodeParams:
        """Current parameters (selection and node settings)."""
        return self._p.params

    @property
    def frontier_params(self) -> FrontierParams:
        """Current detection parameters (``frontier.*``)."""
        return self._fp.params

    @property
    def state(self) -> State:
        """Current state of the decision loop."""
        return self._state

    @property
    def explorer(self) -> Explorer:
        """The decision core."""
        return self._explorer

    @property
    def nav(self) -> NavClient | None:
        """The navigator's status/cancel client (None with ``nav_action: ''``)."""
        return self._nav

    @property
    def manager(self):  # noqa: ANN201 (the Explorer's GoalManager)
        """The decision core's goal manager (current goal, blacklist)."""
        return self._explorer.manager

    def _now_s(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def _params_changed(self, old: SelectorNodeParams, new: SelectorNodeParams) -> None:
        self._explorer.set_params(selection=new)
        if new.rate_hz != old.rate_hz:
            self._timer.cancel()
            self.destroy_timer(self._timer)
            self._timer = self.create_timer(1.0 / new.rate_hz, self._tick)
        if new.pose_topic_type != old.pose_topic_type or new.nav_action != old.nav_action:
            self._warn("restart_params",
                       "pose_topic_type and nav_action changes take effect after a restart")

    def _publish_done(self, done: bool) -> None:
        if self._done_published is done:
            return
        self._done_published = done
        self._pub_done.publish(Bool(data=done))

    def _overlay_params_changed(self, old: ScanOverlayParams, new: ScanOverlayParams) -> None:
        self._corrections.settings = new
        self._explorer.set_params(overlay=new)

    def _map_corrected(self) -> None:
        """The SLAM corrections the detector found (and queued) since the last call: the
        overlay forgets the scans taken before each (they were laid at uncorrected
        poses)."""
        for c in self._corrections.take():
            self._explorer.map_corrected(c.stamp_ns * 1e-9)
            self.get_logger().info(f"SLAM correction at {c.stamp_ns * 1e-9:.3f} s "
                                   f"({c.source}: {c.detail}): the scan overlay forgets the "
                                   "scans before it")

    # -------------------------------------------------------------- callbacks
    def _on_map(self, msg: OccupancyGrid) -> None:
        try:
            self._grid = convert.grid_from_msg(msg, self._lp.params)
        except ValueError as err:
            self._warn("map", f"dropped map: {err}")
            return
        self._labels_dirty = True
        if self._op.params.enabled:
            self._corrections.observe_map(self._grid)
            self._map_corrected()

    def _on_layer(self, msg: OccupancyGrid) -> None:
        try:
            self._layer = convert.grid_from_msg(msg, self._lp.params)
        except ValueError as err:
            self._warn("object_costmap", f"dropped object_costmap: {err}")

    def _on_regions(self, msg: Image) -> None:
        self._regions_img = msg
        self._labels_dirty = True

    def _on_regions_info(self, msg: MapMetaData) -> None:
        self._regions_info = msg
        self._labels_dirty = True

    def _set_pose(self, t_ns: int, pose: tuple[float, float, float]) -> None:
        """A new newest map-frame pose (from :class:`PoseInput`)."""
        self._pose_stamp_ns = t_ns
        self._pose = pose
        self._pose_time_ns = self.get_clock().now().nanoseconds
        self._scans.note_pose(t_ns, pose)
        if self._op.params.enabled:
            self._corrections.observe_pose(t_ns, pose)
            self._map_corrected()

    # --------------------------------------------------------------- services
    def _srv_start(self, request: Trigger.Request, response: Trigger.Response
                   ) -> Trigger.Response:
        self._explorer.reset(clear_blacklist=True)
        self._state = State.WAITING_FOR_MAP
        self._publish_done(False)
        response.success, response.message = True, "exploration (re)started"
        return response

    def _srv_stop(self, request: Trigger.Request, response: Trigger.Response
                  ) -> Trigger.Response:
        was = self._state
        self._state = State.STOPPED
        response.success = True
        canceled = self._cancel_goal("stop")
        response.message = ("already stopped" if was is State.STOPPED else
                            "stopped, navigation goal canceled" if canceled else
                            "stopped (no new goals; the navigator keeps its current goal)")
        return response

    def _cancel_goal(self, why: str) -> bool:
        """Cancel our goal at the navigator; the goal is then forgotten, not blacklisted."""
        if self._nav is None or not self._nav.cancel(why):
            return False
        self._explorer.report_navigation(NavOutcome.CANCELED_BY_US)
        self._nav.tracker.clear()
        return True

    def _follow_navigation(self) -> None:
        """Report the navigator's outcomes (status topic, accept timeout) to the core."""
        if self._nav is None:
            return
        for ev in self._nav.poll():
            if ev.outcome is None:
                continue
            applied = self._explorer.report_navigation(ev.outcome, ev.goal_xy_m)
            self.get_logger().info(ev.message + ("" if applied else " (no longer our goal)"))

    def destroy_node(self) -> None:
        """Cancel our navigation goal (not waiting for the answer), then destroy."""
        if self._nav is not None:
            try:
                self._cancel_goal("shutdown")
            except Exception as err:  # noqa: BLE001 - shutting down: log, never raise
                self.get_logger().warn(f"cancel at shutdown failed: {err}")
        super().destroy_node()

    def _srv_resume(self, request: Trigger.Request, response: Trigger.Response
                    ) -> Trigger.Response:
        if self._state is State.DONE or self.manager.done:
            goal_kept = False
            self._explorer.reset(clear_blacklist=False)
            self._publish_done(False)
        else:
            goal_kept = self.manager.goal is not None
        if self._state in (State.STOPPED, State.DONE):
            self._state = State.WAITING_FOR_MAP
            response.message = "resumed" + (" with the previous goal" if goal_kept else "")
        else:
            response.message = "already running"
        response.success = True
        return response

    # ------------------------------------------------------------------- tick
    def _update_labels(self, grid: GridMap) -> None:
        if not self._labels_dirty:
            return
        self._labels_dirty = False
        self._labels = None
        if self._regions_img is None or self._regions_info is None:
            return
        try:
            labels, geom = convert.labels_from_msgs(self._regions_img, self._regions_info,
                                                    self._lp.params)
        except ValueError as err:
            self._warn("regions", f"dropped regions: {err}")
            return
        if geom.frame_id != grid.frame_id or abs(geom.resolution_m - grid.resolution_m) > 1e-9:
            self._warn("regions_geometry", "regions are in frame "
                                           f"{geom.frame_id!r} at {geom.resolution_m} m, the map "
                                           f"in {grid.frame_id!r} at {grid.resolution_m} m: "
                                           "ignored until they match")
            return  # a new map or new labels mark them dirty again
        if not geom.same_geometry(grid):
            # Labels of a slightly older map (the map grew or shifted since): carry them
            # over cell by cell through world coordinates; new cells get no region (0).
            labels = resample_array(labels, geom, grid, fill=0)
        self._labels = labels

    def _check_clock(self, now_ns: int) -> None:
        """A clock jump restarts the goal's timers and forgets a pose of the old time line."""
        jump = self._time.observe("clock", now_ns, int(1e9 / self.params.rate_hz))
        if jump is None:
            return
        if jump.backwards:
            self._pose = None
            self._pose_in.clear()
            self._scans.clear()
            self._corrections.reset()
        self._explorer.clock_jumped(now_ns * 1e-9)
        self._warn("clock_jump", jump.describe() + "; goal timers restarted")

    def _stall_reason(self) -> str:
        if self._pose is None:
            return "no valid robot pose received (see the dropped pose warnings, if any)"
        age_s = (self.get_clock().now().nanoseconds - self._pose_time_ns) * 1e-9
        return (f"newest pose received {age_s:.1f} s ago (pose_timeout_s "
                f"{self.params.pose_timeout_s:g}; pose stamp "
                f"{(self._pose_stamp_ns or 0) * 1e-9:.3f} s)")

    @failsafe("goal selection")
    def _tick(self) -> None:
        if self._state is State.DONE:
            return      # idle: only ~/start or ~/resume wake it
        self._follow_navigation()
        if self._state is State.STOPPED:
            return
        self._check_clock(self.get_clock().now().nanoseconds)
        reason = self._stall.tick(self._grid is not None, self._tick_decides(),
                                  self._stall_reason)
        if reason is not None:
            self._warn("stall", f"map received but no decision for "
                                f"{self._lp.params.stall_periods} periods: {reason}")

    def _tick_decides(self) -> bool:
        """One decision cycle; False when it waited for an input."""
        grid = self._grid
        if grid is None:
            self._state = State.WAITING_FOR_MAP
            return False
        p = self.params
        now_ns = self.get_clock().now().nanoseconds
        if self._pose is None or (now_ns - self._pose_time_ns) * 1e-9 > p.pose_timeout_s:
            self._state = State.WAITING_FOR_POSE
            return False
        self._update_labels(grid)
        out = self._explorer.step(self._now_s(), grid, self._pose, self._layer, self._labels)
        for key, text in out.warnings:
            self._warn(key, text)
        self.frontiers = out.frontiers
        if out.detected:
            self._pub_frontiers.publish(out.frontiers, grid)
        self.last_reason = out.reason
        self._log_region_gain(out)
        self._act(out.action, out.goal, out.reason, grid)
        timing = Float64MultiArray()
        timing.layout.dim = [MultiArrayDimension(
            label="detect_cluster_ms,selection_ms,frontiers", size=3, stride=3)]
        timing.data = [out.detect_s * 1e3, out.select_s * 1e3, float(len(out.frontiers))]
        self._pub_timing.publish(timing)
        return True

    def _log_region_gain(self, out: ExplorerStep) -> None:
        """Say once when a region strategy runs without region labels."""
        sel = out.selection
        if (sel is not None and self._explorer.strategy.region_term
                and not sel.region_gain_active and not self._region_warned and out.frontiers):
            self._region_warned = True
            self.get_logger().info("regionGain is 0 (no region labels for the map or the "
                                   "robot's cell): ranking by distance and size only")

    def _act(self, action: Action, goal: Goal | None, reason: str, grid: GridMap) -> None:
        p = self.params
        now_s = self._now_s()
        if action is Action.NEW_GOAL and goal is not None:
            self._send_goal(goal, grid)
            self._state = State.NAVIGATING
            self.get_logger().info(f"goal ({goal.xy_m[0]:.2f}, {goal.xy_m[1]:.2f}): {reason}")
        elif action is Action.KEEP and goal is not None:
            self._state = State.NAVIGATING
            if p.goal_republish_s > 0 and now_s - self._last_goal_pub_s >= p.goal_republish_s:
                self._send_goal(goal, grid)
        elif action is Action.DONE:
            self._state = State.DONE
            self._publish_done(True)
            self.get_logger().info(f"exploration done: {reason}")
            self._cancel_goal("exploration done")
        else:
            self._state = State.SELECTING
        self._publish_markers(grid)

    def _send_goal(self, goal: Goal, grid: GridMap) -> None:
        self._pub_goal.publish(convert.pose_stamped(goal.xy_m[0], goal.xy_m[1], goal.yaw_rad,
                                                    grid.frame_id,
                                                    self.get_clock().now().to_msg()))
        self._last_goal_pub_s = self._now_s()
        self.goals_sent += 1
        if self._nav is not None:
            self._nav.goal_sent(goal.xy_m)

    def _publish_markers(self, grid: GridMap) -> None:
        header = convert.make_header(grid.frame_id, self.get_clock().now().to_msg())
        out = MarkerArray()
        clear = Marker()
        clear.header, clear.action = header, Marker.DELETEALL
        out.markers.append(clear)
        goal = self.manager.goal
        if goal is not None:
            arrow = Marker()
            arrow.header, arrow.ns, arrow.id = header, "goal", 0
            arrow.type, arrow.action = Marker.ARROW, Marker.ADD
            arrow.pose = convert.pose_from_2d(goal.xy_m[0], goal.xy_m[1], goal.yaw_rad)
            arrow.scale.x, arrow.scale.y = _ARROW_M
            arrow.scale.z = _ARROW_M[1]
            arrow.color = ColorRGBA(r=0.1, g=0.9, b=0.2, a=1.0)
            out.markers.append(arrow)
        if self.manager.blacklist:
            bl = Marker()
            bl.header, bl.ns, bl.id = header, "blacklist", 0
            bl.type, bl.action = Marker.SPHERE_LIST, Marker.ADD
            bl.pose.orientation.w = 1.0
            bl.scale.x = bl.scale.y = bl.scale.z = _BLACKLIST_MARKER_M
            bl.color = ColorRGBA(r=0.9, g=0.1, b=0.1, a=0.8)
            bl.points = [Point(x=bx, y=by, z=0.0) for bx, by in self.manager.blacklist]
            out.markers.append(bl)
        self._pub_markers.publish(out)


def main(args: list[str] | None = None) -> int:
    """Console script ``target_selector``."""
    return run(TargetSelectorNode, args)


if __name__ == "__main__":
    main()
