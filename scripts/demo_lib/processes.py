"""The demo's child processes: their command lines (simulator, explorer with the
strategy mapped onto its parameters) and a started process with its log."""

from __future__ import annotations

import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

from scripts.demo_lib.config import REAL_ROBOT_SIM, ROOT, DemoConfig
from sim_bridge.engine import SimParams
from sim_bridge.lockstep import LockstepParams, strategy_spec


def sim_command(cfg: DemoConfig) -> list[str]:
    """Command line of the simulator process."""

    spec = strategy_spec(cfg.strategy)
    sp = SimParams()
    w = max(16, int(round(sp.camera_width_px * cfg.camera_scale)))
    h = max(16, int(round(sp.camera_height_px * cfg.camera_scale)))
    params = {
        "world": cfg.world, "seed": cfg.seed, "real_time_factor": float(cfg.real_time_factor),
        "enable_camera": spec.use_objects, "camera_rate_hz": float(cfg.camera_rate_hz),
        "camera_width_px": w, "camera_height_px": h,
        "camera_fx_px": sp.camera_fx_px * w / sp.camera_width_px,
        "camera_fy_px": sp.camera_fy_px * h / sp.camera_height_px,
        "camera_cx_px": (w - 1) / 2.0, "camera_cy_px": (h - 1) / 2.0,
        "output_dir": str(Path(cfg.out_dir) / "sim"),
        **(REAL_ROBOT_SIM if cfg.real_robot_pose else {}),
    }
    cmd = [sys.executable, "-m", "sim_bridge.node", "--ros-args"]
    for k, v in params.items():
        cmd += ["-p", f"{k}:={ros_value(v)}"]
    return cmd + list(cfg.sim_args)


def explorer_command(cfg: DemoConfig) -> list[str]:
    """Command line of the explorer process (strategy mapped onto its parameters)."""
    spec = strategy_spec(cfg.strategy)
    cmd = [sys.executable, "-m", "explore_seg.explorer", "--threads", str(cfg.explorer_threads)]
    if not spec.use_objects:
        cmd += ["--without", "object_costmap"]
    if not spec.use_regions:
        cmd += ["--without", "segmentation"]
    cmd += ["--ros-args"]
    if cfg.params_file:
        cmd += ["--params-file", cfg.params_file]
    params = {"use_sim_time": True, "strategy": spec.selection,
              "use_regions": spec.use_regions, "frontier.use_object_costmap": spec.use_objects,
              "pose_topic_type": "fused" if cfg.real_robot_pose else "odom"}
    if spec.use_objects:
        # The oracle backend as in the lock-step runs (LockstepParams): boxes from the
        # simulator's semantic image with 10 % misses and 2 px corner jitter.
        lp = LockstepParams()
        params.update({"detector.backend": "oracle",
                       "detector.oracle_miss_prob": lp.oracle_miss_prob,
                       "detector.oracle_jitter_px": lp.oracle_jitter_px,
                       "detector.oracle_seed": int(cfg.seed)})
    for k, v in params.items():
        cmd += ["-p", f"{k}:={ros_value(v)}"]
    return cmd + list(cfg.explorer_args)


def ros_value(v: Any) -> str:
    """A parameter value as ``--ros-args -p NAME:=VALUE`` takes it."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


class Child:
    """A started process with its log file; stopped by SIGINT, then SIGTERM, then SIGKILL."""

    def __init__(self, name: str, cmd: list[str], log_path: Path, env: dict[str, str]) -> None:
        self.name = name
        self.log_path = log_path
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log = open(log_path, "w")
        self._log.write("$ " + " ".join(cmd) + "\n")
        self._log.flush()
        self.proc = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT,
                                     cwd=str(ROOT), env=env, start_new_session=True)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def tail(self, n: int = 25) -> str:
        try:
            lines = self.log_path.read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return "\n".join(lines[-n:])

    def stop(self, timeout_s: float = 10.0) -> None:
        for sig, wait in ((signal.SIGINT, timeout_s), (signal.SIGTERM, 5.0),
                          (signal.SIGKILL, 5.0)):
            if self.proc.poll() is not None:
                break
            try:
                self.proc.send_signal(sig)
            except ProcessLookupError:
                break
            try:
                self.proc.wait(wait)
            except subprocess.TimeoutExpired:
                continue
        self._log.close()
