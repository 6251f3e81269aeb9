"""Checks beside the lock-step runs: the real detector's time per frame, and the same
runs through ROS (``scripts/demo.py``) to compare with lock step."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from bench.worlds import ROOT, load, sim_params_for, world_path
from sim_bridge.lockstep import LockstepParams, run_exploration, strategy_spec


def time_yolo(frames: int, world_spec: str = "house_cluttered") -> dict[str, Any]:
    """Time the real detector (auto backend) on frames rendered along the world.

    Returns a dict with the backend, per-frame milliseconds (p50, p95, mean) and the
    frame size, or ``{"error": ...}`` when the model files are missing.
    """
    from explore_seg.core.detector import Detector, DetectorParams
    from sim_bridge.sensors import CameraParams, DepthCamera

    try:
        det = Detector(DetectorParams())
    except (FileNotFoundError, ImportError, ValueError) as err:
        return {"error": f"{type(err).__name__}: {err}"}
    world, gt = load(world_spec)
    cam = DepthCamera(world, CameraParams())
    rng = np.random.default_rng(0)
    free = np.argwhere(gt.inside)
    times, n_dets = [], []
    for k in range(frames + 1):
        r, c = free[rng.integers(len(free))]
        x, y = gt.lidar.cell_to_world(int(r), int(c))
        frame = cam.render((x, y, float(rng.uniform(-math.pi, math.pi))))
        t0 = time.perf_counter()
        dets = det.detect(frame.rgb)
        if k:  # the first call warms up (graph build, allocations)
            times.append((time.perf_counter() - t0) * 1e3)
            n_dets.append(len(dets))
    a = np.asarray(times)
    return {"backend": det.backend_name, "input_size": det.params.input_size,
            "threads": det.params.num_threads, "frames": frames,
            "frame_size": [cam.params.width, cam.params.height],
            "ms_p50": round(float(np.percentile(a, 50)), 1),
            "ms_p95": round(float(np.percentile(a, 95)), 1),
            "ms_mean": round(float(a.mean()), 1),
            "detections_mean": round(float(np.mean(n_dets)), 2)}


def compare_with_ros(world: str, strategy: str, seeds: list[int], out: Path, rtf: float,
                     max_sim_time_s: float, camera_mount: tuple[float, float] | None = None,
                     nav_margin: float | None = None) -> dict[str, Any]:
    """The same world/strategy/seeds in lock step and through ROS (``scripts/demo.py``:
    ``sim_bridge`` + ``explorer`` processes), both stopping at 99 % coverage.

    The lock-step runs use the unperturbed start (the simulator node has no start
    perturbation); sensor noise and message timing still differ, so the two agree in
    distribution, not run for run.
    """
    rows = []
    world_obj, gt = load(world)
    for seed in seeds:
        r = run_exploration(world_obj, strategy, seed,
                            ground_truth=gt, sim_params=sim_params_for(camera_mount, nav_margin),
                            params=LockstepParams(max_sim_time_s=max_sim_time_s,
                                                  start_jitter_m=0.0, start_yaw_jitter_rad=0.0))
        rows.append({"seed": seed, "mode": "lock-step", "stop": r.stop_reason,
                     "coverage_pct": r.coverage_pct, "sim_time_s": r.sim_time_s,
                     "path_length_m": r.path_length_m, "collisions": r.collisions,
                     "goals": r.goals_sent, "objects": r.n_objects,
                     "object_frames": "every frame" if strategy_spec(strategy).use_objects
                     else "-"})
        d = out / f"seed{seed}"
        cmd = [sys.executable, str(ROOT / "scripts" / "demo.py"), str(d), "--world",
               world_path(world), "--strategy", strategy, "--seed", str(seed), "--rtf", str(rtf),
               "--max-sim-time", str(max_sim_time_s), "--stop-coverage", "99"]
        if camera_mount is not None:   # the same mount in the simulator and the node
            z, pitch = camera_mount
            cmd += ["--sim-arg=-p", f"--sim-arg=camera_mount_z_m:={z}",
                    "--sim-arg=-p", f"--sim-arg=camera_pitch_rad:={pitch}",
                    "--explorer-arg=-p", f"--explorer-arg=camera_z_m:={z}",
                    "--explorer-arg=-p", f"--explorer-arg=camera_pitch_rad:={pitch}"]
        if nav_margin is not None:
            cmd += ["--sim-arg=-p", f"--sim-arg=nav_inflation_margin_m:={nav_margin}"]
        proc = subprocess.run(cmd, cwd=str(ROOT), capture_output=True, text=True)
        mj = d / "metrics.json"
        m = json.loads(mj.read_text()) if mj.is_file() else {}
        rows.append({"seed": seed, "mode": "ROS",
                     "stop": m.get("stop_reason") or f"rc={proc.returncode}",
                     "coverage_pct": m.get("coverage_pct"), "sim_time_s": m.get("sim_time_s"),
                     "path_length_m": m.get("path_length_m"),
                     "collisions": m.get("collisions"), "goals": m.get("goals_sent"),
                     "objects": m.get("n_objects"),
                     "object_frames": (f"{m['object_frames_processed']} of "
                                       f"{m['camera_frames_rendered']}"
                                       if m.get("camera_frames_rendered") else "-")})
        print(f"[bench] ROS seed {seed}: {rows[-1]}", file=sys.stderr)
    note = (f"World `{world}`, strategy `{strategy}`, unperturbed start; the ROS runs use "
            f"`sim_bridge` + `explorer` processes at real-time factor {rtf} "
            "(`scripts/demo.py`). Both stop at 99 % coverage. Object frames: camera frames "
            "the object costmap processed, of those rendered.")
    return {"note": note, "rows": rows}
