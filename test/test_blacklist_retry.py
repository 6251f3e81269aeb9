"""Blacklisted goals retried once the map near them changed (selection/blacklist.py,
GoalManager.retry_changed): a goal that failed on a noisy map (a doorway closed by a
doubled wall, speckle) gets another chance when later scans or a loop-closure re-render
change the map there, not only at the blacklist retry before DONE."""

from __future__ import annotations

import numpy as np

from explore_seg.core.explorer import Explorer
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.selection import Action, NavOutcome
from explore_seg.core.selection.areas import AreaCounts
from explore_seg.core.selection.blacklist import Blacklist, near_counts
from selection_cases import split_params

# Room A (robot R) and room B joined by an open doorway; room B opens onto unknown space.
ROOMS = """
###############
#.............#
#.............#
#...R.........#
#.............#
#.............#
####.......####
#.............#
#.............#
#.............#
#.............#
#.............#
#?????????????#
###############
"""


def _scene(**kw):
    g, marks = grid_from_ascii(ROOMS, resolution_m=0.1)
    params = dict(strategy="nearest", robot_radius_m=0.2, min_group_size_cells=1,
                  path_block_cells=1, blacklist_retries=0, done_confirmations=3,
                  turn_looks=0)
    params.update(kw)
    fp, sp = split_params(**params)
    x, y = g.cell_to_world(*marks["R"][0])
    return g, (x, y, 0.0), Explorer(fp, sp), sp


def _blacklisted(ex, g, pose):
    """The first goal, rejected by the navigator: blacklisted."""
    goal = ex.step(0.0, g, pose).goal
    assert ex.report_navigation(NavOutcome.REJECTED, goal)
    out = ex.step(1.0, g, pose)
    assert out.action is Action.WAIT and ex.manager.blacklist == (goal.xy_m,)
    return goal


def _changed_near(g, goal, k):
    """``g`` with ``k`` free cells next to the goal turned occupied (as a re-render
    that moved a wall would), the frontier kept."""
    data = g.data.copy()
    r, _ = g.world_to_cell(*goal.xy_m)
    # room B's side walls thickened, rows r - 1 .. r + 3 (the frontier's row stays)
    cells = [(r + i, c) for c in (1, 13, 2, 12) for i in range(-1, 4)][:k]
    assert len(cells) == k and all(data[rc] == 0 for rc in cells)
    for rc in cells:
        data[rc] = 100
    return g.with_data(data)


def test_a_blacklisted_goal_is_retried_once_the_map_near_it_changed():
    g, pose, ex, sp = _scene()
    goal = _blacklisted(ex, g, pose)
    assert ex.step(2.0, g.with_data(g.data.copy()), pose).action is Action.WAIT  # same map
    cells = int(np.ceil(sp.retry_change_m2 / g.resolution_m ** 2))
    out = ex.step(3.0, _changed_near(g, goal, cells), pose)
    assert ex.manager.blacklist == ()
    assert out.action is Action.NEW_GOAL and np.hypot(out.goal.xy_m[0] - goal.xy_m[0],
                                                      out.goal.xy_m[1] - goal.xy_m[1]) < 1.0


def test_a_small_change_or_retry_change_m2_0_keeps_the_goal_blacklisted():
    g, pose, ex, sp = _scene()
    goal = _blacklisted(ex, g, pose)
    cells = int(np.ceil(sp.retry_change_m2 / g.resolution_m ** 2))
    ex.step(2.0, _changed_near(g, goal, cells - 1), pose)
    assert ex.manager.blacklist == (goal.xy_m,)
    g, pose, ex, sp = _scene(retry_change_m2=0.0)
    goal = _blacklisted(ex, g, pose)
    ex.step(2.0, _changed_near(g, goal, 20), pose)
    assert ex.manager.blacklist == (goal.xy_m,)


def test_retries_on_a_map_change_per_area_are_limited():
    g, pose, ex, sp = _scene(change_retries=1)
    goal = _blacklisted(ex, g, pose)
    changed = _changed_near(g, goal, 20)
    assert ex.step(2.0, changed, pose).action is Action.NEW_GOAL      # retried once
    again = ex.step(3.0, changed, pose).goal
    assert ex.report_navigation(NavOutcome.REJECTED, again)
    ex.step(4.0, changed, pose)
    ex.step(5.0, g, pose)                      # changed back: no second retry here
    assert len(ex.manager.blacklist) == 1


def test_counts_ignore_a_small_shift_and_see_an_opened_doorway():
    data = np.zeros((60, 60), np.int8)
    data[30, :] = 100                          # a wall across
    data[40:, :] = -1
    g = GridMap(data, 0.05, (0.0, 0.0))
    bl = Blacklist(5)
    bl.add((1.5, 1.4))
    assert bl.changed(g, 0.5, 65, 10) == []
    shifted = np.roll(data, 1, axis=1)         # the map re-rendered 5 cm to the side
    assert bl.changed(g.with_data(shifted), 0.5, 65, 10) == []
    opened = data.copy()
    opened[30, 25:35] = 0                      # a doorway in the wall
    assert bl.changed(g.with_data(opened), 0.5, 65, 10) == [(1.5, 1.4)]
    assert near_counts(g, (1.5, 1.4), 0.5, 65) == (19, 0)   # the wall 2 cells off: 2 * 9 + 1
    areas = AreaCounts()
    assert bl.drop_changed(g.with_data(opened), (0.5, 65, 10), areas, 1) == 1
    assert len(bl) == 0 and areas.count_near((1.5, 1.4), 0.5) == 1
