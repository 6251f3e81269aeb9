#!/usr/bin/env python3
"""Benchmark the object costmap in the simulator: coverage of the furniture, false
positives and per-frame cost (the object layer's acceptance figures on the 20 x 20 m houses).

For each world the robot visits the viewpoints of ``test/test_object_layer_sim.py``
(1.5-2.5 m from every chair / desk / table, collision-free, facing it; up to 3 per
object), renders a 640 x 480 RGB-D frame and a scan at each, and runs the node's per-frame
pipeline: oracle detection, ``process_frame`` (with the scan), ``ObjectMap.update``. The
layer is ``ObjectMap.rasterize`` on the ground-truth grid (0.05 m).

Printed per world: per object (name, class, most pixels seen in one frame, footprint
cells = floor projection of all its primitives, covered %), the min / mean coverage over
the seen objects (>= SEEN_MIN_PX pixels), a PASS / FAIL line for the target "every seen
chair / desk >= 90 % covered", the false-positive cells (seen free floor
farther than 0.3 m from any object that the layer covers), and p50 / p95 per frame of the
oracle detection and of process_frame + ObjectMap.update. The column ``union`` is a
diagnostic: the coverage when every fused box is rasterised on its own and the results
are OR-ed (it differs from ``covered`` while ObjectMap.rasterize drops overlaps).

Worlds: ``house_cluttered`` (generated) and ``shared/house_cluttered_plus`` (the package's
``worlds/house_cluttered_plus.world.yaml``) unless ``--world`` names others.
Prints, never asserts.

Usage::

    .venv/bin/python bench/bench_object_layer.py [--world SPEC ...]
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

from bench.percentiles import pct  # noqa: E402
from explore_seg.core.grid import GridMap  # noqa: E402
from explore_seg.core.objects import UNKNOWN_CLASS, ObjectMap  # noqa: E402
from sim_bridge.worlds import ground_truth, load_world  # noqa: E402
# Viewpoints, pipeline run and coverage of the simulator-level acceptance tests.
from test_object_layer_sim import (MIN_COVERAGE, SEEN_MIN_PX, PipelineRun,  # noqa: E402
                                   coverage_report, free_floor_far, object_footprint,
                                   plan_viewpoints, run_pipeline)



def union_layer(run: PipelineRun, grid: GridMap, classes: set[str] | None = None
                ) -> np.ndarray:
    """Cells covered by some fused box, each box rasterised alone, (H, W) bool.

    ``classes`` restricts the boxes to those classes.
    """
    om = run.object_map
    out = np.zeros(grid.shape, dtype=bool)
    for obj in om.objects():
        if classes is not None and obj.cls not in classes:
            continue
        single = ObjectMap(om.params, om.priors)
        single.update([obj])
        out |= single.rasterize(grid).data >= om.params.object_value
    return out


def bench_world(label: str, world) -> None:
    t0 = time.perf_counter()
    gt = ground_truth(world)
    views = plan_viewpoints(world, gt)
    run = run_pipeline(world, gt, views)
    t_run = time.perf_counter() - t0
    t1 = time.perf_counter()
    layer = run.object_map.rasterize(gt.lidar)
    t_raster = (time.perf_counter() - t1) * 1e3
    report = coverage_report(world, gt, run, layer)
    union = union_layer(run, gt.lidar)
    print(f"\n=== {label}: {len(world.objects)} objects, {len(views)} viewpoints, "
          f"{len(run.object_map)} fused boxes "
          f"({sum(o.cls == UNKNOWN_CLASS for o in run.object_map.objects())} unknown); "
          f"{t_run:.1f} s")
    print(f"{'object':<18} {'class':<7} {'seen_px':>8} {'cells':>6} {'covered':>8} {'union':>7}")
    union_cov = {}
    for o in report.objects:
        fp = object_footprint(world, o.name, gt.resolution_m)
        u = union_cov[o.name] = float((union & fp).sum() / max(int(fp.sum()), 1))
        mark = "" if o.seen_px >= SEEN_MIN_PX else "   (not seen)"
        print(f"{o.name:<18} {o.cls:<7} {o.seen_px:>8d} {o.footprint_cells:>6d} "
              f"{100 * o.covered:>7.1f}% {100 * u:>6.1f}%{mark}")
    seen = report.seen()
    cov = [o.covered for o in seen]
    low = sum(c < MIN_COVERAGE for c in cov)
    print(f"seen objects: {len(seen)}; coverage min {100 * min(cov, default=np.nan):.1f}% "
          f"mean {100 * float(np.mean(cov)) if cov else np.nan:.1f}%; "
          f"{low} below {100 * MIN_COVERAGE:.0f}%")
    print(f"false positives: {report.false_positive_cells} of {report.free_far_cells} seen free "
          f"cells far from objects ({100 * report.false_positive_share:.2f}%)")
    verdict = "PASS" if low == 0 else "FAIL"
    print(f"{verdict}: every seen chair/desk >= {100 * MIN_COVERAGE:.0f}% covered "
          f"({len(seen) - low} of {len(seen)})")
    # Diagnostics: every box rasterised alone; which boxes make the false positives.
    far_free = free_floor_far(world, gt, run.seen_floor)
    ucov = [union_cov[o.name] for o in seen]
    print(f"  union (boxes alone): coverage min {100 * min(ucov, default=np.nan):.1f}% mean "
          f"{100 * float(np.mean(ucov)) if ucov else np.nan:.1f}%, "
          f"{sum(c < MIN_COVERAGE for c in ucov)} below {100 * MIN_COVERAGE:.0f}%; false "
          f"positives {int((union & far_free).sum())} "
          f"({100 * (union & far_free).sum() / max(int(far_free.sum()), 1):.2f}%)")
    unknown = union_layer(run, gt.lidar, {UNKNOWN_CLASS})
    classified = union & ~unknown
    print(f"  false-positive cells by source: unknown-class boxes "
          f"{int((unknown & far_free).sum())}, only classified boxes "
          f"{int((classified & far_free).sum())}")
    print(f"per frame (ms): detection (oracle) p50 {pct(run.detect_ms, 50):.1f} "
          f"p95 {pct(run.detect_ms, 95):.1f}; process_frame + update p50 "
          f"{pct(run.update_ms, 50):.1f} p95 {pct(run.update_ms, 95):.1f}; "
          f"rasterize {t_raster:.1f} ms once")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world", action="append", default=None,
                    help="world spec: name, shared/NAME, eb/NAME or *.yaml path (repeatable); "
                         "default: house_cluttered and shared/house_cluttered_plus")
    args = ap.parse_args(argv)
    specs = args.world or ["house_cluttered", "shared/house_cluttered_plus"]
    for spec in specs:
        bench_world(Path(spec).name if spec.endswith((".yaml", ".yml")) else spec,
                    load_world(spec))


if __name__ == "__main__":
    main()
