"""BENCHMARKS.md's table of the strategies under a SLAM-like mapping error.

A benchmark folder holds runs of one mapping error profile (``bench/run_bench.py
--mapping-noise PROFILE``, :class:`sim_bridge.engine.SimParams` ``mapping_error``). The
report of the noise-free folder takes the folders of the other profiles
(``bench/report.py OUT --mapping-noise-dir realistic=OUT_R``) and gives, per strategy and
profile, over the worlds both ran: runs and their seeds (a profile's folder may hold fewer
seeds than the noise-free one), complete, runs that ended "done" below
:data:`EARLY_DONE_PCT` (exploration declared finished too early: the failure a noisy map
causes), contacts, median T95, and the median per-seed ratio of T95 to the same
strategy's noise-free run on the same world and seeded start, with its bootstrap
interval.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

from bench.store import seed_ranges

#: A run that ends "done" below this coverage stopped exploring too early.
EARLY_DONE_PCT = 97.0


def parse_dirs(items: list[str]) -> list[tuple[str, Path]]:
    """``PROFILE=DIR`` items -> (profile, folder), in the order given.

    Raises
    ------
    ValueError
        On an item without ``=``, an empty profile, ``none`` (the report's own folder),
        a profile given twice, or a folder that does not exist.
    """
    out: list[tuple[str, Path]] = []
    for item in items:
        profile, sep, folder = item.partition("=")
        profile = profile.strip()
        if not sep or not profile or not folder:
            raise ValueError(f"--mapping-noise-dir expects PROFILE=DIR, got {item!r}")
        if profile == "none":
            raise ValueError("--mapping-noise-dir: 'none' is the report's own folder")
        if profile in {p for p, _ in out}:
            raise ValueError(f"--mapping-noise-dir: profile {profile!r} given twice")
        path = Path(folder)
        if not path.is_dir():
            raise ValueError(f"--mapping-noise-dir {profile}: no folder {folder}")
        out.append((profile, path))
    return out


def early_done(r: dict[str, Any]) -> bool:
    """True when the run ended "done" below :data:`EARLY_DONE_PCT` coverage."""
    return r.get("stop_reason") == "done" and float(r["coverage_pct"]) < EARLY_DONE_PCT


def noise_lines(base: list[dict[str, Any]], profiles: list[tuple[str, list[dict[str, Any]],
                                                                  str]],
                strategies: list[str], t_or_end: Callable[[dict[str, Any], str],
                                                          tuple[float, bool]],
                bootstrap: Callable[[list[float]], tuple[float, float]],
                median_time: Callable[[list[dict[str, Any]], str], str]) -> list[str]:
    """The section's lines: a row per strategy and profile (``none`` = ``base``).

    Parameters
    ----------
    base : list of run records
        The noise-free runs (the report's own).
    profiles : list of (profile, runs, code)
        Each other profile's runs and the code version they ran on.
    strategies : list of str
        Row order; strategies without runs in a profile are left out of it.
    t_or_end, bootstrap, median_time
        The report's time-to-milestone (a run that never got there: its end time and
        True), bootstrap interval and median time cell, so the figures read as the
        report's others.
    """
    ref = {(r["world"], r["strategy"], int(r["seed"])): r for r in base}
    head = ("| strategy | mapping error | worlds | runs | seeds | complete | done < "
            f"{EARLY_DONE_PCT:.0f} % | contacts | median T95 [s] | T95 ÷ no error [95 % CI] |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    rows = [("none", base)] + [(p, rs) for p, rs, _ in profiles]
    for st in strategies:
        for profile, rs in rows:
            mine = [r for r in rs if r["strategy"] == st]
            if not mine:
                continue
            n = len(mine)
            line = (f"| {st} | {profile} | {len({r['world'] for r in mine})} | {n} | "
                    f"{seed_ranges(sorted({int(r['seed']) for r in mine}))} | "
                    f"{sum(1 for r in mine if r['completed'])}/{n} | "
                    f"{sum(1 for r in mine if early_done(r))} | "
                    f"{sum(int(r.get('collisions') or 0) for r in mine)} | "
                    f"{median_time(mine, '95')} |")
            line += " " + _ratio_cell(mine, ref, profile, t_or_end, bootstrap) + " |"
            lines.append(line)
    codes = ", ".join(f"`{p}` on `{c}`" for p, _, c in profiles)
    return lines + ["", f"Code versions: {codes}."] if profiles else lines


def _ratio_cell(mine: list[dict[str, Any]], ref: dict[tuple[str, str, int], dict[str, Any]],
                profile: str, t_or_end: Callable[[dict[str, Any], str], tuple[float, bool]],
                bootstrap: Callable[[list[float]], tuple[float, float]]) -> str:
    """Median per-seed T95 ratio against the noise-free run, its interval, † when a run
    of a pair never reached 95 % (its end time counts), n when fewer pairs than runs."""
    if profile == "none":
        return "1 (reference)"
    ratios, cens = [], False
    for r in mine:
        b = ref.get((r["world"], r["strategy"], int(r["seed"])))
        if b is None:
            continue
        (ta, ca), (tb, cb) = t_or_end(r, "95"), t_or_end(b, "95")
        if tb > 0:
            ratios.append(ta / tb)
            cens = cens or ca or cb
    if not ratios:
        return "-"
    lo, hi = bootstrap(ratios)
    return (f"{np.median(ratios):.2f} [{lo:.2f}, {hi:.2f}]"
            + (f" n={len(ratios)}" if len(ratios) < len(mine) else "") + (" †" if cens else ""))
