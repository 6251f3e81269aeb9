"""Benchmark: frontier detection + grouping and target selection on a 40 x 40 m map.

Builds a maze-like 800 x 800 map at 0.05 m (rooms with doors and clutter), keeps as known
only the cells near a random walk (a partially explored map), and times the decision core
(:class:`explore_seg.core.explorer.Explorer`, as the node and the lock step call it) over
``--reps`` robot positions:

* detect+cluster+graph: passable mask, frontier cells, groups, cPoints and the coarse path
  graph (what the first decision after a map update does first);
* distances+selection, first step: one-sweep path lengths to every cPoint + costs + goal
  choice on the new map;
* distances+selection, next step: the same with frontiers and graph of the unchanged map
  reused (what a decision does when only the robot moved).

Prints p50/p95 in milliseconds; asserts nothing. Usage::

    .venv/bin/python bench/bench_frontiers.py [--reps 50] [--seed 0] [--strategy paper]
        [--block-cells 4] [--walk-steps 400]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.percentiles import pct_ms  # noqa: E402
from explore_seg.core.block_graph import BlockGraph  # noqa: E402
from explore_seg.core.explorer import Explorer  # noqa: E402
from explore_seg.core.frontiers import FrontierParams, traversable_mask  # noqa: E402
from explore_seg.core.grid import GridMap  # noqa: E402
from explore_seg.core.paths import disk_kernel  # noqa: E402
from explore_seg.core.selection import SelectionParams  # noqa: E402


def maze_world(size_cells: int, room_cells: int, rng: np.random.Generator) -> np.ndarray:
    """Ground truth (H, W) bool occupancy: a grid of rooms with doors, plus clutter."""
    occ = np.zeros((size_cells, size_cells), dtype=bool)
    wall, door = 2, room_cells // 4
    for k in range(0, size_cells, room_cells):
        occ[k:k + wall, :] = True
        occ[:, k:k + wall] = True
    for i in range(0, size_cells, room_cells):
        for j in range(0, size_cells, room_cells):
            if rng.random() < 0.85:   # door in the room's left wall
                d = i + rng.integers(wall + 1, room_cells - door - 1)
                occ[d:d + door, j:j + wall] = False
            if rng.random() < 0.85:   # door in the room's bottom wall
                d = j + rng.integers(wall + 1, room_cells - door - 1)
                occ[i:i + wall, d:d + door] = False
    occ[:wall, :] = occ[-wall:, :] = True
    occ[:, :wall] = occ[:, -wall:] = True
    for _ in range(size_cells // 2):   # furniture-like boxes
        r, c = rng.integers(0, size_cells - 12, 2)
        occ[r:r + rng.integers(3, 12), c:c + rng.integers(3, 12)] = True
    return occ


def explored_map(occ: np.ndarray, steps: int, sensor_cells: int,
                 rng: np.random.Generator) -> np.ndarray:
    """int8 map known only within ``sensor_cells`` of a random walk through free space."""
    h, w = occ.shape
    seen = np.zeros_like(occ)
    r, c = h // 2, w // 2
    while occ[r, c]:
        c += 1
    for _ in range(steps):
        for _ in range(20):
            dr, dc = rng.integers(-sensor_cells // 2, sensor_cells // 2 + 1, 2)
            nr, nc = int(np.clip(r + dr, 0, h - 1)), int(np.clip(c + dc, 0, w - 1))
            if not occ[nr, nc]:
                r, c = nr, nc
                break
        seen[r, c] = True
    import cv2
    seen = cv2.dilate(seen.astype(np.uint8), disk_kernel(sensor_cells)).astype(bool)
    data = np.full(occ.shape, -1, dtype=np.int8)
    data[seen] = np.where(occ[seen], 100, 0)
    return data


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=50)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--strategy", default="paper")
    ap.add_argument("--block-cells", type=int, default=SelectionParams.path_block_cells)
    ap.add_argument("--walk-steps", type=int, default=400,
                    help="random-walk steps of the explored area (more = larger known area)")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    res = 0.05
    occ = maze_world(800, 80, rng)
    grid = GridMap(explored_map(occ, args.walk_steps, 60, rng), res, (-20.0, -20.0))
    params = SelectionParams(strategy=args.strategy, path_block_cells=args.block_cells)
    fparams = FrontierParams()
    labels = np.zeros(grid.shape, dtype=np.int32)   # rooms as regions, known cells only
    rr, cc = np.indices(grid.shape)
    labels[grid.data == 0] = (1 + (rr // 80) * 10 + cc // 80)[grid.data == 0]

    BlockGraph(np.ones((8, 8), bool), res, params.path_block_cells)   # build lookup tables
    t_det, t_cold, t_warm, n_groups, n_cells = [], [], [], [], []
    passable = traversable_mask(grid, None, fparams)
    free_cells = np.argwhere(passable)
    for _ in range(args.reps):
        robot = tuple(int(v) for v in free_cells[rng.integers(len(free_cells))])
        x, y = grid.cell_to_world(*robot)
        explorer = Explorer(fparams, params)      # a new map: detection + graph + selection
        cold = explorer.step(0.0, grid, (x, y, 0.0), None, labels)
        warm = explorer.step(0.1, grid, (x, y, 0.0), None, labels)   # same map: cached
        t_det.append(cold.detect_s)
        t_cold.append(cold.select_s)
        t_warm.append(warm.select_s)
        n_groups.append(len(cold.frontiers))
        n_cells.append(sum(f.size_cells for f in cold.frontiers))
    known = float((grid.data >= 0).mean())
    print(f"map 800x800 @ {res} m, known {known:.0%}, passable {int(passable.sum())} cells, "
          f"{np.mean(n_groups):.0f} groups / {np.mean(n_cells):.0f} frontier cells, "
          f"block {params.path_block_cells}, "
          f"strategy {params.strategy}, {args.reps} robot positions")
    print(f"detect+cluster+graph {pct_ms(t_det)}   (Explorer.step on a new map)")
    print(f"distances+selection  {pct_ms(t_cold)}   (first step on the map)")
    print(f"distances+selection  {pct_ms(t_warm)}   (next step, frontiers and graph cached)")


if __name__ == "__main__":
    main()
