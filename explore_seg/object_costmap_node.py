"""``object_costmap`` node: furniture boxes from YOLO + depth (+ laser legs) as a map layer.

Callbacks only store the newest inputs. A timer on the ROS clock (``_POLLS_PER_PERIOD`` times
per ``1 / rate_hz``), and a guard condition woken when a depth image arrives or a pose
reaches a waiting image's stamp, take the oldest waiting colour/depth pair whose stamps
match (``sync_tolerance_s``) and lie at least ``_MIN_GAP_PERIODS / rate_hz`` after the last
one processed (a camera at ``rate_hz`` has every frame processed, a faster one about
``rate_hz`` of them), the robot pose nearest to it, run the detector and
:func:`explore_seg.core.objects.process_frame`, fuse the boxes into an
:class:`~explore_seg.core.objects.ObjectMap` and publish the layer (aligned with the latest
``map``), the virtual cloud, markers and timings (cloud and markers only while subscribed).
Frames that arrive while a frame is processed are dropped (the newest few are kept for
pairing); when the node processes less than half of the frames it could (``rate_hz`` or the
camera's rate, whichever is lower) over ``_LAG_WINDOW_S`` of ROS time, it warns, naming the
cause (malformed frames, frames without a robot pose at their stamp, or too little CPU). A
bad ``scan`` is dropped on arrival and the last good one kept. While ``exploration_done``
is true (and ``idle_when_done``) the timer is paused (:class:`~explore_seg.done_gate.DoneGate`).
A SLAM correction (a loop closure), found in the map-frame poses (a jump that driving does
not explain) or in ``map`` (occupied cells that moved; ``correction_*`` parameters,
:mod:`explore_seg.core.objects.corrections`), drops the boxes and depth voxels placed since
the previous correction, except those seen within ``correction_move_recent_s`` before it,
which move with the pose's jump when the poses showed the correction, as the lock step does
at the simulator's closures
(:class:`~explore_seg.object_costmap_helpers.CorrectionHandler`).
"""
from __future__ import annotations

import collections
import time
from enum import Enum
from typing import Any

import numpy as np
from nav_msgs.msg import OccupancyGrid
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image, LaserScan, PointCloud2
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from visualization_msgs.msg import MarkerArray

from explore_seg import convert
from explore_seg.core.camera import base_from_optical, map_from_base
from explore_seg.core.detector import Detector, DetectorParams
from explore_seg.core.grid import GridMap
from explore_seg.core.limits import InputLimits
from explore_seg.core.pose_fusion import PoseFusionParams
from explore_seg.core.objects import (CorrectionDetector, DepthFrame, Object3D,
                                      ObjectCostmapNodeParams, ObjectMap, WallMask,
                                      load_priors, parse_class_ids, process_frame, wall_mask)
from explore_seg.done_gate import DoneGate
from explore_seg.node_util import WarnThrottle, config_file, failsafe, run
from explore_seg.object_costmap_helpers import CorrectionHandler, closest, markers, stamp_ns
from explore_seg.object_inputs import lag_warning, purge_newer, wait_reason
from explore_seg.params import ParamBinding
from explore_seg.pose_input import PoseHooks, PoseInput
from explore_seg.qos import MAP_QOS, POSE_QOS, SENSOR_QOS, map_qos
from explore_seg.time_guard import StallWatchdog, TimeGuard

#: Colour/depth/semantic messages kept for stamp pairing (older ones are dropped).
_PAIR_BUFFER = 8
#: Seconds between repeated warnings of one kind.
_WARN_PERIOD_S = 5.0
#: Timer ticks per 1 / rate_hz (a frame is taken soon after it arrives).
_POLLS_PER_PERIOD = 4
#: Least stamp gap between two processed frames, in periods 1 / rate_hz (below 1: the
#: camera's own jitter does not make a camera at rate_hz lose every other frame).
_MIN_GAP_PERIODS = 0.9
#: ROS-clock seconds over which the processed share of the camera frames is checked.
_LAG_WINDOW_S = 20.0
#: Wall seconds between repeated lag warnings.
_LAG_WARN_PERIOD_S = 30.0


class State(Enum):
    """What the node is waiting for."""

    WAITING_FOR_CAMERA_INFO = 0
    WAITING_FOR_FRAMES = 1
    RUNNING = 2


class ObjectCostmapNode(Node):
    """Object costmap layer (see module docstring)."""

    def __init__(self, *, context=None, parameter_overrides=None,
                 node_name: str = "object_costmap", namespace: str = "") -> None:
        super().__init__(node_name, context=context,
                         parameter_overrides=parameter_overrides or [], namespace=namespace)
        self._p = ParamBinding(self, ObjectCostmapNodeParams())
        self._dp = ParamBinding(self, DetectorParams(), prefix="detector.")
        self._lp = ParamBinding(self, InputLimits(), prefix="input.")
        self._pfp = ParamBinding(self, PoseFusionParams(), prefix="pose_fusion.")
        p = self._p.params
        # the installed share's priors when no file is given (the core knows the source tree)
        self._priors = load_priors(p.priors_path or config_file("object_priors.yaml"))
        self._objects = ObjectMap(p, self._priors)
        self._corrections = CorrectionHandler(CorrectionDetector(p), self._objects,
                                              self.get_logger().info)
        self._detector: Detector | None = None
        self._detector_failed = False
        self._init_state()
        self._init_topics(p)

    def _init_state(self) -> None:
        """Inputs, state machine, counters and time model before the first message."""
        self._info = None
        self._colors: collections.deque = collections.deque(maxlen=_PAIR_BUFFER)
        self._depths: collections.deque = collections.deque(maxlen=_PAIR_BUFFER)
        self._semantics: collections.deque = collections.deque(maxlen=_PAIR_BUFFER)
        self._walls: WallMask | None = None     # wall_mask of self._grid
        self._scan: LaserScan | None = None
        self._grid: GridMap | None = None
        self._grid_published: GridMap | None = None
        self._last_depth_ns: int | None = None
        self._state = State.WAITING_FOR_CAMERA_INFO
        #: Count of dropped inputs per reason (bounded by the fixed set of reasons).
        self.dropped: collections.Counter = collections.Counter()
        #: Last message per drop reason.
        self.last_drop: dict[str, str] = {}
        self.frames_processed = 0
        #: Depth images received (each one a camera frame).
        self.frames_received = 0
        #: Frames taken for processing but dropped: malformed, or no robot pose at their stamp.
        self.frames_malformed = 0
        self.frames_without_pose = 0
        #: The last frame taken was dropped for want of a robot pose at its stamp.
        self._pose_missing = False
        #: (ROS time ns, frames_received, frames_processed, frames_malformed,
        #: frames_without_pose) at the start of the lag window.
        self._lag_mark: tuple[int, int, int, int, int] | None = None
        self._warn = WarnThrottle(self, _WARN_PERIOD_S)
        self.failures = 0          # cycles lost to an exception (node_util.failsafe)
        self._warn_lag = WarnThrottle(self, _LAG_WARN_PERIOD_S)
        # Time model: jumps of the camera/pose stamps or the clock reset what is keyed by
        # time; the watchdog says why frames that arrive are not processed.
        self._time = TimeGuard(self._lp.params.clock_jump_s,
                               clock=lambda: self.get_clock().now().nanoseconds)
        self._stall = StallWatchdog(self._lp.params.stall_periods * _POLLS_PER_PERIOD)
        #: Clock jumps seen (any stream).
        self.time_jumps = 0

    def _init_topics(self, p: ObjectCostmapNodeParams) -> None:
        """Publishers, subscriptions (sensors through the done gate), timer, wake-up."""
        self._pub_grid = self.create_publisher(OccupancyGrid, "object_costmap", MAP_QOS)
        self._pub_cloud = self.create_publisher(PointCloud2, "object_costmap/cloud", 1)
        self._pub_markers = self.create_publisher(MarkerArray, "object_costmap/markers", 1)
        self._pub_timing = self.create_publisher(Float64MultiArray, "~/timing", 10)

        # Sensor streams through the gate: unsubscribed while idle after exploration_done.
        self._done_gate = DoneGate(self, "object costmap", lambda: [self._timer],
                                   lambda: self.params.idle_when_done, self._resumed)
        sub = self._done_gate.subscribe
        sub(Image, "camera/color/image_raw", self._on_color, SENSOR_QOS)
        sub(Image, "camera/depth/image_raw", self._on_depth, SENSOR_QOS)
        sub(CameraInfo, "camera/color/camera_info", self._on_info, SENSOR_QOS)
        sub(LaserScan, "scan", self._on_scan, SENSOR_QOS)
        self.create_subscription(OccupancyGrid, "map", self._on_map,
                                 map_qos(p.map_transient_local))
        # Poses in their own callback group: with a multi-threaded executor they keep
        # arriving while a frame is processed (else the poses around the next image's
        # stamp are lost and that frame is dropped).
        self._pose_in = PoseInput(
            self, p.pose_topic_type, self._pfp.params, POSE_QOS, PoseHooks(
                map_frame=lambda: self.params.map_frame, limits=lambda: self._lp.params,
                warn=self._warn, drop=lambda text: self._drop("pose", text),
                on_pose=self._on_robot_pose, on_stamp=self._observe, grid=lambda: self._grid),
            callback_group=MutuallyExclusiveCallbackGroup(), subscribe=sub)
        # Used (and required for pairing) only by the oracle detector backend.
        sub(Image, "camera/semantic/image_raw", self._on_semantic, SENSOR_QOS)
        self._timer = self.create_timer(1.0 / (p.rate_hz * _POLLS_PER_PERIOD), self._tick)
        # Woken as soon as a frame arrives or a pose reaches a waiting frame's stamp (in the
        # timer's callback group): on sim time a busy executor fires a timer at most once
        # per clock update, so a timer alone lets frames age out of the buffer.
        self._wake = self.create_guard_condition(self._on_wake)
        self._pose_seen_ns: int | None = None
        self._p.on_change(self._params_changed)
        self._dp.on_change(self._detector_params_changed)
        self._lp.on_change(self._limits_changed)
        self._pfp.on_change(lambda old, new: self._pose_in.set_params(new))

    # ---------------------------------------------------------------- helpers
    @property
    def params(self) -> ObjectCostmapNodeParams:
        """Current parameters."""
        return self._p.params

    @property
    def state(self) -> State:
        """Current state of the tick state machine."""
        return self._state

    def objects(self) -> list[Object3D]:
        """Fused objects (map frame)."""
        return self._objects.objects()

    def _drop(self, reason: str, detail: str) -> None:
        """Count a dropped input and warn at most every _WARN_PERIOD_S per reason."""
        self.dropped[reason] += 1
        self.last_drop[reason] = detail
        self._warn(reason, f"dropped {reason}: {detail}")

    def _params_changed(self, old: ObjectCostmapNodeParams,
                        new: ObjectCostmapNodeParams) -> None:
        self._objects.params = new
        self._corrections.detector.settings = new
        self._walls = None                      # wall_min_length_m / wall_margin_m
        if new.rate_hz != old.rate_hz:
            self._timer.cancel()
            self.destroy_timer(self._timer)
            self._timer = self._done_gate.adopt(self.create_timer(
                1.0 / (new.rate_hz * _POLLS_PER_PERIOD), self._tick))
        self._done_gate.update()                # idle_when_done

    @property
    def paused(self) -> bool:
        """True while idle after exploration_done (see :class:`DoneGate`)."""
        return self._done_gate.paused

    def _resumed(self) -> None:
        """After a pause: the clock moved on and no frame was processed on purpose, so
        neither is a clock jump, a stall nor a lag."""
        self._time.forget()
        self._stall.reset()
        self._pose_missing = False
        self._lag_mark = None

    def _limits_changed(self, old: InputLimits, new: InputLimits) -> None:
        self._time.jump_s = new.clock_jump_s
        self._stall.periods = new.stall_periods * _POLLS_PER_PERIOD

    def _detector_params_changed(self, old: DetectorParams, new: DetectorParams) -> None:
        self._detector = None
        self._detector_failed = False

    # -------------------------------------------------------------- callbacks
    def _on_color(self, msg: Image) -> None:
        if self._timed("camera", msg):
            self._colors.append(msg)

    def _on_depth(self, msg: Image) -> None:
        if self._timed("camera", msg):
            self._depths.append(msg)
            self.frames_received += 1
            self._wake.trigger()

    def _on_semantic(self, msg: Image) -> None:
        if self._timed("camera", msg):
            self._semantics.append(msg)

    def _timed(self, stream: str, msg: Any) -> bool:
        """Check a timed input's stamp and feed it to the time model; False: dropped."""
        try:
            t_ns = convert.checked_stamp_ns(msg.header.stamp, stream)
        except ValueError as err:
            self._drop(stream, str(err))
            return False
        self._observe(stream, t_ns)
        return True

    def _observe(self, stream: str, t_ns: int, expected_gap_ns: int = 0) -> None:
        jump = self._time.observe(stream, t_ns, expected_gap_ns)
        if jump is None:
            return
        self.time_jumps += 1
        if jump.backwards:
            # Everything stamped after the new time line began is from the old one (or was
            # future-stamped): forget it, so that new frames are not held back by it.
            horizon = t_ns + int(self._time.jump_s * 1e9)
            for buf in (self._colors, self._depths, self._semantics):
                purge_newer(buf, horizon, stamp_ns)
            self._pose_in.drop_newer(horizon)
            if self._last_depth_ns is not None and self._last_depth_ns > horizon:
                self._last_depth_ns = None
            self._corrections.time_went_back()
            self._objects.time_went_back(t_ns)
            self._lag_mark = None
        self._warn(f"jump_{stream}", jump.describe() + (
            "; frames, poses and stamps of the old time line dropped, objects and depth "
            "voxels restamped to the new time" if jump.backwards else ""))

    def _on_info(self, msg: CameraInfo) -> None:
        try:
            self._info = convert.intrinsics_from_msg(msg)
        except ValueError as err:
            self._drop("camera_info", str(err))

    def _on_scan(self, msg: LaserScan) -> None:
        # Checked on arrival: a bad scan is dropped once and the last good one kept (it is
        # used for every frame until the next scan).
        try:
            convert.checked_stamp_ns(msg.header.stamp, "scan")
            convert.scan_ranges(msg)
        except ValueError as err:
            self._drop("scan", str(err))
            return
        self._scan = msg

    def _on_map(self, msg: OccupancyGrid) -> None:
        try:
            self._grid = convert.grid_from_msg(msg, self._lp.params)
            self._walls = None                  # recomputed once per map, not per frame
            self._corrections.detector.observe_map(self._grid)
        except ValueError as err:
            self._drop("map", str(err))

    def _on_robot_pose(self, t_ns: int, pose: tuple[float, float, float]) -> None:
        self._objects.note_robot_position(pose[0], pose[1])   # swept path: cleared
        self._corrections.detector.observe_pose(t_ns, pose)
        # A frame that waited for a pose at or after its stamp can be processed now.
        prev, self._pose_seen_ns = self._pose_seen_ns, t_ns
        if prev is not None and any(prev < stamp_ns(d) <= t_ns for d in list(self._depths)):
            self._wake.trigger()

    @failsafe("object costmap update")
    def _on_wake(self) -> None:
        # Every frame that became processable (at most the buffer's worth).
        for _ in range(_PAIR_BUFFER):
            if self.paused:
                return
            done = self.frames_processed
            self._tick_inner()
            if self.frames_processed == done:
                return

    # ------------------------------------------------------------------- tick
    @failsafe("object costmap update")
    def _tick(self) -> None:
        period_ns = int(1e9 / (self.params.rate_hz * _POLLS_PER_PERIOD))
        self._observe("clock", self.get_clock().now().nanoseconds, period_ns)
        processed = self.frames_processed
        self._tick_inner()
        # A last frame dropped for want of a pose counts as waiting: with poses stamped
        # ahead of the camera each frame is taken and dropped at once, none waits.
        reason = self._stall.tick(self._frames_waiting() or self._pose_missing,
                                  self.frames_processed > processed, self._wait_reason)
        if reason is not None:
            self._warn("stall", f"camera frames arrive but none was processed for "
                                f"{self._lp.params.stall_periods} periods: {reason}")

    def _min_gap_ns(self) -> int:
        """Least stamp gap between two processed frames (ns)."""
        return int(_MIN_GAP_PERIODS / self.params.rate_hz * 1e9)

    def _frames_waiting(self) -> bool:
        """A buffered depth image is due (at least the least gap after the last processed
        one): the buffer still holding the processed ones is no stall."""
        if self._last_depth_ns is None:
            return bool(self._depths)
        due_ns = self._last_depth_ns + self._min_gap_ns()
        return any(stamp_ns(d) >= due_ns for d in self._depths)

    def _wait_reason(self) -> str:
        p = self.params
        span = self._pose_in.span_ns()
        text = wait_reason([stamp_ns(m) for m in self._depths],
                           [stamp_ns(m) for m in self._colors],
                           [] if span is None else list(span),
                           self._last_depth_ns, p.sync_tolerance_s, p.pose_tolerance_s,
                           _MIN_GAP_PERIODS / p.rate_hz)
        skew = self._time.disagreement("camera", "pose")
        return text + (f"; {skew}" if skew else "")

    def _tick_inner(self) -> None:
        if self._corrections.apply():            # a SLAM correction: what it moved goes
            self._publish_grid()
        if self._info is None:
            self._state = State.WAITING_FOR_CAMERA_INFO
            if self._depths:
                self._drop("frame", "no CameraInfo received yet")
                self._depths.clear()
            return
        pair = self._newest_pair()
        if pair is None:
            if self._state != State.RUNNING:
                self._state = State.WAITING_FOR_FRAMES
            self._publish_grid_if_map_changed()
            return
        self._state = State.RUNNING
        self._process(*pair)
        self._check_lag()

    def _check_lag(self) -> None:
        """Warn when fewer than half of the frames that could be processed were, naming
        the main cause: malformed frames, frames without a robot pose, or too little CPU."""
        now = self.get_clock().now().nanoseconds
        mark = self._lag_mark
        counts = (self.frames_received, self.frames_processed, self.frames_malformed,
                  self.frames_without_pose)
        if mark is None or now < mark[0]:          # first frame, or the clock jumped back
            self._lag_mark = (now, *counts)
            return
        span_s = (now - mark[0]) / 1e9
        if span_s < _LAG_WINDOW_S:
            return
        received, processed, malformed, no_pose = (c - m for c, m in zip(counts, mark[1:]))
        possible = min(received, span_s * self.params.rate_hz)
        self._lag_mark = (now, *counts)
        if processed < 0.5 * possible:
            self._warn_lag("lag", lag_warning(processed, received, span_s, self.params.rate_hz,
                                              malformed, no_pose))

    def _newest_pair(self) -> tuple[Image, Image, Image | None] | None:
        """Oldest unprocessed depth at least the least gap after the last processed one,
        with a robot pose and a colour (and semantic) image close in time.

        Oldest first: when the pose stream caught up with several waiting frames at once,
        each is processed in turn (newest first skipped the older ones); the buffer's
        length (``_PAIR_BUFFER`` frames) bounds how stale a frame can be.
        """
        tol_ns = int(self.params.sync_tolerance_s * 1e9)
        oracle = self._dp.params.backend == "oracle"
        # Frames newer than the newest pose wait for a pose at or after their stamp while
        # poses keep arriving (the pose stream may lag behind the images while this node
        # is busy); when none arrived for pose_tolerance_s, the nearest within it will do.
        newest_pose = self._pose_in.newest_ns()
        pose_tol_ns = int(self.params.pose_tolerance_s * 1e9)
        arrival = self._pose_in.arrival_ns
        poses_flow = (arrival is not None
                      and self.get_clock().now().nanoseconds - arrival < pose_tol_ns)
        min_gap_ns = self._min_gap_ns()
        for depth in sorted(self._depths, key=stamp_ns):
            t = stamp_ns(depth)
            if self._last_depth_ns is not None and t < self._last_depth_ns + min_gap_ns:
                continue        # processed, or too soon after the last one
            if newest_pose is not None and t > newest_pose and (
                    t > newest_pose + pose_tol_ns or poses_flow):
                return None     # this one and every newer one wait for a pose
            color = closest(self._colors, t, tol_ns)
            semantic = closest(self._semantics, t, tol_ns) if oracle else None
            if color is not None and (semantic is not None or not oracle):
                return depth, color, semantic
        return None

    def _pose_at(self, t_ns: int) -> tuple[float, float, float] | None:
        return self._pose_in.pose_at(t_ns, int(self.params.pose_tolerance_s * 1e9))

    def _ensure_detector(self) -> Detector | None:
        if self._detector is None and not self._detector_failed:
            dp = self._dp.params
            try:
                ids = parse_class_ids(self.params.oracle_sim_class_ids) \
                    if dp.backend == "oracle" else None
                self._detector = Detector(dp, sim_class_ids=ids)
                self.get_logger().info(f"detector backend: {self._detector.backend_name} "
                                       f"on {self._detector.device_name}")
                if self._detector.device_note:
                    self.get_logger().warn(self._detector.device_note)
            except (OSError, ValueError, ImportError, RuntimeError) as err:
                self._detector_failed = True
                self.get_logger().error(
                    f"detector unavailable ({err}); only unclassified objects are found")
        return self._detector

    def _process(self, depth_msg: Image, color_msg: Image, semantic_msg: Image | None) -> None:
        p = self.params
        t_ns = stamp_ns(depth_msg)
        pose = self._pose_at(t_ns)
        self._last_depth_ns = t_ns
        self._pose_missing = False
        if pose is None:
            self.frames_without_pose += 1
            self._pose_missing = True
            skew = self._time.disagreement("camera", "pose")
            self._drop("frame", f"no robot pose within {p.pose_tolerance_s} s of the image "
                                f"({t_ns / 1e9:.2f} s; {self._pose_in.describe()})"
                                + (f"; {skew}" if skew else ""))
            return
        try:
            depth = convert.depth_from_msg(depth_msg)
            rgb = convert.rgb_from_msg(color_msg)
            semantic = convert.image_from_msg(semantic_msg) if semantic_msg is not None else None
            if depth.shape != self._info.shape:
                raise ValueError(f"depth is {depth.shape[1]}x{depth.shape[0]}, CameraInfo says "
                                 f"{self._info.width}x{self._info.height}")
            if rgb.shape[:2] != depth.shape:
                raise ValueError(f"colour {rgb.shape[1]}x{rgb.shape[0]} and depth "
                                 f"{depth.shape[1]}x{depth.shape[0]} differ in size")
            if semantic is not None and semantic.shape[:2] != depth.shape:
                raise ValueError(f"semantic image {semantic.shape[1]}x{semantic.shape[0]} and "
                                 f"depth {depth.shape[1]}x{depth.shape[0]} differ in size")
            if not np.isfinite(depth).any():
                raise ValueError("depth image has no valid pixel")
        except ValueError as err:
            self.frames_malformed += 1
            self._drop("frame", str(err))
            return
        t0 = time.perf_counter()
        detections = []
        detector = self._ensure_detector()
        if detector is not None:
            try:
                sem = semantic if semantic is None or semantic.ndim == 2 else semantic[:, :, 0]
                detections = detector.detect(rgb, semantic=sem) \
                    if self._dp.params.backend == "oracle" else detector.detect(rgb)
            except ValueError as err:
                self._drop("detection", str(err))
        t1 = time.perf_counter()
        transform = map_from_base(*pose) @ base_from_optical(
            p.camera_x_m, p.camera_y_m, p.camera_z_m, p.camera_roll_rad, p.camera_pitch_rad,
            p.camera_yaw_rad)
        frame = DepthFrame(depth, self._info, transform)
        scan_xy = self._scan_points(t_ns, pose)
        if self._walls is None and self._grid is not None:
            self._walls = wall_mask(self._grid, p)
        walls = self._walls
        result = process_frame(frame, detections, self._priors, p, scan_xy, walls)
        for reason in result.dropped:
            self._drop("box", reason)
        self._objects.update(result.objects + result.unknown, frame, t_ns, robot_xy=pose[:2],
                             walls=walls)
        t2 = time.perf_counter()
        self.frames_processed += 1
        self._publish(t_ns)
        timing = Float64MultiArray()
        timing.layout.dim = [MultiArrayDimension(
            label="detect_ms,update_ms,frames_received,frames_processed", size=4, stride=4)]
        timing.data = [(t1 - t0) * 1e3, (t2 - t1) * 1e3, float(self.frames_received),
                       float(self.frames_processed)]
        self._pub_timing.publish(timing)

    def _scan_points(self, t_ns: int, frame_pose: tuple[float, float, float]):
        p = self.params
        if not p.unknown_enabled or self._scan is None:
            return None
        pose = self._pose_at(stamp_ns(self._scan)) or frame_pose
        try:
            return convert.scan_to_points(self._scan, pose,
                                          (p.lidar_x_m, p.lidar_y_m, p.lidar_yaw_rad))
        except ValueError as err:
            self._drop("scan", str(err))
            return None

    # ---------------------------------------------------------------- outputs
    def _publish_grid_if_map_changed(self) -> None:
        if self._grid is not None and (self._grid_published is None
                                       or not self._grid.same_geometry(self._grid_published)):
            self._publish_grid()

    def _publish_grid(self) -> None:
        if self._grid is None:
            return
        layer = self._objects.rasterize(self._grid)
        self._pub_grid.publish(convert.grid_to_msg(layer))
        self._grid_published = self._grid

    def _publish(self, t_ns: int) -> None:
        p = self.params
        self._publish_grid()
        header = convert.make_header(convert.normalize_frame(p.map_frame), t_ns)
        # The cloud (for a Nav2 voxel layer) and the markers (RViz) cost a share of every
        # frame's time: only for subscribers.
        if self._pub_cloud.get_subscription_count() > 0:
            cloud = self._objects.virtual_cloud()
            self._pub_cloud.publish(convert.cloud_to_msg(convert.xyz_cloud(cloud), header))
        if self._pub_markers.get_subscription_count() > 0:
            self._pub_markers.publish(markers(self._objects.boxes(), header))


def main(args: list[str] | None = None) -> int:
    """Console script ``object_costmap``."""
    return run(ObjectCostmapNode, args)


if __name__ == "__main__":
    raise SystemExit(main())
