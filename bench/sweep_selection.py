"""Sweep of the paper cost weights (alpha, beta, gamma) in seeded lock-step runs.

The tool that chooses the defaults of ``SelectionParams`` (the paper does not publish
usable values): every configuration explores the same world from the same seeded starts, and
the script prints, per configuration, time to 95 % / 99 %, path length and how many runs
stopped early, plus the per-seed difference to the first configuration (paired, so the
start-to-start spread cancels). Use seeds disjoint from the benchmark's (``run_bench.py``
uses 0..N-1) so the choice is not tuned on the reported runs.

Usage::

    .venv/bin/python bench/sweep_selection.py --world house_cluttered --strategy paper_noobj \\
        --seeds 100-109 --configs 1:0.01:1,1:0.001:1
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing as mp
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
for _p in (ROOT, ROOT / "bench"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

import numpy as np  # noqa: E402

from run_bench import Progress, load  # noqa: E402
from sim_bridge.lockstep import (STRATEGIES, LockstepParams,  # noqa: E402
                                 load_explorer_params, run_exploration)

Config = tuple[float, float, float]


def _task(args: tuple[str, str, int, Config, float]) -> dict[str, Any]:
    world, strategy, seed, (a, b, g), max_t = args
    w, gt = load(world)
    ep = load_explorer_params()
    ep = replace(ep, selection=replace(ep.selection, alpha=a, beta=b, gamma=g))
    r = run_exploration(w, strategy, seed, explorer_params=ep, ground_truth=gt,
                        params=LockstepParams(max_sim_time_s=max_t))
    return {"config": [a, b, g], "seed": seed, "t95": r.time_to_s.get("95", math.nan),
            "t99": r.time_to_s.get("99", math.nan), "completed": bool(r.completed),
            "stop": r.stop_reason, "coverage": r.coverage_pct, "path": r.path_length_m,
            "wall": r.wall_time_s}


def _seeds(text: str) -> list[int]:
    out: list[int] = []
    for part in text.split(","):
        if "-" in part:
            lo, hi = part.split("-")
            out += list(range(int(lo), int(hi) + 1))
        elif part:
            out.append(int(part))
    return out


def _configs(text: str) -> list[Config]:
    cfgs = []
    for part in text.split(","):
        a, b, g = (float(v) for v in part.split(":"))
        cfgs.append((a, b, g))
    return cfgs


def _fmt(v: list[float]) -> str:
    f = [x for x in v if math.isfinite(x)]
    if not f:
        return "-"
    n = f" ({len(f)})" if len(f) < len(v) else ""
    return f"{np.mean(f):.0f} ± {np.std(f):.0f}{n}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--world", default="house_cluttered")
    ap.add_argument("--strategy", default="paper_noobj", choices=STRATEGIES)
    ap.add_argument("--seeds", default="100-109", help="e.g. 100-109 or 1,5,7")
    ap.add_argument("--configs", default="1:0.01:1,1:0.001:1",
                    help="comma-separated alpha:beta:gamma")
    ap.add_argument("--max-sim-time", type=float, default=2000.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--jsonl", default="", help="also write every run here")
    a = ap.parse_args(argv)
    seeds, cfgs = _seeds(a.seeds), _configs(a.configs)
    tasks = [(a.world, a.strategy, s, c, a.max_sim_time) for c in cfgs for s in seeds]
    rows: list[dict[str, Any]] = []
    bar = Progress(len(tasks), "sweep")
    with mp.Pool(max(1, a.jobs)) as pool:
        for r in pool.imap_unordered(_task, tasks):
            rows.append(r)
            bar.update(f"{r['config']} seed {r['seed']}: {r['stop']} {r['coverage']:.1f} %")
    if a.jsonl:
        Path(a.jsonl).write_text("".join(json.dumps(r) + "\n" for r in rows))
    print(f"world {a.world}, strategy {a.strategy}, seeds {seeds}")
    print("| alpha:beta:gamma | completed | time to 95 % [s] | time to 99 % [s] | path [m] "
          "| paired t95 diff to first [s] |")
    print("|---|---|---|---|---|---|")
    base = {r["seed"]: r["t95"] for r in rows if tuple(r["config"]) == cfgs[0]}
    for c in cfgs:
        rs = sorted((r for r in rows if tuple(r["config"]) == c), key=lambda r: r["seed"])
        diff = [r["t95"] - base[r["seed"]] for r in rs
                if math.isfinite(r["t95"]) and math.isfinite(base.get(r["seed"], math.nan))]
        print(f"| {c[0]:g}:{c[1]:g}:{c[2]:g} | {sum(r['completed'] for r in rs)}/{len(rs)} "
              f"| {_fmt([r['t95'] for r in rs])} | {_fmt([r['t99'] for r in rs])} "
              f"| {_fmt([r['path'] for r in rs])} | {_fmt(diff)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
