"""The outcome and measurements of one lock-step run (:class:`RunResult`)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

#: Timing keys of :attr:`RunResult.timings_ms` (one list entry per update).
TIMING_KEYS = ("frontier", "selection", "segmentation", "detection", "objects", "decision",
               "core")


@dataclass
class RunResult:
    """Outcome and measurements of one run (JSON-able through :meth:`to_dict`).

    Attributes
    ----------
    world, strategy : str
    seed : int
    completed : bool
        Coverage reached ``coverage_target_pct``.
    stop_reason : str
        ``"coverage"``, ``"done"`` (no reachable frontier left) or ``"timeout"``.
    sim_time_s, wall_time_s : float
        Sim time at the stop and wall time the run took.
    coverage_pct : float
        Final coverage (% of the explorable area the map knows, see sim_bridge.metrics).
    explorable_area_m2 : float
    path_length_m : float
        Distance travelled.
    time_to_s, path_to_m : dict of str to float
        Per milestone (key ``"50"``, ``"90"``, ...): sim time and path length when the
        coverage first reached it (NaN when never).
    collisions : int
    collision_places : list of (x, y, what)
    goals_sent, goal_switches : int
        Goals sent to navigation; goals replaced by a cheaper frontier while the
        previous goal's frontier was still there and reachable (a vanished frontier, a
        reached or blacklisted goal is not a switch).
    goals_blacklisted, nav_aborts : int
    start_pose : (x, y, yaw)
    n_objects : int
        Objects in the object map at the end (0 without it).
    timings_ms : dict of str to list of float
        Per-update wall times of frontier detect+cluster, selection (graph, path
        lengths, costs, goal manager), segmentation, object costmap and the whole
        decision.
    coverage_samples : list of (t_s, coverage_pct, path_m)
    goals : list of (x, y)
    contacts : list of dict
        Every contact classified (:func:`sim_bridge.contacts.classify_contact`: what was
        hit, whether the map / object layer had it, speed, cause); empty in records made
        before it existed.
    early_stop : dict or None
        For a run that stopped below its coverage target: the frontiers left and the
        unseen gaps with their causes (:func:`sim_bridge.early_stop.explain_stop`).
    """

    world: str
    strategy: str
    seed: int
    completed: bool = False
    stop_reason: str = ""
    sim_time_s: float = 0.0
    wall_time_s: float = 0.0
    coverage_pct: float = 0.0
    explorable_area_m2: float = 0.0
    path_length_m: float = 0.0
    time_to_s: dict[str, float] = field(default_factory=dict)
    path_to_m: dict[str, float] = field(default_factory=dict)
    collisions: int = 0
    collision_places: list[tuple[float, float, str]] = field(default_factory=list)
    goals_sent: int = 0
    goal_switches: int = 0
    goals_blacklisted: int = 0
    nav_aborts: int = 0
    start_pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    n_objects: int = 0
    timings_ms: dict[str, list[float]] = field(default_factory=dict)
    coverage_samples: list[tuple[float, float, float]] = field(default_factory=list)
    goals: list[tuple[float, float]] = field(default_factory=list)
    contacts: list[dict[str, Any]] = field(default_factory=list)
    early_stop: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        """All fields as plain JSON-able values (NaN -> None)."""
        return _json_clean(asdict(self))

    def summary_row(self) -> dict[str, Any]:
        """One flat CSV row: scalars, milestones and p50/p95 of every timing."""
        row: dict[str, Any] = {
            "world": self.world, "strategy": self.strategy, "seed": self.seed,
            "completed": int(self.completed), "stop_reason": self.stop_reason,
            "sim_time_s": round(self.sim_time_s, 2), "wall_time_s": round(self.wall_time_s, 2),
            "coverage_pct": round(self.coverage_pct, 2),
            "explorable_area_m2": round(self.explorable_area_m2, 2),
            "path_length_m": round(self.path_length_m, 2),
        }
        for key in sorted(self.time_to_s, key=float):
            row[f"time_to_{key}_s"] = _round(self.time_to_s[key])
            row[f"path_to_{key}_m"] = _round(self.path_to_m.get(key, math.nan))
        row.update({"collisions": self.collisions, "goals_sent": self.goals_sent,
                    "goal_switches": self.goal_switches,
                    "goals_blacklisted": self.goals_blacklisted, "nav_aborts": self.nav_aborts,
                    "n_objects": self.n_objects,
                    "collision_places": ";".join(f"{x:.2f},{y:.2f},{w}"
                                                 for x, y, w in self.collision_places),
                    "contact_causes": ";".join(f"{k}:{v}" for k, v in
                                               _counts(c.get("cause", "") for c in self.contacts)),
                    "stop_cause": (self.early_stop or {}).get("cause", "")})
        for key in TIMING_KEYS:
            vals = self.timings_ms.get(key, [])
            row[f"{key}_ms_p50"] = _round(float(np.percentile(vals, 50)) if vals else math.nan, 3)
            row[f"{key}_ms_p95"] = _round(float(np.percentile(vals, 95)) if vals else math.nan, 3)
        return row



def _counts(keys: Any) -> list[tuple[str, int]]:
    out: dict[str, int] = {}
    for k in keys:
        out[k] = out.get(k, 0) + 1
    return sorted(out.items())


def _round(v: float, nd: int = 2) -> float:
    return round(v, nd) if math.isfinite(v) else math.nan


def _json_clean(v: Any) -> Any:
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {str(k): _json_clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_clean(x) for x in v]
    return v
