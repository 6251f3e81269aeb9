"""Speed of the simulator engine (no ROS): real-time factor and per-part timings.

Runs on the generated 20 x 20 m house (``default_world("house")``):

1. lidar + mapping only: a scripted drive (``set_cmd_vel``), no navigation, no camera;
2. lidar + mapping + the navigation stand-in driving to random reachable goals;
3. as 1 with the RGB-D camera at 15 Hz.

Prints the CPU model, the real-time factor of each run (sim seconds per wall second),
and p50/p95 of one lidar scan, one scan integration and one plan. Never asserts.

    .venv/bin/python bench/bench_sim.py [--sim-s 120]
"""

from __future__ import annotations

import argparse
import math
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.percentiles import pct_ms  # noqa: E402
from sim_bridge import worlds  # noqa: E402
from sim_bridge.engine import SimEngine, SimParams  # noqa: E402
from sim_bridge.navigation import NavState  # noqa: E402


def cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=5).stdout
        for line in out.splitlines():
            if line.startswith("Model name"):
                return line.split(":", 1)[1].strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return platform.processor() or "unknown"


class Timed:
    """Wraps a method and records its wall durations."""

    def __init__(self, obj, name: str) -> None:
        self.times: list[float] = []
        fn = getattr(obj, name)

        def wrapper(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.times.append(time.perf_counter() - t)

        setattr(obj, name, wrapper)


def scripted_drive(eng: SimEngine, sim_s: float) -> float:
    """Drive straight, turn when blocked; returns wall seconds."""
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    end = eng.time_s + sim_s
    while eng.time_s < end:
        n = eng.metrics.n_collisions
        eng.set_cmd_vel(0.26, 0.0)
        eng.run_until(lambda e: e.metrics.n_collisions > n, min(8.0, end - eng.time_s))
        eng.set_cmd_vel(0.0, 1.82 * rng.choice([-1.0, 1.0]))
        eng.step(min(rng.uniform(0.5, 1.7), max(0.0, end - eng.time_s)))
    return time.perf_counter() - t0


def goal_drive(eng: SimEngine, sim_s: float) -> tuple[float, int, int]:
    """Send random goals inside the explored map; returns (wall s, reached, aborted)."""
    gt = eng.ground_truth
    rows, cols = np.nonzero(gt.inside)
    xs, ys = gt.lidar.cells_to_world(rows, cols)
    rng = np.random.default_rng(1)
    t0 = time.perf_counter()
    end = eng.time_s + sim_s
    while eng.time_s < end:
        for _ in range(100):
            i = int(rng.integers(xs.size))
            try:
                eng.set_goal(float(xs[i]), float(ys[i]), 0.0)
                break
            except ValueError:
                continue
        eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, end - eng.time_s)
    return time.perf_counter() - t0, eng.metrics.goals_reached, eng.metrics.goals_aborted


def make_engine(world, **kw) -> SimEngine:
    return SimEngine(world, SimParams(**kw), ground_truth=worlds.ground_truth(world))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sim-s", type=float, default=120.0, help="sim seconds per run")
    ap.add_argument("--camera-sim-s", type=float, default=10.0, help="sim seconds with camera")
    args = ap.parse_args()
    world = worlds.default_world("house")
    gt = worlds.ground_truth(world)
    print(f"CPU: {cpu_model()} ({platform.machine()}), python {platform.python_version()}")
    print(f"world: generated house {world.bounds}, {len(world.primitives)} primitives, "
          f"explorable {gt.free_area_m2:.0f} m2")

    eng = make_engine(world)
    scan_t = Timed(eng._lidar, "scan")  # noqa: SLF001 - instrumentation only
    map_t = Timed(eng._mapper, "integrate_scan")  # noqa: SLF001
    wall = scripted_drive(eng, args.sim_s)
    print(f"[lidar+mapping] {eng.time_s:.0f} sim s in {wall:.2f} wall s: "
          f"real-time factor {eng.time_s / wall:.1f}x (target >= 50x); "
          f"coverage {eng.metrics.coverage_pct:.1f} %, map {eng.map.shape}")
    print(f"  lidar scan ({eng.scan_geometry.num_beams} beams): {pct_ms(scan_t.times, count=True)}")
    print(f"  scan integration: {pct_ms(map_t.times, count=True)}")

    eng = make_engine(world)
    plan_t = Timed(eng.navigator, "_plan")  # noqa: SLF001
    wall, reached, aborted = goal_drive(eng, args.sim_s)
    print(f"[lidar+mapping+navigation] {eng.time_s:.0f} sim s in {wall:.2f} wall s: "
          f"real-time factor {eng.time_s / wall:.1f}x; goals reached {reached}, aborted "
          f"{aborted}, collisions {eng.metrics.n_collisions}")
    print(f"  plan (downsample {eng.params.nav_plan_downsample}): {pct_ms(plan_t.times, count=True)}")

    eng = make_engine(world, enable_camera=True)
    cam_t = Timed(eng._camera, "render")  # noqa: SLF001
    wall = scripted_drive(eng, args.camera_sim_s)
    p = eng.params
    print(f"[lidar+mapping+camera {p.camera_width_px}x{p.camera_height_px} @ "
          f"{p.camera_rate_hz:g} Hz] {eng.time_s:.0f} sim s in {wall:.2f} wall s: "
          f"real-time factor {eng.time_s / wall:.1f}x")
    print(f"  camera frame: {pct_ms(cam_t.times, count=True)}")
    if not math.isfinite(eng.metrics.coverage_pct):
        print("  (coverage unavailable)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
