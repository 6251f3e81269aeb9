"""Turn looks (explore_seg.core.selection.areas, GoalManager): before exploration ends,
the robot turns in place so that a keyframe map (slam_toolbox's: a scan after 0.5 m or
0.5 rad of motion) gains a scan from where it stands; a doorway closed only by map noise
opens again and exploration goes on."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.selection import Action, GoalManager, NavOutcome
from explore_seg.core.selection.areas import TURN_LOOK_RAD, turn_goal, turned
from selection_cases import split_params

# Room A (robot R) and room B joined by a doorway that one noise cell (*) closes for a
# robot of radius 0.2 m; room B opens onto unknown space (a frontier).
DOORWAY = """
###############
#.............#
#.............#
#...R.........#
#.............#
#.............#
####...*...####
#.............#
#.............#
#.............#
#.............#
#.............#
#?????????????#
###############
"""


def _scene(**kw):
    noisy, marks = grid_from_ascii(DOORWAY.replace("*", "#"), resolution_m=0.1)
    clear, _ = grid_from_ascii(DOORWAY.replace("*", "."), resolution_m=0.1)
    # no approach goals: the turn alone
    params = dict(strategy="nearest", robot_radius_m=0.2, min_group_size_cells=1,
                  path_block_cells=1, blacklist_retries=0, done_confirmations=1,
                  speckle_max_cells=0, lookout_goals=False)
    params.update(kw)
    fp, sp = split_params(**params)
    x, y = noisy.cell_to_world(*marks["R"][0])
    return noisy, clear, (x, y, 0.3), Explorer(fp, sp), sp


def _stamped(g, t_s):
    """``g`` stamped ``t_s`` (a newer map with the same cells)."""
    return GridMap(g.data.copy(), g.resolution_m, g.origin_xy_m, g.origin_yaw_rad,
                   g.frame_id, int(round(t_s * 1e9)))


def test_a_turn_that_clears_the_noise_lets_exploration_go_on():
    noisy, clear, pose, ex, sp = _scene()
    out = ex.step(0.0, noisy, pose)
    assert np.isinf(out.dist_m).all()
    assert out.action is Action.NEW_GOAL and out.goal.is_turn and "turning" in out.reason
    assert out.goal.xy_m == pytest.approx(pose[:2])
    assert math.cos(out.goal.yaw_rad - pose[2]) == pytest.approx(-1.0)   # half a turn
    assert ex.step(1.0, noisy, pose).action is Action.KEEP               # turning
    after = (pose[0], pose[1], out.goal.yaw_rad + 0.1)
    assert ex.step(2.0, noisy, after).action is Action.KEEP              # map not yet newer
    # The map of the turn's keyframe: the doorway's noise cleared.
    nxt = ex.step(5.0, _stamped(clear, 4.0), after)
    assert nxt.action is Action.NEW_GOAL and not nxt.goal.is_turn
    assert np.isfinite(nxt.dist_m).any() and nxt.blacklisted == 0 and not ex.done


def test_turns_per_area_then_done_without_blacklisting():
    noisy, _, pose, ex, sp = _scene(turn_looks=2)
    t, yaw, turns = 0.0, pose[2], 0
    for _ in range(20):
        out = ex.step(t, _stamped(noisy, t), (pose[0], pose[1], yaw))
        if out.action is Action.DONE:
            break
        if out.action is Action.NEW_GOAL:
            assert out.goal.is_turn
            turns += 1
            yaw = out.goal.yaw_rad            # the navigator turns at once
            ex.report_navigation(NavOutcome.SUCCEEDED, out.goal)
        t += 1.0
    assert out.action is Action.DONE and turns == 2
    assert ex.manager.blacklist_added == 0


def test_a_turn_the_navigator_aborts_is_dropped_not_blacklisted():
    noisy, _, pose, ex, sp = _scene(turn_looks=1, abort_retries=3)
    goal = ex.step(0.0, noisy, pose).goal
    assert goal.is_turn
    assert ex.report_navigation(NavOutcome.ABORTED, goal)
    out = ex.step(1.0, noisy, pose)
    assert ex.manager.blacklist_added == 0 and ex.manager.goal is None
    assert out.action is Action.DONE                   # one turn per area, then done


def test_a_turn_not_done_in_time_is_given_up():
    noisy, _, pose, ex, sp = _scene(turn_looks=1)
    assert ex.step(0.0, noisy, pose).goal.is_turn
    assert ex.step(sp.progress_timeout_s - 1.0, noisy, pose).action is Action.KEEP
    out = ex.step(sp.progress_timeout_s + 1.0, noisy, pose)   # never turned
    assert ex.manager.blacklist_added == 0
    assert out.action is Action.DONE


def test_no_turn_when_nothing_is_left():
    _, clear, pose, ex, sp = _scene(turn_looks=2)
    explored = clear.with_data(np.where(clear.data < 0, 100, clear.data).astype(np.int8))
    out = ex.step(0.0, explored, pose)
    assert not out.frontiers and out.action is Action.DONE


def test_no_turn_without_a_heading_or_with_turn_looks_0():
    noisy, _, pose, ex, sp = _scene(turn_looks=0)
    assert ex.step(0.0, noisy, pose).action is Action.DONE
    m = GoalManager(replace(sp, turn_looks=2))
    # a bare GoalManager step without the robot's heading: no turn
    assert m.step(0.0, pose[:2], noisy, [], []).action is Action.DONE


def test_turn_goal_is_half_a_turn_and_turned_within_tolerance():
    g = turn_goal((1.0, 2.0), 3.0, (20, 10))
    assert g.is_turn and g.xy_m == (1.0, 2.0) and g.rc == (20, 10)
    assert math.cos(g.yaw_rad - 3.0 - TURN_LOOK_RAD) == pytest.approx(1.0)
    assert -math.pi <= g.yaw_rad <= math.pi
    assert turned(g, g.yaw_rad + 0.2, 0.3) and not turned(g, g.yaw_rad + 0.4, 0.3)
    assert not turned(g, None, 0.3)
