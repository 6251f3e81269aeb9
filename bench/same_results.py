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

Each recorded run carries the code version it ran on (:func:`bench.store.code_version`:
the commit, ``+modified`` when the code differs from it). ``compare --certificate FILE``
also writes, when every run is identical and each file ran on one clean commit, a
*certificate* that :mod:`bench.report` reads: benchmark runs of ``before`` that it lists
count as runs of ``after``. It is JSON::

    {"certificate": "same-results", "format": 1,
     "before": "<commit>", "after": "<commit>",
     "runs": {"WORLD/STRATEGY/SEED": {"coverage_pct": ..., "sim_time_s": ...,
                                      "path_length_m": ..., "collisions": ...,
                                      "goals_sent": ..., "stop_reason": ...}, ...}}

The figures of each run (:data:`FINGERPRINT`) let the report check that a benchmark run
it applies the certificate to is the run that was compared, not another run of the same
key (other settings, another seed offset).
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
WALL_FIELDS = ("wall_time_s", "timings_ms", "cpu_time_s")
#: Fields of a run that a certificate lists, and the report compares with the benchmark's.
FINGERPRINT = ("coverage_pct", "sim_time_s", "path_length_m", "collisions", "goals_sent",
               "stop_reason")
CERTIFICATE = "same-results"
CERTIFICATE_FORMAT = 1


def record(path: Path, worlds: list[str], strategies: list[str], seeds: list[int],
           max_sim_time_s: float, overrides: str = "") -> None:
    """Run every world x strategy x seed and write their results (see the module doc).

    The file is rewritten after every run; runs already in it are kept and not run again
    (an interrupted record continues). A run that raises is recorded with its error.
    """
    from bench.store import code_version
    from bench.tasks import fix_explorer_params, run_task
    from bench.worlds import PAPER_CAMERA_MOUNT, load, sim_time_limit

    explorer = fix_explorer_params()
    code = code_version()
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
                runs.append({"key": key, "code": code, **({"set": overrides} if overrides else {}),
                             "wall_s": round(wall, 2), "cpu_s": round(cpu, 2),
                             "load1": round(os.getloadavg()[0], 2), "result": result})
                path.write_text(json.dumps({"runs": runs}, indent=0))
                print(f"{key}: {wall:.1f} s wall, {cpu:.1f} s CPU, {what}", file=sys.stderr,
                      flush=True)


def certificate(a: dict[str, dict[str, Any]], b: dict[str, dict[str, Any]]
                ) -> tuple[dict[str, Any] | None, str]:
    """The certificate of two recorded files' runs (key -> run, see the module
    docstring), or None and why there is none: a run that differs, is missing from
    ``b``, raised, or files that did not each run on one clean commit."""
    if any("set" in r for r in (*a.values(), *b.values())):
        return None, ("runs recorded with --set: a certificate vouches for the benchmark's "
                      "own settings only")
    codes = []
    for name, runs in (("before", a), ("after", b)):
        c = {r.get("code") for r in runs.values()}
        if len(c) != 1 or None in c:
            return None, (f"the {name} file ran on {sorted(map(str, c))}: a certificate "
                          "needs one code version per file (recorded since it exists)")
        code = next(iter(c))
        if code == "unknown" or "+modified" in code:
            return None, (f"the {name} file ran on {code}: a certificate needs committed "
                          "code (commit the change, then record)")
        codes.append(code)
    if codes[0] == codes[1]:
        return None, f"both files ran on {codes[0]}: nothing to certify"
    out: dict[str, Any] = {}
    for key, ra in a.items():
        rb = b.get(key)
        if rb is None or ra["result"] != rb["result"] or "error" in ra["result"]:
            return None, f"{key} is missing, differs or raised"
        out[key] = {k: ra["result"].get(k) for k in FINGERPRINT}
    return {"certificate": CERTIFICATE, "format": CERTIFICATE_FORMAT,
            "before": codes[0], "after": codes[1], "runs": out}, ""


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


def compare(before: Path, after: Path, cert_path: Path | None = None) -> int:
    """Print per run: identical or the differing fields, wall and CPU s before/after (CPU
    where both files have it); 0 = all same. With ``cert_path``, write the certificate
    there when there is one (:func:`certificate`), else say why not (status 1)."""
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
    if cert_path is not None:
        cert, why = certificate(a, b)
        if cert is None:
            print(f"no certificate written: {why}", file=sys.stderr)
            return 1
        cert_path.parent.mkdir(parents=True, exist_ok=True)
        cert_path.write_text(json.dumps(cert, indent=1, sort_keys=True) + "\n")
        print(f"certificate: {len(cert['runs'])} runs of {cert['before']} count as "
              f"{cert['after']} ({cert_path})", file=sys.stderr)
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
    cmp_.add_argument("--certificate", default="", metavar="FILE",
                      help="when every run is identical, write the certificate that lets "
                           "bench/report.py count benchmark runs of the before commit as "
                           "runs of the after commit (e.g. bench/results/certificates/"
                           "BEFORE-AFTER.json)")
    a = ap.parse_args(argv)
    if a.cmd == "compare":
        return compare(Path(a.before), Path(a.after),
                       Path(a.certificate) if a.certificate else None)
    record(Path(a.out), [w for w in a.worlds.split(",") if w],
           [s for s in a.strategies.split(",") if s],
           [int(s) for s in a.seeds.split(",") if s], a.max_sim_time, a.set)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
