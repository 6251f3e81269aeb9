"""CPU time of the floor-plan prediction per decision, printed (never asserted).

One decision of ``foresight`` predicts the map once and rates every viewpoint candidate
on the prediction. This script takes a world's lidar raster (default the generated 20 x 20
m ``house``), hides what a few scans from the start pose (and random known free cells
next to unknown space) did not see (:func:`bench.predictor_data.partial_maps`' scheme),
and times ``FloorPlanPredictor.predict`` plus ``expected_view_gain`` of ``--candidates``
cells in CPU seconds (``time.process_time``: the load of other processes does not count)
at each torch thread count of ``--threads``.

    nice -n 10 .venv/bin/python bench/bench_predictor.py --world house --threads 1,2
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.predictor_data import POSE_CLEARANCE_M, SCAN_RANGE_M, scan_walk  # noqa: E402
from explore_seg.core.prediction.gain import expected_view_gain  # noqa: E402
from explore_seg.core.prediction.inference import load_predictor  # noqa: E402
from sim_bridge.worlds import ground_truth, load_world  # noqa: E402


def partial_grid(world_spec: str, poses: int, seed: int):
    """The world's lidar raster with only what ``poses`` scans saw."""
    from scipy import ndimage

    gt = ground_truth(load_world(world_spec))
    res = gt.resolution_m
    occ = gt.lidar.data >= 65
    clear = ndimage.distance_transform_edt(~occ) * res >= POSE_CLEARANCE_M
    free, hit = scan_walk(occ, gt.inside, clear, gt.start_cell, poses,
                          np.random.default_rng(seed), SCAN_RANGE_M / res)
    data = np.full(occ.shape, -1, np.int8)
    data[free] = 0
    data[hit] = 100
    return gt.lidar.with_data(data), free


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world", default="house")
    ap.add_argument("--poses", default="3,10,30", help="scan poses of the partial maps")
    ap.add_argument("--candidates", type=int, default=600)
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--weights", default=None, help="weight file (default: the shipped one)")
    args = ap.parse_args(argv)
    print(f"world {args.world}, {args.candidates} candidates, {args.repeats} decisions per "
          f"row; CPU ms per decision (predict + gains)")
    print("threads poses  map_cells   p50_ms  p95_ms  max_ms  predict_p50_ms")
    for threads in (int(t) for t in args.threads.split(",")):
        predictor, why = load_predictor(args.weights, threads=threads)
        if predictor is None:
            print(f"no predictor: {why}")
            return 1
        for poses in (int(p) for p in args.poses.split(",")):
            grid, free = partial_grid(args.world, poses, args.seed)
            rng = np.random.default_rng(args.seed)
            cells = np.argwhere(free)
            cells = cells[rng.integers(len(cells), size=args.candidates)]
            predictor.predict(grid)   # warm-up
            total, pred = [], []
            for _ in range(args.repeats):
                t0 = time.process_time()
                pm = predictor.predict(grid)
                t1 = time.process_time()
                expected_view_gain(pm, cells, 5.0, 24)
                total.append(time.process_time() - t0)
                pred.append(t1 - t0)
            ms = 1000 * np.asarray(total)
            print(f"{threads:7d} {poses:5d} {grid.data.size:10d} {np.median(ms):8.1f} "
                  f"{np.percentile(ms, 95):7.1f} {ms.max():7.1f} "
                  f"{1000 * np.median(pred):15.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
