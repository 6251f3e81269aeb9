"""Settings of a demo run, and how it fails."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from sim_bridge.lockstep import STRATEGY_SPECS

#: The repository (the children's working directory and import path).
ROOT = Path(__file__).resolve().parents[2]
#: Longer side of the animation frames (px).
GIF_SIDE_PX = 480
#: Simulator parameters of DemoConfig.real_robot_pose: 3 % odometry distance error, a
#: 0.01 rad/s gyro bias, SLAM poses after slam_toolbox's default 0.5 m / 0.5 rad of motion.
REAL_ROBOT_SIM = {"odom_frame": "odom", "odom_drift_scale": 0.03, "odom_drift_yaw_radps": 0.01,
                  "slam_pose": True, "slam_min_travel_m": 0.5, "slam_min_turn_rad": 0.5}


@dataclass(frozen=True)
class DemoConfig:
    """Settings of one demo run (see the module docstring)."""

    out_dir: str
    world: str = "house_cluttered"
    strategy: str = "routed"
    seed: int = 0
    real_time_factor: float = 4.0
    max_sim_time_s: float = 1500.0
    wall_timeout_s: float = 900.0
    stall_wall_s: float = 30.0
    stall_sim_s: float = 300.0
    startup_timeout_s: float = 60.0
    progress_period_s: float = 5.0
    frame_period_sim_s: float = 5.0
    gif_max_frames: int = 120
    camera_scale: float = 0.5
    camera_rate_hz: float = 2.0
    explorer: bool = True
    #: Executor threads of the explorer process (its --threads).
    explorer_threads: int = 1
    params_file: str = ""
    stop_coverage_pct: float = 0.0
    #: The real-robot pose contract: the simulator publishes drifting odometry in 'odom'
    #: and slam_toolbox-like 'pose' corrections (REAL_ROBOT_SIM), the explorer and the
    #: monitor fuse them (pose_topic_type 'fused'). False: odometry is the map-frame pose.
    real_robot_pose: bool = True
    sim_args: tuple[str, ...] = field(default_factory=tuple)
    explorer_args: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        if self.strategy not in STRATEGY_SPECS:
            raise ValueError(f"strategy must be one of {tuple(STRATEGY_SPECS)}, "
                             f"got {self.strategy!r}")
        for name in ("real_time_factor", "max_sim_time_s", "wall_timeout_s", "stall_wall_s",
                     "stall_sim_s", "startup_timeout_s", "progress_period_s",
                     "frame_period_sim_s", "camera_scale", "camera_rate_hz"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if self.camera_scale > 1:
            raise ValueError(f"camera_scale must be <= 1, got {self.camera_scale}")
        if self.explorer_threads < 1:
            raise ValueError(f"explorer_threads must be >= 1, got {self.explorer_threads}")
        if self.gif_max_frames < 2:
            raise ValueError(f"gif_max_frames must be >= 2, got {self.gif_max_frames}")


class DemoError(RuntimeError):
    """The demo failed (message says why)."""
