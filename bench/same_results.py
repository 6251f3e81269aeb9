"""Check that a code change leaves lock-step results bit-identical, and time it.

``record`` runs every world x strategy x seed once (one process, in order) and writes, per
run, its full :meth:`RunResult.to_dict` without the wall-clock fields (wall time, per-update
timings) plus its wall seconds, to a JSON file. ``compare`` reads two such files (before and
after a change) and reports every run whose results differ (coverage curve, goals,
collisions, milestones, ...: any field) and the wall seconds per run before/after.

Usage::

    .venv/bin/python bench/same_results.py record before.json \\
        --worlds shared/house_cluttered,eb/room_2,house_cluttered \\
        --strategies paper,nearest,explore_lite --seeds 0,1
    # ... change the code ...
    .venv/bin/python bench/same_results.py record after.json  (same options)
    .venv/bin/python bench/same_results.py compare before.json after.json

Exit status of ``compare``: 0 when every run is identical, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

#: Fields of RunResult.to_dict that measure the machine, not the run.
WALL_FIELDS = ("wall_time_s", "timings_ms")


def record(path: Path, worlds: list[str], strategies: list[str], seeds: list[int],
           max_sim_time_s: float) -> None:
    """Run every world x strategy x seed and write their results (see the module doc).

    The file is rewritten after every run; runs already in it are kept and not run again
    (an interrupted record continues). A run that raises is recorded with its error.
    """
    from bench.tasks import fix_explorer_params, run_task
    from bench.worlds import PAPER_CAMERA_MOUNT, load, sim_time_limit

    fix_explorer_params()
    runs: list[dict[str, Any]] = (json.loads(path.read_text())["runs"] if path.is_file()
                                  else [])
    have = {r["key"] for r in runs}
    for w in worlds:
        world, gt = load(w)
        limit = sim_time_limit(float(gt.explorable_area_m2), max_sim_time_s)
        for s in strategies:
            for seed in seeds:
                key = f"{w}/{s}/{seed}"
                if key in have:
                    continue
                t0 = time.perf_counter()
                try:
                    d = run_task((w, s, seed, limit, None, PAPER_CAMERA_MOUNT, None))
                    result = {k: v for k, v in d.items() if k not in WALL_FIELDS}
                    what = f"{d['coverage_pct']:.2f} % {d['stop_reason']}"
                except Exception as err:    # recorded: a change may fix or cause it
                    result = {"error": f"{type(err).__name__}: {err}"}
                    what = result["error"]
                wall = time.perf_counter() - t0
                runs.append({"key": key, "wall_s": round(wall, 2), "result": result})
                path.write_text(json.dumps({"runs": runs}, indent=0))
                print(f"{key}: {wall:.1f} s, {what}", file=sys.stderr, flush=True)


def compare(before: Path, after: Path) -> int:
    """Print per run: identical or the differing fields, wall s before/after; 0 = all same."""
    a = {r["key"]: r for r in json.loads(before.read_text())["runs"]}
    b = {r["key"]: r for r in json.loads(after.read_text())["runs"]}
    bad = 0
    tot_a = tot_b = 0.0
    print(f"{'run':44s} {'before s':>9s} {'after s':>8s} {'speed-up':>8s}  results")
    for key in a:
        if key not in b:
            print(f"{key:44s} missing after")
            bad += 1
            continue
        ra, rb = a[key]["result"], b[key]["result"]
        diff = sorted(k for k in set(ra) | set(rb) if ra.get(k) != rb.get(k))
        bad += bool(diff)
        wa, wb = a[key]["wall_s"], b[key]["wall_s"]
        tot_a += wa
        tot_b += wb
        print(f"{key:44s} {wa:9.1f} {wb:8.1f} {wa / max(wb, 1e-9):7.2f}x  "
              + ("identical" if not diff else "DIFFERENT: " + ", ".join(diff)))
    print(f"{'total':44s} {tot_a:9.1f} {tot_b:8.1f} {tot_a / max(tot_b, 1e-9):7.2f}x  "
          f"{len(a) - bad}/{len(a)} identical")
    return 1 if bad else 0


def main(argv: list[str] | None = None) -> int:
    """Command line (see the module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    rec = sub.add_parser("record", help="run and write the results")
    rec.add_argument("out")
    rec.add_argument("--worlds", default="shared/house_cluttered,eb/room_2,house_cluttered")
    rec.add_argument("--strategies", default="paper,nearest,explore_lite")
    rec.add_argument("--seeds", default="0,1")
    rec.add_argument("--max-sim-time", type=float, default=0.0,
                     help="sim time limit per run in s (0 = the benchmark's)")
    cmp_ = sub.add_parser("compare", help="compare two recorded files")
    cmp_.add_argument("before")
    cmp_.add_argument("after")
    a = ap.parse_args(argv)
    if a.cmd == "compare":
        return compare(Path(a.before), Path(a.after))
    record(Path(a.out), [w for w in a.worlds.split(",") if w],
           [s for s in a.strategies.split(",") if s],
           [int(s) for s in a.seeds.split(",") if s], a.max_sim_time)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
