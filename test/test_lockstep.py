"""Lock-step exploration runner (and every strategy against the coverage tour)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import FrontierParams
from sim_bridge.coverage_tour import coverage_tour
from sim_bridge.engine import Collider, SimParams
from sim_bridge.lockstep import (STRATEGIES, LockstepParams, RunResult,
                                 load_explorer_params, perturbed_start, run_exploration)
from sim_bridge.slam_error import LoopClosure
from sim_bridge.worlds import default_world, ground_truth

SEED = 1
MAX_SIM_TIME_S = 600.0


@pytest.fixture(scope="module")
def small_house():
    w = default_world("small_house")
    return w, ground_truth(w)


@pytest.fixture(scope="module")
def runs(small_house):
    """One run of every strategy on the small house (shared by the tests below)."""
    w, gt = small_house
    return {s: run_exploration(w, s, SEED, params=LockstepParams(max_sim_time_s=MAX_SIM_TIME_S),
                               ground_truth=gt)
            for s in STRATEGIES}


@pytest.mark.parametrize("strategy", ["paper", "nearest", "routed"])
def test_explores_small_house_to_completion(runs, strategy):
    r = runs[strategy]
    assert r.stop_reason == "coverage", (r.stop_reason, r.coverage_pct)
    assert r.completed and r.coverage_pct >= 99.0
    t = [r.time_to_s[k] for k in ("50", "90", "95", "99")]
    p = [r.path_to_m[k] for k in ("50", "90", "95", "99")]
    assert all(math.isfinite(v) for v in t + p)
    assert t == sorted(t) and p == sorted(p)
    assert t[-1] <= r.sim_time_s and p[-1] <= r.path_length_m + 1e-9
    assert r.goals_sent >= 1 and r.goals_sent == len(r.goals)
    # detection when the published map, the object layer or the scans laid over the map
    # changed (the scans change between most decisions), timed each time
    assert 1 <= len(r.timings_ms["frontier"]) <= len(r.timings_ms["selection"])
    assert len(r.timings_ms["frontier"]) >= len(r.timings_ms["selection"]) // 2
    # the decision core: detection + selection of each decision, inside the lock step's
    # decision (which adds segmentation and sending the goal)
    core, sel, dec = (np.asarray(r.timings_ms[k]) for k in ("core", "selection", "decision"))
    assert len(core) == len(sel) == len(dec)
    assert (core >= sel).all() and (core <= dec).all()


def test_paper_runs_every_module(runs):
    r = runs["paper"]
    for key in ("frontier", "selection", "segmentation", "detection", "objects"):
        assert len(r.timings_ms[key]) >= 1, key
    assert not runs["nearest"].timings_ms["segmentation"]
    assert not runs["nearest"].timings_ms["objects"]


def test_coverage_samples_are_monotone_in_time(runs):
    for r in runs.values():
        t = [s[0] for s in r.coverage_samples]
        assert t == sorted(t) and t[-1] == pytest.approx(r.sim_time_s)
        path = [s[2] for s in r.coverage_samples]
        assert path == sorted(path)


def test_same_seed_same_result(small_house):
    w, gt = small_house
    a = run_exploration(w, "paper", 3, params=LockstepParams(max_sim_time_s=40.0),
                        ground_truth=gt).to_dict()
    b = run_exploration(w, "paper", 3, params=LockstepParams(max_sim_time_s=40.0),
                        ground_truth=gt).to_dict()
    for d in (a, b):
        d.pop("wall_time_s")
        d.pop("timings_ms")
    assert a == b


def test_seeds_perturb_the_start():
    w = default_world("small_house")
    p = LockstepParams()
    starts = [perturbed_start(w, s, p) for s in range(8)]
    assert len(set(starts)) == 8
    coll = Collider(w, 0.22, 1.1)
    for x, y, yaw in starts:
        assert abs(x - w.start_pose[0]) <= p.start_jitter_m + 1e-12
        assert abs(y - w.start_pose[1]) <= p.start_jitter_m + 1e-12
        assert -math.pi <= yaw < math.pi
        assert coll.clearance(x, y)[0] >= p.start_min_clearance_m
    assert perturbed_start(w, 5, p) == starts[5]


def test_coverage_tour_is_below_every_strategy(runs, small_house):
    # The tour is an estimate (greedy viewpoints, then a tour over them), not the optimum:
    # a run may come within a few per cent below it, never far.
    w, gt = small_house
    problems = []
    for strategy, r in runs.items():
        if not r.completed:
            problems.append(f"{strategy} did not complete ({r.coverage_pct:.1f} %)")
            continue
        tour = coverage_tour(w, start_xy=r.start_pose[:2], ground_truth=gt)
        if not 0.0 < tour.length_m <= 1.05 * r.path_to_m["99"]:
            problems.append(f"{strategy}: tour {tour.length_m:.1f} m > 1.05 x path to 99 % "
                            f"{r.path_to_m['99']:.1f} m")
    assert not problems, problems




def test_summary_row_is_flat():
    r = RunResult("w", "paper", 0, time_to_s={"99": math.nan}, path_to_m={"99": 12.5},
                  timings_ms={"frontier": [1.0, 3.0]})
    row = r.summary_row()
    assert row["path_to_99_m"] == 12.5 and math.isnan(row["time_to_99_s"])
    assert row["frontier_ms_p50"] == 2.0 and math.isnan(row["selection_ms_p50"])
    assert all(not isinstance(v, (list, dict)) for v in row.values())
    assert r.to_dict()["time_to_s"] == {"99": None}


def test_unknown_strategy_is_rejected():
    with pytest.raises(ValueError, match="strategy must be one of"):
        run_exploration(default_world("small_house"), "greedy", 0)


@pytest.mark.parametrize("field, value, match", [
    ("max_sim_time_s", 0.0, "max_sim_time_s must be finite and > 0"),
    ("decision_period_s", -1.0, "decision_period_s must be finite and >= 0"),
    ("coverage_target_pct", 101.0, "coverage_target_pct must be in"),
    ("oracle_miss_prob", 1.5, "oracle_miss_prob must be in"),
    ("milestones_pct", (50.0, 0.0), "milestones_pct must be in"),
    ("camera_scale", 2.0, "camera_scale must be <= 1"),
])
def test_lockstep_params_validation(field, value, match):
    with pytest.raises(ValueError, match=match):
        LockstepParams(**{field: value})


def test_load_explorer_params_reads_each_node_section(tmp_path):
    f = tmp_path / "explorer.yaml"
    f.write_text(
        "/**:\n  ros__parameters:\n    use_sim_time: true\n    frontier:\n"
        "      robot_radius_m: 0.3\n"
        "target_selector:\n  ros__parameters:\n    gamma: 2.5\n    strategy: nearest\n"
        "segmentation:\n  ros__parameters:\n    tau_m: 3.0\n"
        "object_costmap:\n  ros__parameters:\n    rate_hz: 4.0\n    detector.backend: oracle\n")
    ep = load_explorer_params(f)
    assert ep.selection.gamma == 2.5 and ep.selection.strategy == "nearest"
    assert ep.frontier.robot_radius_m == 0.3 and ep.objects.robot_radius_m != 0.3
    assert ep.segmentation.tau_m == 3.0 and ep.objects.rate_hz == 4.0
    assert ep.frontier.min_group_size_cells == FrontierParams().min_group_size_cells


@pytest.mark.parametrize("text, match", [
    ("- a\n- b\n", "expected a mapping of node names"),
    ("target_selector:\n  gamma: 1.0\n", "lacks 'ros__parameters'"),
    ("target_selector:\n  ros__parameters:\n    gamma: -1.0\n", "gamma must be finite"),
])
def test_load_explorer_params_errors(tmp_path, text, match):
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    with pytest.raises(ValueError, match=match):
        load_explorer_params(f)


def test_a_rerendering_closure_makes_the_overlay_forget_its_scans(monkeypatch, small_house):
    """The simulator's closures reach the target_selector's overlay: one that re-rendered
    the map makes it forget the scans laid before it (at the next decision, with the time
    the closure was seen); one that did not changes nothing."""
    calls: list[tuple[float | None, float]] = []
    forget = Explorer.map_corrected

    def spy(self, stamp_s=None):
        calls.append((stamp_s, self._overlay._newest_s))
        forget(self, stamp_s)
    monkeypatch.setattr(Explorer, "map_corrected", spy)
    added: list[float] = []

    def observer(state):
        slam = state.engine.slam_error
        t = state.engine.time_s
        if len(added) < 2 and t >= 4.0 + 4.0 * len(added):
            slam.closures.append(LoopClosure(keyframe=1, matched=0, shift_m=0.3,
                                             shift_rad=0.0, rerendered=len(added) == 1))
            added.append(t)
    w, gt = small_house
    run_exploration(w, "nearest", SEED, params=LockstepParams(max_sim_time_s=16.0),
                    sim_params=SimParams(mapping_error="harsh"), ground_truth=gt, observer=observer)
    assert len(added) == 2
    assert len(calls) == 1                           # the re-rendering closure only
    stamp, newest = calls[0]
    assert added[1] < stamp <= added[1] + 1.0 and newest >= stamp - 0.2
