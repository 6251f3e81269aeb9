"""Check that a code change leaves lock-step results bit-identical, and time it.

``record`` runs every world x strategy x seed once (one process, in order) and writes, per
run, its full :meth:`RunResult.to_dict` without the wall-clock fields (wall time, per-update
timings) plus its wall seconds, process CPU seconds and the 1-minute load average at its
end, to a JSON file. ``compare`` reads two such files (before and after a change) and
reports every run whose results differ (coverage curve, goals, collisions, milestones, ...:
any field) and the wall and CPU seconds per run before/after.

Usage::

    .venv/bin/python bench/same_results.py record before.json \\
        --worlds shared/house_cluttered,eb/room_2,house_cluttered \\
        --strategies paper,nearest,explore_lite --seeds 0,1
    # ... change the code ...
    .venv/bin/python bench/same_results.py record after.json  (same options)
    .venv/bin/python bench/same_results.py compare before.json after.json

``record --set "sim.FIELD=VALUE;..."`` runs with parameters overridden (``bench/paired.py``'s
arm syntax): a new parameter set back to the old behaviour must reproduce the old results.

Exit status of ``compare``: 0 when every run is identical, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
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
           max_sim_time_s: float, overrides: str = "") -> None:
    """Run every world x strategy x seed and write their results (see the module doc).

    The file is rewritten after every run; runs already in it are kept and not run again
    (an interrupted record continues). A run that raises is recorded with its error.
    """
    from bench.tasks import fix_explorer_params, run_task
    from bench.worlds import PAPER_CAMERA_MOUNT, load, sim_time_limit

    explorer = fix_explorer_params()
    run = run_task
    if overrides:
        run = _overridden_run(overrides, explorer)
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
                c0 = time.process_time()
                try:
                    d = run((w, s, seed, limit, None, PAPER_CAMERA_MOUNT, None))
                    result = {k: v for k, v in d.items() if k not in WALL_FIELDS}
                    what = f"{d['coverage_pct']:.2f} % {d['stop_reason']}"
                except Exception as err:    # recorded: a change may fix or cause it
                    result = {"error": f"{type(err).__name__}: {err}"}
                    what = result["error"]
                wall = time.perf_counter() - t0
                cpu = time.process_time() - c0
                runs.append({"key": key, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
                             "load1": round(os.getloadavg()[0], 2), "result": result})
                path.write_text(json.dumps({"runs": runs}, indent=0))
                print(f"{key}: {wall:.1f} s wall, {cpu:.1f} s CPU, {what}", file=sys.stderr,
                      flush=True)


def _overridden_run(overrides: str, explorer: Any) -> Any:
    """A :func:`bench.tasks.run_task` with the parameters of ``overrides`` (paired.py's
    ``KEY=VALUE;...``) changed; rejects an unknown key before any run."""
    import dataclasses

    from bench.paired import build_params, parse_arm
    from bench.worlds import load, sim_params_for
    from sim_bridge.lockstep import LockstepParams, run_exploration

    arm = parse_arm("set:" + overrides)

    def run(task: tuple[Any, ...]) -> dict[str, Any]:
        spec, strategy, seed, max_t, _, mount, nav_margin = task
        ex, sim, ls = build_params(arm, explorer, sim_params_for(mount, nav_margin),
                                   LockstepParams())
        world, gt = load(spec)
        return run_exploration(world, strategy, seed,
                               params=dataclasses.replace(ls, max_sim_time_s=max_t),
                               sim_params=sim, explorer_params=ex,
                               ground_truth=gt).to_dict()

    build_params(arm, explorer, sim_params_for(None), LockstepParams())
    return run


def compare(before: Path, after: Path) -> int:
    """Print per run: identical or the differing fields, wall and CPU s before/after (CPU
    where both files have it); 0 = all same."""
    a = {r["key"]: r for r in json.loads(before.read_text())["runs"]}
    b = {r["key"]: r for r in json.loads(after.read_text())["runs"]}
    bad = 0
    tot = {"wall_s": [0.0, 0.0], "cpu_s": [0.0, 0.0]}
    print(f"{'run':40s} {'wall before':>11s} {'after':>7s} {'x':>6s} {'CPU before':>10s} "
          f"{'after':>7s} {'x':>6s}  results")

    def col(k: str, ra: dict[str, Any], rb: dict[str, Any]) -> str:
        va, vb = ra.get(k), rb.get(k)
        if va is None or vb is None:
            return f"{'-':>11s} {'-':>7s} {'-':>6s}" if k == "wall_s" else \
                f"{'-':>10s} {'-':>7s} {'-':>6s}"
        tot[k][0] += va
        tot[k][1] += vb
        w = 11 if k == "wall_s" else 10
        return f"{va:{w}.1f} {vb:7.1f} {va / max(vb, 1e-9):5.2f}x"

    for key in a:
        if key not in b:
            print(f"{key:40s} missing after")
            bad += 1
            continue
        ra, rb = a[key]["result"], b[key]["result"]
        diff = sorted(k for k in set(ra) | set(rb) if ra.get(k) != rb.get(k))
        bad += bool(diff)
        print(f"{key:40s} {col('wall_s', a[key], b[key])} {col('cpu_s', a[key], b[key])}  "
              + ("identical" if not diff else "DIFFERENT: " + ", ".join(diff)))
    (wa, wb), (ca, cb) = tot["wall_s"], tot["cpu_s"]
    print(f"{'total':40s} {wa:11.1f} {wb:7.1f} {wa / max(wb, 1e-9):5.2f}x {ca:10.1f} {cb:7.1f} "
          f"{ca / max(cb, 1e-9):5.2f}x  {len(a) - bad}/{len(a)} identical")
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
    rec.add_argument("--set", default="", metavar="KEY=VALUE;...",
                     help="parameter overrides (bench/paired.py's arm syntax: sim.FIELD, "
                          "lockstep.FIELD, explorer.SECTION.FIELD)")
    cmp_ = sub.add_parser("compare", help="compare two recorded files")
    cmp_.add_argument("before")
    cmp_.add_argument("after")
    a = ap.parse_args(argv)
    if a.cmd == "compare":
        return compare(Path(a.before), Path(a.after))
    record(Path(a.out), [w for w in a.worlds.split(",") if w],
           [s for s in a.strategies.split(",") if s],
           [int(s) for s in a.seeds.split(",") if s], a.max_sim_time, a.set)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
