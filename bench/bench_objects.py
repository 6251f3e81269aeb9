#!/usr/bin/env python3
"""Benchmark the object costmap update: p50/p95 milliseconds per 640x480 frame.

Times what the ``object_costmap`` node does per frame after detection: detection boxes ->
3D boxes (crop, SOR, clustering, fit, priors), unclassified objects from laser legs,
fusion into the object map, rasterisation onto a 20 x 20 m map at 0.05 m and the virtual
cloud. Two inputs:

* synthetic: a ray-cast room (table, two chairs, a wall, and an undetected table whose 4
  legs are in the scan) seen by a camera 1 m up, with the boxes of the detected objects;
* real: ``tum_fr3_office`` from the test frames (``test/data/rgbd``) with its
  hand-annotated boxes; no scan.

Prints, never asserts. Target: <= 40 ms per frame.

Usage::

    .venv/bin/python bench/bench_objects.py [--iterations 30] [--warmup 3]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for extra in (ROOT, ROOT / "test"):
    if str(extra) not in sys.path:
        sys.path.insert(0, str(extra))

from explore_seg.core.grid import GridMap  # noqa: E402
from explore_seg.core.objects import (DepthFrame, ObjectMap, ObjectParams,  # noqa: E402
                                      load_priors, process_frame)
# Scene helpers of the object tests (ray caster, leg scan, 2D box projection, real frames).
from objects_scene import (K, Det, box_parts, camera_pose, leg_scan,  # noqa: E402
                           project_box, real_frames, render_depth, table_parts)



def synthetic_case():
    """(frame, detections, scan points) of the synthetic room."""
    pose = camera_pose()
    table = table_parts((2.6, 0.6), 1.4, 0.8, 0.75, 0.2)
    chairs = [box_parts((1.8, -0.2), (0.5, 0.5, 0.9)), box_parts((2.0, 1.5), (0.5, 0.5, 0.9))]
    hidden = table_parts((3.4, -1.2), 1.0, 0.7, 0.72)
    wall = [box_parts((4.2, 0.0), (0.1, 6.0, 2.5))]
    depth = render_depth(table + chairs + hidden + wall, pose)
    dets = [Det("dining table", project_box(table, pose))]
    dets += [Det("chair", project_box([c], pose)) for c in chairs]
    scan = np.vstack([leg_scan([p[0][:2] for p in hidden[1:]]),
                      np.stack([np.full(300, 4.15), np.linspace(-3, 3, 300)], axis=1)])
    return DepthFrame(depth, K, pose), dets, scan


def real_case():
    """(frame, detections, None) of tum_fr3_office with its annotated boxes."""
    names = {"chair": "chair", "desk": "dining table", "table": "dining table"}
    f, frame = next(real_frames(["tum_fr3_office"]))
    return frame, [Det(names[o["class"]], o["bbox_px"]) for o in f["objects"]], None


def bench(name, case, iterations, warmup):
    frame, dets, scan = case
    params = ObjectParams()
    priors = load_priors()
    grid = GridMap(np.zeros((400, 400), np.int8), 0.05, (-10.0, -10.0))
    omap = ObjectMap(params, priors)
    totals, fits = [], []
    n_obj = 0
    for i in range(warmup + iterations):
        t0 = time.perf_counter()
        res = process_frame(frame, dets, priors, params, scan)
        t1 = time.perf_counter()
        omap.update(res.objects + res.unknown, frame)
        layer = omap.rasterize(grid)
        cloud = omap.virtual_cloud()
        t2 = time.perf_counter()
        if i >= warmup:
            totals.append((t2 - t0) * 1e3)
            fits.append((t1 - t0) * 1e3)
        n_obj = len(res.objects) + len(res.unknown)
    p50, p95 = np.percentile(totals, [50, 95])
    f50, f95 = np.percentile(fits, [50, 95])
    print(f"{name:28s} total p50 {p50:6.1f} ms  p95 {p95:6.1f} ms | boxes+unknown p50 "
          f"{f50:6.1f} p95 {f95:6.1f} ms | {n_obj} objects/frame, {len(omap)} in map, "
          f"{int((layer.data == 100).sum())} cells, {len(cloud)} cloud pts")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=30)
    ap.add_argument("--warmup", type=int, default=3)
    args = ap.parse_args(argv)
    print(f"object costmap update per 640x480 frame ({args.iterations} iterations)")
    bench("synthetic (3 det + 1 legs)", synthetic_case(), args.iterations, args.warmup)
    bench("tum_fr3_office (3 boxes)", real_case(), args.iterations, args.warmup)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
