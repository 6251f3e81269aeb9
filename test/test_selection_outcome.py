"""Navigation outcomes reported to the goal manager / Explorer (Nav2 action status)."""

from __future__ import annotations

import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.selection import Action, GoalManager, NavOutcome, SelectionParams
from selection_cases import manager_world


@pytest.mark.parametrize("outcome", [NavOutcome.ABORTED, NavOutcome.REJECTED,
                                     NavOutcome.CANCELED])
def test_failed_outcome_blacklists_at_once_and_the_next_step_picks_another(outcome):
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert m.report_navigation(outcome, goal.xy_m)
    assert m.goal is None and m.blacklist == (fr[0].point_xy_m,)
    res = m.step(0.5, (1.0, 1.0), g, fr, [1.0, 3.0])     # 0.5 s later, not 30 s
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert res.reason == f"navigation {outcome.value}: blacklisted"


def test_outcome_of_another_goal_is_ignored():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest"))
    m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert not m.report_navigation(NavOutcome.ABORTED, (7.0, 7.0))
    assert m.goal is not None and m.blacklist == ()
    assert not GoalManager().report_navigation(NavOutcome.ABORTED)   # no goal at all


def test_our_cancel_drops_the_goal_without_blacklisting():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest"))
    m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert m.report_navigation(NavOutcome.CANCELED_BY_US)
    assert m.goal is None and m.blacklist == ()


def test_succeeded_counts_as_arrival_beyond_the_tolerance():
    # Nav2's goal checker can be looser than goal_reached_tolerance_m (or its planner moved
    # the goal out of a lethal cell): SUCCEEDED still ends the goal and judges its frontier.
    g, fr = manager_world()
    g.data[5, 10:20] = -1          # fr[0]'s cells stay unknown: the visit revealed nothing
    m = GoalManager(SelectionParams(strategy="nearest", goal_reached_tolerance_m=0.01,
                                    arrival_wait_s=2.0))
    m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert m.report_navigation(NavOutcome.SUCCEEDED)
    res = m.step(1.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert res.action is Action.KEEP and "waiting for the map" in res.reason
    res = m.step(3.0, (1.0, 1.0), g, fr, [1.0, 3.0])     # frontier still there: judged
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert m.blacklist == (fr[0].point_xy_m,)


def test_return_goal_aborted_ends_exploration():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1,
                                    return_to_start=True))
    m.step(0.0, (0.5, 0.5), g, fr, [1.0, 3.0])
    assert m.step(1.0, (2.0, 2.0), g, [], []).goal.is_return
    assert m.report_navigation(NavOutcome.ABORTED)
    res = m.step(2.0, (2.0, 2.0), g, [], [])
    assert res.action is Action.DONE and "aborted returning to start" in res.reason


def test_explorer_counts_a_reported_blacklisting_in_the_next_step():
    grid, marks = grid_from_ascii('''
##########
#R.......?
#........?
#?########''', resolution_m=0.1)
    ex = Explorer(FrontierParams(min_group_size_cells=1, robot_radius_m=0.0),
                  SelectionParams(strategy="nearest"))
    pose = (*grid.cell_to_world(*marks["R"][0]), 0.0)
    first = ex.step(0.0, grid, pose)
    assert first.action is Action.NEW_GOAL
    assert ex.report_navigation(NavOutcome.ABORTED, first.goal)
    out = ex.step(0.1, grid, pose)
    assert out.blacklisted == 1 and not out.switched
    assert out.action is Action.NEW_GOAL and out.goal.xy_m != first.goal.xy_m
    assert ex.step(0.2, grid, pose).blacklisted == 0
