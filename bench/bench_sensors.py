"""Speed of the simulated sensors: lidar scans/s and camera ms/frame (p50/p95).

Run: ``.venv/bin/python bench/bench_sensors.py [--worlds house house_cluttered] [--scans 2000]
[--frames 60]``. Poses are seeded random free poses of each world. Prints, never asserts.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.percentiles import pct_ms  # noqa: E402
from sim_bridge.sensors import CameraParams, DepthCamera, Lidar, LidarParams  # noqa: E402
from sim_bridge.worlds import default_world, ground_truth  # noqa: E402

#: Keep bench poses this far from obstacles below 0.5 m (robot radius-ish).
POSE_CLEARANCE_M = 0.25


def _poses(world, n: int, seed: int) -> list[tuple[float, float, float]]:
    gt = ground_truth(world)
    dist = ndimage.distance_transform_edt(gt.footprint.data < 65) * gt.resolution_m
    rr, cc = np.nonzero(gt.inside & (dist >= POSE_CLEARANCE_M))
    rng = np.random.default_rng(seed)
    pick = rng.integers(0, rr.size, n)
    xs, ys = gt.lidar.cells_to_world(rr[pick], cc[pick])
    return [(float(x), float(y), float(a)) for x, y, a in zip(xs, ys, rng.uniform(-3.2, 3.2, n))]


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--worlds", nargs="+", default=["house", "house_cluttered"])
    ap.add_argument("--scans", type=int, default=2000)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    for name in args.worlds:
        world = default_world(name)
        t0 = time.perf_counter()
        lidar = Lidar(world, LidarParams())
        cam = DepthCamera(world, CameraParams())
        setup = time.perf_counter() - t0
        print(f"== {name}: {len(world.primitives)} primitives, {lidar.num_segments} segments + "
              f"{lidar.num_circles} circles in the scan plane (setup {setup * 1e3:.1f} ms)")
        poses = _poses(world, max(args.scans, args.frames), args.seed)
        per = []
        t0 = time.perf_counter()
        for pose in poses[:args.scans]:
            t1 = time.perf_counter()
            lidar.scan(pose)
            per.append(time.perf_counter() - t1)
        total = time.perf_counter() - t0
        print(f"lidar  {args.scans / total:8.0f} scans/s   {pct_ms(per, decimals=3)}")
        per = []
        for pose in poses[:args.frames]:
            t1 = time.perf_counter()
            cam.render(pose)
            per.append(time.perf_counter() - t1)
        print(f"camera 640x480            {pct_ms(per, decimals=3)}  ({1.0 / np.median(per):.1f} fps)")


if __name__ == "__main__":
    main()
