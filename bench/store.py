"""The files of a benchmark folder besides the run records (:mod:`bench.records`):
``meta.json`` and its parts, CSV tables, backups, ``--resume`` and ``--merge``.

Each command that runs (or adds) runs is a *part* in ``meta.json`` (command, start, code
version, runs run, wall time, interrupted, failed runs); the settings that must match for
runs of two parts to be comparable are in ``meta["settings"]``.
"""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

from bench import records

ROOT = Path(__file__).resolve().parents[1]

#: Settings that parts of earlier versions did not record, with the value they ran on.
SETTING_DEFAULTS: dict[str, Any] = {"nav_inflation_margin_m": 0.0,
                                     "nav_inflation_soft_margin_m": 0.0,
                                     "nav_arc_check_edges": False,
                                     "nav_inflation_edge_cost": 0.0,
                                     "object_confirm_hits": 1,
                                     "mapping_error": "none"}


def code_version() -> str:
    """Git commit of the repository, ``+modified`` when the code differs from it."""
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", "explore_seg",
                                "sim_bridge", "bench", "config", ":(exclude)bench/results"],
                               cwd=ROOT, timeout=10).returncode != 0
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return (rev or "unknown") + ("+modified" if dirty and rev else "")


def default_report_path(out: Path) -> Path:
    """The repository's BENCHMARKS.md when ``out`` is the matrix's folder (``out/bench``
    of the repository), else ``out/BENCHMARKS.md``: a small or experimental run never
    overwrites the committed report."""
    if out.resolve() == (ROOT / "out" / "bench").resolve():
        return ROOT / "BENCHMARKS.md"
    return out / "BENCHMARKS.md"


def read_json(path: Path) -> dict[str, Any]:
    """A JSON object file, {} when absent or unreadable."""
    try:
        d = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return d if isinstance(d, dict) else {}


def backup(path: Path) -> Path:
    """A copy of ``path`` as ``<name>.bak``, ``.bak1``, ... (never over an earlier copy)."""
    bak, k = path.with_name(path.name + ".bak"), 1
    while bak.exists():
        bak, k = path.with_name(f"{path.name}.bak{k}"), k + 1
    shutil.copyfile(path, bak)
    return bak


def merge(out: Path, other: Path, meta: dict[str, Any], old_meta: dict[str, Any]) -> str:
    """Add the runs of ``other`` to ``out`` (a run of both: ``other``'s is kept) and its
    parts to ``old_meta``'s; '' or what is wrong (then nothing was changed). Merging a
    folder again adds no part twice."""
    o_meta = read_json(other / "meta.json")
    if not o_meta:
        return f"{other} has no meta.json"
    if not same_settings(o_meta.get("settings"), meta["settings"]):
        return (f"the runs in {other} were made with other settings ({o_meta.get('settings')}, "
                f"now {meta['settings']})")
    theirs = records.read(other)
    if not theirs:
        return f"{other} holds no runs"
    stray = sorted({f"{d['world']}:{d['strategy']}" for d in theirs
                    if d["world"] not in meta["worlds"] or d["strategy"] not in meta["strategies"]})
    if stray:
        return f"{other} holds runs of worlds/strategies this command does not name: {stray}"
    mine = {records.key_of(d): d for d in records.read(out)}
    keys = {records.key_of(d) for d in theirs}
    if any(k in mine for k in keys):
        for name in (records.FULL, records.COMPACT):
            if (out / name).is_file():
                backup(out / name)
    merged = [d for k, d in mine.items() if k not in keys] + theirs
    with open(out / records.FULL, "w") as jl:        # both files hold the merged runs
        for d in merged:
            jl.write(json.dumps(d) + "\n")
    records.write_compact(out, merged)
    parts = parts_of(old_meta)
    have = {(p.get("started"), p.get("command")) for p in parts}
    o_parts = [dict(p, merged_from=str(other)) for p in parts_of(o_meta)
               if (p.get("started"), p.get("command")) not in have]
    old_meta["parts"] = parts + o_parts
    old_meta.setdefault("settings", meta["settings"])
    tours = out / "tours.csv"
    if (other / "tours.csv").is_file():
        have_t = {r["world"] for r in read_csv(tours)}
        extra = [r for r in read_csv(other / "tours.csv") if r["world"] not in have_t]
        if extra:
            write_csv(tours, read_csv(tours) + extra)
    print(f"[bench] --merge: {len(theirs)} runs and {len(o_parts)} parts of {other} added",
          file=sys.stderr)
    return ""


def same_settings(old: dict[str, Any] | None, new: dict[str, Any]) -> bool:
    """Settings of two parts compare equal; a setting an older part did not record had
    the value it was always run with (:data:`SETTING_DEFAULTS`)."""
    if old is None:
        return False
    return ({**SETTING_DEFAULTS, **old} == {**SETTING_DEFAULTS, **new})


def _part_of(meta: dict[str, Any]) -> dict[str, Any]:
    """A pre-``parts`` meta.json as one part."""
    return {"command": meta.get("command"), "started": meta.get("started"),
            "runs_run": None, "wall_s": meta.get("wall_s")}


def slug(spec: str) -> str:
    """A world spec as part of a file name."""
    return spec.replace("/", "_").replace(".", "_")


def write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    """``rows`` as a CSV file, columns in order of first appearance (empty: an empty file)."""
    if not rows:
        path.write_text("")
        return
    keys = list(rows[0])
    for r in rows[1:]:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


def read_csv(path: Path) -> list[dict[str, str]]:
    """Rows of a CSV file as dicts ([] when absent or empty)."""
    if not path.is_file() or not path.read_text().strip():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def parts_of(meta: dict[str, Any]) -> list[dict[str, Any]]:
    """The parts of a meta.json (a pre-``parts`` one as one part; [] for none)."""
    return meta.get("parts") or ([_part_of(meta)] if meta else [])


def write_meta(out: Path, meta: dict[str, Any], old_meta: dict[str, Any],
               part: dict[str, Any]) -> None:
    """``meta.json`` of ``out``: ``meta`` with the parts of ``old_meta`` and ``part`` after
    them, and their summed wall time."""
    parts = parts_of(old_meta) + [part]
    meta["parts"] = parts
    meta["wall_s"] = round(sum(float(p.get("wall_s") or 0.0) for p in parts), 1)
    (out / "meta.json").write_text(json.dumps(meta, indent=1))


def unasked_runs(out: Path, keys: list[tuple]) -> str:
    """The runs of ``out`` whose (world, strategy, seed) is not among ``keys``, in words
    ("12 runs (nearest x 10, paper x 2) in 3 worlds, seeds 10-13"); '' when there are
    none."""
    wanted = {k[:3] for k in keys}
    left = [d for d in records.read(out) if (d["world"], d["strategy"], d["seed"]) not in wanted]
    if not left:
        return ""
    per = Counter(d["strategy"] for d in left)
    seeds = sorted({int(d["seed"]) for d in left})
    worlds = {d["world"] for d in left}
    return (f"{len(left)} run{'s' if len(left) > 1 else ''} ("
            + ", ".join(f"{st} x {n}" for st, n in per.most_common()) + f") in {len(worlds)} "
            f"world{'s' if len(worlds) > 1 else ''}, seed{'s' if len(seeds) > 1 else ''} "
            + seed_ranges(seeds))


def seed_ranges(seeds: list[int]) -> str:
    """Seeds as ranges: [0, 1, 2, 5] -> '0-2, 5'."""
    spans: list[list[int]] = []
    for k in sorted(seeds):
        if spans and k == spans[-1][1] + 1:
            spans[-1][1] = k
        else:
            spans.append([k, k])
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in spans)


def resume(out: Path, tasks: list[tuple], redo_keys: list[tuple[str | None, str]]
           ) -> tuple[list[dict[str, Any]], list[tuple]]:
    """``--resume``: the runs of ``out`` that ``tasks`` ask for (and ``redo_keys`` =
    (world or None, strategy) do not name), and the tasks still to run. The runs left out
    stay in a copy of the run files."""
    wanted = {t[:3] for t in tasks
              if not any(st == t[1] and w in (None, t[0]) for w, st in redo_keys)}
    old = records.read(out)
    kept: list[dict[str, Any]] = []
    for d in old:
        key = (d["world"], d["strategy"], d["seed"])
        if key in wanted:
            wanted.discard(key)  # a duplicate line counts once
            kept.append(d)
    if len(kept) < len(old):  # runs this command does not ask for: keep a copy
        baks = [backup(out / name) for name in (records.FULL, records.COMPACT)
                if (out / name).is_file()]
        print(f"[bench] resume: {len(old) - len(kept)} runs not asked for or to "
              f"redo are left out (copy in {', '.join(map(str, baks))})", file=sys.stderr)
    done = {(d["world"], d["strategy"], d["seed"]) for d in kept}
    tasks = [t for t in tasks if t[:3] not in done]
    print(f"[bench] resume: {len(kept)} runs kept, {len(tasks)} to run",
          file=sys.stderr)
    return kept, tasks
