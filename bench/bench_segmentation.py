#!/usr/bin/env python3
"""Benchmark of the DuDe room segmentation: batch time, incremental time, quality.

Prints (never asserts):

1. full decomposition time of a 40 x 40 m map at 0.05 m (a generated house and a maze
   from ``sim_bridge.worlds``), p50/p95 over ``--reps`` runs; target <= 300 ms;
2. incremental update time p50/p95 over a synthetic exploration of the 40 m house: the
   map is revealed by a disc of ``--radius`` m whose centre walks a raster of
   ``--step`` m (nearest-neighbour order from the start), as in the protocol of
   Fermin-Leon et al.'s draft; every map is cropped to the known cells plus a margin,
   so the origin moves by whole cells as with slam_toolbox; target p95 <= 25 ms. The
   final incremental labels are scored against the batch result and the rooms;
   The same two figures on a 20 x 20 m furnished office map
   (``sim_bridge.worlds.furnished``);
3. recall / precision (IPA definition) on ``--houses`` generated 20 m houses, plain and
   cluttered; targets recall >= 90 %, precision >= 95 %;
4. peak memory of one full and one incremental update of a big, mostly unknown map (a
   40 m house, half explored, in a ``--mem-cells`` x ``--mem-cells`` grid at 0.05 m;
   ``--mem-layout tiled``: the grid filled with copies of the house, all known, the
   worst case), each in a fresh subprocess: the segmenter on the known cells' crop (what
   :meth:`IncrementalSegmenter.update` does) and on the whole grid; peak traced
   allocations during the updates (tracemalloc) and the process's peak RSS (ru_maxrss).

Usage::

    python bench/bench_segmentation.py [--reps 5] [--houses 6] [--tau 1.6]
    python bench/bench_segmentation.py --only memory [--mem-cells 5000]
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time
import tracemalloc
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for p in (ROOT, ROOT / "bench"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

from bench.percentiles import pct  # noqa: E402
from eval_segmentation import run_houses  # noqa: E402

from explore_seg.core.grid import GridMap  # noqa: E402
from explore_seg.core.segmentation.eval import evaluate  # noqa: E402
from explore_seg.core.segmentation import (IncrementalSegmenter,  # noqa: E402
                                           SegmentationParams, segment)

#: Unknown cells kept around the known ones when cropping a revealed map.
CROP_MARGIN_CELLS = 10


def exploration_maps(grid: GridMap, start_rc: tuple[int, int], radius_m: float,
                     step_m: float):
    """Maps of a progressive reveal: discs along a nearest-neighbour raster walk."""
    h, w = grid.shape
    res = grid.resolution_m
    free = grid.data == 0
    step = max(1, round(step_m / res))
    rad = round(radius_m / res)
    centres = [(r, c) for r in range(step // 2, h, step) for c in range(step // 2, w, step)
               if free[max(0, r - 5):r + 6, max(0, c - 5):c + 6].any()]
    order, cur = [], start_rc
    while centres:
        d = [(a - cur[0]) ** 2 + (b - cur[1]) ** 2 for a, b in centres]
        cur = centres.pop(int(np.argmin(d)))
        order.append(cur)
    rr, cc = np.mgrid[0:h, 0:w]
    known = np.zeros((h, w), bool)
    for r, c in order:
        known |= (rr - r) ** 2 + (cc - c) ** 2 <= rad * rad
        rows = np.flatnonzero(known.any(axis=1))
        cols = np.flatnonzero(known.any(axis=0))
        r0, r1 = max(0, rows[0] - CROP_MARGIN_CELLS), min(h, rows[-1] + 1 + CROP_MARGIN_CELLS)
        c0, c1 = max(0, cols[0] - CROP_MARGIN_CELLS), min(w, cols[-1] + 1 + CROP_MARGIN_CELLS)
        data = np.where(known, grid.data, -1).astype(np.int8)[r0:r1, c0:c1]
        yield GridMap(data, res, (grid.origin_xy_m[0] + c0 * res,
                                  grid.origin_xy_m[1] + r0 * res)), (r0, c0)


def memory_child(mode: str, cells: int, tau_m: float, layout: str) -> str:
    """One memory measurement (run in a fresh process): ``mode`` ``crop`` or ``whole``.
    Returns the line to print."""
    from sim_bridge.worlds import generate_house, ground_truth

    house = ground_truth(generate_house(3, size_m=(40.0, 40.0))).as_map("lidar")
    h, w = house.shape
    if layout == "tiled":
        reps = (-(-cells // h), -(-cells // w))
        data = np.tile(house.data, reps)[:cells, :cells].copy()
        data2 = data.copy()
        data2[h // 2, : cells // 2] = 100                  # a new wall: an update
    else:
        known = np.zeros(house.shape, bool)
        known[:, : w // 2] = True                          # half explored
        data = np.full((cells, cells), -1, np.int8)
        r0, c0 = (cells - h) // 3, (cells - w) // 3
        data[r0:r0 + h, c0:c0 + w] = np.where(known, house.data, -1)
        data2 = data.copy()
        data2[r0:r0 + h, c0:c0 + w] = np.where(known | (np.arange(w) < w * 0.6),
                                               house.data, -1)
    grid = GridMap(data, house.resolution_m)
    grid2 = GridMap(data2, house.resolution_m)
    seg = IncrementalSegmenter(SegmentationParams(tau_m=tau_m))
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    run = (seg.update if mode == "crop"
           else lambda g: seg._update_grid(g, time.perf_counter()))   # noqa: SLF001
    tracemalloc.start()
    peaks, times = [], []
    for g in (grid, grid2):
        tracemalloc.reset_peak()
        t0 = time.perf_counter()
        run(g)
        times.append(time.perf_counter() - t0)
        peaks.append(tracemalloc.get_traced_memory()[1] / 2**20)
    tracemalloc.stop()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return (f"[memory] {layout} {mode:5s} {cells}x{cells} cells ({cells * cells / 1e6:.0f} M), "
            f"{int((data != -1).sum())} known: traced peak full update {peaks[0]:.0f} MB, "
            f"incremental {peaks[1]:.0f} MB ({seg.last_update_info.mode}); peak RSS "
            f"{rss:.0f} MB ({rss0:.0f} MB before the updates); {times[0] * 1e3:.0f} ms + "
            f"{times[1] * 1e3:.0f} ms")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=5, help="batch repetitions")
    ap.add_argument("--houses", type=int, default=6, help="houses per quality set")
    ap.add_argument("--tau", type=float, default=SegmentationParams().tau_m)
    ap.add_argument("--seed", type=int, default=3, help="seed of the 40 m house and maze")
    ap.add_argument("--radius", type=float, default=5.0, help="reveal disc radius (m)")
    ap.add_argument("--step", type=float, default=2.5, help="reveal raster step (m)")
    ap.add_argument("--only", choices=("memory", "timing"),
                    help="run only this part (timing: parts 1 and 2, no quality sets)")
    ap.add_argument("--seg", action="append", default=[], metavar="NAME=VALUE",
                    help="set a SegmentationParams field (repeatable), e.g. "
                         "--seg furniture_min_thickness_m=0.7")
    ap.add_argument("--mem-cells", type=int, default=5000,
                    help="side of the big map of the memory part (cells)")
    ap.add_argument("--mem-layout", choices=("house", "tiled"), default="house",
                    help="memory part: one half-explored house in unknown space, or the "
                         "grid tiled with known houses")
    ap.add_argument("--memory-child", choices=("crop", "whole"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.memory_child:
        print(memory_child(args.memory_child, args.mem_cells, args.tau, args.mem_layout),
              flush=True)
        return 0
    if args.only == "memory":
        return memory_part(args)

    from sim_bridge.worlds import generate_house, generate_maze, ground_truth

    from bench.eval_segmentation import parse_overrides

    try:
        params = SegmentationParams(**{"tau_m": args.tau, **parse_overrides(args.seg)})
    except (TypeError, ValueError) as err:
        ap.error(f"--seg: {err}")
    print(f"DuDe segmentation benchmark, tau = {args.tau} m{' ' if args.seg else ''}"
          f"{' '.join(args.seg)} (times are wall clock on this machine, including other "
          f"processes' load; process CPU time where given)")

    # 1. batch ------------------------------------------------------------------------
    house = generate_house(args.seed, size_m=(40.0, 40.0))
    gt_house = ground_truth(house)
    house_map = gt_house.as_map("lidar")
    maze = generate_maze(args.seed, size_m=(40.0, 40.0))
    maze_map = ground_truth(maze).as_map("lidar")
    segment(house_map, params)                     # warm-up (imports, OpenCV init)
    for name, grid in (("house 40x40 m", house_map), ("maze 40x40 m", maze_map)):
        times, cpu = [], []
        for _ in range(args.reps):
            t0, c0 = time.perf_counter(), time.process_time()
            labels = segment(grid, params)
            times.append((time.perf_counter() - t0) * 1e3)
            cpu.append((time.process_time() - c0) * 1e3)
        print(f"[batch] {name} ({grid.width}x{grid.height} cells at {grid.resolution_m} m): "
              f"p50 {pct(times, 50):.0f} ms  p95 {pct(times, 95):.0f} ms  "
              f"({len(np.unique(labels[labels > 0]))} regions; target <= 300 ms); process "
              f"CPU p50 {pct(cpu, 50):.0f} ms  p95 {pct(cpu, 95):.0f} ms")

    # 1b./2b. the same on a 20 x 20 m furnished office map at 0.05 m ------------------
    from sim_bridge.worlds.furnished import furnished_map

    fm = furnished_map(args.seed, "office")
    times, cpu = [], []
    for _ in range(args.reps):
        t0, c0 = time.perf_counter(), time.process_time()
        segment(fm.furnished, params)
        times.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)
    print(f"[batch] furnished office {fm.name} ({fm.furnished.width}x{fm.furnished.height} "
          f"cells at {fm.furnished.resolution_m} m): p50 {pct(times, 50):.0f} ms  p95 "
          f"{pct(times, 95):.0f} ms  (target <= 300 ms); process CPU p50 {pct(cpu, 50):.0f} "
          f"ms  p95 {pct(cpu, 95):.0f} ms")
    seg = IncrementalSegmenter(params)
    times, cpu = [], []
    for grid, _off in exploration_maps(fm.furnished, fm.start_cell, args.radius, args.step):
        t0, c0 = time.perf_counter(), time.process_time()
        seg.update(grid)
        times.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.process_time() - c0) * 1e3)
    print(f"[incremental] furnished office {fm.name}, {len(times)} maps: p50 "
          f"{pct(times, 50):.1f} ms  p95 {pct(times, 95):.1f} ms  max {max(times):.0f} ms  "
          f"(target p95 <= 25 ms); process CPU p50 {pct(cpu, 50):.1f} ms  p95 "
          f"{pct(cpu, 95):.1f} ms")

    # 2. incremental -----------------------------------------------------------------
    seg = IncrementalSegmenter(params)
    times, cpu, modes, areas = [], [], Counter(), []
    full_labels = None
    for grid, (r0, c0) in exploration_maps(house_map, gt_house.start_cell, args.radius,
                                          args.step):
        t0, c0_s = time.perf_counter(), time.process_time()
        lab = seg.update(grid)
        times.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.process_time() - c0_s) * 1e3)
        info = seg.last_update_info
        modes[info.mode] += 1
        areas.append(info.work_areas)
        full_labels = np.zeros(house_map.shape, np.int32)
        full_labels[r0:r0 + grid.height, c0:c0 + grid.width] = lab
    inc_times = times
    print(f"[incremental] house 40x40 m, {len(times)} maps (disc {args.radius} m, step "
          f"{args.step} m): p50 {pct(inc_times, 50):.1f} ms  p95 {pct(inc_times, 95):.1f} ms"
          f"  max {max(inc_times):.0f} ms  (target p95 <= 25 ms); process CPU p50 "
          f"{pct(cpu, 50):.1f} ms  p95 {pct(cpu, 95):.1f} ms; modes {dict(modes)}; "
          f"mean work areas {np.mean(areas):.2f}")
    batch = segment(house_map, params)
    e_b = evaluate(full_labels, batch)
    e_g = evaluate(full_labels, house.room_labels)
    e_bg = evaluate(batch, house.room_labels)
    print(f"[incremental] final labels vs batch: recall {e_b['recall'] * 100:.1f} precision "
          f"{e_b['precision'] * 100:.1f}; vs rooms: recall {e_g['recall'] * 100:.1f} "
          f"precision {e_g['precision'] * 100:.1f} (batch vs rooms: recall "
          f"{e_bg['recall'] * 100:.1f} precision {e_bg['precision'] * 100:.1f})")

    if args.only == "timing":
        return 0
    # 3. quality -----------------------------------------------------------------------
    seeds = list(range(args.houses))
    for cluttered in (False, True):
        r = run_houses(seeds, [args.tau], cluttered, 20.0, params, verbose=False)[args.tau]
        kind = "cluttered" if cluttered else "plain"
        print(f"[quality] {len(seeds)} {kind} 20 m houses: recall {r['recall'] * 100:.1f} +- "
              f"{r['recall_std'] * 100:.1f} %  precision {r['precision'] * 100:.1f} +- "
              f"{r['precision_std'] * 100:.1f} %  (targets >= 90 / >= 95); mean batch "
              f"{r['time_ms']:.0f} ms")
        rec, prec = [], []
        for seed in seeds:
            w = generate_house(seed, cluttered=cluttered)
            gt = ground_truth(w)
            grid = gt.as_map("lidar")
            seg = IncrementalSegmenter(params)
            final = np.zeros(grid.shape, np.int32)
            for g, (r0, c0) in exploration_maps(grid, gt.start_cell, args.radius, args.step):
                lab = seg.update(g)
                final[:] = 0
                final[r0:r0 + g.height, c0:c0 + g.width] = lab
            e = evaluate(final, w.room_labels)
            rec.append(e["recall"])
            prec.append(e["precision"])
        print(f"[quality] same houses, final labels of an incremental exploration: recall "
              f"{np.mean(rec) * 100:.1f} +- {np.std(rec) * 100:.1f} %  precision "
              f"{np.mean(prec) * 100:.1f} +- {np.std(prec) * 100:.1f} %")
    return memory_part(args)


def memory_part(args: argparse.Namespace) -> int:
    """4. peak memory, each mode in a fresh subprocess."""
    for mode in ("crop", "whole"):
        out = subprocess.run([sys.executable, __file__, "--memory-child", mode,
                              "--mem-cells", str(args.mem_cells), "--tau", str(args.tau),
                              "--mem-layout", args.mem_layout],
                             capture_output=True, text=True, check=False)
        print(out.stdout.strip() or f"[memory] {mode}: failed (exit {out.returncode}): "
                                    f"{out.stderr.strip()[-300:]}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
