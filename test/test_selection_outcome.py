"""Navigation outcomes reported to the goal manager / Explorer (Nav2 action status)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.selection import Action, GoalManager, NavOutcome, SelectionParams
from selection_cases import manager_world


@pytest.mark.parametrize("outcome", [NavOutcome.REJECTED, NavOutcome.CANCELED])
def test_failed_outcome_blacklists_at_once_and_the_next_step_picks_another(outcome):
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert m.report_navigation(outcome, goal.xy_m)
    assert m.goal is None and m.blacklist == (fr[0].point_xy_m,)
    res = m.step(0.5, (1.0, 1.0), g, fr, [1.0, 3.0])     # 0.5 s later, not 30 s
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert res.reason == f"navigation {outcome.value}: blacklisted"


def test_abort_of_a_goal_the_map_has_a_path_to_is_blacklisted_at_the_next_step():
    # The navigator and the explorer's map disagree: a retry would repeat the abort.
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert m.report_navigation(NavOutcome.ABORTED, goal.xy_m)
    assert m.goal is None and m.blacklist == ()          # judged on the next map
    res = m.step(0.5, (1.0, 1.0), g, fr, [1.0, 3.0])     # 0.5 s later, not 30 s
    assert m.blacklist == (fr[0].point_xy_m,)
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert res.reason == ("navigation aborted, but the map has a path to its frontier: "
                          "blacklisted")


def test_abort_with_no_path_on_the_map_either_waits_for_the_map_to_open_one():
    # Map noise closed a doorway after the goal was sent: the navigator aborts "no path"
    # and the explorer's map has none either. The frontier is not blacklisted: it is no
    # candidate while it has no path, and a goal again once the map opens the doorway.
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1,
                                    blacklist_retries=0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert goal.xy_m == fr[0].point_xy_m
    assert m.report_navigation(NavOutcome.ABORTED, goal.xy_m)
    res = m.step(1.0, (1.0, 1.0), g, fr, [np.inf, 3.0])
    assert m.blacklist == ()
    assert res.reason == ("navigation aborted, and the map has no path to its frontier: "
                          "it waits")
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    res = m.step(2.0, (1.0, 1.0), g, fr, [1.0, 3.0])     # the doorway opened again
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[0].point_xy_m


def test_aborts_with_no_path_are_bounded_per_area_then_blacklisted():
    # A doorway that opens and closes (noise mapped into it, cleared, mapped again): the
    # frontier behind it is chosen and aborted abort_retries times, then blacklisted.
    g, fr = manager_world()
    p = SelectionParams(strategy="nearest", abort_retries=3)
    m = GoalManager(p)
    t, reasons = 0.0, []
    for _ in range(10):
        res = m.step(t, (1.0, 1.0), g, fr, [1.0, 3.0])   # the doorway is open
        if res.goal.xy_m != fr[0].point_xy_m:
            break
        assert m.report_navigation(NavOutcome.ABORTED, res.goal.xy_m)
        reasons.append(m.step(t + 0.5, (1.0, 1.0), g, fr, [np.inf, 3.0]).reason)
        t += 1.0
    assert res.goal.xy_m == fr[1].point_xy_m
    assert len(reasons) == p.abort_retries
    assert reasons[-1] == ("navigation aborted 3 times here with no path on the map either: "
                           "area blacklisted")
    assert m.blacklist == (fr[0].point_xy_m,) * p.abort_retries


def test_abort_retries_0_blacklists_every_abort_at_once():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", abort_retries=0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert m.report_navigation(NavOutcome.ABORTED, goal.xy_m)
    assert m.goal is None and m.blacklist == (fr[0].point_xy_m,)
    with pytest.raises(ValueError, match="abort_retries must be >= 0, got -1"):
        SelectionParams(abort_retries=-1)


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
