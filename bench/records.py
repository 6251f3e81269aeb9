"""Run records of a benchmark folder, and the compact copy of them that is kept in git.

A run record is what :meth:`sim_bridge.lockstep.RunResult.to_dict` returns. Its
per-update timings make ``runs.jsonl`` tens of MB, so that file stays out of git and a
new checkout would lose every run with it. :func:`compact` keeps everything of a record
but those lists, in their place:

* ``timing_p``: per timing key ``[p50, p95]`` of the run, exact (what ``runs.csv`` shows);
* ``timing_hist``: per key ``{"n", "sum", "bins"}``, a histogram on log-spaced bins
  (:data:`BIN_RATIO` wide), from which the report pools all runs of a world (the paper's
  Table I: p50 within half a bin, mean exact).

``runs.jsonl.gz`` holds the compact records (about 10 kB gzipped for a 5000 s maze
run, mostly its coverage samples; 1-3 kB for a house) and is the truth that ``--resume``
reads; the full record of the same run in the local ``runs.jsonl`` is used in its place
(:func:`read`). Records rebuilt from an old ``runs.csv`` alone (:func:`from_csv_row`,
``record: "csv"``) carry the table's scalars and ``timing_p`` but no coverage samples and
no histogram.

Usage (once, for a folder whose ``runs.jsonl`` is lost)::

    .venv/bin/python bench/records.py import-csv bench/results --timing-md BENCHMARKS.md

Records made before runs carried their code version get it from the git history of the
folder's ``runs.csv`` and ``meta.json`` (:func:`codes_from_history`)::

    .venv/bin/python bench/records.py attribute-code bench/results
"""

from __future__ import annotations

import argparse
import csv
import gzip
import json
import math
import re
import subprocess
import sys
import zlib
from collections import Counter
from pathlib import Path
from typing import Any, Iterable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from sim_bridge.run_result import TIMING_KEYS  # noqa: E402

FULL = "runs.jsonl"
COMPACT = "runs.jsonl.gz"
#: Timing pooled from the full records of runs whose full records were later lost.
LEGACY_TIMING = "timing_legacy.json"
#: Width of a timing histogram bin (ratio of its edges) and the smallest time binned (ms).
BIN_RATIO = 1.01
BIN_MIN_MS = 1e-3
#: The timing keys of the report's per-module table, with their row labels.
TIMING_ROWS = (("frontier", "frontier detect + cluster"),
               ("selection", "path lengths + select (incl. goal manager)"),
               ("segmentation", "DuDe segmentation update"),
               ("detection", "object detection (oracle, lock-step)"),
               ("objects", "object costmap update (3D boxes, fusion, layer)"))
#: Column headings of the same keys in the report's table (a row per world).
TIMING_COLUMNS = {"frontier": "frontier", "selection": "selection",
                  "segmentation": "segmentation", "detection": "detection",
                  "objects": "costmap"}
_LOG_RATIO = math.log(BIN_RATIO)


def key_of(d: dict[str, Any]) -> tuple[str, str, int]:
    return d["world"], d["strategy"], int(d["seed"])


def by_world_strategy(runs: list[dict[str, Any]]
                      ) -> dict[tuple[str, str], list[dict[str, Any]]]:
    """The records grouped by (world, strategy), in order of first appearance."""
    g: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in runs:
        g.setdefault((r["world"], r["strategy"]), []).append(r)
    return g


def as_float(v: Any) -> float:
    """A record's number as a float, NaN when missing (None or a CSV's empty cell)."""
    return math.nan if v is None or v == "" else float(v)


# ------------------------------------------------------------------ histograms


def histogram(values: Iterable[float]) -> dict[str, Any]:
    """``{"n", "sum", "first", "counts"}`` of ``values`` (ms): ``counts[j]`` values in bin
    ``i = first + j``, which holds ``BIN_MIN_MS * BIN_RATIO**i <= v < BIN_MIN_MS *
    BIN_RATIO**(i+1)`` (smaller values, zero included, in bin 0)."""
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=np.float64)
    if v.size == 0:
        return {"n": 0, "sum": 0.0, "first": 0, "counts": []}
    idx = np.floor(np.log(np.maximum(v, BIN_MIN_MS) / BIN_MIN_MS) / _LOG_RATIO).astype(np.int64)
    first = int(idx.min())
    counts = np.bincount(idx - first)
    return {"n": int(v.size), "sum": float(v.sum()), "first": first,
            "counts": [int(k) for k in counts]}


def _bins(h: dict[str, Any]) -> dict[int, int]:
    """bin index -> count of a histogram (also of the sparse ``bins`` form)."""
    if "bins" in h:
        return {int(i): int(k) for i, k in h["bins"].items() if int(k)}
    first = int(h.get("first", 0))
    return {first + j: int(k) for j, k in enumerate(h.get("counts") or []) if k}


def merge_histograms(hists: Iterable[dict[str, Any]]) -> dict[str, Any]:
    n, total, bins = 0, 0.0, {}
    for h in hists:
        n += int(h["n"])
        total += float(h["sum"])
        for i, k in _bins(h).items():
            bins[i] = bins.get(i, 0) + k
    if not bins:
        return {"n": n, "sum": total, "first": 0, "counts": []}
    first = min(bins)
    counts = [0] * (max(bins) - first + 1)
    for i, k in bins.items():
        counts[i - first] = k
    return {"n": n, "sum": total, "first": first, "counts": counts}


def hist_stats(h: dict[str, Any]) -> tuple[float, float, float] | None:
    """(p50, mean, p95) of a histogram, None when empty. A percentile is the geometric
    centre of the bin that holds it (within half a bin of the exact value)."""
    if not h or int(h["n"]) == 0:
        return None
    items = sorted(_bins(h).items())
    idx = np.asarray([i for i, _ in items], dtype=np.float64)
    cum = np.cumsum([k for _, k in items])
    n = int(h["n"])

    def pct(q: float) -> float:
        # the value of rank ceil(q * n) (1-based), as numpy's "lower"/"higher" bracket it
        rank = max(1, math.ceil(q / 100.0 * n))
        j = int(np.searchsorted(cum, rank))
        return float(BIN_MIN_MS * BIN_RATIO ** (idx[j] + 0.5))

    return pct(50.0), float(h["sum"]) / n, pct(95.0)


# ------------------------------------------------------------------ records


def _samples(samples: Iterable[Any]) -> list[list[Any]]:
    """Coverage samples (t s, coverage %, path m) rounded to 0.01 (what a figure shows)."""
    return [[None if v is None else round(float(v), 2) for v in smp] for smp in samples]


def compact(d: dict[str, Any]) -> dict[str, Any]:
    """The record without its per-update timings and with its coverage samples rounded
    to 0.01 (see the module docstring). A compact record comes back in today's form."""
    out = {k: v for k, v in d.items() if k not in ("timings_ms", "goals")}
    out["coverage_samples"] = _samples(d.get("coverage_samples") or [])
    if "timings_ms" not in d:
        if d.get("timing_hist"):
            out["timing_hist"] = {k: merge_histograms([h]) for k, h in d["timing_hist"].items()}
        return out
    tp, th = {}, {}
    for key, vals in (d.get("timings_ms") or {}).items():
        v = [x for x in vals if x is not None]
        tp[key] = ([round(float(np.percentile(v, 50)), 3), round(float(np.percentile(v, 95)), 3)]
                   if v else [None, None])
        th[key] = histogram(v)
    out["timing_p"], out["timing_hist"] = tp, th
    out["record"] = "compact"
    return out


#: Fields that tell two records of one (world, strategy, seed) apart when they come from
#: different runs (the wall time differs between any two runs).
_RUN_FIELDS = ("wall_time_s", "sim_time_s", "coverage_pct", "path_length_m", "goals_sent",
               "collisions", "stop_reason")


def same_run(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two records are of the same run (a full record and its compact copy)."""
    return all(a.get(k) == b.get(k) for k in _RUN_FIELDS)


def timing_hist(d: dict[str, Any], key: str) -> dict[str, Any] | None:
    """The histogram of one timing of a record (built from the full list when it has
    one), None when the record has neither."""
    if "timings_ms" in d:
        return histogram(d["timings_ms"].get(key) or [])
    return (d.get("timing_hist") or {}).get(key)


def _float(v: str) -> float | None:
    if v is None or v == "":
        return None
    x = float(v)
    return x if math.isfinite(x) else None


def from_csv_row(row: dict[str, str]) -> dict[str, Any]:
    """A record rebuilt from one row of ``runs.csv`` (no coverage samples, no timing
    histograms, no start pose or goals: those were never in the CSV)."""
    milestones = sorted({m.group(1) for k in row if (m := re.fullmatch(r"time_to_(\d+)_s", k))},
                        key=float)
    places = []
    for item in (row.get("collision_places") or "").split(";"):
        if item:
            x, y, what = item.split(",", 2)
            places.append([float(x), float(y), what])
    contacts = []        # causes only (columns of newer CSVs): "cause:n;cause:n"
    for item in (row.get("contact_causes") or "").split(";"):
        if item:
            cause, n = item.rsplit(":", 1)
            contacts += [{"cause": cause} for _ in range(int(n))]
    return {
        "world": row["world"], "strategy": row["strategy"], "seed": int(row["seed"]),
        "completed": bool(int(row["completed"])), "stop_reason": row["stop_reason"],
        "sim_time_s": float(row["sim_time_s"]), "wall_time_s": float(row["wall_time_s"]),
        "coverage_pct": _float(row["coverage_pct"]),
        "explorable_area_m2": _float(row["explorable_area_m2"]),
        "path_length_m": float(row["path_length_m"]),
        "time_to_s": {m: _float(row[f"time_to_{m}_s"]) for m in milestones},
        "path_to_m": {m: _float(row[f"path_to_{m}_m"]) for m in milestones},
        "collisions": int(row["collisions"]), "collision_places": places,
        "goals_sent": int(row["goals_sent"]), "goal_switches": int(row["goal_switches"]),
        "goals_blacklisted": int(row["goals_blacklisted"]),
        "nav_aborts": int(row["nav_aborts"]), "n_objects": int(row["n_objects"]),
        "timing_p": {k: [_float(row.get(f"{k}_ms_p50", "")), _float(row.get(f"{k}_ms_p95", ""))]
                     for k in TIMING_KEYS if f"{k}_ms_p50" in row},
        "coverage_samples": [],
        "contacts": contacts,
        "early_stop": {"cause": row["stop_cause"]} if row.get("stop_cause") else None,
        "record": "csv",
        **({"code": row["code"]} if row.get("code") else {}),
        **({"cpu_time_s": float(row["cpu_time_s"])} if row.get("cpu_time_s") else {}),
    }


def read_jsonl(path: Path) -> list[dict[str, Any]]:
    """The run records of a JSON-lines file, plain or gzipped (unreadable lines, e.g. a cut
    last line, skipped; [] when absent)."""
    out: list[dict[str, Any]] = []
    if not path.is_file():
        return out
    opener = gzip.open if path.suffix == ".gz" else open
    try:
        with opener(path, "rt") as f:
            for line in f:
                try:
                    d = json.loads(line)
                except ValueError:
                    continue
                if isinstance(d, dict) and {"world", "strategy", "seed"} <= d.keys():
                    out.append(d)
    except (EOFError, OSError, zlib.error) as err:  # cut short by a kill: keep what came
        print(f"[records] {path}: unreadable after {len(out)} records ({err}); "
              "the rest is left out", file=sys.stderr)
    return out


def read(folder: Path) -> list[dict[str, Any]]:
    """Every run of a benchmark folder, one record per (world, strategy, seed).

    ``runs.jsonl.gz`` (in git) is the truth; the full record of ``runs.jsonl`` (local)
    replaces a compact one only when it is of the same run (:func:`same_run`), so a local
    file left from before a newer part was committed elsewhere cannot bring old runs
    back. Runs only in ``runs.jsonl`` (a part that was not committed) are kept. Order: as
    they first appear, compact file first; a later duplicate in one file replaces an
    earlier one.
    """
    by_key: dict[tuple[str, str, int], dict[str, Any]] = {}
    for d in read_jsonl(folder / COMPACT):
        by_key[key_of(d)] = d
    stale, from_full = 0, set()
    for d in read_jsonl(folder / FULL):
        k = key_of(d)
        if k in from_full or k not in by_key or same_run(d, by_key[k]):
            by_key[k] = d
            from_full.add(k)
        else:
            stale += 1
    if stale:
        print(f"[records] {folder}: {stale} runs of {FULL} differ from those of {COMPACT} "
              f"(older or newer runs of the same seeds); {COMPACT}'s are used",
              file=sys.stderr)
    return list(by_key.values())


def compact_line(d: dict[str, Any]) -> bytes:
    """A record's line in ``runs.jsonl.gz``: its compact form, keys sorted."""
    return (json.dumps(compact(d), sort_keys=True, separators=(",", ":")) + "\n").encode()


def write_compact(folder: Path, records: Iterable[dict[str, Any]]) -> None:
    """``runs.jsonl.gz`` anew from ``records`` (written beside, then moved over it). The
    gzip header carries no time stamp, so the same runs give the same bytes."""
    tmp = folder / (COMPACT + ".tmp")
    with open(tmp, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", mtime=0) as f:
        for d in records:
            f.write(compact_line(d))
    tmp.replace(folder / COMPACT)


def append_compact(folder: Path, d: dict[str, Any]) -> None:
    """One more record at the end of ``runs.jsonl.gz`` (a gzip member of its own, so a
    run that is killed later loses nothing written before)."""
    with open(folder / COMPACT, "ab") as raw, gzip.GzipFile(fileobj=raw, mode="wb",
                                                            mtime=0) as f:
        f.write(compact_line(d))


# ------------------------------------------------------------------ legacy timing


def timing_from_markdown(text: str, strategy: list[str] | None = None
                         ) -> dict[str, dict[str, list[float]]]:
    """world -> timing key -> [p50, mean, p95] read from the per-module timing table of
    a BENCHMARKS.md written by :mod:`bench.report`: a row per world (its column headings
    name the keys, :data:`TIMING_COLUMNS`) or a row per module (the earlier layout: its
    row labels name them); the strategy the table is of goes into ``strategy[0]``."""
    strategy = strategy if strategy is not None else [""]
    label_key = {label: key for key, label in TIMING_ROWS}
    column_key = {col: key for key, col in TIMING_COLUMNS.items()}
    lines = text.splitlines()
    try:
        start = next(i for i, ln in enumerate(lines) if ln.startswith("## Per-module timing"))
    except StopIteration:
        return {}
    worlds: list[str] = []
    columns: list[str | None] = []
    out: dict[str, dict[str, list[float]]] = {}
    for ln in lines[start + 1:]:
        if ln.startswith("## "):
            break
        if (m := re.match(r"Strategy `([^`]+)`", ln)):
            strategy[0] = m.group(1)
        cells = [c.strip() for c in ln.strip().strip("|").split("|")]
        if ln.startswith("| module |"):
            worlds = cells[1:]
            continue
        if ln.startswith("| world |"):
            columns = [column_key.get(c) for c in cells[1:]]
            continue
        if columns and ln.startswith("| ") and not ln.startswith("|---"):
            for key, cell in zip(columns, cells[1:]):
                parts = [p.strip() for p in cell.split("/")]
                if key is not None and len(parts) == 3:
                    out.setdefault(cells[0], {})[key] = [float(p.split()[0]) for p in parts]
            continue
        if not worlds or cells[0] not in label_key:
            continue
        for w, cell in zip(worlds, cells[1:]):
            parts = [p.strip() for p in cell.split("/")]
            if len(parts) == 3:
                out.setdefault(w, {})[label_key[cells[0]]] = [float(p.split()[0]) for p in parts]
    return out


def import_csv(folder: Path, timing_md: Path | None) -> int:
    """``runs.jsonl.gz`` from ``runs.csv`` (and the pooled timing of ``timing_md``)."""
    if (folder / COMPACT).exists() or (folder / FULL).exists():
        print(f"[records] {folder} has run records already; nothing imported", file=sys.stderr)
        return 2
    with open(folder / "runs.csv", newline="") as f:
        recs = [from_csv_row(r) for r in csv.DictReader(f)]
    write_compact(folder, recs)
    n_t = 0
    if timing_md is not None:
        strategy = ["paper"]
        timing = timing_from_markdown(timing_md.read_text(), strategy)
        (folder / LEGACY_TIMING).write_text(json.dumps(
            {"source": f"per-module timing table of {timing_md.name} (pooled from the full "
                       "records of the runs imported from runs.csv, which were not kept)",
             "strategy": strategy[0],
             "worlds": timing}, indent=1, sort_keys=True))
        n_t = len(timing)
    print(f"[records] {len(recs)} runs imported into {folder / COMPACT}"
          + (f", timing of {n_t} worlds into {folder / LEGACY_TIMING}" if timing_md else ""),
          file=sys.stderr)
    return 0


# ------------------------------------------------------------------ code versions from git


def _git(*args: str) -> str:
    return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout


def _at(commit: str, path: str) -> str | None:
    """A file's text at ``commit``, None when it was not there."""
    try:
        return _git("show", f"{commit}:{path}")
    except subprocess.CalledProcessError:
        return None


def _fingerprint(row: dict[str, Any]) -> tuple[float, ...]:
    """What tells one run of a key from another in ``runs.csv`` (wall time differs)."""
    return tuple(round(float(row.get(k) or "nan"), 2)
                 for k in ("wall_time_s", "sim_time_s", "path_length_m"))


def _redo_items(command: str) -> list[tuple[str | None, str]]:
    """The (world or None, strategy) items of a part's ``--redo``."""
    m = re.search(r"--redo[ =](\S+)", command or "")
    return [((w or None), s) for w, _, s in (x.rpartition(":") for x in m.group(1).split(","))] \
        if m else []


def codes_from_history(folder: Path) -> tuple[dict[tuple[str, str, int], str], list[str]]:
    """The code version of every run of ``folder`` (a folder of this repository whose
    ``runs.csv`` and ``meta.json`` were committed after each part), read from git: the
    runs that are new or changed in a commit of ``runs.csv`` ran in the parts that commit
    added to ``meta.json`` (all its runs when a part ran without ``--resume``: a fresh
    benchmark). When it added parts of several versions, the runs go to them
    by the order of the commit's ``runs.jsonl.gz`` (appended as they ran: the last part's
    ``runs_run`` runs last) or, without it, by the parts' ``--redo`` lists. Returns key ->
    code (``unknown`` where it cannot be told) and a line per commit saying what it did."""
    rel = folder.resolve().relative_to(ROOT).as_posix()
    commits = _git("log", "--reverse", "--format=%H", "--", f"{rel}/runs.csv").split()
    fps: dict[tuple[str, str, int], tuple[float, ...]] = {}
    code: dict[tuple[str, str, int], str] = {}
    seen_parts: set[tuple[Any, Any]] = set()
    log = []
    for c in commits:
        text = _at(c, f"{rel}/runs.csv") or ""
        rows = list(csv.DictReader(text.splitlines())) if text.strip() else []
        meta_text = _at(c, f"{rel}/meta.json")
        meta = json.loads(meta_text) if meta_text else {}
        parts = meta.get("parts") or ([meta] if meta else [])
        new_parts = [p for p in parts if (p.get("started"), p.get("command")) not in seen_parts]
        seen_parts |= {(p.get("started"), p.get("command")) for p in parts}
        running = [p for p in new_parts if p.get("runs_run") is None or p["runs_run"] > 0]
        fresh = any("--resume" not in (p.get("command") or "--resume") for p in running)
        changed = [(r["world"], r["strategy"], int(r["seed"])) for r in rows
                   if fresh or fps.get((r["world"], r["strategy"], int(r["seed"])))
                   != _fingerprint(r)]
        fps = {(r["world"], r["strategy"], int(r["seed"])): _fingerprint(r) for r in rows}
        versions = {str(p.get("code") or "unknown") for p in running}
        got: dict[tuple[str, str, int], str] = {}
        if len(versions) == 1:
            got = {k: next(iter(versions)) for k in changed}
        elif running:
            order: list[tuple[str, str, int]] = []
            gz = _git_bytes(c, f"{rel}/{COMPACT}")
            if gz is not None:
                for line in gzip.decompress(gz).decode().splitlines():
                    d = json.loads(line)
                    order.append(key_of(d))
                pos = {k: i for i, k in enumerate(order)}
                left = sorted(changed, key=lambda k: pos.get(k, -1))
                for p in reversed(running):
                    n = int(p.get("runs_run") or 0)
                    take, left = left[len(left) - n:] if n else [], left[:len(left) - n]
                    got.update({k: str(p.get("code") or "unknown") for k in take})
            else:
                left = list(changed)
                for p in reversed(running):
                    items = _redo_items(p.get("command", ""))
                    if items and p is not running[0]:
                        take = [k for k in left if any(s == k[1] and w in (None, k[0])
                                                       for w, s in items)]
                    else:
                        take = left
                    got.update({k: str(p.get("code") or "unknown") for k in take})
                    left = [k for k in left if k not in take]
        for k in changed:
            code[k] = got.get(k, "unknown")
        tally = sorted(Counter(got.get(k, "unknown") for k in changed).items())
        log.append(f"{c[:12]}: {len(changed)} runs new or changed, parts "
                   + ", ".join(f"{p.get('code')} ({p.get('runs_run')} run)" for p in new_parts)
                   + " -> " + ", ".join(f"{v}: {n}" for v, n in tally))
    return code, log


def _git_bytes(commit: str, path: str) -> bytes | None:
    try:
        return subprocess.run(["git", "show", f"{commit}:{path}"], cwd=ROOT,
                              capture_output=True, check=True).stdout
    except subprocess.CalledProcessError:
        return None


def attribute_codes(folder: Path) -> int:
    """Write into ``folder``'s records without a ``code`` the one
    :func:`codes_from_history` finds (only when its ``runs.csv`` row is the committed
    one); prints what each commit did."""
    code, log = codes_from_history(folder)
    for line in log:
        print(f"[records] {line}", file=sys.stderr)
    rows = {(r["world"], r["strategy"], int(r["seed"])): r
            for r in csv.DictReader((folder / "runs.csv").read_text().splitlines())}
    recs = read_jsonl(folder / COMPACT)
    n = 0
    for d in recs:
        k = key_of(d)
        if d.get("code") or k not in code or k not in rows:
            continue
        d["code"] = code[k]
        n += 1
    write_compact(folder, recs)
    print(f"[records] code version written into {n} of {len(recs)} records: "
          + ", ".join(f"{c}: {k}" for c, k in Counter(d.get("code") for d in recs).most_common()),
          file=sys.stderr)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    imp = sub.add_parser("import-csv", help="runs.jsonl.gz from runs.csv (lost runs.jsonl)")
    imp.add_argument("folder")
    imp.add_argument("--timing-md", default="",
                     help="BENCHMARKS.md whose timing table was pooled from those runs")
    att = sub.add_parser("attribute-code", help="the code version of each run from the "
                         "git history of the folder's runs.csv and meta.json")
    att.add_argument("folder")
    a = ap.parse_args(argv)
    if a.cmd == "attribute-code":
        return attribute_codes(Path(a.folder))
    return import_csv(Path(a.folder), Path(a.timing_md) if a.timing_md else None)


if __name__ == "__main__":
    ROOT = Path(__file__).resolve().parents[1]
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    raise SystemExit(main())
