"""``sim_bridge`` node: the 2.5D simulator on ROS topics, in place of Gazebo + SLAM + Nav2.

It owns the clock: a wall-clock (steady) timer advances the :class:`SimEngine` by
``real_time_factor`` x the elapsed wall time (or by ``lockstep_dt_s`` per tick in
lock-step mode) and publishes ``/clock``; every stamp is sim time, so the other nodes
run with ``use_sim_time: true``. Exploration nodes need none of the ``sim/*`` topics.

Published: ``/clock``, ``scan``, ``odom`` (the map-frame pose in ``map``; with
``odom_frame`` ``odom``: drifting odometry of the true motion, :mod:`sim_bridge.odometry`),
``pose`` (with ``slam_pose``: the scan-rate map-frame pose slam_toolbox would publish),
``map`` (the engine's published map: keyframe scans, every ``map_update_interval_s``, as
slam_toolbox publishes it), ``plan``, ``camera/*`` (with
``enable_camera``), ``sim/metrics``. Subscribed: ``goal_pose`` and
the OccupancyGrid layers named in ``costmap_layers``. Service: ``sim/save_metrics``.
The map-frame pose is the engine's SLAM pose: the true pose, or with ``mapping_error`` the
pose consistent with the erroneous map (:mod:`sim_bridge.slam_error`).
With ``nav_action`` (default ``navigate_to_pose``) the navigation stand-in also looks like
Nav2's action from outside: ``<action>/_action/status`` and ``<action>/_action/cancel_goal``
(:mod:`sim_bridge.nav_action`).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry, Path as PathMsg
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg
from sensor_msgs.msg import CameraInfo, Image, LaserScan
from std_srvs.srv import Trigger

from explore_seg import convert
from explore_seg.core.grid import GridMap
from explore_seg.node_util import WarnThrottle, run
from explore_seg.params import ParamBinding
from explore_seg.qos import MAP_QOS, POSE_QOS, RELIABLE_QOS, SENSOR_QOS
from sim_bridge.engine import CameraSample, ScanFrame, SimEngine, SimParams, engine_from_params
from sim_bridge.metrics import CollisionEvent
from sim_bridge.nav_action import SimNavAction
from sim_bridge.navigation import NavState
from sim_bridge.odometry import DriftingOdometry, SlamPoses
from sim_bridge.render import engine_overlays, render_map_png

MAP_FRAME = "map"
#: Wall seconds between two INFO lines about new goals (a planner may send 40 per second).
_GOAL_LOG_PERIOD_S = 1.0
BASE_FRAME = "base_footprint"
SCAN_FRAME = "base_scan"
CAMERA_FRAME = "camera_color_optical_frame"
#: /clock: reliable, depth 1 (matches rclpy's best-effort and reliable subscribers).
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
_NS_PER_S = 1_000_000_000


def _ns(t_s: float) -> int:
    return int(round(t_s * _NS_PER_S))


class SimBridgeNode(Node):
    """The simulator node (see the module docstring)."""

    def __init__(self, *, context=None, parameter_overrides=None, node_name: str = "sim_bridge",
                 namespace: str = "") -> None:
        super().__init__(node_name, context=context,
                         parameter_overrides=parameter_overrides or [], namespace=namespace)
        self._p = ParamBinding(self, SimParams())
        p = self._p.params
        self._engine: SimEngine = engine_from_params(p)
        self._engine.on_collision(self._on_collision)
        self._wall = Clock(clock_type=ClockType.STEADY_TIME)
        self._last_wall_ns: int | None = None
        self._published_maps = 0
        self._next_metrics_s = 0.0
        self._published_plan_version = -1
        self._nav_state = NavState.IDLE

        self._clock_pub = self.create_publisher(ClockMsg, "/clock", CLOCK_QOS)
        self._scan_pub = self.create_publisher(LaserScan, "scan", SENSOR_QOS)
        # Depth 100 (POSE_QOS): a subscriber busy with a camera frame must not lose the
        # odometry of the scans and frames meanwhile (KEEP_LAST 10 dropped them at 4x).
        self._odom_pub = self.create_publisher(Odometry, "odom", POSE_QOS)
        self._odometry = (None if p.odom_frame.lstrip("/") == MAP_FRAME else
                          DriftingOdometry(p.odom_drift_scale, p.odom_drift_yaw_radps))
        self._slam_pub = (self.create_publisher(PoseWithCovarianceStamped, "pose", POSE_QOS)
                          if p.slam_pose else None)
        self._slam = SlamPoses(p.slam_min_travel_m, p.slam_min_turn_rad)
        self._map_pub = self.create_publisher(OccupancyGrid, "map", MAP_QOS)
        self._plan_pub = self.create_publisher(PathMsg, "plan", RELIABLE_QOS)
        self._metrics_pub = self.create_publisher(DiagnosticArray, "sim/metrics", RELIABLE_QOS)
        self._cam_pubs: dict[str, object] = {}
        if p.enable_camera:
            self._cam_pubs = {
                "rgb": self.create_publisher(Image, "camera/color/image_raw", SENSOR_QOS),
                "depth": self.create_publisher(Image, "camera/depth/image_raw", SENSOR_QOS),
                "semantic": self.create_publisher(Image, "camera/semantic/image_raw",
                                                  SENSOR_QOS),
                "info": self.create_publisher(CameraInfo, "camera/color/camera_info",
                                              SENSOR_QOS),
                "depth_info": self.create_publisher(CameraInfo, "camera/depth/camera_info",
                                                    SENSOR_QOS),
            }
        self.create_subscription(PoseStamped, "goal_pose", self._on_goal, RELIABLE_QOS)
        self._layer_subs: dict[str, object] = {}
        self._last_layers: dict[str, GridMap] = {}
        self._goal_seen = False       # startup_real_time_factor applies until then
        self._last_logged_goal: tuple[float, float, float] | None = None
        self._goal_info = WarnThrottle(self, _GOAL_LOG_PERIOD_S).info
        self._subscribe_layers(p.costmap_layers)
        self.create_service(Trigger, "sim/save_metrics", self._on_save_metrics)
        self._nav_action = (SimNavAction(self, self._engine, p.nav_action)
                            if p.nav_action else None)
        self._p.on_change(self._on_params)
        # Wall-clock timer: the sim is the clock, so it must not wait for /clock itself.
        self._timer = self.create_timer(p.tick_period_s, self._tick, clock=self._wall)
        self.get_logger().info(
            f"world {p.world!r} ({len(self._engine.world.primitives)} primitives), start "
            f"{self._engine.pose}, real_time_factor {p.real_time_factor}"
            + (" (lock-step)" if p.lockstep else ""))

    # ------------------------------------------------------------- accessors
    @property
    def engine(self) -> SimEngine:
        """The simulated world (for tests and composed launches)."""
        return self._engine

    @property
    def nav_action(self) -> SimNavAction | None:
        """The stand-in's action status / cancel (None with ``nav_action: ''``)."""
        return self._nav_action

    # ------------------------------------------------------------- callbacks
    def _on_goal(self, msg: PoseStamped) -> None:
        try:
            frame = msg.header.frame_id.lstrip("/")
            if frame not in ("", MAP_FRAME):
                raise ValueError(f"goal frame must be {MAP_FRAME!r}, got {msg.header.frame_id!r}")
            x, y, yaw = convert.pose2d_from_pose_msg(msg)
        except ValueError as err:
            self._engine.metrics.goal_rejected()
            self.get_logger().warn(f"rejected goal_pose: {err}", throttle_duration_sec=5.0)
            return
        self._goal_seen = True
        try:
            self._engine.set_goal(x, y, yaw)
        except ValueError as err:
            self.get_logger().warn(f"rejected goal_pose: {err}", throttle_duration_sec=5.0)
            return
        if self._nav_action is not None:
            self._nav_action.accepted()
        self._goal_log(x, y, yaw)

    def _goal_log(self, x: float, y: float, yaw: float) -> None:
        """INFO for a new goal, at most once per _GOAL_LOG_PERIOD_S; re-sent goals: none."""
        goal = (round(x, 2), round(y, 2), round(yaw, 2))
        if goal != self._last_logged_goal:
            self._last_logged_goal = goal
            self._goal_info("goal", f"goal ({x:.2f}, {y:.2f}, {yaw:.2f})")

    def _make_layer_cb(self, name: str):
        def cb(msg: OccupancyGrid) -> None:
            try:
                grid = convert.grid_from_msg(msg)
                if grid.frame_id.lstrip("/") != MAP_FRAME:
                    raise ValueError(f"layer frame must be {MAP_FRAME!r}, got {grid.frame_id!r}")
                last = self._last_layers.get(name)
                if (last is not None and last.same_geometry(grid)
                        and np.array_equal(last.data, grid.data)):
                    return          # republished unchanged: no forced replan
                self._last_layers[name] = grid
                self._engine.add_costmap_layer(name, grid)
            except ValueError as err:
                self.get_logger().warn(f"dropped layer {name!r}: {err}",
                                       throttle_duration_sec=5.0)
        return cb

    def _subscribe_layers(self, names: tuple[str, ...]) -> None:
        for name in list(self._layer_subs):
            if name not in names:
                self.destroy_subscription(self._layer_subs.pop(name))
                self._last_layers.pop(name, None)
                self._engine.remove_costmap_layer(name)
        for name in names:
            if name not in self._layer_subs:
                self._layer_subs[name] = self.create_subscription(
                    OccupancyGrid, name, self._make_layer_cb(name), MAP_QOS)

    def _on_params(self, old: SimParams, new: SimParams) -> None:
        try:
            self._engine.update_params(new)
        except ValueError as err:  # read-only fields are rejected by rclpy already
            self.get_logger().warn(f"parameters not applied: {err}")
            return
        if new.costmap_layers != old.costmap_layers:
            self._subscribe_layers(new.costmap_layers)
        if self._odometry is not None:
            self._odometry.scale = new.odom_drift_scale
            self._odometry.yaw_bias_radps = new.odom_drift_yaw_radps
        self._slam.min_travel_m, self._slam.min_turn_rad = (new.slam_min_travel_m,
                                                            new.slam_min_turn_rad)

    def _on_collision(self, ev: CollisionEvent) -> None:
        self.get_logger().warn(
            f"collision #{self._engine.metrics.n_collisions} at t={ev.t_s:.2f} s "
            f"({ev.x_m:.2f}, {ev.y_m:.2f}) with {ev.object or ev.cls} ({ev.part})",
            throttle_duration_sec=1.0)

    def _on_save_metrics(self, request: Trigger.Request, response: Trigger.Response
                         ) -> Trigger.Response:
        p = self._p.params
        stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(p.world).name.split(".")[0]) or "world"
        out = Path(p.output_dir)
        try:
            js = self._engine.metrics.to_json(out / f"{stem}_metrics.json")
            png = render_map_png(out / f"{stem}_map.png", self._engine.map,
                                 engine_overlays(self._engine, path_xy=self._engine.trail))
        except OSError as err:
            response.success = False
            response.message = f"could not write to {out}: {err}"
            return response
        response.success = True
        response.message = f"{js} {png}"
        return response

    # ------------------------------------------------------------------ tick
    def _tick(self) -> None:
        p = self._p.params
        now_ns = self._wall.now().nanoseconds
        if p.lockstep:
            dt = p.lockstep_dt_s
        else:
            if self._last_wall_ns is None:
                self._last_wall_ns = now_ns
                return
            rtf = (p.startup_real_time_factor
                   if p.startup_real_time_factor > 0 and not self._goal_seen
                   else p.real_time_factor)
            dt = min(rtf * (now_ns - self._last_wall_ns) / _NS_PER_S,
                     p.max_sim_step_per_tick_s)
        self._last_wall_ns = now_ns
        eng = self._engine
        eng.step(dt)
        t = eng.time_s
        stamp = _ns(t)
        if p.publish_clock:
            clk = ClockMsg()
            clk.clock = convert.ns_to_stamp(stamp)
            self._clock_pub.publish(clk)
        # In time order, odometry at each scan's and each frame's capture first (a real
        # odom stream has one within a few ms of every scan and image), so consumers need
        # not match stale poses to them however long this tick was.
        sensed = sorted([(s.stamp_s, 0, s) for s in eng.drain_scans()]
                        + [(f.stamp_s, 1, f) for f in eng.drain_camera()],
                        key=lambda e: e[:2])
        for stamp_s, kind, sample in sensed:
            self._publish_odom(stamp_s, sample.pose, sample.map_pose or sample.pose)
            if kind == 0:
                self._publish_scan(sample)
            else:
                self._publish_camera(sample)
        self._publish_odom(t, eng.pose, eng.slam_pose)
        if eng.map_publishes != self._published_maps:
            # One message per tick however many publications it spanned (the latest).
            self._published_maps = eng.map_publishes
            self._map_pub.publish(convert.grid_to_msg(eng.map))
        if eng.plan_version != self._published_plan_version:
            self._published_plan_version = eng.plan_version
            self._plan_pub.publish(convert.path_msg(eng.plan, MAP_FRAME, stamp))
        if self._nav_action is not None:
            self._nav_action.publish()
        state = eng.nav_status.state
        if state is not self._nav_state:
            self._nav_state = state
            reason = eng.nav_status.reason
            self.get_logger().info(f"navigation {state.value}" + (f": {reason}" if reason else ""))
        if t >= self._next_metrics_s:
            self._next_metrics_s = t + 1.0 / p.metrics_rate_hz
            eng.metrics.set_time(t)
            self._publish_metrics(stamp)

    def _publish_odom(self, t_s: float, true_pose: tuple[float, float, float],
                      map_pose: tuple[float, float, float]) -> None:
        """Odometry at ``t_s``: the map-frame (SLAM) pose in ``map``, or odometry of the
        true motion drifting in ``odom_frame``."""
        if self._odometry is None:
            pose, frame = map_pose, MAP_FRAME
        else:
            pose, frame = self._odometry.update(t_s, true_pose), self._p.params.odom_frame
        self._odom_pub.publish(convert.odometry_msg(pose, self._engine.velocity, frame,
                                                    BASE_FRAME, _ns(t_s)))

    def _publish_scan(self, scan: ScanFrame) -> None:
        g = self._engine.scan_geometry
        msg = convert.scan_to_msg(scan.ranges, g.angle_min_rad, g.angle_increment_rad,
                                  g.range_min_m, g.range_max_m,
                                  convert.make_header(SCAN_FRAME, _ns(scan.stamp_s)),
                                  scan_time_s=1.0 / self._p.params.scan_rate_hz)
        self._scan_pub.publish(msg)
        if self._slam_pub is not None and self._slam.take(scan.pose):
            pose = PoseWithCovarianceStamped()
            pose.header = convert.make_header(MAP_FRAME, _ns(scan.stamp_s))
            pose.pose.pose = convert.pose_from_2d(*(scan.map_pose or scan.pose))
            self._slam_pub.publish(pose)

    def _publish_camera(self, sample: CameraSample) -> None:
        header = convert.make_header(CAMERA_FRAME, _ns(sample.stamp_s))
        f = sample.frame
        self._cam_pubs["rgb"].publish(convert.image_to_msg(f.rgb, "rgb8", header))
        self._cam_pubs["depth"].publish(
            convert.depth_to_msg(f.depth_m, self._p.params.camera_depth_encoding, header))
        self._cam_pubs["semantic"].publish(convert.image_to_msg(f.semantic, "mono8", header))
        info = convert.intrinsics_to_msg(self._p.params.camera_params().intrinsics(), header)
        self._cam_pubs["info"].publish(info)
        self._cam_pubs["depth_info"].publish(info)

    def _publish_metrics(self, stamp_ns: int) -> None:
        eng = self._engine
        status = DiagnosticStatus()
        status.name = "sim_bridge"
        status.hardware_id = self._p.params.world
        n = eng.metrics.n_collisions
        status.level = DiagnosticStatus.WARN if n else DiagnosticStatus.OK
        status.message = f"coverage {eng.metrics.coverage_pct:.1f} %, {n} collisions"
        pairs = eng.metrics.to_diagnostics() + [("nav_state", eng.nav_status.state.value),
                                                ("nav_reason", eng.nav_status.reason)]
        status.values = [KeyValue(key=k, value=v) for k, v in pairs]
        arr = DiagnosticArray()
        arr.header = convert.make_header("", stamp_ns)
        arr.status = [status]
        self._metrics_pub.publish(arr)


def main(args: list[str] | None = None) -> int:
    """Console entry point ``sim_bridge``."""
    return run(SimBridgeNode, args)


if __name__ == "__main__":
    raise SystemExit(main())
