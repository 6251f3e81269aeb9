"""The ROS-free simulator: a TurtleBot3-waffle-sized robot in a 2.5D world.

:class:`SimEngine` advances a unicycle robot at a fixed physics step, stops it on
contact with any obstacle part that reaches below the robot's height (chair seats and
table tops included, although the lidar at 0.17 m never sees them), produces lidar
scans (10 Hz) and camera frames (15 Hz, optional), integrates the scans into a growing
occupancy map (:mod:`sim_bridge.mapping`), and runs the navigation stand-in
(:mod:`sim_bridge.navigation`). Everything is driven by :meth:`SimEngine.step`, so
benchmarks and tests run in lock step without ROS; :mod:`sim_bridge.node` wraps it.

Robot model (TurtleBot3 waffle): the body is 281 x 306 mm, i.e. a circumscribed radius
of about 0.21 m around ``base_footprint``; the collision disk uses 0.22 m. Limits are
the waffle's 0.26 m/s and 1.82 rad/s. ``robot_height_m`` defaults to 1.1 m: a waffle
carrying a camera mast (the paper's camera sits ~0.99 m above the floor) is about 1 m
tall, and 1.1 m makes every chair seat (0.42-0.50 m) and every desk/table top
(0.72-1.015 m) of the worlds a collision, while door lintels (2.0 m) and window heads
(1.7 m) stay above it. Collision is exact against the primitives (box/cylinder
cross-sections vs the disk); for map-only worlds occupied cells act as walls.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap
from explore_seg.core.fields import param_meta as _doc
from sim_bridge import worlds
from sim_bridge.mapping import MappingParams, ScanMapper
from sim_bridge.metrics import CollisionEvent, SimMetrics
from sim_bridge.navigation import NavParams, NavState, NavStatus, Navigator
from sim_bridge.observable import with_observable
from sim_bridge.sensors import CameraParams, DepthCamera, Lidar, LidarParams
from sim_bridge.world import World

#: Encodings the node can publish depth images in.
DEPTH_ENCODINGS = ("16UC1", "32FC1")


@dataclass(frozen=True)
class SimParams:
    """All simulator parameters (one ROS parameter each in :mod:`sim_bridge.node`).

    Fields marked read-only take effect only when the engine is built.
    """

    world: str = field(default="small_house", metadata=_doc(
        "world name (house, house_cluttered, maze, small_house, small_cluttered) or a "
        "path to a *.world.yaml / map_server *.yaml", read_only=True))
    seed: int = field(default=0, metadata=_doc("seed of the sensor and pose noise", read_only=True))
    physics_dt_s: float = field(default=0.02, metadata=_doc(
        "fixed physics step", "s", read_only=True))
    real_time_factor: float = field(default=1.0, metadata=_doc(
        "sim seconds per wall second when the node owns the clock"))
    startup_real_time_factor: float = field(default=1.0, metadata=_doc(
        "real-time factor until the first goal_pose arrives, while the explorer's nodes "
        "discover the topics and start up (at a high real_time_factor those wall seconds "
        "would cost many sim seconds, which the lock-step runs do not lose); 0 = "
        "real_time_factor from the start"))
    # --- robot
    robot_radius_m: float = field(default=NavParams.robot_radius_m, metadata=_doc(
        "collision disk radius (waffle 281 x 306 mm -> 0.21 m circumscribed)", "m",
        read_only=True))
    robot_height_m: float = field(default=1.1, metadata=_doc(
        "parts whose zmin is below this collide (seats and table tops included)", "m",
        read_only=True))
    collision_backup_m: float = field(default=0.15, metadata=_doc(
        "after a collision the robot backs off this far (Nav2 BackUp recovery; 0 = stay)",
        "m"))
    collision_backup_speed_mps: float = field(default=0.1, metadata=_doc(
        "speed of that back-off", "m/s"))
    max_linear_speed_mps: float = field(default=NavParams.max_linear_speed_mps, metadata=_doc(
        "forward speed limit", "m/s"))
    max_angular_speed_radps: float = field(default=NavParams.max_angular_speed_radps,
                                           metadata=_doc("turn rate limit", "rad/s"))
    # --- sensors
    scan_rate_hz: float = field(default=LidarParams.rate_hz, metadata=_doc("lidar scan rate", "Hz"))
    lidar_num_beams: int = field(default=LidarParams.num_beams, metadata=_doc(
        "beams per 360 deg scan", read_only=True))
    lidar_range_max_m: float = field(default=LidarParams.range_max_m, metadata=_doc(
        "lidar maximum range (paper: 5 m; LDS-01: 3.5 m)", "m", read_only=True))
    lidar_range_min_m: float = field(default=LidarParams.range_min_m, metadata=_doc(
        "lidar minimum range", "m", read_only=True))
    lidar_noise_std_m: float = field(default=0.01, metadata=_doc(
        "Gaussian range noise", "m", read_only=True))
    lidar_mount_x_m: float = field(default=0.0, metadata=_doc(
        "lidar x in base_footprint (waffle: -0.064; 0 lets tf-less consumers treat "
        "base_scan as base_footprint)", "m", read_only=True))
    enable_camera: bool = field(default=False, metadata=_doc(
        "render RGB-D + semantic frames", read_only=True))
    camera_rate_hz: float = field(default=CameraParams.rate_hz, metadata=_doc(
        "camera frame rate", "Hz"))
    camera_width_px: int = field(default=CameraParams.width, metadata=_doc(
        "image width", "px", read_only=True))
    camera_height_px: int = field(default=CameraParams.height, metadata=_doc(
        "image height", "px", read_only=True))
    camera_fx_px: float = field(default=CameraParams.fx, metadata=_doc(
        "focal length x", "px", read_only=True))
    camera_fy_px: float = field(default=CameraParams.fy, metadata=_doc(
        "focal length y", "px", read_only=True))
    camera_cx_px: float = field(default=CameraParams.cx, metadata=_doc(
        "principal point x", "px", read_only=True))
    camera_cy_px: float = field(default=CameraParams.cy, metadata=_doc(
        "principal point y", "px", read_only=True))
    camera_mount_x_m: float = field(default=CameraParams.mount_x_m, metadata=_doc(
        "camera x in base_footprint (forward)", "m", read_only=True))
    camera_mount_z_m: float = field(default=CameraParams.mount_z_m, metadata=_doc(
        "camera height above the floor", "m", read_only=True))
    camera_pitch_rad: float = field(default=CameraParams.pitch_rad, metadata=_doc(
        "camera pitch, positive looks down", "rad", read_only=True))
    camera_range_max_m: float = field(default=CameraParams.range_max_m, metadata=_doc(
        "depth beyond which pixels read NaN", "m", read_only=True))
    camera_depth_encoding: str = field(default="16UC1", metadata=_doc(
        "encoding of the published depth image: 16UC1 (millimetres, 0 = no reading; what "
        "RealSense and Astra drivers publish, half the bytes) or 32FC1 (metres, NaN = no "
        "reading)", read_only=True))
    # --- mapping
    map_resolution_m: float = field(default=MappingParams.resolution_m, metadata=_doc(
        "occupancy map cell size", "m", read_only=True))
    map_rate_hz: float = field(default=1.0, metadata=_doc("map publish rate (sim time)", "Hz"))
    pose_noise_xy_m: float = field(default=0.0, metadata=_doc(
        "std of the position error of the pose each scan is mapped at", "m"))
    pose_noise_yaw_rad: float = field(default=0.0, metadata=_doc(
        "std of the heading error of the pose each scan is mapped at", "rad"))
    # --- navigation stand-in
    nav_allow_unknown: bool = field(default=NavParams.allow_unknown, metadata=_doc(
        "plan through unknown space (Nav2 allow_unknown)"))
    nav_inflation_margin_m: float = field(default=NavParams.inflation_margin_m, metadata=_doc(
        "clearance beyond the robot radius every plan keeps", "m"))
    nav_inflation_radius_m: float = field(default=NavParams.inflation_radius_m, metadata=_doc(
        "obstacle cost decays to zero at this distance (Nav2 inflation_radius)", "m"))
    nav_unknown_cost: float = field(default=NavParams.unknown_cost, metadata=_doc(
        "extra cost per metre through unknown cells"))
    nav_replan_period_s: float = field(default=NavParams.replan_period_s, metadata=_doc(
        "replan at most this often while the map changes", "s"))
    nav_plan_downsample: int = field(default=NavParams.plan_downsample, metadata=_doc(
        "plan on cells this many times coarser than the map"))
    nav_goal_tolerance_xy_m: float = field(default=NavParams.goal_tolerance_xy_m,
                                           metadata=_doc("goal position tolerance", "m"))
    nav_goal_tolerance_yaw_rad: float = field(default=NavParams.goal_tolerance_yaw_rad,
                                              metadata=_doc("goal heading tolerance", "rad"))
    nav_progress_timeout_s: float = field(default=NavParams.progress_timeout_s, metadata=_doc(
        "abort a goal without 0.5 m progress for this long (0 = off)", "s"))
    nav_goal_timeout_s: float = field(default=NavParams.goal_timeout_s, metadata=_doc(
        "abort a goal after this long (0 = off)", "s"))
    nav_collision_retries: int = field(default=NavParams.collision_retries, metadata=_doc(
        "after a collision and the back-up, replan and go on this many times per goal "
        "before aborting it (0 = abort at the first)"))
    # --- node (clock, publishing)
    lockstep: bool = field(default=False, metadata=_doc(
        "advance lockstep_dt_s of sim time per tick, as fast as ticks come, instead of "
        "real_time_factor x wall time"))
    lockstep_dt_s: float = field(default=0.05, metadata=_doc(
        "sim time per tick in lock-step mode", "s"))
    tick_period_s: float = field(default=0.02, metadata=_doc(
        "wall-clock period of the simulation tick", "s", read_only=True))
    max_sim_step_per_tick_s: float = field(default=1.0, metadata=_doc(
        "cap on sim time advanced in one tick (the sim slows down rather than jump)", "s"))
    publish_clock: bool = field(default=True, metadata=_doc(
        "publish /clock (the sim owns time; other nodes run with use_sim_time)"))
    costmap_layers: tuple[str, ...] = field(default=("object_costmap",), metadata=_doc(
        "OccupancyGrid topics whose occupied cells the navigation stand-in avoids"))
    output_dir: str = field(default="out/sim", metadata=_doc(
        "where sim/save_metrics writes JSON and PNG"))
    metrics_rate_hz: float = field(default=1.0, metadata=_doc(
        "sim/metrics publish rate (sim time)", "Hz"))
    # --- metrics
    coverage_period_s: float = field(default=1.0, metadata=_doc(
        "how often coverage is evaluated (sim time)", "s"))
    compute_coverage: bool = field(default=True, metadata=_doc(
        "rasterise the ground truth and track coverage", read_only=True))
    coverage_observable: bool = field(default=True, metadata=_doc(
        "measure coverage over the free cells a robot can observe from poses it can reach "
        "(false: over every free cell connected to the start, gaps narrower than the robot "
        "included)", read_only=True))

    def __post_init__(self) -> None:
        if not (math.isfinite(self.startup_real_time_factor)
                and self.startup_real_time_factor >= 0):
            raise ValueError(f"startup_real_time_factor must be finite and >= 0, got "
                             f"{self.startup_real_time_factor}")
        positive = ("physics_dt_s", "real_time_factor", "robot_radius_m", "robot_height_m",
                    "max_linear_speed_mps", "max_angular_speed_radps", "map_resolution_m",
                    "map_rate_hz", "coverage_period_s", "lockstep_dt_s", "tick_period_s",
                    "max_sim_step_per_tick_s", "metrics_rate_hz",
                    "collision_backup_speed_mps")
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        non_negative = ("pose_noise_xy_m", "pose_noise_yaw_rad", "collision_backup_m")
        for name in non_negative:
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        if not self.world:
            raise ValueError("world must name a world or a file, got ''")
        if self.camera_depth_encoding not in DEPTH_ENCODINGS:
            raise ValueError(f"camera_depth_encoding must be one of {DEPTH_ENCODINGS}, got "
                             f"{self.camera_depth_encoding!r}")
        for name in self.costmap_layers:
            if not name or any(ch.isspace() for ch in name):
                raise ValueError(f"costmap_layers entries must be topic names, got {name!r}")
        if self.physics_dt_s > 0.1:
            raise ValueError(f"physics_dt_s must be <= 0.1 s, got {self.physics_dt_s}")
        # The sub-parameter classes validate their own fields.
        self.nav_params()
        self.mapping_params()
        self.lidar_params()
        self.camera_params()

    def nav_params(self) -> NavParams:
        """The navigation stand-in's parameters."""
        return NavParams(
            robot_radius_m=self.robot_radius_m,
            inflation_margin_m=self.nav_inflation_margin_m,
            inflation_radius_m=self.nav_inflation_radius_m,
            unknown_cost=self.nav_unknown_cost,
            allow_unknown=self.nav_allow_unknown,
            replan_period_s=self.nav_replan_period_s,
            plan_downsample=self.nav_plan_downsample,
            goal_tolerance_xy_m=self.nav_goal_tolerance_xy_m,
            goal_tolerance_yaw_rad=self.nav_goal_tolerance_yaw_rad,
            max_linear_speed_mps=self.max_linear_speed_mps,
            max_angular_speed_radps=self.max_angular_speed_radps,
            progress_timeout_s=self.nav_progress_timeout_s,
            goal_timeout_s=self.nav_goal_timeout_s,
            collision_retries=self.nav_collision_retries)

    def mapping_params(self) -> MappingParams:
        """The mapper's parameters."""
        return MappingParams(resolution_m=self.map_resolution_m)

    def lidar_params(self) -> LidarParams:
        """The lidar's parameters."""
        return LidarParams(num_beams=self.lidar_num_beams, range_min_m=self.lidar_range_min_m,
                           range_max_m=self.lidar_range_max_m,
                           noise_std_m=self.lidar_noise_std_m, rate_hz=self.scan_rate_hz,
                           mount_xy_m=(self.lidar_mount_x_m, 0.0))

    def camera_params(self) -> CameraParams:
        """The camera's parameters."""
        return CameraParams(width=self.camera_width_px, height=self.camera_height_px,
                            fx=self.camera_fx_px, fy=self.camera_fy_px, cx=self.camera_cx_px,
                            cy=self.camera_cy_px, mount_x_m=self.camera_mount_x_m,
                            mount_z_m=self.camera_mount_z_m, pitch_rad=self.camera_pitch_rad,
                            range_max_m=self.camera_range_max_m, rate_hz=self.camera_rate_hz)


@dataclass(frozen=True)
class ScanGeometry:
    """Angles and range limits of the simulated lidar (LaserScan fields)."""

    angle_min_rad: float
    angle_increment_rad: float
    range_min_m: float
    range_max_m: float
    num_beams: int


@dataclass(frozen=True)
class ScanFrame:
    """One lidar scan: sim time, the true pose it was taken at, ranges (inf = no return)."""

    stamp_s: float
    pose: tuple[float, float, float]
    ranges: npt.NDArray[np.float32]


@dataclass(frozen=True)
class CameraSample:
    """One camera frame (the sensors' CameraFrame) with its sim time and robot pose."""

    stamp_s: float
    pose: tuple[float, float, float]
    frame: Any


class Collider:
    """Disk-vs-world overlap tests for the robot body.

    Parameters
    ----------
    world : World
    radius_m : float
        Robot disk radius.
    height_m : float
        Primitives with ``zmin < height_m`` collide; a map-only world's occupied cells
        (``base_grid``) always do.
    """

    def __init__(self, world: World, radius_m: float, height_m: float) -> None:
        self.radius_m = float(radius_m)
        prims = [p for p in world.primitives if p.zmin < height_m]
        boxes = [p for p in prims if p.shape == "box"]
        cyls = [p for p in prims if p.shape == "cylinder"]
        self._boxes = boxes
        self._cyls = cyls
        self._bx = np.array([[p.x, p.y, math.cos(p.yaw), math.sin(p.yaw),
                              p.size[0] / 2.0, p.size[1] / 2.0] for p in boxes],
                            dtype=np.float64).reshape(-1, 6)
        self._cy = np.array([[p.x, p.y, p.size[0]] for p in cyls],
                            dtype=np.float64).reshape(-1, 3)
        # Map-only worlds carry their occupied cells as wall boxes too; the raster is
        # used only when a world has no primitives at all.
        self._grid: GridMap | None = None
        if world.base_grid is not None and not world.primitives:
            self._grid = world.base_grid  # type: ignore[assignment]

    def clearance(self, x: float, y: float) -> tuple[float, str, str, str]:
        """Distance from (x, y) to the nearest solid, and that solid's object/class/part.

        Returns ``(inf, "", "", "")`` in an empty world. Inside a solid the distance is 0.
        """
        best = (math.inf, "", "", "")
        if len(self._bx):
            b = self._bx
            dx, dy = x - b[:, 0], y - b[:, 1]
            u = np.abs(dx * b[:, 2] + dy * b[:, 3]) - b[:, 4]
            v = np.abs(-dx * b[:, 3] + dy * b[:, 2]) - b[:, 5]
            d = np.hypot(np.maximum(u, 0.0), np.maximum(v, 0.0))
            i = int(np.argmin(d))
            if d[i] < best[0]:
                p = self._boxes[i]
                best = (float(d[i]), p.object, p.cls, p.part)
        if len(self._cy):
            c = self._cy
            d = np.maximum(np.hypot(x - c[:, 0], y - c[:, 1]) - c[:, 2], 0.0)
            i = int(np.argmin(d))
            if d[i] < best[0]:
                p = self._cyls[i]
                best = (float(d[i]), p.object, p.cls, p.part)
        if self._grid is not None:
            d = self._grid_clearance(x, y)
            if d < best[0]:
                best = (d, "map", "wall", "cell")
        return best

    def _grid_clearance(self, x: float, y: float) -> float:
        """Distance to the nearest occupied cell square within the radius (inf if none)."""
        g = self._grid
        assert g is not None
        res = g.resolution_m
        rad = int(math.ceil(self.radius_m / res)) + 1
        r, c = g.world_to_cell(x, y)
        r0, r1 = max(0, r - rad), min(g.height, r + rad + 1)
        c0, c1 = max(0, c - rad), min(g.width, c + rad + 1)
        if r0 >= r1 or c0 >= c1:
            return math.inf
        rr, cc = np.nonzero(g.data[r0:r1, c0:c1] >= OCCUPIED_THRESHOLD)
        if rr.size == 0:
            return math.inf
        # Point in the grid frame (cells), then distance to each unit square.
        fr, fc = g.world_to_cell_float(x, y)
        du = np.maximum(np.abs(float(fc) - (cc + c0 + 0.5)) - 0.5, 0.0)
        dv = np.maximum(np.abs(float(fr) - (rr + r0 + 0.5)) - 0.5, 0.0)
        return float(np.hypot(du, dv).min() * res)

    def overlaps(self, x: float, y: float) -> bool:
        """True when the robot disk at (x, y) overlaps a solid."""
        return self.clearance(x, y)[0] < self.radius_m


class SimEngine:
    """Lock-step simulator.

    Parameters
    ----------
    world : World
    params : SimParams
    lidar : object, optional
        Anything with ``scan(pose, rng) -> float32[num_beams]``; default
        ``sensors.Lidar(world, LidarParams from params)``.
    camera : object, optional
        Anything with ``render(pose, rng) -> CameraFrame``; default ``sensors.DepthCamera``
        when ``params.enable_camera``.
    ground_truth : object, optional
        A ``worlds.GroundTruth`` (``inside`` mask aligned with its ``lidar`` GridMap) for
        coverage; computed from the world when ``params.compute_coverage`` and not given.
        With ``params.coverage_observable`` its ``observable`` mask is added when missing.
    scan_geometry : ScanGeometry, optional
        Angles/limits of the lidar's ranges; default from ``params``.
    event_queue_len : int
        Bound of :attr:`scan_events` (camera events: 1/8 of it, at least 1).
    trail_spacing_m, trail_max : float, int
        Spacing and bound of the recorded trail (halved when full).

    Notes
    -----
    Time advances only in :meth:`step`. Published poses are true poses (localisation
    assumed perfect, as with slam_toolbox + Nav2 in a well-behaved run); pose noise only
    perturbs the pose each scan is mapped at.
    """

    def __init__(self, world: World, params: SimParams | None = None, *,
                 lidar: Any = None, camera: Any = None, ground_truth: Any = None,
                 scan_geometry: ScanGeometry | None = None,
                 event_queue_len: int = 64, trail_spacing_m: float = 0.05,
                 trail_max: int = 20000) -> None:
        self.params = params if params is not None else SimParams()
        p = self.params
        self.world = world
        self._rng = np.random.default_rng(p.seed)
        lp = p.lidar_params()
        self._lidar = lidar if lidar is not None else Lidar(world, lp)
        if camera is None and p.enable_camera:
            camera = DepthCamera(world, p.camera_params())
        self._camera = camera if p.enable_camera else None
        self.scan_geometry = scan_geometry if scan_geometry is not None else ScanGeometry(
            lp.angle_min_rad, lp.angle_increment_rad, lp.range_min_m, lp.range_max_m,
            lp.num_beams)
        self._lidar_mount = lp.mount_xy_m
        if ground_truth is None and p.compute_coverage:
            ground_truth = worlds.ground_truth(world, resolution_m=p.map_resolution_m)
        if isinstance(ground_truth, worlds.GroundTruth):
            ground_truth = (with_observable(world, ground_truth, lp, p.robot_radius_m)
                            if p.coverage_observable
                            else replace(ground_truth, observable=None))
        self.ground_truth = ground_truth
        self.collider = Collider(world, p.robot_radius_m, p.robot_height_m)
        x, y, yaw = (float(v) for v in world.start_pose)
        self._pose = (x, y, yaw)
        self._vel = (0.0, 0.0)
        self._cmd = (0.0, 0.0)
        self._time_s = 0.0
        self._step_count = 0
        self._accum_s = 0.0
        self._mapper = ScanMapper((x, y), p.mapping_params())
        self._nav = Navigator(p.nav_params())
        self._map_stamp_ns = 0
        self._nav.set_map(lambda: self._mapper.grid(self._map_stamp_ns), 0)
        self.metrics = SimMetrics(ground_truth)
        self._in_contact = False
        self._next_scan_s = 0.0
        self._next_camera_s = 0.0
        self._next_coverage_s = 0.0
        self._latest_scan: ScanFrame | None = None
        self._latest_camera: CameraSample | None = None
        self.scan_events: deque[ScanFrame] = deque(maxlen=event_queue_len)
        self.camera_events: deque[CameraSample] = deque(maxlen=max(1, event_queue_len // 8))
        self._layers: dict[str, GridMap] = {}
        self._nav_prev_state = NavState.IDLE
        self._on_collision: list[Callable[[CollisionEvent], None]] = []
        self._backup_left_m = 0.0
        self._backup_dir = -1.0
        self._trail: list[tuple[float, float]] = [(x, y)]
        self._trail_spacing_m = trail_spacing_m
        self._trail_max = max(16, trail_max)

    # ------------------------------------------------------------ properties
    @property
    def pose(self) -> tuple[float, float, float]:
        """True robot pose (x, y, yaw) of base_footprint in the map/world frame."""
        return self._pose

    @property
    def velocity(self) -> tuple[float, float]:
        """Body velocity (v m/s, w rad/s) applied in the last physics step."""
        return self._vel

    @property
    def time_s(self) -> float:
        """Sim time in seconds."""
        return self._time_s

    @property
    def time_ns(self) -> int:
        """Sim time in integer nanoseconds."""
        return int(round(self._time_s * 1e9))

    @property
    def map(self) -> GridMap:
        """The current occupancy map (stamped with the sim time of its last change)."""
        return self._mapper.grid(self._map_stamp_ns)

    @property
    def map_version(self) -> int:
        """Changes whenever a scan changed the map."""
        return self._mapper.version

    @property
    def nav_status(self) -> NavStatus:
        """Status of the current/last goal."""
        return self._nav.status

    @property
    def plan(self) -> npt.NDArray[np.float64]:
        """Current plan, world points shape (N, 2)."""
        return self._nav.plan_xy

    @property
    def plan_version(self) -> int:
        """Changes whenever :attr:`plan` is replaced."""
        return self._nav.plan_version

    @property
    def latest_scan(self) -> ScanFrame | None:
        """Most recent scan (None before the first)."""
        return self._latest_scan

    @property
    def latest_camera(self) -> CameraSample | None:
        """Most recent camera frame (None before the first or with the camera off)."""
        return self._latest_camera

    @property
    def trail(self) -> npt.NDArray[np.float64]:
        """Travelled path (x, y) sampled every few centimetres, shape (N, 2), bounded."""
        return np.asarray(self._trail + [self._pose[:2]], dtype=np.float64)

    @property
    def backing_up(self) -> bool:
        """True while the robot backs off after a collision."""
        return self._backup_left_m > 0.0

    @property
    def in_contact(self) -> bool:
        """True while the robot is pressed against an obstacle (since the last contact)."""
        return self._in_contact

    @property
    def layers(self) -> dict[str, GridMap]:
        """Extra obstacle layers given to the navigation stand-in."""
        return dict(self._layers)

    @property
    def navigator(self) -> Navigator:
        """The navigation stand-in (for diagnostics)."""
        return self._nav

    # ---------------------------------------------------------------- inputs
    def set_goal(self, x: float, y: float, yaw: float = 0.0) -> None:
        """Send a navigation goal (like publishing ``goal_pose``); replaces any active one.

        Raises
        ------
        ValueError
            NaN/inf values, no map yet, or a goal outside the current map. The rejection
            is counted in the metrics.
        """
        try:
            self._nav.set_goal(x, y, yaw, self._time_s, self._pose)
        except ValueError:
            self.metrics.goal_rejected()
            raise
        self.metrics.goal_received()
        self._nav_prev_state = NavState.ACTIVE
        self._cmd = (0.0, 0.0)

    def cancel_goal(self) -> None:
        """Cancel the active goal; the robot stops."""
        self._nav.cancel()

    def set_cmd_vel(self, v_mps: float, w_radps: float) -> None:
        """Direct velocity command (teleop / scripted drives); cancels an active goal.

        It stays in force until changed, until a goal is sent or until a collision.

        Raises
        ------
        ValueError
            When a value is not finite.
        """
        if not (math.isfinite(v_mps) and math.isfinite(w_radps)):
            raise ValueError(f"cmd_vel must be finite, got ({v_mps}, {w_radps})")
        self._nav.cancel("replaced by cmd_vel")
        self._backup_left_m = 0.0
        self._cmd = (float(v_mps), float(w_radps))

    def add_costmap_layer(self, name: str, grid: GridMap) -> None:
        """Add or replace an obstacle layer (its occupied cells block planning)."""
        if not isinstance(grid, GridMap):
            raise ValueError(f"layer {name!r} must be a GridMap, got {type(grid).__name__}")
        self._layers[name] = grid
        self._nav.set_layer(name, grid)

    def remove_costmap_layer(self, name: str) -> None:
        """Remove an obstacle layer (no-op when absent)."""
        if self._layers.pop(name, None) is not None:
            self._nav.set_layer(name, None)

    def update_params(self, params: SimParams) -> None:
        """Apply changed parameters; read-only ones (world, sensors, map resolution,
        robot size, physics step) keep the values the engine was built with.

        Raises
        ------
        ValueError
            When a read-only field differs.
        """
        frozen = [f.name for f in fields(SimParams) if f.metadata.get("read_only")
                  and getattr(params, f.name) != getattr(self.params, f.name)]
        if frozen:
            raise ValueError(f"read-only parameters cannot change at run time: {frozen}")
        self.params = params
        self._nav.set_params(params.nav_params())

    def drain_scans(self) -> list[ScanFrame]:
        """Scans produced since the last call, oldest first (bounded queue)."""
        out = list(self.scan_events)
        self.scan_events.clear()
        return out

    def drain_camera(self) -> list[CameraSample]:
        """Camera frames produced since the last call, oldest first (bounded queue)."""
        out = list(self.camera_events)
        self.camera_events.clear()
        return out

    def on_collision(self, callback: Callable[[CollisionEvent], None]) -> None:
        """Call ``callback(event)`` for every new contact event."""
        self._on_collision.append(callback)

    # --------------------------------------------------------------- running
    def step(self, dt_s: float) -> None:
        """Advance the simulation by ``dt_s`` seconds (whole physics steps; the remainder
        carries over to the next call).

        Raises
        ------
        ValueError
            When ``dt_s`` is negative or not finite.
        """
        if not (math.isfinite(dt_s) and dt_s >= 0):
            raise ValueError(f"dt_s must be finite and >= 0, got {dt_s}")
        dt = self.params.physics_dt_s
        self._accum_s += dt_s
        n = int(math.floor(self._accum_s / dt + 1e-9))
        self._accum_s -= n * dt
        for _ in range(n):
            self._physics_step(dt)

    def run_until(self, predicate: Callable[["SimEngine"], bool], timeout_s: float) -> bool:
        """Step until ``predicate(engine)`` holds or ``timeout_s`` sim seconds pass."""
        end = self._time_s + timeout_s
        dt = self.params.physics_dt_s
        while self._time_s < end - 1e-9:
            if predicate(self):
                return True
            self._physics_step(dt)
        return bool(predicate(self))

    def _physics_step(self, dt: float) -> None:
        p = self.params
        t = self._time_s
        # Sensors first, at the pose of this instant.
        if t >= self._next_scan_s - 1e-9:
            self._next_scan_s += 1.0 / p.scan_rate_hz
            self._do_scan()
        if self._camera is not None and t >= self._next_camera_s - 1e-9:
            self._next_camera_s += 1.0 / p.camera_rate_hz
            frame = self._camera.render(self._pose, self._rng)
            self._latest_camera = CameraSample(t, self._pose, frame)
            self.camera_events.append(self._latest_camera)
        if self.ground_truth is not None and t >= self._next_coverage_s - 1e-9:
            self._next_coverage_s += p.coverage_period_s
            self.metrics.update_coverage(self.map, t)
        # Command: the post-collision back-up, else the navigator while a goal is active,
        # else the direct command.
        backing = self._backup_left_m > 0.0
        if backing:
            v, w = self._backup_dir * p.collision_backup_speed_mps, 0.0
        elif self._nav.status.state is NavState.ACTIVE:
            v, w = self._nav.update(self._pose, t)
        else:
            v, w = self._cmd
        self._track_nav_outcome()
        v = max(-p.max_linear_speed_mps, min(p.max_linear_speed_mps, v))
        w = max(-p.max_angular_speed_radps, min(p.max_angular_speed_radps, w))
        moved = self._move(v, w, dt)
        if backing:
            self._backup_left_m = 0.0 if moved == 0.0 else self._backup_left_m - moved
        self._step_count += 1
        self._time_s = self._step_count * dt  # no drift from summing dt

    def _track_nav_outcome(self) -> None:
        state = self._nav.status.state
        if state is not self._nav_prev_state:
            if state is NavState.SUCCEEDED:
                self.metrics.goal_reached()
            elif state is NavState.ABORTED:
                self.metrics.goal_aborted(self._nav.status.reason)
            self._nav_prev_state = state

    def _move(self, v: float, w: float, dt: float) -> float:
        """Integrate one step unless it runs into a solid; returns the distance moved."""
        x, y, yaw = self._pose
        if abs(w) > 1e-9:
            nyaw = yaw + w * dt
            nx = x + v / w * (math.sin(nyaw) - math.sin(yaw))
            ny = y - v / w * (math.cos(nyaw) - math.cos(yaw))
        else:
            nyaw = yaw
            nx, ny = x + v * dt * math.cos(yaw), y + v * dt * math.sin(yaw)
        nyaw = (nyaw + math.pi) % (2.0 * math.pi) - math.pi
        moved = math.hypot(nx - x, ny - y)
        if moved > 0.0:
            clear_new, obj, cls, part = self.collider.clearance(nx, ny)
            r = self.collider.radius_m
            if clear_new < r:
                clear_old = self.collider.clearance(x, y)[0]
                # Already overlapping (spawned in contact): moves that increase the
                # clearance are allowed so the robot can back out.
                if not (clear_old < r and clear_new > clear_old):
                    self._collide(obj, cls, part, v)
                    self._pose = (x, y, nyaw)
                    self._vel = (0.0, w)
                    return 0.0
            self._in_contact = False
            self.metrics.add_distance(moved)
            lx, ly = self._trail[-1]
            if math.hypot(nx - lx, ny - ly) >= self._trail_spacing_m:
                self._trail.append((nx, ny))
                if len(self._trail) >= self._trail_max:  # bounded: halve, coarser spacing
                    self._trail = self._trail[::2]
                    self._trail_spacing_m *= 2.0
        self._pose = (nx, ny, nyaw)
        self._vel = (v, w)
        return moved

    def _collide(self, obj: str, cls: str, part: str, v: float) -> None:
        """Stop: zero the command, abort the goal, back off (like Nav2's BackUp recovery)
        unless already backing; count a new contact event once."""
        self._cmd = (0.0, 0.0)
        if self._backup_left_m <= 0.0 and self.params.collision_backup_m > 0.0:
            self._backup_left_m = self.params.collision_backup_m
            self._backup_dir = -1.0 if v >= 0.0 else 1.0
        else:
            self._backup_left_m = 0.0
        self._nav.recover(f"collision with {obj or cls} ({part})", self._time_s, self._pose)
        self._track_nav_outcome()
        if self._in_contact:
            return
        self._in_contact = True
        ev = CollisionEvent(self._time_s, self._pose[0], self._pose[1], obj, cls, part)
        self.metrics.add_collision(ev)
        for cb in self._on_collision:
            cb(ev)

    def _do_scan(self) -> None:
        p = self.params
        g = self.scan_geometry
        pose = self._pose
        ranges = np.asarray(self._lidar.scan(pose, self._rng), dtype=np.float32)
        if ranges.shape != (g.num_beams,):
            raise ValueError(f"lidar returned shape {ranges.shape}, expected ({g.num_beams},)")
        # Ranges are measured from the lidar, mounted at mount_xy in base_footprint.
        mx, my = self._lidar_mount
        c, sn = math.cos(pose[2]), math.sin(pose[2])
        map_pose = (pose[0] + c * mx - sn * my, pose[1] + sn * mx + c * my, pose[2])
        if p.pose_noise_xy_m > 0 or p.pose_noise_yaw_rad > 0:
            nx, ny, nyaw = self._rng.normal(0.0, 1.0, 3)
            map_pose = (map_pose[0] + nx * p.pose_noise_xy_m,
                        map_pose[1] + ny * p.pose_noise_xy_m,
                        map_pose[2] + nyaw * p.pose_noise_yaw_rad)
        self._mapper.integrate_scan(map_pose, ranges, g.angle_min_rad, g.angle_increment_rad,
                                    g.range_max_m, g.range_min_m)
        self._map_stamp_ns = self.time_ns
        self._nav.set_map(lambda: self._mapper.grid(self._map_stamp_ns), self._mapper.version)
        self._latest_scan = ScanFrame(self._time_s, pose, ranges)
        self.scan_events.append(self._latest_scan)


# ------------------------------------------------------------------ defaults


def load_world(spec: str) -> World:
    """A world from a name (:func:`sim_bridge.worlds.default_world`) or a file path.

    Raises
    ------
    ValueError
        On an unknown name or an unreadable/invalid file.
    """
    if spec.endswith((".yaml", ".yml")) or "/" in spec:
        return worlds.load_world(Path(spec))
    return worlds.default_world(spec)


def engine_from_params(params: SimParams) -> SimEngine:
    """Load ``params.world`` and build an engine with the default sensors."""
    return SimEngine(load_world(params.world), params)
