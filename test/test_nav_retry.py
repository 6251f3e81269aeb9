"""Navigation failures on a noisy map (issue #54): a goal the navigator failed comes off
the blacklist on a newer map, ``nav_failure_retries`` times per goal area, then stays."""

from __future__ import annotations

from dataclasses import replace

from explore_seg.core.explorer import Explorer
from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.selection import Action, NavOutcome
from selection_cases import split_params

ROOM = """
##########
#........#
#..R.....#
#........#
#........#
#........?
#........?
#........?
##########
"""


def _scene(**kw):
    g, marks = grid_from_ascii(ROOM, resolution_m=0.1)
    params = dict(strategy="nearest", robot_radius_m=0.2, min_group_size_cells=1,
                  path_block_cells=1, blacklist_retries=0, done_confirmations=1,
                  speckle_max_cells=0)
    params.update(kw)
    fp, sp = split_params(**params)
    x, y = g.cell_to_world(*marks["R"][0])
    return replace(g, stamp_ns=1), (x, y, 0.0), Explorer(fp, sp)


def test_without_retries_a_navigation_failure_ends_exploration():
    g, pose, ex = _scene(nav_failure_retries=0)
    assert ex.step(0.0, g, pose).action is Action.NEW_GOAL
    assert ex.report_navigation(NavOutcome.ABORTED)
    assert ex.step(1.0, replace(g, stamp_ns=2), pose).action is Action.DONE


def test_a_failed_goal_is_retried_on_a_newer_map_only_then_stays_blacklisted():
    g, pose, ex = _scene(nav_failure_retries=2)
    first = ex.step(0.0, g, pose)
    assert first.action is Action.NEW_GOAL
    cur = g
    for k in range(2):
        assert ex.report_navigation(NavOutcome.ABORTED)
        assert ex.step(1.0 + k, cur, pose).action is Action.DONE   # the same map
        assert ex.manager.blacklist
        ex.manager.reset()                           # DONE is final until a reset
        cur = replace(cur, stamp_ns=cur.stamp_ns + 1)
        again = ex.step(1.5 + k, cur, pose)          # a newer map: retried
        assert again.action is Action.NEW_GOAL
        assert again.goal.xy_m == first.goal.xy_m
    assert ex.report_navigation(NavOutcome.ABORTED)  # third failure: retries spent
    assert ex.step(3.0, replace(cur, stamp_ns=cur.stamp_ns + 1), pose).action is Action.DONE


def test_a_goal_canceled_by_us_or_reached_is_not_a_navigation_failure():
    g, pose, ex = _scene(nav_failure_retries=2)
    ex.step(0.0, g, pose)
    assert ex.report_navigation(NavOutcome.CANCELED_BY_US)
    assert not ex.manager.blacklist and not ex._nav_failed
