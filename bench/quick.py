"""``make bench-quick``: a representative subset of the benchmark for iteration, and how
well its ratios predicted the full run.

Runs :mod:`bench.run_bench` on :data:`QUICK_WORLDS` x the subject strategy (``--subject``,
by default the explorer's default strategy, ``routed``), ``nearest`` and ``explore_lite`` x
:data:`QUICK_RUNS` seeds (about 8 minutes of wall time on 2 cores with the full run's
per-run times; no tours, no detector timing, BENCHMARKS.md untouched), then writes
``QUICK.md`` beside its results: per world the time-to-95 % ratios subject /
``explore_lite`` and subject / ``nearest`` of the subset, of the full run in ``--full``
(default ``bench/results/matrix``, the one-version matrix, all its seeds) and of the full run on the subset's seeds only
(equal to the subset's when nothing that affects decisions changed since the full run),
and how far the subset's ratios are from the full run's (mean absolute difference, and in
how many worlds both say the same about the subject being faster). A full run without
rows of the subject gives the subset's ratios only, and says so.

The worlds mix the generated cluttered house, the shipped houses and Explore-Bench rooms,
corridors and loops; the maze and the large generated worlds are left out (one of their
``paper`` runs takes minutes).

Usage::

    .venv/bin/python bench/quick.py [--out out/bench-quick] [--full bench/results/matrix]
        [--subject paper] [--list] [run_bench.py options, e.g. --resume or --jobs 2]

``--list`` (``make bench-quick BENCH_ARGS=--list``) prints the subset's worlds with the
file each one loads and runs nothing.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench import run_bench, store  # noqa: E402
from explore_seg.core.selection.params import SelectionParams  # noqa: E402

QUICK_WORLDS = ("house_cluttered", "shared/house", "shared/house_cluttered", "eb/room_2",
                "eb/corridor", "eb/loop", "eb/corner")
QUICK_RUNS = 4
BASELINES = ("explore_lite", "nearest")
#: The strategy the subset judges unless ``--subject`` says otherwise: the default one.
DEFAULT_SUBJECT = SelectionParams().strategy


def t95_ratios(rows: list[dict[str, str]], seeds: set[int] | None = None,
               subject: str = DEFAULT_SUBJECT) -> dict[tuple[str, str], float]:
    """{(world, baseline): mean time to 95 % of ``subject`` / of the baseline} over the
    rows (of ``seeds`` only when given; runs that never reached 95 % are left out of a
    mean)."""
    acc: dict[tuple[str, str], list[float]] = {}
    for r in rows:
        if seeds is not None and int(r["seed"]) not in seeds:
            continue
        v = float(r["time_to_95_s"]) if r.get("time_to_95_s") not in (None, "", "nan") \
            else math.nan
        if math.isfinite(v):
            acc.setdefault((r["world"], r["strategy"]), []).append(v)
    mean = {k: sum(v) / len(v) for k, v in acc.items()}
    out: dict[tuple[str, str], float] = {}
    for (w, s), t in mean.items():
        if s != subject:
            continue
        for b in BASELINES:
            if (w, b) in mean:
                out[(w, b)] = t / mean[(w, b)]
    return out


def comparison(quick: list[dict[str, str]], full: list[dict[str, str]],
               subject: str = DEFAULT_SUBJECT) -> list[str]:
    """QUICK.md's lines: the ratio table and how well the subset predicted the full run."""
    seeds = {int(r["seed"]) for r in quick}
    q = t95_ratios(quick, subject=subject)
    f, fs = t95_ratios(full, subject=subject), t95_ratios(full, seeds, subject=subject)
    worlds = list(dict.fromkeys(r["world"] for r in quick))
    lines = ["# Quick benchmark against the full run", "",
             f"Time to 95 %: ratio = mean of `{subject}` / mean of the baseline; quick = this "
             f"subset ({len(seeds)} seeds), full = the full run (all its seeds), full@seeds = "
             "the full run on the subset's seeds only (same as quick when nothing that "
             "affects decisions changed).", "",
             "| world | baseline | quick | full | full@seeds | quick - full |",
             "|---|---|---|---|---|---|"]
    diffs: list[float] = []
    agree = 0
    for w in worlds:
        for b in BASELINES:
            k = (w, b)
            cells = [f"{d[k]:.2f}" if k in d else "-" for d in (q, f, fs)]
            delta = "-"
            if k in q and k in f:
                diffs.append(q[k] - f[k])
                agree += (q[k] < 1.0) == (f[k] < 1.0)
                delta = f"{q[k] - f[k]:+.2f}"
            lines.append(f"| {w} | {b} | {' | '.join(cells)} | {delta} |")
    lines.append("")
    if diffs:
        mad = sum(abs(d) for d in diffs) / len(diffs)
        lines.append(f"Prediction of the full run: mean |quick - full| = {mad:.2f} over "
                     f"{len(diffs)} world x baseline ratios (largest {max(map(abs, diffs)):.2f}); "
                     f"both say the same about `{subject}` being faster (ratio < 1) in {agree} "
                     f"of {len(diffs)}.")
    elif not any(r["strategy"] == subject for r in full):
        lines.append(f"The full run has no `{subject}` runs: only the subset's ratios are "
                     "shown (run the full benchmark with it to check the subset's "
                     "predictions).")
    else:
        lines.append("No world of the subset has ratios in both runs.")
    return lines


def main(argv: list[str] | None = None) -> int:
    """Run the subset (see the module docstring), write QUICK.md; run_bench's exit status."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="out/bench-quick")
    ap.add_argument("--full", default=str(ROOT / "bench" / "results" / "matrix"),
                    help="output folder of the full run to compare with (its runs.csv)")
    ap.add_argument("--subject", default=DEFAULT_SUBJECT,
                    help="the strategy judged against the baselines (default: the "
                         "explorer's default strategy)")
    ap.add_argument("--list", action="store_true",
                    help="print the worlds (with the file each loads), strategies and runs "
                         "of the subset, and run nothing")
    a, rest = ap.parse_known_args(argv)
    if a.subject in BASELINES:
        ap.error(f"--subject must not be a baseline ({', '.join(BASELINES)})")
    out = Path(a.out)
    rc = run_bench.main(["--worlds", ",".join(QUICK_WORLDS),
                         "--strategies", ",".join((a.subject,) + BASELINES),
                         "--runs", str(QUICK_RUNS), "--no-tour", "--yolo-frames", "0",
                         "--md", "", "--out", str(out)] + rest + (["--list"] if a.list else []))
    if a.list or rc == 2 and not (out / "runs.csv").is_file():
        return rc
    quick = store.read_csv(out / "runs.csv")
    full = store.read_csv(Path(a.full) / "runs.csv")
    text = "\n".join(comparison(quick, full, a.subject)) + "\n"
    (out / "QUICK.md").write_text(text)
    print(text)
    return rc


if __name__ == "__main__":
    raise SystemExit(main())
