"""Decision trace of lock-step runs: every decision's cost terms, and where the time goes.

For each run (world x strategy x seed) this runs :func:`sim_bridge.lockstep.run_exploration`
with an observer and writes one CSV row per decision (``--out``/trace_WORLD_STRATEGY_SEED.csv):
time, coverage, robot pose, action, reason, goal, the robot's region, and for the chosen
frontier its path distance, size, region and cost; for ``paper`` also the three terms of
eq. 1-3 of the chosen frontier and whether the region term or the size term changed the
choice (the argmin without that term differs); for ``routed`` the tour length and the
viewpoint's gain.

The summary (printed, and ``summary.json``) per run: time to 95 %, the time the robot
stood still (moved < ``--still-m`` in a decision period while exploring), NEW_GOAL
decisions and how many the region / size term decided, changes of the robot's region id
(and how many were back to the id it had two changes before: flicker), goal switches,
blacklistings, the time from 95 % coverage to the end, and the share of the path driven
while coverage did not grow, and for runs that ended DONE how long after coverage reached
its final value (within 0.05 %) DONE came (``done_lag_s``; ``--coverage-target 100`` lets
runs go on until DONE).

``--mapping-noise PROFILE`` maps the scans with the simulator's SLAM-like error
(``SimParams.mapping_error``), as ``bench/paired.py`` does.

``--groups T0:T1`` also writes, for every decision between T0 and T1 s of sim time
(``groups_WORLD_STRATEGY_SEED.csv``), one row per frontier group: its goal point (the
viewpoint under ``routed``), centroid, size, selection cost, and under ``routed`` its
viewpoint's gain, tour cost, place in the tour and DuDe region, and whether it was chosen:
what a decision saw, for finding why a tour passed a corner and came back for it.

Usage::

    .venv/bin/python bench/trace_decisions.py --worlds eb/room_2,house --strategies paper \\
        --seeds 0,1,2 --out out/trace
    .venv/bin/python bench/trace_decisions.py --worlds eb/loop_with_corridor \\
        --strategies routed --seeds 7 --groups 100:130 --out out/trace
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.tasks import explorer_params  # noqa: E402
from bench.worlds import PAPER_CAMERA_MOUNT, load, sim_params_for, sim_time_limit  # noqa: E402
from explore_seg.core.selection import Action  # noqa: E402
from sim_bridge.lockstep import LockstepParams, LockstepState, run_exploration  # noqa: E402

FIELDS = ("t_s", "coverage_pct", "x_m", "y_m", "action", "reason", "goal_x_m", "goal_y_m",
          "robot_region", "n_frontiers", "chosen_dist_m", "chosen_size_cells",
          "chosen_region", "chosen_cost", "dist_term", "size_term", "region_term",
          "dist_term_spread", "region_decided", "size_decided", "tour_m", "gain_m2")
GROUP_FIELDS = ("t_s", "group", "point_x_m", "point_y_m", "centroid_x_m", "centroid_y_m",
                "size_cells", "cost", "gain_m2", "tour_cost_m", "tour_position", "region",
                "chosen")


def group_rows(t_s: float, st: LockstepState) -> list[dict[str, Any]]:
    """One row per frontier group of the decision in ``st`` (module docstring)."""
    step = st.step
    if step is None:
        return []
    sel, tour = step.selection, step.tour
    place = ({int(g): k for k, g in enumerate(tour.order)} if tour is not None else {})
    rows = []
    for i, f in enumerate(step.frontiers):
        row: dict[str, Any] = dict(
            t_s=round(t_s, 2), group=i, point_x_m=round(f.point_xy_m[0], 2),
            point_y_m=round(f.point_xy_m[1], 2), centroid_x_m=round(f.centroid_xy_m[0], 2),
            centroid_y_m=round(f.centroid_xy_m[1], 2), size_cells=f.size_cells,
            chosen=int(sel is not None and sel.index == i))
        if sel is not None:
            row["cost"] = round(float(sel.costs[i]), 4)
        if tour is not None:
            row.update(gain_m2=round(float(tour.gain_m2[i]), 2),
                       tour_cost_m=round(float(tour.tour_cost_m[i]), 2),
                       tour_position=place.get(i), region=int(tour.regions[i]))
        rows.append(row)
    return rows


def paper_terms(st: LockstepState, alpha: float, beta: float, gamma: float
                ) -> dict[str, Any]:
    """The chosen frontier's eq. 1-3 terms and whether the region / size term decided."""
    step = st.step
    sel = step.selection if step is not None else None
    if sel is None or sel.index is None or step.dist_m is None:
        return {}
    d = np.asarray(step.dist_m, dtype=np.float64)
    fin = np.isfinite(sel.costs)
    size = np.asarray([f.size_cells for f in step.frontiers], dtype=np.float64)
    dist_term = np.where(fin, alpha * d / d[fin].sum(), np.inf) if d[fin].sum() > 0 else \
        np.zeros(len(d))
    size_term = beta / (size / size.sum())
    region_term = sel.costs - dist_term - size_term
    i = sel.index
    no_region = np.where(fin, dist_term + size_term, np.inf)
    no_size = np.where(fin, dist_term + region_term, np.inf)
    spread = float(np.ptp(dist_term[fin])) if fin.sum() > 1 else 0.0
    return dict(dist_term=round(float(dist_term[i]), 4), size_term=round(float(size_term[i]), 4),
                region_term=round(float(region_term[i]), 4), dist_term_spread=round(spread, 4),
                region_decided=int(int(np.argmin(no_region)) != i),
                size_decided=int(int(np.argmin(no_size)) != i))


@dataclass(frozen=True)
class TraceOptions:
    """How a traced run runs: when it stops, which decisions dump their groups, and the
    simulator's mapping error."""

    #: Stop at this coverage (None: the lock step's 99 %).
    coverage_target_pct: float | None = None
    #: Dump the groups of the decisions between these sim times (s).
    groups_window: tuple[float, float] | None = None
    #: Caps the benchmark's time limit (s).
    max_sim_time_s: float | None = None
    #: ``SimParams.mapping_error`` (none, realistic, harsh, custom).
    mapping_error: str = "none"


def trace_run(world_spec: str, strategy: str, seed: int, out_dir: Path,
              still_m: float, opts: TraceOptions = TraceOptions()) -> dict[str, Any]:
    """One traced run: writes its CSV (and with ``opts.groups_window`` the groups' CSV),
    returns its summary."""
    coverage_target_pct, groups_window = opts.coverage_target_pct, opts.groups_window
    max_sim_time_s = opts.max_sim_time_s
    world, gt = load(world_spec)
    ep = explorer_params()
    sp = ep.selection
    rows: list[dict[str, Any]] = []
    groups: list[dict[str, Any]] = []
    last_xy: list[tuple[float, float]] = []

    def observe(st: LockstepState) -> None:
        eng = st.engine
        x, y = float(eng.pose[0]), float(eng.pose[1])
        step = st.step
        row: dict[str, Any] = dict(t_s=round(eng.time_s, 2),
                                   coverage_pct=round(float(eng.metrics.coverage_pct), 2),
                                   x_m=round(x, 2), y_m=round(y, 2), action=st.action,
                                   reason=st.reason)
        if st.goal_xy is not None:
            row.update(goal_x_m=round(st.goal_xy[0], 2), goal_y_m=round(st.goal_xy[1], 2))
        if step is not None:
            row["n_frontiers"] = len(step.frontiers)
            sel = step.selection
            if sel is not None:
                row["robot_region"] = sel.robot_region
                if sel.index is not None and step.dist_m is not None:
                    i = sel.index
                    row.update(chosen_dist_m=round(float(step.dist_m[i]), 2),
                               chosen_size_cells=step.frontiers[i].size_cells,
                               chosen_region=int(sel.regions[i]),
                               chosen_cost=round(float(sel.costs[i]), 4))
                    if strategy.startswith("paper"):
                        row.update(paper_terms(st, sp.alpha, sp.beta,
                                               sp.gamma if st.labels is not None else 0.0))
            if step.tour is not None:
                row["tour_m"] = round(step.tour.length_m, 2)
                if sel is not None and sel.index is not None:
                    row["gain_m2"] = round(float(step.tour.gain_m2[sel.index]), 2)
        rows.append(row)
        last_xy.append((x, y))
        if groups_window is not None and groups_window[0] <= eng.time_s <= groups_window[1]:
            groups.extend(group_rows(eng.time_s, st))

    lp = LockstepParams()
    if coverage_target_pct is not None:
        lp = replace(lp, coverage_target_pct=coverage_target_pct)
    limit = sim_time_limit(float(gt.explorable_area_m2), None)
    if max_sim_time_s is not None:
        limit = min(limit, max_sim_time_s)
    res = run_exploration(world, strategy, seed, ground_truth=gt, explorer_params=ep,
                          params=replace(lp, max_sim_time_s=float(limit)),
                          sim_params=replace(sim_params_for(PAPER_CAMERA_MOUNT, None),
                                             mapping_error=opts.mapping_error),
                          observer=observe)
    out_dir.mkdir(parents=True, exist_ok=True)
    name = f"trace_{world_spec.replace('/', '_')}_{strategy}_{seed}.csv"
    with open(out_dir / name, "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=FIELDS)
        wr.writeheader()
        wr.writerows(rows)
    if groups_window is not None:
        with open(out_dir / name.replace("trace_", "groups_", 1), "w", newline="") as fh:
            wr = csv.DictWriter(fh, fieldnames=GROUP_FIELDS)
            wr.writeheader()
            wr.writerows(groups)
    return summarise(rows, res, world_spec, strategy, seed, still_m)


def summarise(rows: list[dict[str, Any]], res: Any, world: str, strategy: str, seed: int,
              still_m: float) -> dict[str, Any]:
    """Where the time went in one traced run (module docstring)."""
    t95 = res.time_to_s.get("95", math.nan)
    still_s = 0.0
    flat_path = 0.0
    for a, b in zip(rows, rows[1:]):
        moved = math.hypot(b["x_m"] - a["x_m"], b["y_m"] - a["y_m"])
        dt = b["t_s"] - a["t_s"]
        if moved < still_m and a["action"] != Action.DONE.value:
            still_s += dt
        if b["coverage_pct"] - a["coverage_pct"] < 0.01:
            flat_path += moved
    new = [r for r in rows if r["action"] == Action.NEW_GOAL.value]
    regions = [r.get("robot_region", 0) for r in rows if r.get("robot_region", 0) > 0]
    changes = [k for k in range(1, len(regions)) if regions[k] != regions[k - 1]]
    # A -> B -> A: back to the id the robot had before the previous change.
    flicker = sum(1 for j in range(1, len(changes))
                  if regions[changes[j]] == regions[changes[j - 1] - 1])
    total_path = res.path_length_m
    final = res.coverage_pct
    t_final = next((r["t_s"] for r in rows if r["coverage_pct"] >= final - 0.05), res.sim_time_s)
    return dict(world=world, strategy=strategy, seed=seed, t95_s=t95, end_s=res.sim_time_s,
                stop=res.stop_reason, coverage_pct=round(res.coverage_pct, 2),
                still_s=round(still_s, 1), new_goals=len(new),
                region_decided=sum(int(r.get("region_decided", 0) or 0) for r in new),
                size_decided=sum(int(r.get("size_decided", 0) or 0) for r in new),
                median_dist_term_spread=(round(float(np.median(
                    [r["dist_term_spread"] for r in new if "dist_term_spread" in r])), 4)
                    if any("dist_term_spread" in r for r in new) else None),
                region_changes=len(changes), region_flicker=flicker,
                switches=res.goal_switches, blacklisted=res.goals_blacklisted,
                after_95_s=round(res.sim_time_s - t95, 1) if math.isfinite(t95) else None,
                path_m=round(total_path, 1),
                done_lag_s=(round(res.sim_time_s - t_final, 1) if res.stop_reason == "done"
                            else None),
                path_no_gain_pct=round(100.0 * flat_path / total_path, 1) if total_path else 0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--worlds", default="eb/room_2")
    ap.add_argument("--strategies", default="paper")
    ap.add_argument("--seeds", default="0")
    ap.add_argument("--out", default="out/trace")
    ap.add_argument("--still-m", type=float, default=0.05,
                    help="moved less than this in a decision period = standing still")
    ap.add_argument("--coverage-target", type=float, default=None,
                    help="stop at this coverage (default: the lock step's 99 %%; 100 lets a "
                         "run go on until DONE, to measure how late DONE comes)")
    ap.add_argument("--groups", default=None, metavar="T0:T1",
                    help="also write every frontier group of the decisions between T0 and "
                         "T1 s of sim time (groups_*.csv)")
    ap.add_argument("--max-sim-time", type=float, default=None,
                    help="end runs at this sim time (s) if the benchmark's limit is later")
    ap.add_argument("--mapping-noise", default="none", metavar="PROFILE",
                    help="SLAM-like mapping error (SimParams.mapping_error: none, realistic, "
                         "harsh, custom)")
    a = ap.parse_args(argv)
    out = Path(a.out)
    window = None
    if a.groups is not None:
        try:
            t0, t1 = (float(v) for v in a.groups.split(":"))
        except ValueError:
            ap.error(f"--groups expects T0:T1 in seconds, got {a.groups!r}")
        window = (t0, t1)
    if a.max_sim_time is not None and not a.max_sim_time > 0:
        ap.error(f"--max-sim-time must be > 0 s, got {a.max_sim_time}")
    summaries = []
    for w in a.worlds.split(","):
        for s in a.strategies.split(","):
            for seed in (int(x) for x in a.seeds.split(",")):
                summ = trace_run(w, s, seed, out, a.still_m, TraceOptions(
                    a.coverage_target, window, a.max_sim_time, a.mapping_noise))
                print(json.dumps(summ), flush=True)
                summaries.append(summ)
    with open(out / "summary.json", "a") as fh:
        for summ in summaries:
            fh.write(json.dumps(summ) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
