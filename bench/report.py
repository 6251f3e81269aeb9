"""Figures and BENCHMARKS.md from the files :mod:`bench.run_bench` writes.

* ``coverage_<world>.png``: coverage vs sim time, mean +- std over the runs of each
  strategy (the paper's Fig. 10). A run that stopped keeps its final coverage.
* ``time_to_95.png``: box plots of the time to 95 % coverage per world and strategy
  (runs that never reached it are counted in the table, not drawn).
* ``BENCHMARKS.md``: the code version and the command, a table per world with a row per
  strategy (:func:`write_all`), the per-module timing table (the paper's Table I) with
  the real detector timed on rendered frames, the lock-step vs ROS comparison when
  present, and links to the figures and to the experiment reports in
  ``OUT/experiments/`` (which it does not include).

A report is of one code version. Every run record carries the commit it ran on
(``code``, :func:`bench.store.code_version`); runs of another commit that a certificate
of :mod:`bench.same_results` (in ``OUT/certificates/`` or ``--certificate``) lists as
identical count as the certificate's ``after`` commit. Runs of several versions are
refused, naming each version and its number of runs, unless ``--allow-mixed``, which
marks every row with its versions.

Usage: ``.venv/bin/python bench/report.py OUT [--md BENCHMARKS.md] [--allow-mixed]
[--certificate FILE] [--mapping-noise-dir PROFILE=DIR]`` (the last adds the table under a
SLAM-like mapping error, :mod:`bench.noise_table`).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench import noise_table, records, same_results, store  # noqa: E402
from bench.figures import plot_coverage, plot_time_to  # noqa: E402
from bench.records import TIMING_ROWS, as_float, by_world_strategy  # noqa: E402
from bench.store import read_csv, slug  # noqa: E402
from bench.worlds import FULL_RUNS, WORLD_RUNS, default_worlds  # noqa: E402
from sim_bridge.strategy_specs import MATRIX_STRATEGIES  # noqa: E402

#: The strategy the ratios are against: the explorer's default.
DEFAULT_STRATEGY = "routed"
#: The code version of a record that names none (runs from before versions were kept).
UNKNOWN = "unknown"
#: Bootstrap resamples and the seed of their generator (the intervals are reproducible).
BOOT_N = 2000
BOOT_SEED = 0
#: Folder of ``out`` with the certificates of bench/same_results.py the report applies.
CERT_DIR = "certificates"
#: Folder of ``out`` with the experiment reports (linked, not included).
EXPERIMENTS = "experiments"


def load_runs(out: Path) -> list[dict[str, Any]]:
    """Every run of ``out`` (:func:`bench.records.read`)."""
    return records.read(out)


# ------------------------------------------------------------------------ tables


def timing_table(runs: list[dict[str, Any]], yolo: dict[str, Any] | None,
                 legacy: dict[str, Any] | None = None) -> list[str]:
    """The paper's Table I, a row per world: per-module p50 / mean / p95 ms over all
    updates of all runs of one strategy (``routed``, else ``paper``, else all).

    Pooled from the runs' timing histograms (:mod:`bench.records`: percentiles within
    half a 1 % bin, means exact). A world none of whose runs has timings left (records
    rebuilt from ``runs.csv``) takes its cells from ``legacy`` (the contents of
    ``timing_legacy.json``: ``worlds``: world -> key -> [p50, mean, p95], pooled when those
    runs' full records still existed, for the table's ``strategy``), marked with †.
    """
    strat = next((s for s in (DEFAULT_STRATEGY, "paper") if any(r["strategy"] == s
                                                               for r in runs)), None)
    sel = [r for r in runs if strat is None or r["strategy"] == strat]
    worlds = list(dict.fromkeys(r["world"] for r in sel))
    # old cells only under the heading of the strategy they were pooled for
    legacy = ((legacy or {}).get("worlds") or {}
              if (legacy or {}).get("strategy", "paper") == (strat or "all") else {})
    marked = partial = False

    def pooled(w: str, key: str) -> tuple[Any, int, int]:
        """(p50, mean, p95) of ``key`` over world ``w``'s runs or None, runs with it, runs."""
        in_w = [r for r in sel if r["world"] == w]
        hists = [h for r in in_w for h in [records.timing_hist(r, key)] if h is not None]
        st = records.hist_stats(records.merge_histograms(hists)) if hists else None
        return st, len(hists), len(in_w)

    has_core = any(pooled(w, "core")[0] is not None for w in worlds)
    real = bool(yolo and "ms_mean" in yolo)
    head = ("| world | " + " | ".join(records.TIMING_COLUMNS[k] for k, _ in TIMING_ROWS)
            + " | total | " + ("decision core | " if has_core else "")
            + ("total, real detector | " if real else ""))
    lines = [f"Strategy `{strat or 'all'}`; each cell p50 / mean / p95 in ms over every "
             "update of every run (frontier, selection and segmentation once per decision, "
             "detection and costmap once per processed camera frame); "
             + "; ".join(f"*{records.TIMING_COLUMNS[k]}* = {label}" for k, label in TIMING_ROWS)
             + "; *total* = sum of the means (oracle detection)"
             + ("; *decision core* = frontier detect + selection of one decision (not added "
                "to the total)" if has_core else "") + ".", "",
             head.rstrip(), "|" + "---|" * (head.count("|") - 1)]
    for w in worlds:
        cells, total = [], 0.0
        for key, _ in TIMING_ROWS:
            st, n_hist, n_runs = pooled(w, key)
            if st is not None:
                part = n_hist < n_runs
                cells.append(f"{st[0]:.1f} / {st[1]:.1f} / {st[2]:.1f}"
                             + (f" ‡{n_hist}/{n_runs}" if part else ""))
                partial |= part
                total += st[1]
            elif not n_hist and key in legacy.get(w, {}):
                p50, mean, p95 = legacy[w][key]
                cells.append(f"{p50:.1f} / {mean:.1f} / {p95:.1f} †")
                total += mean
                marked = True
            else:
                cells.append("-")
        cells.append(f"{total:.1f}")
        if has_core:
            st = pooled(w, "core")[0]
            cells.append(f"{st[0]:.1f} / {st[1]:.1f} / {st[2]:.1f}" if st is not None else "-")
        if real:
            cells.append(f"{total + yolo['ms_mean']:.1f}")
        lines.append(f"| {w} | " + " | ".join(cells) + " |")
    if real:
        lines += ["", f"Real detector (YOLOv3-tiny, {yolo['backend']}, {yolo['input_size']} px, "
                      f"{yolo['threads']} threads) per frame: {yolo['ms_p50']} / "
                      f"{yolo['ms_mean']} / {yolo['ms_p95']} ms (p50 / mean / p95); *total, "
                      "real detector* adds its mean."]
    elif yolo:
        lines += ["", f"Real detector not timed: {yolo.get('error')}"]
    if partial:
        lines += ["", "‡k/n: pooled over the k of the world's n runs whose timings are kept "
                  "(the others' records were rebuilt from `runs.csv`)."]
    if marked:
        lines += ["", "†: pooled over the same runs when their full records (every update's "
                  "time) still existed; only their compact records are kept now "
                  f"(`{records.LEGACY_TIMING}`)."]
    return lines


# ------------------------------------------------------------------ code versions


class MixedVersions(ValueError):
    """The runs of a report ran on more than one code version (and no certificate makes
    them one); the message names each version and its number of runs."""


def run_code(r: dict[str, Any]) -> str:
    """The code version a run record ran on; ``unknown`` for a record without one."""
    return str(r.get("code") or UNKNOWN)


def read_certificates(paths: list[Path]) -> list[dict[str, Any]]:
    """The certificates of :mod:`bench.same_results` in ``paths`` (files, or folders whose
    ``*.json`` are read), checked for their form.

    Raises
    ------
    ValueError
        On a file that is not a same-results certificate of a known format, or one whose
        commits are not clean (the message names the file and what is wrong).
    """
    files: list[Path] = []
    for p in paths:
        files += sorted(p.glob("*.json")) if p.is_dir() else [p]
    certs = []
    for f in files:
        try:
            c = json.loads(f.read_text())
        except (OSError, ValueError) as err:
            raise ValueError(f"certificate {f}: unreadable ({err})") from None
        if not isinstance(c, dict) or c.get("certificate") != same_results.CERTIFICATE:
            raise ValueError(f"certificate {f}: expected a {same_results.CERTIFICATE!r} "
                             f"certificate, got {str(c)[:80]!r}")
        if c.get("format") != same_results.CERTIFICATE_FORMAT:
            raise ValueError(f"certificate {f}: expected format "
                             f"{same_results.CERTIFICATE_FORMAT}, got {c.get('format')!r}")
        for side in ("before", "after"):
            code = c.get(side)
            if not isinstance(code, str) or not code or code == UNKNOWN or "+modified" in code:
                raise ValueError(f"certificate {f}: {side} must be a clean commit, got {code!r}")
        if not isinstance(c.get("runs"), dict) or not c["runs"]:
            raise ValueError(f"certificate {f}: expected a non-empty 'runs' object")
        certs.append(dict(c, file=str(f)))
    return certs


def _same_figures(r: dict[str, Any], listed: dict[str, Any]) -> bool:
    """Whether a run record has the figures a certificate lists for its key."""
    for k in same_results.FINGERPRINT:
        a, b = r.get(k), listed.get(k)
        if isinstance(a, (int, float)) and isinstance(b, (int, float)):
            if not math.isclose(float(a), float(b), rel_tol=0.0, abs_tol=1e-9):
                return False
        elif a != b:
            return False
    return True


def effective_codes(runs: list[dict[str, Any]], certs: list[dict[str, Any]]) -> list[str]:
    """Per run, the code version it counts as: its own, or the ``after`` commit of a
    certificate that lists it (its key, its commit as ``before`` and its figures), followed
    along chains of certificates (A -> B, B -> C: C)."""
    out = []
    for r in runs:
        code = run_code(r)
        key = f"{r['world']}/{r['strategy']}/{int(r['seed'])}"
        seen = {code}
        changed = True
        while changed:
            changed = False
            for c in certs:
                listed = c["runs"].get(key)
                if c["before"] == code and listed is not None and _same_figures(r, listed) \
                        and c["after"] not in seen:
                    code = c["after"]
                    seen.add(code)
                    changed = True
        out.append(code)
    return out


def check_versions(runs: list[dict[str, Any]], codes: list[str], allow_mixed: bool) -> None:
    """Refuse runs of several code versions unless ``allow_mixed``.

    Raises
    ------
    MixedVersions
        Naming every version with its number of runs (and worlds x strategies); runs
        that record no version (``unknown``) are refused too.
    """
    count = Counter(codes)
    if allow_mixed or (len(count) <= 1 and UNKNOWN not in count):
        return
    cells = {c: {(r["world"], r["strategy"]) for r, k in zip(runs, codes) if k == c}
             for c in count}
    detail = "; ".join(f"{c}: {n} runs ({len(cells[c])} world x strategy cells)"
                       for c, n in count.most_common())
    raise MixedVersions(
        f"the runs ran on {len(count)} code version(s) ({detail}); a report is of one "
        "version: rerun the others on one commit (bench/run_bench.py --resume --redo), "
        "certify them with bench/same_results.py compare --certificate, or pass "
        "--allow-mixed to mark every row with its version")


def version_labels(codes: list[str], meta: dict[str, Any]) -> dict[str, str]:
    """Short labels ``v1``, ``v2``, ... of the code versions, in the order of the parts of
    ``meta`` that ran them (versions no part names last, by name)."""
    order = [p.get("code") for p in store.parts_of(meta)]
    known = sorted(set(codes), key=lambda c: (order.index(c) if c in order else len(order), c))
    return {c: f"v{i}" for i, c in enumerate(known, 1)}


# ------------------------------------------------------------------ statistics


def bootstrap_ci(values: list[float], level: float = 0.95, n_boot: int = BOOT_N,
                 seed: int = BOOT_SEED) -> tuple[float, float]:
    """Percentile bootstrap interval of the median of ``values``: the ``(1 - level) / 2``
    and ``(1 + level) / 2`` quantiles (numpy's default, linear) of the medians of
    ``n_boot`` resamples with replacement, drawn from ``numpy.random.default_rng(seed)``,
    so the same values give the same interval.

    Raises
    ------
    ValueError
        On no values or a level outside (0, 1).

    Examples
    --------
    >>> bootstrap_ci([2.0, 2.0, 2.0])
    (2.0, 2.0)
    """
    v = np.asarray(values, dtype=np.float64)
    if v.size == 0:
        raise ValueError("bootstrap_ci needs at least one value, got none")
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level}")
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, v.size, size=(n_boot, v.size))
    med = np.median(v[idx], axis=1)
    lo, hi = np.quantile(med, [(1.0 - level) / 2.0, (1.0 + level) / 2.0])
    return float(lo), float(hi)


def _t(r: dict[str, Any], m: str) -> float:
    """Time to milestone ``m`` of a run, +inf when it never got there."""
    v = as_float((r.get("time_to_s") or {}).get(m))
    return v if math.isfinite(v) else math.inf


def _t_or_end(r: dict[str, Any], m: str) -> tuple[float, bool]:
    """Time to ``m``, or the run's end when it never got there (a lower bound; True)."""
    v = _t(r, m)
    return (v, False) if math.isfinite(v) else (float(r["sim_time_s"]), True)


def paired_ratio(rs: list[dict[str, Any]], ref: list[dict[str, Any]], m: str = "95"
                 ) -> tuple[float, float, float, int, int] | None:
    """Median over the seeds both have of T``m`` / the reference's T``m``, its bootstrap
    interval (:func:`bootstrap_ci`), the number of seeds and of seeds where either run
    never got there (counted with its end time instead); None without a common seed."""
    by_seed = {int(r["seed"]): r for r in ref}
    ratios, cens = [], 0
    for r in rs:
        b = by_seed.get(int(r["seed"]))
        if b is None:
            continue
        ta, ca = _t_or_end(r, m)
        tb, cb = _t_or_end(b, m)
        if tb <= 0:
            continue
        ratios.append(ta / tb)
        cens += ca or cb
    if not ratios:
        return None
    lo, hi = bootstrap_ci(ratios)
    return float(np.median(ratios)), lo, hi, len(ratios), cens


def _median_time(rs: list[dict[str, Any]], m: str) -> str:
    """Median time to ``m`` over all runs, a run that never got there counted as slower
    than any; 'never' when the median is such a run."""
    med = float(np.median([_t(r, m) for r in rs]))
    return f"{med:.0f}" if math.isfinite(med) else "never"


# ------------------------------------------------------------------ the report


def world_table(world: str, g: dict[tuple[str, str], list[dict[str, Any]]],
                strategies: list[str], tour: float | None, codes: dict[int, str] | None,
                labels: dict[str, str]) -> list[str]:
    """One world's table: a row per strategy (see :func:`write_all`), the ratio column
    only when ``strategies`` has the default; ``codes`` (id of a record -> its version)
    adds the version column."""
    with_ref = DEFAULT_STRATEGY in strategies
    head = ("| strategy | runs | complete | contacts / run | T95 median [s] | T99 median [s] |"
            + (f" T95 ÷ `{DEFAULT_STRATEGY}` [95 % CI] |" if with_ref else "")
            + " path / tour |" + (" code |" if codes is not None else ""))
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    ref = g.get((world, DEFAULT_STRATEGY))
    for st in strategies:
        rs = g.get((world, st))
        if not rs:
            continue
        n = len(rs)
        done = sum(1 for r in rs if r["completed"])
        contacts = float(np.mean([int(r.get("collisions") or 0) for r in rs]))
        if st == DEFAULT_STRATEGY:
            ratio = "1 (reference)"
        elif ref is None:
            ratio = "-"
        else:
            pr = paired_ratio(rs, ref)
            ratio = ("-" if pr is None else
                     f"{pr[0]:.2f} [{pr[1]:.2f}, {pr[2]:.2f}]"
                     + (f" n={pr[3]}" if pr[3] < n else "") + (" †" if pr[4] else ""))
        p99 = [as_float((r.get("path_to_m") or {}).get("99")) for r in rs]
        p99 = [p for p in p99 if math.isfinite(p)]
        pt = (f"{np.median(p99) / tour:.2f}" + (f" ({len(p99)})" if len(p99) < n else "")
              if tour and p99 else "-")
        row = (f"| {st} | {n} | {done}/{n} | {contacts:.2f} | {_median_time(rs, '95')} | "
               f"{_median_time(rs, '99')} |" + (f" {ratio} |" if with_ref else "")
               + f" {pt} |")
        if codes is not None:
            cnt = Counter(codes[id(r)] for r in rs)
            order = sorted(cnt, key=lambda c: int(labels[c][1:]))
            row += " " + ", ".join(labels[c] + (f"×{cnt[c]}" if len(cnt) > 1 else "")
                                   for c in order) + " |"
        lines.append(row)
    return lines


def summary_table(g: dict[tuple[str, str], list[dict[str, Any]]], strategies: list[str],
                  codes: dict[int, str] | None, labels: dict[str, str]) -> list[str]:
    """A row per strategy over all worlds: runs, complete, contacts (total and per run),
    the median per-seed T95 ratio against the default over every world with its
    bootstrap interval (``codes``: the version column, as in :func:`world_table`)."""
    with_ref = DEFAULT_STRATEGY in strategies
    head = ("| strategy | worlds | runs | complete | contacts (per run) |"
            + (f" T95 ÷ `{DEFAULT_STRATEGY}` [95 % CI] |" if with_ref else "")
            + (" code |" if codes is not None else ""))
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for st in strategies:
        cells = {w: rs for (w, s), rs in g.items() if s == st}
        rs = [r for v in cells.values() for r in v]
        n = len(rs)
        contacts = sum(int(r.get("collisions") or 0) for r in rs)
        row = (f"| {st} | {len(cells)} | {n} | {sum(1 for r in rs if r['completed'])}/{n} | "
               f"{contacts} ({contacts / max(n, 1):.2f}) |")
        if with_ref:
            if st == DEFAULT_STRATEGY:
                row += " 1 (reference) |"
            else:
                ratios, cens = [], 0
                for w, v in cells.items():
                    ref = g.get((w, DEFAULT_STRATEGY))
                    by_seed = {int(r["seed"]): r for r in ref or []}
                    for r in v:
                        b = by_seed.get(int(r["seed"]))
                        if b is None:
                            continue
                        (ta, ca), (tb, cb) = _t_or_end(r, "95"), _t_or_end(b, "95")
                        if tb > 0:
                            ratios.append(ta / tb)
                            cens += ca or cb
                if ratios:
                    lo, hi = bootstrap_ci(ratios)
                    row += (f" {np.median(ratios):.2f} [{lo:.2f}, {hi:.2f}]"
                            + (f" n={len(ratios)}" if len(ratios) < n else "")
                            + (" †" if cens else "") + " |")
                else:
                    row += " - |"
        if codes is not None:
            cnt = Counter(codes[id(r)] for r in rs)
            order = sorted(cnt, key=lambda c: int(labels[c][1:]))
            row += (f" {labels[order[0]]}" if len(order) == 1 else
                    f" {len(order)} versions, {labels[order[0]]}–{labels[order[-1]]}") + " |"
        lines.append(row)
    return lines


def write_all(out: Path, md: Path | None, command: str | None, allow_mixed: bool = False,
              certificates: list[Path] | None = None,
              noise_dirs: list[tuple[str, Path]] | None = None) -> Path | None:
    """Figures in ``out`` and, when ``md`` is given, the report there.

    The report is of one code version: runs of several (after the certificates in
    ``out/certificates/`` and ``certificates``) are refused (:class:`MixedVersions`)
    unless ``allow_mixed``, which marks every row with its versions instead. Per world a
    table with a row per strategy: runs, complete (coverage >= 99 %), contacts per run,
    median T95 and T99, the median per-seed T95 ratio against ``routed`` with its 95 %
    bootstrap interval, and the median path to 99 % over the world's coverage tour.
    ``noise_dirs`` (profile, folder) adds the table under mapping error
    (:mod:`bench.noise_table`); each folder is held to the same one-version rule.
    """
    runs = load_runs(out)
    meta_path = out / "meta.json"
    meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    cert_paths = ([out / CERT_DIR] if (out / CERT_DIR).is_dir() else []) + list(certificates or [])
    certs = read_certificates(cert_paths)
    codes = effective_codes(runs, certs)
    check_versions(runs, codes, allow_mixed)
    w_order = {w: i for i, w in enumerate(meta.get("worlds", []))}
    s_order = {st: i for i, st in enumerate(meta.get("strategies", []))}
    order = sorted(range(len(runs)), key=lambda i: (
        w_order.get(runs[i]["world"], len(w_order)), runs[i]["world"],
        s_order.get(runs[i]["strategy"], len(s_order)), runs[i]["strategy"], runs[i]["seed"]))
    runs, codes = [runs[i] for i in order], [codes[i] for i in order]
    noise = [_noise_profile(p, d, certs, allow_mixed) for p, d in noise_dirs or []]
    plot_coverage(runs, out)
    plot_time_to(runs, out)
    if md is None:
        return None
    md.write_text("\n".join(report_lines(out, md, runs, codes, meta, certs, command, noise))
                  + "\n")
    return md


def _noise_profile(profile: str, folder: Path, certs: list[dict[str, Any]],
                   allow_mixed: bool) -> tuple[str, list[dict[str, Any]], str]:
    """(profile, runs, code version) of a mapping-error folder; its runs must be of one
    version unless ``allow_mixed`` (then the versions are listed)."""
    runs = load_runs(folder)
    if not runs:
        raise ValueError(f"--mapping-noise-dir {profile}: no runs in {folder}")
    own = read_certificates([folder / CERT_DIR]) if (folder / CERT_DIR).is_dir() else []
    codes = effective_codes(runs, certs + own)
    check_versions(runs, codes, allow_mixed)
    return profile, runs, ", ".join(sorted(set(codes)))


#: run_bench.py options of one part, left out of the command that reruns a matrix: with
#: their argument, and flags.
_PART_OPTIONS = ("--merge", "--redo")
_PART_FLAGS = ("--no-runs", "--prune")


def rerun_command(command: str, out: Path) -> str:
    """The command that reruns or continues the matrix of ``out``: ``command`` (a part's)
    with ``--out`` the folder (relative to the repository when inside it) and without the
    options of one part (``--merge DIR``, ``--redo X``, ``--no-runs``, ``--prune``)."""
    try:
        args = shlex.split(command)
    except ValueError:
        return command
    folder = out.resolve()
    folder_s = (folder.relative_to(ROOT).as_posix() if folder.is_relative_to(ROOT)
                else str(out))
    res: list[str] = []
    i = 0
    while i < len(args):
        a = args[i]
        name = a.split("=", 1)[0]
        if name in _PART_OPTIONS or name in _PART_FLAGS:
            i += 2 if a in _PART_OPTIONS else 1
            continue
        if name == "--out":
            res.append("--out")
            res.append(folder_s)
            i += 2 if a == "--out" else 1
            continue
        res.append(a)
        i += 1
    return " ".join(shlex.quote(a) for a in res)


def experiments_dir(out: Path) -> Path:
    """The experiment reports' folder of a bench folder: its own ``experiments/``, else
    its parent's (``bench/results/experiments`` for ``bench/results/matrix``), else its
    own (absent)."""
    for d in (out / EXPERIMENTS, out.parent / EXPERIMENTS):
        if d.is_dir():
            return d
    return out / EXPERIMENTS


def report_lines(out: Path, md: Path, runs: list[dict[str, Any]], codes: list[str],
                 meta: dict[str, Any], certs: list[dict[str, Any]],
                 command: str | None,
                 noise: list[tuple[str, list[dict[str, Any]], str]] | None = None
                 ) -> list[str]:
    """The lines of BENCHMARKS.md (see :func:`write_all`)."""
    rel = Path(os.path.relpath(out, md.parent))
    exp_dir = experiments_dir(out)
    exp_rel = Path(os.path.relpath(exp_dir, md.parent)).as_posix()
    docs = Path(os.path.relpath(ROOT / "docs", md.parent)).as_posix()
    cmd = rerun_command(command or meta.get("command", "bench/run_bench.py"), out)
    tours_rows = read_csv(out / "tours.csv")
    tours = {r["world"]: float(r["tour_m"]) for r in tours_rows}
    area = {r["world"]: r.get("explorable_area_m2") for r in tours_rows}
    yolo_path = out / "yolo.json"
    yolo = json.loads(yolo_path.read_text()) if yolo_path.is_file() else None
    count = Counter(codes)
    mixed = len(count) > 1
    labels = version_labels(codes, meta)
    g = by_world_strategy(runs)
    worlds = list(dict.fromkeys(r["world"] for r in runs))
    strategies = list(dict.fromkeys(r["strategy"] for r in runs))
    strategies.sort(key=lambda st: st != DEFAULT_STRATEGY)     # the reference row first
    parts = store.parts_of(meta)
    cpu = [float(r["cpu_time_s"]) for r in runs if r.get("cpu_time_s") is not None]
    L = ["# Benchmarks", "",
         "Generated by `bench/report.py` (`make bench` runs it at the end); do not edit by "
         "hand. How to run it, in parts, and how long it takes: "
         f"[docs/benchmarking.md]({docs}/benchmarking.md).", ""]
    if not mixed:
        L += [f"**Code version: `{codes[0] if codes else '-'}`** (every run"
              + (f"; {sum(1 for r, c in zip(runs, codes) if run_code(r) != c)} of them "
                 "certified identical by `bench/same_results.py`" if certs else "") + ")."
              + (" `+modified`: the runs ran on uncommitted changes to that commit, so the "
                 "commit alone does not reproduce them." if codes and "+modified" in codes[0]
                 else ""), ""]
    else:
        L += [f"**Mixed code versions: {len(count)}.** These runs were not made on one "
              "commit; every row names its versions (×n: runs on that version). Figures of "
              "different versions are not comparable as they stand: the one-version run "
              "replaces this file.", "",
              "| label | code | runs | first part started |", "|---|---|---|---|"]
        for c, lab in labels.items():
            first = next((p.get("started") for p in parts if p.get("code") == c), "-")
            L.append(f"| {lab} | `{c}` | {count[c]} | {first} |")
        L.append("")
    L += ["Command (reruns the matrix, or continues it; every part's own command, commit and "
          "wall time are in "
          f"[meta.json]({(rel / 'meta.json').as_posix()})):", "", "```sh",
          f".venv/bin/python {cmd}", "```", ""]
    wall = meta.get("wall_s")
    cpu_parts = [float(p["cpu_s"]) for p in parts if p.get("cpu_s") is not None]
    L += [f"{len(runs)} runs of {len(worlds)} worlds × {len(strategies)} strategies in "
          f"{len(parts)} part(s); {wall if wall is not None else '?'} s wall in all"
          + (f", {sum(cpu_parts):.0f} CPU s" + (f" ({len(parts) - len(cpu_parts)} parts "
             "recorded without it)" if len(cpu_parts) < len(parts) else "")
             if cpu_parts else "")
          + (f", {sum(cpu):.0f} CPU s in the runs" + (f" ({len(runs) - len(cpu)} runs "
             "recorded without a CPU figure)" if len(cpu) < len(runs) else "")
             if cpu else "") + ".", ""]
    L += full_matrix_lines(runs)
    L += parts_lines(parts)
    L += setup_lines(meta, runs)
    missing = [s for s in MATRIX_STRATEGIES if s not in strategies]
    if DEFAULT_STRATEGY not in strategies:
        L += [f"**`{DEFAULT_STRATEGY}`, the default strategy, has no runs in these results**, "
              "so no ratio against it is given; its figures so far are paired comparisons "
              f"on other code versions, in [{exp_rel}/]({exp_rel}/).", ""]
    elif missing:
        L += ["Strategies without runs here: " + ", ".join(f"`{s}`" for s in missing) + ".", ""]
    L += ["How to read the tables: *complete* = runs that reached 99 % of the explorable "
          "area; *contacts / run* = mean contacts of the robot's disk with walls or objects "
          "(by cause: `bench/causes.py`); *T95*, *T99* = sim seconds to 95 % / 99 % "
          "(median over all runs, a run that never got there counted as the slowest; "
          "*never* when that is the median); "
          + (f"*T95 ÷ `{DEFAULT_STRATEGY}`* = median over seeds of the per-seed ratio of T95 "
             f"to `{DEFAULT_STRATEGY}`'s on the same seeded start, with its 95 % percentile "
             f"bootstrap interval ({BOOT_N} resamples of the seeds, seed {BOOT_SEED}; below 1: "
             f"faster than `{DEFAULT_STRATEGY}`; † = on some seed a run never reached 95 % and "
             "counts with its end time, a lower bound of its T95; n = seeds both ran when "
             "fewer than the runs); " if DEFAULT_STRATEGY in strategies else "")
          + "*path / tour* = median path "
          "to 99 % over the world's full-knowledge coverage tour ("
          + (f"[tours.csv]({(rel / 'tours.csv').as_posix()})" if tours_rows
             else "none computed here: `-`") + "; in brackets the runs that reached 99 % when "
          "not all did). Setup: lock-step runs of the explorer's core on the simulator, "
          "seeded starts, the robot a 0.22 m disk ([docs/benchmarking.md]"
          f"({docs}/benchmarking.md#method)).", ""]
    cov_names = {p.name for p in cov_paths(out)}
    id_codes = {id(r): c for r, c in zip(runs, codes)} if mixed else None
    L += ["## Summary", "", f"Over all {len(worlds)} worlds"
          + ("; the ratio pools the per-seed ratios of every world (interval: resampling "
             "world-seed pairs)" if DEFAULT_STRATEGY in strategies else "") + ".", ""]
    L += summary_table(g, strategies, id_codes, labels) + [""]
    if noise:
        L += ["## Under mapping error", "",
              "The same strategies on a SLAM-like map (`--mapping-noise`: drift, jitter, "
              "loop-closure re-renders; [docs/simulation.md]"
              f"({docs}/simulation.md#mapping-error-a-slam-like-map)). *done < "
              f"{noise_table.EARLY_DONE_PCT:.0f} %* = runs that declared exploration finished "
              "below that coverage; *T95 ÷ no error* = median over the seeds of the per-seed "
              "ratio of T95 to the same strategy's run without mapping error (same world, "
              "same seeded start), 95 % bootstrap interval, † and n as above.", ""]
        L += noise_table.noise_lines(runs, noise, strategies, _t_or_end, bootstrap_ci,
                                        _median_time) + [""]
    L += ["## Results per world", ""]
    for w in worlds:
        a = area.get(w)
        L += [f"### {w}" + (f" ({float(a):.0f} m², tour {tours[w]:.0f} m)" if a and w in tours
                            else ""), ""]
        L += world_table(w, g, strategies, tours.get(w), id_codes, labels)
        name = f"coverage_{slug(w)}.png"
        if name in cov_names:
            L += ["", f"Coverage vs time: [{name}]({(rel / name).as_posix()})"]
        L.append("")
    legacy_path = out / records.LEGACY_TIMING
    legacy = json.loads(legacy_path.read_text()) if legacy_path.is_file() else None
    L += (["## Per-module timing (the paper's Table I)", ""]
          + timing_table(runs, yolo, legacy) + [""])
    ros_path = out / "ros.json"
    if ros_path.is_file():
        ros = json.loads(ros_path.read_text())
        L += ["## Lock-step vs ROS", "", ros.get("note", "") + " "
              + (f"Code `{ros['code']}`." if ros.get("code") else "Code version not recorded."),
              "",
              "| seed | mode | stop | coverage [%] | sim time [s] | path [m] | collisions | "
              "goals | objects | object frames |", "|---|---|---|---|---|---|---|---|---|---|"]
        for row in ros.get("rows", []):
            L.append(f"| {row['seed']} | {row['mode']} | {row['stop']} | "
                     f"{_fmt(row.get('coverage_pct'))} | {_fmt(row.get('sim_time_s'))} | "
                     f"{_fmt(row.get('path_length_m'))} | {_count(row.get('collisions', '-'))} | "
                     f"{row.get('goals', '-')} | {row.get('objects', '-')} | "
                     f"{row.get('object_frames', '-')} |")
        L.append("")
    earlier = sorted(exp_dir.glob("benchmarks_*.md"))
    L += ["## Experiments", "",
          "Paired comparisons of settings (`bench/paired.py`) and other experiment reports "
          + (f"are files in [{exp_rel}/]({exp_rel}/), each with its command and code version; "
             if exp_dir.is_dir() else "are not in this folder; ")
          + f"what each decided: [docs/experiments.md]({docs}/experiments.md). They are not "
          "part of the tables above."
          + ("" if not earlier else " Earlier benchmark reports: " + ", ".join(
              f"[{p.stem}]({exp_rel}/{p.name})" for p in earlier) + "."), "",
          f"Files in `{rel.as_posix()}/`: `runs.jsonl.gz` (every run's record: what `--resume` "
          "and this report read), `runs.csv`, `tours.csv`, `meta.json`, the figures"
          + (f"; certificates in `{CERT_DIR}/`" if certs else "") + "."]
    return L


def full_matrix_lines(runs: list[dict[str, Any]]) -> list[str]:
    """What the full matrix (``make bench``: every strategy of ``MATRIX_STRATEGIES`` x
    :func:`bench.worlds.default_worlds` x ``FULL_RUNS`` seeds from 0, ``WORLD_RUNS`` in the
    long worlds) holds that ``runs`` do not: one paragraph naming the worlds without runs
    and, per group of worlds, the seeds some strategy has not run; [] when nothing is
    missing."""
    have = {(r["world"], r["strategy"], int(r["seed"])) for r in runs}
    full = {(w, st, k) for w in default_worlds() for st in MATRIX_STRATEGIES
            for k in range(min(FULL_RUNS, WORLD_RUNS.get(w, FULL_RUNS)))}
    lacking = full - have
    if not lacking:
        return []
    worlds = {w for w, _, _ in have}
    absent = [w for w in default_worlds() if w not in worlds]
    by_seeds: dict[str, list[str]] = {}
    for w in default_worlds():
        if w in worlds:
            seeds = sorted({k for lw, _, k in lacking if lw == w})
            if seeds:
                by_seeds.setdefault(store.seed_ranges(seeds), []).append(w)
    what = ([f"worlds without runs: {', '.join(f'`{w}`' for w in absent)}"] if absent else [])
    what += [f"seeds {seeds} in {len(ws)} world{'s' if len(ws) > 1 else ''}"
             + (f" ({', '.join(f'`{w}`' for w in ws)})" if len(ws) <= 3 else "")
             for seeds, ws in by_seeds.items()]
    n_full = len(full)
    return [f"**Part of the full matrix: {len(full & have)} of its {n_full} runs** "
            f"({len(MATRIX_STRATEGIES)} strategies × {len(default_worlds())} worlds × "
            f"{FULL_RUNS} seeds, "
            + ", ".join(f"{n} in `{w}`" for w, n in WORLD_RUNS.items())
            + "; `--resume` on this folder continues it). Not run yet: " + "; ".join(what) + ".", ""]


def parts_lines(parts: list[dict[str, Any]]) -> list[str]:
    """One line per part when the runs were made in several (commands that continued
    with ``--resume`` or added another folder's runs with ``--merge``); [] for one."""
    if len(parts) < 2:
        return []
    L = [f"Run in {len(parts)} parts, each later one with `--resume` (runs already in the "
         "folder that the command asks for are kept, the rest are run):", ""]
    for i, part in enumerate(parts, 1):
        ran = part.get("runs_run")
        L.append(f"{i}. {part.get('started', '?')}, code `{part.get('code') or UNKNOWN}`, "
                 + (f"{ran} runs, " if ran is not None else "")
                 + f"{part.get('wall_s', '?')} s wall"
                 + (" (interrupted)" if part.get("interrupted") else "")
                 + (f" ({len(part['failed'])} runs failed: "
                    + "; ".join(f"`{f}`" for f in part["failed"]) + ")"
                    if part.get("failed") else "")
                 + (f" (run in `{part['merged_from']}`, added with `--merge`)"
                    if part.get("merged_from") else ""))
    return L + [""]


def setup_lines(meta: dict[str, Any], runs: list[dict[str, Any]]) -> list[str]:
    """The settings the runs were made with (those :func:`bench.store.same_settings`
    compares), as one paragraph."""
    settings = {**store.SETTING_DEFAULTS, **(meta.get("settings") or {})}
    mount = meta.get("camera_mount")
    margin = float(settings.get("nav_inflation_margin_m") or 0.0)
    limit = float(settings.get("max_sim_time") or 0.0)
    n_csv = sum(1 for r in runs if r.get("record") == "csv")
    return [
        "Settings: RGB-D camera "
        + (f"{mount[0]:g} m above the floor, pitched {mount[1]:g} rad down"
           + (" (the paper's robot)" if list(mount) == [0.894, 0.1] else "")
           if mount else "at the simulator's default mount")
        + "; the navigation stand-in keeps its arc "
        + (f"the robot radius + {margin:g} m" if margin else "the robot radius")
        + " from obstacles; mapping error "
        + f"`{settings.get('mapping_error', 'none')}`; sim time limit "
        + (f"{limit:g} s per run" if limit else "5 s per m² of explorable area, "
           "600..7200 s") + "."
        + (f" {n_csv} of the {len(runs)} records were rebuilt from `runs.csv` (their "
           "coverage curves and timings are the ones drawn and pooled before)." if n_csv
           else ""), ""]


def cov_paths(out: Path) -> list[Path]:
    """The coverage figures in ``out`` (drawn now or kept from earlier runs)."""
    return sorted(out.glob("coverage_*.png"))


def _fmt(v: Any) -> str:
    return f"{v:.1f}" if isinstance(v, (int, float)) and math.isfinite(v) else str(v)


def _count(v: Any) -> str:
    """A count as an integer (the ROS metrics topic carries counts as floats)."""
    return str(int(v)) if isinstance(v, float) and v.is_integer() else str(v)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="Plots and BENCHMARKS.md from a bench folder.")
    ap.add_argument("out", help="folder written by bench/run_bench.py")
    ap.add_argument("--md", default=None,
                    help="where to write the report; default: the repository's BENCHMARKS.md "
                         "for the matrix's own folder (out/bench), OUT/BENCHMARKS.md for any "
                         "other")
    ap.add_argument("--allow-mixed", action="store_true",
                    help="report runs of several code versions, every row marked with its "
                         "versions (without it they are refused)")
    ap.add_argument("--certificate", action="append", default=[], metavar="PATH",
                    help="a certificate of bench/same_results.py (or a folder of them), "
                         f"besides OUT/{CERT_DIR}/; repeatable")
    ap.add_argument("--mapping-noise-dir", action="append", default=[],
                    metavar="PROFILE=DIR",
                    help="a folder of the same matrix under a mapping error profile "
                         "(run_bench.py --mapping-noise PROFILE --out DIR): adds the table "
                         "under mapping error; repeatable")
    a = ap.parse_args(argv)
    try:
        md = store.default_report_path(Path(a.out)) if a.md is None else a.md
        path = write_all(Path(a.out), Path(md) if md else None, None,
                         allow_mixed=a.allow_mixed,
                         certificates=[Path(c) for c in a.certificate],
                         noise_dirs=noise_table.parse_dirs(a.mapping_noise_dir))
    except ValueError as err:             # MixedVersions or a bad certificate
        print(f"[report] {err}", file=sys.stderr)
        return 2
    print(f"[report] wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
