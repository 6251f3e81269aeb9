"""The demo's monitor: one rclpy node subscribed to the simulator's metrics and the
explorer's outputs, and the progress line it prints."""

from __future__ import annotations

import math
import time

import numpy as np

from explore_seg.core.selection.nav_status import STATUS_ABORTED, STATUS_CANCELED, \
    STATUS_SUCCEEDED


def metrics_from_diagnostics(msg) -> dict[str, float | str]:
    """The ``sim_bridge`` status of a DiagnosticArray as a dict (numbers parsed).

    Raises
    ------
    ValueError
        When the array holds no ``sim_bridge`` status.
    """
    for st in msg.status:
        if st.name == "sim_bridge":
            out: dict[str, float | str] = {}
            for kv in st.values:
                try:
                    out[kv.key] = float(kv.value)
                except ValueError:
                    out[kv.key] = kv.value
            return out
    raise ValueError(f"no 'sim_bridge' status in sim/metrics, got "
                     f"{[s.name for s in msg.status]}")


def boxes_from_markers(msg) -> list[np.ndarray]:
    """Footprints (4 x 2 corners) of the CUBE markers of namespace ``objects``.

    The object costmap publishes a DELETEALL then one cube per object, so every message
    is the full set.
    """
    from explore_seg.core.grid import yaw_from_quaternion
    from explore_seg.core.objects import rect_corners

    out = []
    for m in msg.markers:
        if m.ns != "objects" or m.type != m.CUBE or m.action != m.ADD:
            continue
        q = m.pose.orientation
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        out.append(rect_corners((m.pose.position.x, m.pose.position.y),
                                (m.scale.x, m.scale.y), yaw))
    return out


#: action_msgs/GoalStatus terminal codes.
_TERMINAL = {STATUS_SUCCEEDED: "succeeded", STATUS_CANCELED: "canceled",
             STATUS_ABORTED: "aborted"}


def nav_outcomes(ends: list[tuple[int, float, bool]], goal_times: list[float]) -> dict:
    """Goals navigation ended, by outcome, and for each goal navigation gave up on the
    sim seconds until the next goal was published (None: none came).

    Parameters
    ----------
    ends : list of (status code, end time s, replaced)
        One entry per goal: its terminal action_msgs/GoalStatus code, when the monitor
        saw it end, and whether a new goal appeared in that same status array.
    goal_times : list of float
        When the monitor received each ``goal_pose`` (s).

    Returns
    -------
    dict
        ``counts`` (succeeded / canceled / aborted / preempted), ``abort_wait_s`` (per
        aborted goal, in end order), and its mean and median. An aborted goal that a new
        goal replaced was preempted by the explorer (a newer ``goal_pose``), not given up
        by navigation: it counts as ``preempted``.
    """
    counts = {name: 0 for name in _TERMINAL.values()}
    counts["preempted"] = 0
    waits: list[float | None] = []
    for status, t, replaced in sorted(ends, key=lambda e: e[1]):
        name = _TERMINAL[status]
        if name == "aborted" and replaced:
            name = "preempted"
        counts[name] += 1
        if name == "aborted":
            nxt = [g for g in goal_times if g > t]
            waits.append(round(min(nxt) - t, 2) if nxt else None)
    done = [w for w in waits if w is not None]
    return {"counts": counts, "abort_wait_s": waits,
            "abort_wait_mean_s": round(float(np.mean(done)), 2) if done else None,
            "abort_wait_median_s": round(float(np.median(done)), 2) if done else None}


class Monitor:
    """Subscriptions of the demo (one rclpy node); the state is read by :func:`run_demo`."""

    def __init__(self, context, pose_source: str = "odom",
                 nav_action: str = "navigate_to_pose") -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseStamped
        from nav_msgs.msg import MapMetaData, OccupancyGrid
        from rclpy.node import Node
        from sensor_msgs.msg import Image
        from std_msgs.msg import Bool, Float64MultiArray
        from visualization_msgs.msg import MarkerArray

        from explore_seg.core.limits import InputLimits
        from explore_seg.core.pose_fusion import PoseFusionParams
        from explore_seg.pose_input import PoseHooks, PoseInput
        from explore_seg.qos import MAP_QOS, POSE_QOS, RELIABLE_QOS

        from rclpy.parameter import Parameter
        # On sim time: goal and navigation-outcome times are sim seconds.
        self.node = Node("demo_monitor", context=context, parameter_overrides=[
            Parameter("use_sim_time", Parameter.Type.BOOL, True)])
        n = self.node
        self.metrics: dict[str, float | str] = {}
        self.metrics_wall = time.monotonic()
        self.samples: list[tuple[float, float]] = []
        self.goals: list[tuple[float, float]] = []
        self.done = False
        self.grid = None
        self.labels = None
        self._regions_img = None
        self._regions_info = None
        self.boxes: list[np.ndarray] = []
        # (sim time, footprints) each time the set of boxes changed: what the object
        # costmap believed when, e.g. at a collision (object_history.jsonl).
        self.box_history: list[tuple[float, list[np.ndarray]]] = []
        self.pose: tuple[float, float, float] | None = None
        self.trail: list[tuple[float, float]] = []
        self.trail_spacing_m = 0.05
        self.trail_max = 20000
        self.dropped: dict[str, str] = {}
        n.create_subscription(DiagnosticArray, "sim/metrics", self._on_metrics, RELIABLE_QOS)
        n.create_subscription(PoseStamped, "goal_pose", self._on_goal, RELIABLE_QOS)
        n.create_subscription(Bool, "exploration_done", self._on_done, MAP_QOS)
        n.create_subscription(OccupancyGrid, "map", self._on_map, MAP_QOS)
        # The robot pose as the explorer takes it (odom, or odom fused with SLAM poses).
        self.pose_input = PoseInput(n, pose_source, PoseFusionParams(), POSE_QOS, PoseHooks(
            map_frame=lambda: "map", limits=InputLimits,
            warn=lambda key, text: n.get_logger().warn(text, throttle_duration_sec=5.0),
            drop=lambda text: self._drop("pose", text), on_pose=self._on_pose))
        n.create_subscription(Image, "regions", self._on_regions, MAP_QOS)
        n.create_subscription(MapMetaData, "regions/info", self._on_regions_info, MAP_QOS)
        n.create_subscription(MarkerArray, "object_costmap/markers", self._on_markers,
                              RELIABLE_QOS)
        # One timing message per camera frame the object costmap processed; it carries the
        # node's own counts of depth frames received and processed.
        self.object_frames = 0
        self.object_frames_received = 0
        self.object_frames_counted = 0
        self.object_frame_ms: list[float] = []      # detection + update per processed frame
        n.create_subscription(Float64MultiArray, "object_costmap/timing",
                              self._on_object_timing, 10)
        # How navigation ended each goal (the action's status topic) and when the next goal
        # came: the time a goal that navigation gave up on costs before the robot moves on.
        from action_msgs.msg import GoalStatusArray

        from explore_seg.qos import ACTION_STATUS_QOS
        self.nav_ends: dict[bytes, tuple[int, float, bool]] = {}
        self._nav_seen: dict[bytes, float] = {}      # goal id -> first seen in a status
        self.goal_times: list[float] = []
        n.create_subscription(GoalStatusArray, nav_action + "/_action/status",
                              self._on_nav_status, ACTION_STATUS_QOS)

    def _drop(self, what: str, err: Exception) -> None:
        self.dropped[what] = str(err)
        self.node.get_logger().warn(f"dropped {what}: {err}", throttle_duration_sec=5.0)

    def _on_metrics(self, msg) -> None:
        try:
            m = metrics_from_diagnostics(msg)
        except ValueError as err:
            self._drop("sim/metrics", err)
            return
        self.metrics = m
        self.metrics_wall = time.monotonic()
        t, c = m.get("sim_time_s"), m.get("coverage_pct")
        if isinstance(t, float) and isinstance(c, float) and math.isfinite(c):
            if not self.samples or t > self.samples[-1][0]:
                self.samples.append((t, c))

    def _on_goal(self, msg) -> None:
        self.goals.append((msg.pose.position.x, msg.pose.position.y))
        # The monitor's own (sim) clock, as for the outcomes: the explorer's stamps and the
        # simulator's acceptance stamps come from other processes' clocks, which lag
        # differently under load.
        self.goal_times.append(self.node.get_clock().now().nanoseconds * 1e-9)

    def _on_nav_status(self, msg) -> None:
        now_s = self.node.get_clock().now().nanoseconds * 1e-9
        ids = [bytes(st.goal_info.goal_id.uuid) for st in msg.status_list]
        # A goal aborted in the same status array that brings a new goal was replaced by
        # it (Nav2 and the stand-in end a preempted goal as ABORTED).
        new_goal = any(gid not in self._nav_seen for gid in ids)
        for gid, st in zip(ids, msg.status_list):
            self._nav_seen.setdefault(gid, now_s)
            if st.status in _TERMINAL and gid not in self.nav_ends:
                self.nav_ends[gid] = (int(st.status), now_s, new_goal)

    def nav_outcomes(self) -> dict:
        """:func:`nav_outcomes` of what the monitor saw."""
        return nav_outcomes(list(self.nav_ends.values()), self.goal_times)

    def _on_done(self, msg) -> None:
        self.done = self.done or bool(msg.data)

    def _on_map(self, msg) -> None:
        from explore_seg import convert
        try:
            self.grid = convert.grid_from_msg(msg)
        except ValueError as err:
            self._drop("map", err)
            return
        self._match_regions()

    def _on_pose(self, t_ns: int, pose: tuple[float, float, float]) -> None:
        self.pose = pose
        x, y = pose[0], pose[1]
        if not self.trail or math.hypot(x - self.trail[-1][0],
                                        y - self.trail[-1][1]) >= self.trail_spacing_m:
            self.trail.append((x, y))
            if len(self.trail) >= self.trail_max:  # bounded: halve, coarser spacing
                self.trail = self.trail[::2]
                self.trail_spacing_m *= 2.0

    def _on_regions(self, msg) -> None:
        self._regions_img = msg
        self._match_regions()

    def _on_regions_info(self, msg) -> None:
        self._regions_info = msg
        self._match_regions()

    def _match_regions(self) -> None:
        """Labels of the latest regions image when they share the map's geometry."""
        from explore_seg import convert
        img, info = self._regions_img, self._regions_info
        if img is None or info is None or self.grid is None:
            return
        # Image and info are separate messages: use them only as a pair (same stamp).
        st, lt = img.header.stamp, info.map_load_time
        if (st.sec, st.nanosec) != (lt.sec, lt.nanosec) or \
                (img.height, img.width) != (info.height, info.width):
            return
        try:
            labels, geom = convert.labels_from_msgs(self._regions_img, self._regions_info)
        except ValueError as err:
            self._drop("regions", err)
            return
        if geom.shape == self.grid.shape and geom.same_geometry(self.grid):
            self.labels = labels

    def _on_object_timing(self, msg) -> None:
        self.object_frames += 1
        if len(msg.data) >= 2:
            self.object_frame_ms.append(float(msg.data[0]) + float(msg.data[1]))
        if len(msg.data) >= 4:          # [detect ms, update ms, received, processed]
            self.object_frames_received = int(msg.data[2])
            self.object_frames_counted = int(msg.data[3])

    def _on_markers(self, msg) -> None:
        boxes = boxes_from_markers(msg)
        changed = len(boxes) != len(self.boxes) or any(
            not np.allclose(a, b, atol=1e-3) for a, b in zip(boxes, self.boxes))
        self.boxes = boxes
        if changed:
            self.box_history.append((self.sim_time_s, boxes))

    @property
    def sim_time_s(self) -> float:
        v = self.metrics.get("sim_time_s", 0.0)
        return float(v) if isinstance(v, float) else 0.0

    @property
    def coverage_pct(self) -> float:
        v = self.metrics.get("coverage_pct", math.nan)
        return float(v) if isinstance(v, float) else math.nan

    def n_regions(self) -> int:
        return 0 if self.labels is None else int(len(np.unique(self.labels[self.labels > 0])))

    def overlays(self, collisions: list[tuple[float, float]] | None = None):
        from sim_bridge.render import Overlays
        labels = self.labels if (self.labels is not None and self.grid is not None
                                 and self.labels.shape == self.grid.shape) else None
        return Overlays(robot_path=np.asarray(self.trail) if len(self.trail) >= 2 else None,
                        robot_pose=self.pose, regions=labels, boxes=list(self.boxes),
                        goals=list(self.goals), collisions=collisions or [])


def progress_line(mon: Monitor, wall_s: float) -> str:
    m = mon.metrics
    return (f"[demo] wall {wall_s:6.1f} s | sim {mon.sim_time_s:7.1f} s | coverage "
            f"{mon.coverage_pct:5.1f} % | goals {len(mon.goals):3d} | collisions "
            f"{int(m.get('collisions', 0) or 0)} | objects {len(mon.boxes)} "
            f"({mon.object_frames} frames) | regions "
            f"{mon.n_regions()} | nav {m.get('nav_state', '-')}")
