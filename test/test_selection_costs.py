"""Costs of the three strategies, regions, the choice, and the selection parameters."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.selection import (COST_FUNCTIONS, STRATEGIES, SelectionParams,
                                        SelectorNodeParams, compute_costs, region_at,
                                        select_goal)
from selection_cases import B, make_frontier, two_frontiers

#: The paper's cases (``routed``, the default, needs the Router's tour costs).
PAPER = SelectionParams(strategy="paper")


@pytest.mark.parametrize("strategy,expected", [
    ("paper", [0.25 + B / 0.25, 0.75 + B / 0.75 + 1.0]),
    ("nearest", [1.0, 3.0]),
    ("explore_lite", [3.0 * 1.0 - 10 * 0.05, 3.0 * 3.0 - 30 * 0.05]),
])
def test_cost_formulas(strategy, expected):
    _, fr, labels = two_frontiers()
    costs = compute_costs(fr, [1.0, 3.0], labels, 1, SelectionParams(strategy=strategy))
    assert costs.tolist() == pytest.approx(expected)


def test_unreachable_frontier_costs_inf_and_leaves_the_normalisation():
    g, fr, labels = two_frontiers()
    f2 = make_frontier(2, [(20, 40), (20, 41)], (21, 40), g)
    costs = compute_costs(fr + [f2], [1.0, 3.0, np.inf], labels, 1, PAPER)
    assert np.isinf(costs[2])
    # sizeGain counts every candidate (42 cells), distGain only the reachable ones
    assert costs[:2].tolist() == pytest.approx([0.25 + B * 42 / 10, 0.75 + B * 42 / 30 + 1])


def test_non_passable_cpoint_costs_inf():
    g, fr, labels = two_frontiers()
    blocked = make_frontier(1, fr[1].cells, fr[1].point_rc, g, passable=False)
    costs = compute_costs([fr[0], blocked], [1.0, 3.0], None, 0, PAPER)
    assert np.isfinite(costs[0]) and np.isinf(costs[1])


def test_frontier_without_region_counts_as_same_region():
    _, fr, labels = two_frontiers()
    labels[40:] = 0
    costs = compute_costs(fr, [1.0, 3.0], labels, 1, PAPER)
    assert costs[1] == pytest.approx(0.75 + B / 0.75)


def test_all_unreachable_selects_nothing():
    _, fr, labels = two_frontiers()
    sel = select_goal(fr, [np.inf, np.inf], labels, (1, 1), PAPER)
    assert sel.index is None and np.isinf(sel.costs).all()


def test_excluded_frontier_is_not_chosen():
    _, fr, labels = two_frontiers()
    sel = select_goal(fr, [1.0, 3.0], None, (1, 1), SelectionParams(strategy="nearest"),
                      excluded=np.array([True, False]))
    assert sel.index == 1


@pytest.mark.parametrize("dist,match", [([1.0], "one per frontier"),
                                        ([1.0, np.nan], "NaN or negative"),
                                        ([1.0, -2.0], "NaN or negative")])
def test_bad_distances_raise(dist, match):
    _, fr, labels = two_frontiers()
    with pytest.raises(ValueError, match=match):
        compute_costs(fr, dist, labels, 1, PAPER)


def test_excluded_length_mismatch_raises():
    _, fr, _ = two_frontiers()
    with pytest.raises(ValueError, match="excluded has 1 entries"):
        select_goal(fr, [1.0, 2.0], None, (0, 0), PAPER, excluded=np.array([True]))


def test_region_at_uses_nearest_labelled_cell():
    labels = np.zeros((5, 5), np.int32)
    labels[0, 0] = 3
    labels[4, 4] = 7
    assert region_at(labels, (0, 0), 0) == 3
    assert region_at(labels, (1, 1), 2) == 3
    assert region_at(labels, (2, 2), 1) == 0
    assert region_at(labels, (9, 9), 3) == 0



def test_strategies_are_the_cost_table():
    assert STRATEGIES == tuple(COST_FUNCTIONS) == ("paper", "nearest", "explore_lite",
                                                   "rrt_exploration", "routed",
                                                   "foresight")
    for name in STRATEGIES:
        SelectionParams(strategy=name)


@pytest.mark.parametrize("kwargs,match", [
    ({"strategy": "random"}, "strategy must be one of"),
    ({"alpha": -1.0}, "alpha must be finite and >= 0"),
    ({"progress_timeout_s": 0.0}, "progress_timeout_s must be finite and > 0"),
    ({"path_block_cells": 5}, "path_block_cells must be in"),
    ({"blacklist_max": 0}, "blacklist_max must be >= 1"),
    ({"done_confirmations": 0}, "done_confirmations must be >= 1"),
])
def test_params_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SelectionParams(**kwargs)


def test_selection_params_hold_no_detection_or_node_settings():
    # one home per parameter: detection in FrontierParams, node settings in the node class
    names = {f.name for f in dataclasses.fields(SelectionParams)}
    assert not names & {f.name for f in dataclasses.fields(FrontierParams)}
    assert not names & {"rate_hz", "pose_topic_type", "autostart", "map_transient_local"}



@pytest.mark.parametrize("cls,kwargs,match", [
    (SelectorNodeParams, {"pose_topic_type": "tf"}, "pose_topic_type must be one of"),
    (SelectorNodeParams, {"rate_hz": 0.0}, "rate_hz must be finite and > 0"),
    (SelectorNodeParams, {"strategy": "random"}, "strategy must be one of"),
    (FrontierParams, {"min_group_size_cells": 0}, "min_group_size_cells must be >= 1"),
    (FrontierParams, {"group_connectivity": 6}, "group_connectivity must be 4 or 8"),
])
def test_node_and_detection_params_validation(cls, kwargs, match):
    with pytest.raises(ValueError, match=match):
        cls(**kwargs)
