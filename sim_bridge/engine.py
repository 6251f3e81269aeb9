"""The ROS-free simulator: a TurtleBot3-waffle-sized robot in a 2.5D world.

:class:`SimEngine` advances a unicycle robot at a fixed physics step, stops it on
contact with any obstacle part that reaches below the robot's height (chair seats and
table tops included, although the lidar at 0.17 m never sees them), produces lidar
scans (5 Hz) and camera frames (15 Hz, optional), integrates the scans into a growing
occupancy map (:mod:`sim_bridge.mapping`), and runs the navigation stand-in
(:mod:`sim_bridge.navigation`). Everything is driven by :meth:`SimEngine.step`, so
benchmarks and tests run in lock step without ROS; :mod:`sim_bridge.node` wraps it.

Rates of the real stack (:class:`SimParams` fields; 0 gives back every scan / every step):
the explorer's :attr:`SimEngine.map` holds keyframe scans only, republished every
``map_update_interval_s`` (slam_toolbox, :mod:`sim_bridge.published_map`); navigation plans
on :attr:`SimEngine.live_map`, updated by every scan (Nav2's costmaps mark and clear from
the scan topic), and follows its plan at ``nav_controller_rate_hz`` (Nav2's
``controller_frequency``, the command held in between) while physics steps every
``physics_dt_s``; it replans at ``nav_replan_period_s`` (Nav2's 1 Hz) or at once on a
blocked plan.

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
from dataclasses import dataclass, fields, replace
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from sim_bridge import worlds
from sim_bridge.collision import Collider
from sim_bridge.mapping import ScanMapper
from sim_bridge.metrics import CollisionEvent, SimMetrics
from sim_bridge.navigation import NavState, NavStatus, Navigator
from sim_bridge.observable import with_observable
from sim_bridge.params import DEPTH_ENCODINGS, SimParams
from sim_bridge.sensors import DepthCamera, Lidar
from sim_bridge.published_map import KeyframeMapper, MapPublication
from sim_bridge.slam_error import LidarGeometry, SlamErrorModel
from sim_bridge.world import World

#: Re-exported: SimParams and Collider live in sim_bridge.params / sim_bridge.collision.
__all__ = ["DEPTH_ENCODINGS", "CameraSample", "Collider", "ScanFrame", "ScanGeometry",
           "SimEngine", "SimParams", "engine_from_params"]


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
    """One lidar scan: sim time, the true pose it was taken at, ranges (inf = no return),
    and the SLAM pose then (the map-frame pose consistent with the map; None: ``pose``)."""

    stamp_s: float
    pose: tuple[float, float, float]
    ranges: npt.NDArray[np.float32]
    map_pose: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class CameraSample:
    """One camera frame (the sensors' CameraFrame) with its sim time, true robot pose and
    SLAM pose (None: ``pose``)."""

    stamp_s: float
    pose: tuple[float, float, float]
    frame: Any
    map_pose: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class EngineBuffers:
    """Bounds of what a :class:`SimEngine` records.

    Attributes
    ----------
    event_queue_len : int
        Bound of ``SimEngine.scan_events`` (camera events: 1/8 of it, at least 1).
    trail_spacing_m, trail_max : float, int
        Spacing and bound of the recorded trail (halved when full; at least 16 points).
    """

    event_queue_len: int = 64
    trail_spacing_m: float = 0.05
    trail_max: int = 20000


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
    buffers : EngineBuffers
        Bounds of the recorded scan / camera events and trail.

    Notes
    -----
    Time advances only in :meth:`step`. With ``params.mapping_error`` "none" the map is
    built at true poses and the SLAM pose is the true pose (localisation assumed perfect);
    pose noise only perturbs the pose each scan is mapped at. Otherwise
    (:mod:`sim_bridge.slam_error`) :attr:`map` is the erroneous SLAM map and
    :attr:`slam_pose` the pose consistent with it, which navigation tracks (as Nav2 does
    with SLAM's map -> base transform); physics, collisions and coverage (measured on
    :attr:`true_map`) stay in the true world.
    """

    def __init__(self, world: World, params: SimParams | None = None, *,
                 lidar: Any = None, camera: Any = None, ground_truth: Any = None,
                 scan_geometry: ScanGeometry | None = None,
                 buffers: EngineBuffers = EngineBuffers()) -> None:
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
        geometry = LidarGeometry(lp.angle_min_rad, lp.angle_increment_rad, lp.range_max_m,
                                 lp.range_min_m)
        slam = p.slam_error_params()
        self._slam_error = (None if slam is None else SlamErrorModel(
            slam, (x, y), p.mapping_params(), geometry, p.seed))
        # Without a mapping error model and with keyframes on, the keyframe scans at the
        # poses _mapper used (the SLAM map is a keyframe map already).
        keyframes = p.mapping_keyframe_travel_m > 0 or p.mapping_keyframe_turn_rad > 0
        self._kf_mapper = (KeyframeMapper((x, y), p.mapping_params(), geometry,
                                          p.mapping_keyframe_travel_m,
                                          p.mapping_keyframe_turn_rad)
                           if keyframes and slam is None else None)
        self._nav = Navigator(p.nav_params())
        self._map_stamp_ns = 0
        self._nav.set_map(lambda: self.live_map, 0)
        self._published = MapPublication()
        self.metrics = SimMetrics(ground_truth)
        self._in_contact = False
        self._next_scan_s = 0.0
        self._next_camera_s = 0.0
        self._next_coverage_s = 0.0
        self._latest_scan: ScanFrame | None = None
        self._latest_camera: CameraSample | None = None
        self.scan_events: deque[ScanFrame] = deque(maxlen=buffers.event_queue_len)
        self.camera_events: deque[CameraSample] = deque(
            maxlen=max(1, buffers.event_queue_len // 8))
        self._layers: dict[str, GridMap] = {}
        self._nav_prev_state = NavState.IDLE
        self._on_collision: list[Callable[[CollisionEvent], None]] = []
        self._backup_left_m = 0.0
        self._backup_dir = -1.0
        self._trail: list[tuple[float, float]] = [(x, y)]
        self._trail_spacing_m = buffers.trail_spacing_m
        self._trail_max = max(16, buffers.trail_max)

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
    def slam_pose(self) -> tuple[float, float, float]:
        """The robot's pose in the map's frame: the true pose composed with the mapping
        error's drift (:attr:`pose` without a mapping error model)."""
        if self._slam_error is None:
            return self._pose
        return self._slam_error.estimate(self._pose)

    @property
    def slam_error(self) -> SlamErrorModel | None:
        """The mapping error model (None with ``mapping_error`` "none")."""
        return self._slam_error

    @property
    def map(self) -> GridMap:
        """The published occupancy map, slam_toolbox's ``map``: the keyframe scans (the SLAM
        map with a mapping error model), as of the last publication (every
        ``map_update_interval_s``; 0: after every scan, stamped with its time)."""
        if self.params.map_update_interval_s > 0 and self._published.grid is not None:
            return self._published.grid
        return self._keyframe_map()

    @property
    def live_map(self) -> GridMap:
        """The map navigation plans on, updated by every scan (stamped with the last one's
        time): the SLAM map with a mapping error model, else :attr:`true_map`."""
        return (self._slam_error or self._mapper).grid(self._map_stamp_ns)

    @property
    def live_map_version(self) -> int:
        """Changes whenever a scan changed :attr:`live_map`."""
        return (self._slam_error or self._mapper).version

    @property
    def map_publishes(self) -> int:
        """Publications of :attr:`map` so far (one per ``map_update_interval_s``, or per
        scan with 0): a publisher sends one message per increment."""
        return self._published.count

    def _keyframe_map(self, stamp_ns: int | None = None) -> GridMap:
        """The keyframe map now, stamped ``stamp_ns`` (default: the last scan's time)."""
        stamp = self._map_stamp_ns if stamp_ns is None else stamp_ns
        return (self._kf_mapper or self._slam_error or self._mapper).grid(stamp)

    def _keyframe_map_version(self) -> int:
        return (self._kf_mapper or self._slam_error or self._mapper).version

    @property
    def true_map(self) -> GridMap:
        """The map of every scan at its true pose (what coverage is measured on)."""
        return self._mapper.grid(self._map_stamp_ns)

    @property
    def map_version(self) -> int:
        """Changes whenever :attr:`map`'s content changed (a republished unchanged map keeps
        it)."""
        if self.params.map_update_interval_s > 0 and self._published.grid is not None:
            return self._published.version
        return self._keyframe_map_version()

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
            self._nav.set_goal(x, y, yaw, self._time_s, self.slam_pose)
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
            if p.map_update_interval_s <= 0:
                self._published.count += 1
        if self._published.due(t, p.map_update_interval_s):
            self._published.publish(t, p.map_update_interval_s, self._keyframe_map_version(),
                                    self._keyframe_map, self.time_ns)
        if self._camera is not None and t >= self._next_camera_s - 1e-9:
            self._next_camera_s += 1.0 / p.camera_rate_hz
            frame = self._camera.render(self._pose, self._rng)
            self._latest_camera = CameraSample(t, self._pose, frame, self.slam_pose)
            self.camera_events.append(self._latest_camera)
        if self.ground_truth is not None and t >= self._next_coverage_s - 1e-9:
            self._next_coverage_s += p.coverage_period_s
            self.metrics.update_coverage(self.true_map, t)
        # Command: the post-collision back-up, else the navigator while a goal is active,
        # else the direct command.
        backing = self._backup_left_m > 0.0
        if backing:
            v, w = self._backup_dir * p.collision_backup_speed_mps, 0.0
        elif self._nav.status.state is NavState.ACTIVE:
            v, w = self._nav.control(self.slam_pose, t)
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
        backing = self._backup_left_m > 0.0
        if self._backup_left_m <= 0.0 and self.params.collision_backup_m > 0.0:
            self._backup_left_m = self.params.collision_backup_m
            self._backup_dir = -1.0 if v >= 0.0 else 1.0
        else:
            self._backup_left_m = 0.0
        self._nav.recover(f"collision with {obj or cls} ({part})", self._time_s,
                          self.slam_pose)
        self._track_nav_outcome()
        if self._in_contact:
            return
        self._in_contact = True
        ev = CollisionEvent(self._time_s, self._pose[0], self._pose[1], obj, cls, part,
                            float(v), backing)
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
        map_pose = sensor_pose = (pose[0] + c * mx - sn * my, pose[1] + sn * mx + c * my,
                                  pose[2])
        if p.pose_noise_xy_m > 0 or p.pose_noise_yaw_rad > 0:
            nx, ny, nyaw = self._rng.normal(0.0, 1.0, 3)
            map_pose = (map_pose[0] + nx * p.pose_noise_xy_m,
                        map_pose[1] + ny * p.pose_noise_xy_m,
                        map_pose[2] + nyaw * p.pose_noise_yaw_rad)
        self._mapper.integrate_scan(map_pose, ranges, g.angle_min_rad, g.angle_increment_rad,
                                    g.range_max_m, g.range_min_m)
        if self._kf_mapper is not None:
            self._kf_mapper.add_scan(pose, map_pose, ranges)
        if self._slam_error is not None:
            self._slam_error.add_scan(pose, sensor_pose, ranges)
        self._map_stamp_ns = self.time_ns
        self._nav.set_map(lambda: self.live_map, self.live_map_version)
        self._latest_scan = ScanFrame(self._time_s, pose, ranges, self.slam_pose)
        self.scan_events.append(self._latest_scan)


# ------------------------------------------------------------------ defaults


def engine_from_params(params: SimParams) -> SimEngine:
    """Load ``params.world`` and build an engine with the default sensors."""
    return SimEngine(worlds.load_world(params.world), params)
