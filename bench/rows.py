"""The rows of ``runs.csv``: one per run record (:meth:`RunResult.summary_row`), with the
coverage tour of its world beside it."""

from __future__ import annotations

import math
from typing import Any

from sim_bridge.lockstep import RunResult


def row_from_dict(d: dict[str, Any]) -> dict[str, Any]:
    """The CSV row of a run stored as :meth:`RunResult.to_dict` (None -> NaN), with the
    code version it ran on and its CPU seconds ('' when not recorded)."""
    cls = RunResult
    fields = {k: v for k, v in d.items() if k in cls.__dataclass_fields__}
    for k in ("time_to_s", "path_to_m"):
        fields[k] = {kk: (math.nan if vv is None else vv) for kk, vv in fields[k].items()}
    for k in ("coverage_pct", "explorable_area_m2"):
        if fields.get(k) is None:
            fields[k] = math.nan
    row = cls(**fields).summary_row()
    row["code"] = d.get("code") or ""                  # the commit the run ran on
    row["cpu_time_s"] = d.get("cpu_time_s", "")        # its process CPU seconds
    if "timings_ms" not in d:              # compact or CSV record: its per-run percentiles
        for key, (p50, p95) in (d.get("timing_p") or {}).items():
            row[f"{key}_ms_p50"] = p50 if p50 is not None else math.nan
            row[f"{key}_ms_p95"] = p95 if p95 is not None else math.nan
    return row


def runs_csv_rows(results: list[dict[str, Any]], specs: list[str], strategies: list[str],
                  tours: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows of ``results`` in world x strategy order (as ``specs`` x ``strategies``),
    then by seed, with their world's tour length and path / tour of completed runs."""
    tour_by_world = {t["world"]: t["tour_m"] for t in tours}
    rows = []
    order = {(s, st): i for i, (s, st) in enumerate((s, st) for s in specs for st in strategies)}
    for d in sorted(results, key=lambda d: (order[(d["world"], d["strategy"])], d["seed"])):
        row = row_from_dict(d)
        tour = tour_by_world.get(d["world"])
        row["tour_m"] = tour if tour is not None else ""
        row["path_over_tour"] = (round(d["path_length_m"] / tour, 3)
                                 if tour and d["completed"] else "")
        rows.append(row)
    return rows
