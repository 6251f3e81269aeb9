"""Strategies as plug-ins: a strategy defined in this file is registered by name and runs
through ``Explorer.step`` and a short lock-step run; no strategy name is compared outside
the registry."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.selection import (Action, GoalOptions, SelectionParams, Strategy,
                                        get_strategy, register, strategy_names, unregister)
from explore_seg.core.selection.strategies import BUILTIN, COST_FUNCTIONS
from sim_bridge.lockstep import STRATEGY_SPECS, LockstepParams, run_exploration, strategy_spec
from sim_bridge.worlds import default_world, ground_truth

ROOT = Path(__file__).resolve().parents[1]
TOY = "farthest_first"


def farthest_cost(inp, params):
    """The toy strategy: the farthest reachable frontier first (the opposite of nearest)."""
    return -inp.dist_m[inp.finite]


@pytest.fixture
def toy():
    """The toy strategy, registered for one test."""
    strategy = register(Strategy(TOY, farthest_cost, "the farthest frontier first"))
    try:
        yield strategy
    finally:
        unregister(TOY)


CORRIDOR = '''
###############
#R............?
#.............#
#######.#######
#######?#######
'''


def test_a_registered_strategy_decides_through_explorer_step(toy):
    grid, marks = grid_from_ascii(CORRIDOR, resolution_m=0.1)
    x, y = grid.cell_to_world(*marks["R"][0])
    fp = FrontierParams(min_group_size_cells=1, robot_radius_m=0.0)
    picks = {}
    for name in ("nearest", TOY):
        out = Explorer(fp, SelectionParams(strategy=name)).step(0.0, grid, (x, y, 0.0))
        assert out.action is Action.NEW_GOAL
        assert len(out.frontiers) == 2
        d = out.dist_m[out.selection.index]
        picks[name] = d
        others = out.dist_m[np.isfinite(out.dist_m)]
        assert d == (others.min() if name == "nearest" else others.max())
    assert picks[TOY] > picks["nearest"]


def test_a_registered_strategy_runs_in_the_lock_step(toy):
    assert TOY not in STRATEGY_SPECS
    spec = strategy_spec(TOY)
    assert (spec.selection, spec.use_regions, spec.use_objects) == (TOY, False, False)
    w = default_world("small_house")
    r = run_exploration(w, TOY, 0, params=LockstepParams(max_sim_time_s=120.0),
                        ground_truth=ground_truth(w))
    assert r.strategy == TOY
    assert r.goals_sent >= 1 and r.coverage_pct > 10.0


def test_the_registry_rejects_duplicates_and_names_what_it_has(toy):
    with pytest.raises(ValueError, match="already registered"):
        register(Strategy(TOY, farthest_cost, "again"))
    register(Strategy(TOY, farthest_cost, "replaced"), replace=True)
    assert get_strategy(TOY).summary == "replaced"
    with pytest.raises(ValueError, match=r"strategy must be one of \(.*'routed'.*got 'nope'"):
        get_strategy("nope")
    with pytest.raises(ValueError, match="strategy must be one of"):
        SelectionParams(strategy="nope")
    assert SelectionParams(strategy=TOY).strategy == TOY
    assert COST_FUNCTIONS[TOY] is farthest_cost and TOY in strategy_names()
    with pytest.raises(ValueError, match="not_registered_here"):
        strategy_spec("not_registered_here")


def test_unregistered_strategies_are_gone():
    assert TOY not in strategy_names()
    with pytest.raises(ValueError, match="no strategy"):
        unregister(TOY)


@pytest.mark.parametrize("kwargs, match", [
    ({"name": "two words"}, "identifier"),
    ({"cost": 3}, "callable"),
    ({"candidates": "cells"}, "'groups' or 'rrt'"),
    ({"candidates": "rrt", "make_planner": lambda fp, sp: None}, "a planner works on"),
])
def test_a_strategy_is_checked_when_built(kwargs, match):
    args = {"name": "ok", "cost": farthest_cost, "summary": "s"} | kwargs
    with pytest.raises((ValueError, TypeError), match=match):
        Strategy(**args)


def test_register_takes_only_strategies():
    with pytest.raises(TypeError, match="expects a Strategy"):
        register(farthest_cost)


def test_the_builtins_declare_what_their_callers_branched_on():
    by_name = {s.name: s for s in BUILTIN}
    assert tuple(by_name) == ("paper", "nearest", "explore_lite", "rrt_exploration", "routed",
                              "foresight")
    assert {n for n, s in by_name.items() if s.region_term} == {"paper", "routed", "foresight"}
    assert {n for n, s in by_name.items() if s.candidates == "rrt"} == {"rrt_exploration"}
    assert {n for n, s in by_name.items() if s.make_planner} == {"routed", "foresight"}
    routing = ("routed", "foresight")
    for n in routing:
        assert by_name[n].goals == GoalOptions(handover=True, reveal_on_arrival=True)
        assert by_name[n].nav_feedback and STRATEGY_SPECS[n].nav_feedback
    assert all(s.goals == GoalOptions() for n, s in by_name.items() if n not in routing)
    assert not STRATEGY_SPECS["paper"].nav_feedback


def test_no_strategy_name_is_compared_outside_the_registry():
    """`git grep` over the package, the simulator, bench/ and scripts/ (tests may compare)."""
    try:
        out = subprocess.run(["git", "grep", "-nE", r"strategy *(==|!=|in) ", "--",
                              "explore_seg", "sim_bridge", "bench", "scripts"],
                             cwd=ROOT, capture_output=True, text=True, check=False)
    except FileNotFoundError:
        pytest.skip("git is not installed")
    if out.returncode not in (0, 1):
        pytest.skip(f"not a git checkout: {out.stderr.strip()}")
    names = "|".join(s.name for s in BUILTIN)
    hits = [line for line in out.stdout.splitlines()
            if re.search(rf"strategy *(==|!=|in) *['\"]({names})['\"]", line)
            or re.search(r"strategy *(not )?in +[A-Z_]*STRATEGIES\b", line)]
    assert hits == []


def test_each_builtin_strategy_has_its_parameter_dataclass_in_selection_params():
    import dataclasses

    from explore_seg.core.selection.params import (BUILTIN_NAMES, SELECTION_PARTS,
                                                   GoalParams, SelectionParams)

    assert BUILTIN_NAMES == tuple(s.name for s in BUILTIN)
    owned = {s.name: s.params for s in BUILTIN}
    assert owned["nearest"] is None
    for name, cls in owned.items():
        if cls is not None:
            assert cls in SELECTION_PARTS and issubclass(SelectionParams, cls), name
    # the parts partition SelectionParams' fields: each field is one part's, once
    seen: list[str] = []
    for part in SELECTION_PARTS:
        seen += [f.name for f in dataclasses.fields(part)]
    assert sorted(seen) == sorted(f.name for f in dataclasses.fields(SelectionParams))
    assert len(seen) == len(set(seen))
    assert "progress_timeout_s" in {f.name for f in dataclasses.fields(GoalParams)}
    # each part validates its own fields, alone and inside SelectionParams
    with pytest.raises(ValueError, match="alpha must be finite and >= 0"):
        owned["paper"](alpha=-1.0)
    with pytest.raises(ValueError, match="handover_m must be finite and >= 0"):
        SelectionParams(handover_m=-1.0)
    with pytest.raises(ValueError, match="progress_timeout_s must be finite and > 0"):
        SelectionParams(progress_timeout_s=0.0)
