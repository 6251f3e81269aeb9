"""All simulator parameters in one dataclass (one ROS parameter each in :mod:`sim_bridge.node`).

:class:`SimParams` builds the parameters of the parts it drives: the navigation stand-in,
the mapper, the lidar and the camera, which validate their own fields.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from explore_seg.core.fields import param_meta
from sim_bridge.mapping import MappingParams
from sim_bridge.navigation.params import NavParams
from sim_bridge.sensors.camera import CameraParams
from sim_bridge.sensors.lidar import LidarParams
from sim_bridge.slam_error import PROFILES, SlamErrorParams

#: Values of ``SimParams.mapping_error`` besides the named profiles.
MAPPING_ERROR_MODES = ("none", "custom")

#: Encodings the node can publish depth images in.
DEPTH_ENCODINGS = ("16UC1", "32FC1")


@dataclass(frozen=True)
class SimParams:
    """All simulator parameters (one ROS parameter each in :mod:`sim_bridge.node`).

    Fields marked read-only take effect only when the engine is built.
    """

    world: str = field(default="small_house", metadata=param_meta(
        "world: a generated one (house, house_cluttered, maze, small_house, small_cluttered, "
        "office_floor), a shipped file (shared/house, shared/house_cluttered, "
        "shared/house_cluttered_plus, shared/maze, eb/NAME for the Explore-Bench maps) or a "
        "path to a *.world.yaml / map_server *.yaml", read_only=True))
    seed: int = field(default=0, metadata=param_meta(
        "seed of the sensor and pose noise", read_only=True))
    physics_dt_s: float = field(default=0.02, metadata=param_meta(
        "fixed physics step", "s", range=(0.0, 0.1), read_only=True))
    real_time_factor: float = field(default=1.0, metadata=param_meta(
        "sim seconds per wall second when the node owns the clock", range=(0.0, math.inf)))
    startup_real_time_factor: float = field(default=1.0, metadata=param_meta(
        "real-time factor until the first goal_pose arrives, while the explorer's nodes "
        "discover the topics and start up (at a high real_time_factor those wall seconds "
        "would cost many sim seconds, which the lock-step runs do not lose); 0 = "
        "real_time_factor from the start", range=(0.0, math.inf)))
    # --- robot
    robot_radius_m: float = field(default=NavParams.robot_radius_m, metadata=param_meta(
        "collision disk radius (waffle 281 x 306 mm -> 0.21 m circumscribed)", "m",
        range=(0.0, math.inf), read_only=True))
    robot_height_m: float = field(default=1.1, metadata=param_meta(
        "parts whose zmin is below this collide (seats and table tops included)", "m",
        range=(0.0, math.inf), read_only=True))
    collision_backup_m: float = field(default=0.15, metadata=param_meta(
        "after a collision the robot backs off this far (Nav2 BackUp recovery; 0 = stay)",
        "m", range=(0.0, math.inf)))
    collision_backup_speed_mps: float = field(default=0.1, metadata=param_meta(
        "speed of that back-off", "m/s", range=(0.0, math.inf)))
    max_linear_speed_mps: float = field(
        default=NavParams.max_linear_speed_mps,
        metadata=param_meta("forward speed limit", "m/s", range=(0.0, math.inf)))
    max_angular_speed_radps: float = field(
        default=NavParams.max_angular_speed_radps,
        metadata=param_meta("turn rate limit", "rad/s", range=(0.0, math.inf)))
    # --- sensors
    scan_rate_hz: float = field(default=LidarParams.rate_hz, metadata=param_meta(
        "lidar scan rate (TurtleBot3's LDS: 5 Hz)", "Hz", range=(0.0, math.inf)))
    lidar_num_beams: int = field(default=LidarParams.num_beams, metadata=param_meta(
        "beams per 360 deg scan", range=(3, 2**31 - 1), read_only=True))
    lidar_range_max_m: float = field(default=LidarParams.range_max_m, metadata=param_meta(
        "lidar maximum range (paper: 5 m; LDS-01: 3.5 m)", "m",
        range=(0.0, math.inf), read_only=True))
    lidar_range_min_m: float = field(default=LidarParams.range_min_m, metadata=param_meta(
        "lidar minimum range", "m", range=(0.0, math.inf), read_only=True))
    lidar_noise_std_m: float = field(default=0.01, metadata=param_meta(
        "Gaussian range noise", "m", range=(0.0, math.inf), read_only=True))
    lidar_mount_x_m: float = field(default=0.0, metadata=param_meta(
        "lidar x in base_footprint (waffle: -0.064; 0 lets tf-less consumers treat "
        "base_scan as base_footprint)", "m", read_only=True))
    enable_camera: bool = field(default=False, metadata=param_meta(
        "render RGB-D + semantic frames", read_only=True))
    camera_rate_hz: float = field(default=CameraParams.rate_hz, metadata=param_meta(
        "camera frame rate", "Hz", range=(0.0, math.inf)))
    camera_width_px: int = field(default=CameraParams.width, metadata=param_meta(
        "image width", "px", range=(1, 2**31 - 1), read_only=True))
    camera_height_px: int = field(default=CameraParams.height, metadata=param_meta(
        "image height", "px", range=(1, 2**31 - 1), read_only=True))
    camera_fx_px: float = field(default=CameraParams.fx, metadata=param_meta(
        "focal length x", "px", range=(0.0, math.inf), read_only=True))
    camera_fy_px: float = field(default=CameraParams.fy, metadata=param_meta(
        "focal length y", "px", range=(0.0, math.inf), read_only=True))
    camera_cx_px: float = field(default=CameraParams.cx, metadata=param_meta(
        "principal point x", "px", read_only=True))
    camera_cy_px: float = field(default=CameraParams.cy, metadata=param_meta(
        "principal point y", "px", read_only=True))
    camera_mount_x_m: float = field(default=CameraParams.mount_x_m, metadata=param_meta(
        "camera x in base_footprint (forward)", "m", read_only=True))
    camera_mount_z_m: float = field(default=CameraParams.mount_z_m, metadata=param_meta(
        "camera height above the floor", "m", read_only=True))
    camera_pitch_rad: float = field(default=CameraParams.pitch_rad, metadata=param_meta(
        "camera pitch, positive looks down", "rad",
        range=(-math.pi / 2, math.pi / 2), read_only=True))
    camera_range_max_m: float = field(default=CameraParams.range_max_m, metadata=param_meta(
        "depth beyond which pixels read NaN", "m", range=(0.0, math.inf), read_only=True))
    camera_depth_encoding: str = field(default="16UC1", metadata=param_meta(
        "encoding of the published depth image: 16UC1 (millimetres, 0 = no reading; what "
        "RealSense and Astra drivers publish, half the bytes) or 32FC1 (metres, NaN = no "
        "reading)", read_only=True))
    # --- mapping
    map_resolution_m: float = field(default=MappingParams.resolution_m, metadata=param_meta(
        "occupancy map cell size", "m", range=(0.0, math.inf), read_only=True))
    map_update_interval_s: float = field(default=5.0, metadata=param_meta(
        "the map the explorer sees ('map') is republished this often, as slam_toolbox's "
        "map_update_interval: 5 s is the value of slam_toolbox's shipped "
        "mapper_params_online_async.yaml and of Nav2's bringup, what a TurtleBot3 user "
        "running the stock SLAM launch gets; navigation plans on every scan meanwhile (Nav2's "
        "costmaps mark and clear from the scan topic); 0 = after every scan", "s",
        range=(0.0, math.inf)))
    pose_noise_xy_m: float = field(default=0.0, metadata=param_meta(
        "std of the position error of the pose each scan is mapped at", "m",
        range=(0.0, math.inf)))
    pose_noise_yaw_rad: float = field(default=0.0, metadata=param_meta(
        "std of the heading error of the pose each scan is mapped at", "rad",
        range=(0.0, math.inf)))
    # --- SLAM-like mapping error (sim_bridge.slam_error)
    mapping_error: str = field(default="none", metadata=param_meta(
        "mapping error model: 'none' (every scan mapped at the true pose), 'realistic' "
        "(slam_toolbox on a TurtleBot3), 'harsh', or 'custom' (the mapping_* numbers below): "
        "drift between loop closures, keyframes only, the map re-rendered at closures; the "
        "map, the published pose and navigation's pose are the SLAM ones, collisions and "
        "coverage the true ones", read_only=True))
    mapping_drift_xy_m: float = field(default=SlamErrorParams.drift_xy_m, metadata=param_meta(
        "(custom) std of the position random walk after 1 m of travel", "m",
        range=(0.0, math.inf), read_only=True))
    mapping_drift_yaw_per_m_rad: float = field(
        default=SlamErrorParams.drift_yaw_per_m_rad, metadata=param_meta(
        "(custom) std of the heading random walk after 1 m of travel", "rad",
        range=(0.0, math.inf), read_only=True))
    mapping_drift_yaw_per_rad: float = field(
        default=SlamErrorParams.drift_yaw_per_rad, metadata=param_meta(
        "(custom) std of the heading random walk after 1 rad of turning", "rad",
        range=(0.0, math.inf), read_only=True))
    mapping_jitter_xy_m: float = field(default=SlamErrorParams.jitter_xy_m, metadata=param_meta(
        "(custom) std of the per-keyframe position error", "m", range=(0.0, math.inf),
        read_only=True))
    mapping_jitter_yaw_rad: float = field(
        default=SlamErrorParams.jitter_yaw_rad, metadata=param_meta(
        "(custom) std of the per-keyframe heading error", "rad", range=(0.0, math.inf),
        read_only=True))
    mapping_keyframe_travel_m: float = field(
        default=SlamErrorParams.keyframe_travel_m, metadata=param_meta(
        "a scan enters the map ('map', with or without a mapping error model) only as a "
        "keyframe: after this much travel since the last one (slam_toolbox "
        "minimum_travel_distance, 0.5 m shipped); 0 with mapping_keyframe_turn_rad 0 = every "
        "scan enters the map", "m",
        range=(0.0, math.inf), read_only=True))
    mapping_keyframe_turn_rad: float = field(
        default=SlamErrorParams.keyframe_turn_rad, metadata=param_meta(
        "... or this much turning (slam_toolbox minimum_travel_heading, 0.5 rad shipped)",
        "rad", range=(0.0, math.inf), read_only=True))
    mapping_loop_radius_m: float = field(
        default=SlamErrorParams.loop_radius_m, metadata=param_meta(
        "(custom) a keyframe closes a loop with an old one within this distance", "m",
        range=(0.0, math.inf), read_only=True))
    mapping_loop_min_travel_m: float = field(
        default=SlamErrorParams.loop_min_travel_m, metadata=param_meta(
        "(custom) the old keyframe lies this much travel back, and the last closure too",
        "m", range=(0.0, math.inf), read_only=True))
    # --- real-robot pose contract (sim_bridge.odometry)
    odom_frame: str = field(default="map", metadata=param_meta(
        "frame of the published odometry: 'map' (the true pose, no drift) or another name, "
        "e.g. 'odom' (a real robot's odometry: starts on the map frame, as slam_toolbox's "
        "map starts on odom, and drifts by odom_drift_*; pair with slam_pose and "
        "pose_topic_type 'fused')", read_only=True))
    odom_drift_scale: float = field(default=0.0, metadata=param_meta(
        "odometry distance error: travelled distance x (1 + this) (odom_frame != 'map')",
        range=(-0.5, 0.5)))
    odom_drift_yaw_radps: float = field(default=0.0, metadata=param_meta(
        "odometry heading drift while the robot moves (gyro bias; odom_frame != 'map')",
        "rad/s", range=(-1.0, 1.0)))
    slam_pose: bool = field(default=False, metadata=param_meta(
        "publish the true map-frame pose of scans as geometry_msgs/PoseWithCovarianceStamped "
        "on 'pose' (slam_toolbox's pose: scan rate, after slam_min_travel_m / "
        "slam_min_turn_rad of motion)", read_only=True))
    slam_min_travel_m: float = field(default=0.0, metadata=param_meta(
        "a scan yields a SLAM pose only after this much travel since the last one "
        "(slam_toolbox minimum_travel_distance; 0 with slam_min_turn_rad 0: every scan)", "m",
        range=(0.0, math.inf)))
    slam_min_turn_rad: float = field(default=0.0, metadata=param_meta(
        "... or this much turning (slam_toolbox minimum_travel_heading)", "rad",
        range=(0.0, math.inf)))
    # --- navigation stand-in
    nav_allow_unknown: bool = field(default=NavParams.allow_unknown, metadata=param_meta(
        "plan through unknown space (Nav2 allow_unknown)"))
    nav_inflation_margin_m: float = field(
        default=NavParams.inflation_margin_m, metadata=param_meta(
        "clearance beyond the robot radius every plan keeps", "m", range=(0.0, math.inf)))
    nav_inflation_soft_margin_m: float = field(
        default=NavParams.inflation_soft_margin_m, metadata=param_meta(
        "clearance beyond the lethal zone that plans keep where the room allows (a high "
        "cost, not lethal: narrower doors still pass); 0 = off", "m", range=(0.0, math.inf)))
    nav_inflation_edge_cost: float = field(
        default=NavParams.inflation_edge_cost, metadata=param_meta(
        "extra cost per metre through cells outside the lethal zone from which the robot's "
        "disk would overlap an obstacle cell (paths avoid them where another way exists); "
        "0 = off", range=(0.0, math.inf)))
    nav_inflation_radius_m: float = field(
        default=NavParams.inflation_radius_m, metadata=param_meta(
        "obstacle cost decays to zero at this distance (Nav2 inflation_radius)", "m",
        range=(0.0, math.inf)))
    nav_unknown_cost: float = field(default=NavParams.unknown_cost, metadata=param_meta(
        "extra cost per metre through unknown cells", range=(0.0, math.inf)))
    nav_replan_period_s: float = field(default=NavParams.replan_period_s, metadata=param_meta(
        "replan at most this often while the map changes (Nav2's default behaviour tree "
        "replans at 1 Hz: RateController hz=1.0 around ComputePathToPose); a blocked plan is "
        "replaced at once", "s", range=(0.0, math.inf)))
    nav_controller_rate_hz: float = field(default=NavParams.controller_rate_hz, metadata=param_meta(
        "the path follower computes a new velocity command this often, the command held in "
        "between (Nav2 controller_frequency, 20 Hz in Nav2's and TurtleBot3's params); "
        "physics keeps physics_dt_s; 0 = every physics step", "Hz", range=(0.0, math.inf)))
    nav_plan_downsample: int = field(default=NavParams.plan_downsample, metadata=param_meta(
        "plan on cells this many times coarser than the map", range=(1, 8)))
    nav_arc_check_edges: bool = field(default=NavParams.arc_check_edges, metadata=param_meta(
        "the controller's arc keeps nav_arc_clearance_m beyond the robot radius from the "
        "edges of obstacle cells"))
    nav_arc_clearance_m: float = field(default=NavParams.arc_clearance_m, metadata=param_meta(
        "clearance beyond the robot radius the controller's arc keeps (with "
        "nav_arc_check_edges)", "m", range=(0.0, math.inf)))
    nav_goal_tolerance_xy_m: float = field(
        default=NavParams.goal_tolerance_xy_m,
        metadata=param_meta("goal position tolerance", "m", range=(0.0, math.inf)))
    nav_goal_tolerance_yaw_rad: float = field(
        default=NavParams.goal_tolerance_yaw_rad,
        metadata=param_meta("goal heading tolerance", "rad", range=(0.0, math.inf)))
    nav_progress_timeout_s: float = field(
        default=NavParams.progress_timeout_s, metadata=param_meta(
        "abort a goal without 0.5 m progress for this long (0 = off)", "s", range=(0.0, math.inf)))
    nav_goal_timeout_s: float = field(default=NavParams.goal_timeout_s, metadata=param_meta(
        "abort a goal after this long (0 = off)", "s", range=(0.0, math.inf)))
    nav_collision_retries: int = field(default=NavParams.collision_retries, metadata=param_meta(
        "after a collision and the back-up, replan and go on this many times per goal "
        "before aborting it (0 = abort at the first)", range=(0, 2**31 - 1)))
    # --- node (clock, publishing)
    lockstep: bool = field(default=False, metadata=param_meta(
        "advance lockstep_dt_s of sim time per tick, as fast as ticks come, instead of "
        "real_time_factor x wall time"))
    lockstep_dt_s: float = field(default=0.05, metadata=param_meta(
        "sim time per tick in lock-step mode", "s", range=(0.0, math.inf)))
    tick_period_s: float = field(default=0.02, metadata=param_meta(
        "wall-clock period of the simulation tick", "s", range=(0.0, math.inf), read_only=True))
    max_sim_step_per_tick_s: float = field(default=1.0, metadata=param_meta(
        "cap on sim time advanced in one tick (the sim slows down rather than jump)", "s",
        range=(0.0, math.inf)))
    publish_clock: bool = field(default=True, metadata=param_meta(
        "publish /clock (the sim owns time; other nodes run with use_sim_time)"))
    nav_action: str = field(default="navigate_to_pose", metadata=param_meta(
        "serve the navigation stand-in as this action's status topic (<name>/_action/"
        "status) and cancel service (<name>/_action/cancel_goal), as Nav2's bt_navigator "
        "does for goal_pose; '' = neither", read_only=True))
    costmap_layers: tuple[str, ...] = field(default=("object_costmap",), metadata=param_meta(
        "OccupancyGrid topics whose occupied cells the navigation stand-in avoids"))
    output_dir: str = field(default="out/sim", metadata=param_meta(
        "where sim/save_metrics writes JSON and PNG"))
    metrics_rate_hz: float = field(default=1.0, metadata=param_meta(
        "sim/metrics publish rate (sim time)", "Hz", range=(0.0, math.inf)))
    # --- metrics
    coverage_period_s: float = field(default=1.0, metadata=param_meta(
        "how often coverage is evaluated (sim time)", "s", range=(0.0, math.inf)))
    compute_coverage: bool = field(default=True, metadata=param_meta(
        "rasterise the ground truth and track coverage", read_only=True))
    coverage_observable: bool = field(default=True, metadata=param_meta(
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
                    "coverage_period_s", "lockstep_dt_s", "tick_period_s",
                    "max_sim_step_per_tick_s", "metrics_rate_hz",
                    "collision_backup_speed_mps")
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        non_negative = ("pose_noise_xy_m", "pose_noise_yaw_rad", "collision_backup_m",
                        "map_update_interval_s")
        for name in non_negative:
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        if not self.odom_frame or any(ch.isspace() for ch in self.odom_frame):
            raise ValueError(f"odom_frame must be a frame name, got {self.odom_frame!r}")
        if self.odom_frame.lstrip("/") == "map" and (self.odom_drift_scale
                                                     or self.odom_drift_yaw_radps):
            raise ValueError("odom_drift_scale / odom_drift_yaw_radps need an odom_frame "
                             f"other than 'map' (odometry in the map frame is the true pose), "
                             f"got {self.odom_drift_scale}, {self.odom_drift_yaw_radps}")
        for name in ("odom_drift_scale", "odom_drift_yaw_radps", "slam_min_travel_m",
                     "slam_min_turn_rad"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)}")
        if self.slam_min_travel_m < 0 or self.slam_min_turn_rad < 0:
            raise ValueError(f"slam_min_travel_m and slam_min_turn_rad must be >= 0, got "
                             f"{self.slam_min_travel_m}, {self.slam_min_turn_rad}")
        modes = MAPPING_ERROR_MODES + tuple(PROFILES)
        if self.mapping_error not in modes:
            raise ValueError(f"mapping_error must be one of {modes}, got "
                             f"{self.mapping_error!r}")
        if not self.world:
            raise ValueError("world must name a world or a file, got ''")
        if self.camera_depth_encoding not in DEPTH_ENCODINGS:
            raise ValueError(f"camera_depth_encoding must be one of {DEPTH_ENCODINGS}, got "
                             f"{self.camera_depth_encoding!r}")
        if any(ch.isspace() for ch in self.nav_action):
            raise ValueError(f"nav_action must be an action name or '', got {self.nav_action!r}")
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
        self.slam_error_params()

    def nav_params(self) -> NavParams:
        """The navigation stand-in's parameters."""
        return NavParams(
            robot_radius_m=self.robot_radius_m,
            inflation_margin_m=self.nav_inflation_margin_m,
            inflation_radius_m=self.nav_inflation_radius_m,
            inflation_soft_margin_m=self.nav_inflation_soft_margin_m,
            inflation_edge_cost=self.nav_inflation_edge_cost,
            unknown_cost=self.nav_unknown_cost,
            allow_unknown=self.nav_allow_unknown,
            replan_period_s=self.nav_replan_period_s,
            plan_downsample=self.nav_plan_downsample,
            arc_check_edges=self.nav_arc_check_edges,
            arc_clearance_m=self.nav_arc_clearance_m,
            goal_tolerance_xy_m=self.nav_goal_tolerance_xy_m,
            goal_tolerance_yaw_rad=self.nav_goal_tolerance_yaw_rad,
            max_linear_speed_mps=self.max_linear_speed_mps,
            max_angular_speed_radps=self.max_angular_speed_radps,
            progress_timeout_s=self.nav_progress_timeout_s,
            goal_timeout_s=self.nav_goal_timeout_s,
            collision_retries=self.nav_collision_retries,
            controller_rate_hz=self.nav_controller_rate_hz)

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

    def slam_error_params(self) -> SlamErrorParams | None:
        """The mapping error model's numbers: the profile's, the ``mapping_*`` fields'
        (``custom``), or None (``none``); the keyframes are ``mapping_keyframe_*`` in every
        mode."""
        custom = SlamErrorParams(
            drift_xy_m=self.mapping_drift_xy_m,
            drift_yaw_per_m_rad=self.mapping_drift_yaw_per_m_rad,
            drift_yaw_per_rad=self.mapping_drift_yaw_per_rad,
            jitter_xy_m=self.mapping_jitter_xy_m, jitter_yaw_rad=self.mapping_jitter_yaw_rad,
            keyframe_travel_m=self.mapping_keyframe_travel_m,
            keyframe_turn_rad=self.mapping_keyframe_turn_rad,
            loop_radius_m=self.mapping_loop_radius_m,
            loop_min_travel_m=self.mapping_loop_min_travel_m)   # validated in every mode
        if self.mapping_error == "none":
            return None
        profile = PROFILES.get(self.mapping_error, custom)
        # One keyframe rule for every map: the profile's drift and closures, these keyframes.
        return replace(profile, keyframe_travel_m=self.mapping_keyframe_travel_m,
                       keyframe_turn_rad=self.mapping_keyframe_turn_rad)
