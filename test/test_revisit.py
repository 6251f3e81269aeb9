"""Revisit goals (explore_seg.core.selection.revisit): after the SLAM corrected the map, a
robot walled in by a wall that drift mapped across a passage drives back to old places of
its path (where a SLAM closes loops) before exploration ends."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.block_graph import BlockGraph
from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import GridMap
from explore_seg.core.selection import Action, NavOutcome
from explore_seg.core.selection.lookout import Reach
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.revisit import MAX_STEP_M, Revisits
from selection_cases import split_params


def _walled_map(doorway: bool = False):
    """Room A (rows 1-14, the robot's) and room B (rows 16-25) of a 7 m wide building,
    with a wall across the doorway between them (row 15; ``doorway``: open from 3 to
    4 m) and unknown space beyond room B: without the doorway the frontier there has no
    path. 0.1 m cells."""
    data = np.zeros((30, 70), np.int8)
    data[0, :] = data[:, 0] = data[:, 69] = 100
    data[15, :] = 100
    if doorway:
        data[15, 30:40] = 0
    data[26:, 1:69] = -1
    return GridMap(data, 0.1, (0.0, 0.0))


def _walk(ex, g, xs, y=0.75, t=0.0):
    """One decision every 0.1 m along ``xs`` at height ``y``; returns the time after."""
    for x in xs:
        ex.step(t, g, (float(x), y, 0.0))
        t += 0.1
    return t


def _explorer(**kw):
    params = dict(strategy="nearest", robot_radius_m=0.2, min_group_size_cells=1,
                  path_block_cells=1, blacklist_retries=0, done_confirmations=1,
                  turn_looks=0, speckle_max_cells=0, lookout_goals=False,
                  revisit_goals=2, revisit_min_travel_m=10.0, revisit_max_path_m=20.0,
                  revisit_spacing_m=3.0)
    params.update(kw)
    fp, sp = split_params(**params)
    return Explorer(fp, sp)


def _there_and_back(ex, g):
    """0.5 -> 6.0 -> 0.5 -> 3.0 m along room A on the map with the doorway (13.5 m of
    travel), then the goal dropped, as on a resume (the path kept)."""
    g = _walled_map(doorway=True)
    t = _walk(ex, g, np.arange(0.5, 6.001, 0.1))
    t = _walk(ex, g, np.arange(5.9, 0.499, -0.1), t=t)
    t = _walk(ex, g, np.arange(0.6, 3.001, 0.1), t=t)
    ex.reset(clear_blacklist=False)
    return t


def test_after_a_correction_the_walled_in_robot_revisits_old_places_then_ends():
    g = _walled_map()
    ex = _explorer()
    t = _there_and_back(ex, g)
    pose = (3.0, 0.75, 0.0)
    ex.map_corrected(t)
    # instead of DONE: the revisit starts, and is the goal at the next decision
    wait = ex.step(t, g, pose)
    assert wait.action is Action.WAIT and "loop closure" in wait.reason, wait.reason
    first = ex.step(t + 1.0, g, pose)
    assert first.action is Action.NEW_GOAL and "a revisit" in first.reason, first.reason
    # the oldest place >= 10 m of travel back within 20 m of path: where it started
    assert math.hypot(first.goal.xy_m[0] - 0.5, first.goal.xy_m[1] - 0.75) < 0.15
    assert ex._det.passable[first.goal.rc]
    # the navigator gives up on it: it is over; the next revisit lies 3 m or more from
    # the first, among places 10 m or more of travel back
    assert ex.report_navigation(NavOutcome.ABORTED, first.goal)
    assert ex.step(t + 2.0, g, pose).action is Action.WAIT
    second = ex.step(t + 3.0, g, pose)
    assert second.action is Action.NEW_GOAL, second.reason
    assert 3.5 - 0.15 <= second.goal.xy_m[0] <= 4.0 + 0.15
    assert ex.report_navigation(NavOutcome.ABORTED, second.goal)
    # revisit_goals (2) spent: exploration ends as before
    actions = [ex.step(t + 4.0 + k, g, pose).action for k in range(3)]
    assert actions[0] is Action.DONE and Action.NEW_GOAL not in actions


def test_a_revisit_comes_after_the_turn_looks_and_the_blacklist_retry():
    """The goal manager's sequence first: waits, turn looks, then the revisit."""
    g = _walled_map()
    ex = _explorer(done_confirmations=2, turn_looks=1)
    t = _there_and_back(ex, g)
    ex.map_corrected(t)
    pose = (3.0, 0.75, 0.0)
    steps = [ex.step(t + k, g, pose) for k in range(3)]
    assert [s.action for s in steps[:2]] == [Action.WAIT, Action.NEW_GOAL]
    assert steps[1].goal.is_turn                    # the turn look first
    assert "loop closure" not in steps[0].reason


def test_without_a_correction_no_revisit():
    """A map the SLAM never corrected (or made at the true poses): its walls would not
    move at a closure, so exploration ends at once."""
    g = _walled_map()
    ex = _explorer()
    t = _there_and_back(ex, g)
    assert ex.step(t, g, (3.0, 0.75, 0.0)).action is Action.DONE


@pytest.mark.parametrize("kw", [dict(revisit_goals=0), dict(revisit_min_travel_m=14.0)])
def test_no_revisit_when_off_or_no_place_is_old_enough(kw):
    g = _walled_map()
    ex = _explorer(**kw)
    t = _there_and_back(ex, g)
    ex.map_corrected(t)
    assert ex.step(t, g, (3.0, 0.75, 0.0)).action is Action.DONE


def test_a_restart_forgets_the_path():
    g = _walled_map()
    ex = _explorer()
    t = _there_and_back(ex, g)
    ex.map_corrected(t)
    ex.reset(clear_blacklist=True)
    ex.map_corrected(t)
    assert ex.step(t, g, (3.0, 0.75, 0.0)).action is Action.DONE


# ---------------------------------------------------------------------- Revisits alone

def _room():
    """A 10 x 2 m room, all passable inside, the robot at its east end; a frontier cell
    outside any path."""
    data = np.full((40, 200), 100, dtype=np.int8)
    data[5:35, 5:195] = 0
    g = GridMap(data, 0.05, (0.0, 0.0))
    passable = np.zeros(data.shape, bool)
    passable[10:30, 10:190] = True
    f = Frontier(1, 3, 0.15, (38, 100), g.cell_to_world(38, 100), False, (38.0, 100.0),
                 g.cell_to_world(38, 100), np.array([[38, 99], [38, 100], [38, 101]]))
    return g, Reach(BlockGraph(passable, 0.05, 1), (20, 180), passable), f


def _out_and_back():
    """Revisits of a robot that drove from x = 1 to 9 m and back at y = 1 m (16 m), on a
    corrected map."""
    r = Revisits()
    for x in np.arange(1.0, 9.01, 0.5):
        r.add(float(x), 1.0)
    for x in np.arange(8.5, 0.99, -0.5):
        r.add(float(x), 1.0)
    r.corrected()
    return r


def _goal(r, g, reach, f, p, blacklist=()):
    """The revisit under way; when none, the next one is started (as at DONE)."""
    args = (g, [f], np.array([np.inf]), reach, np.array([False]), blacklist, p)
    res = r.goals(*args)
    if res is None:
        r.arm()
        res = r.goals(*args)
    return None if res is None else (res[0][0].point_xy_m, float(res[1][0]))


def test_travel_leaves_pose_jumps_out_and_places_are_spaced():
    r = Revisits(spacing_m=0.5)
    for x in np.arange(0.0, 2.01, 0.1):
        r.add(float(x), 0.0)
    r.add(2.0 + MAX_STEP_M + 1.0, 0.0)          # a jump: no travel
    r.add(float("nan"), 0.0)                    # ignored
    assert r.travel_m == pytest.approx(2.0)
    assert len(r) == 6                          # 0, 0.5, ..., 2.0 and the jumped-to place


def test_places_stay_bounded():
    r = Revisits(spacing_m=0.1, max_points=100)
    for k in range(2000):
        r.add(0.1 * k, 0.0)
    assert len(r) < 100 and r.spacing_m > 0.1
    assert r.travel_m == pytest.approx(199.9)
    r.reset()
    assert len(r) == 0 and r.spacing_m == 0.1 and r.travel_m == 0.0


def test_the_nearest_place_when_none_lies_within_the_path_budget():
    g, reach, f = _room()
    r = _out_and_back()
    # 16 m of travel; places >= 10 m back: x = 1.0 .. 7.0 on the way out; the robot's
    # start cell at x = 9
    xy, d = _goal(r, g, reach, f, SelectionParams(revisit_min_travel_m=10.0,
                                                 revisit_max_path_m=1.0))
    assert xy == (7.0, 1.0) and d == pytest.approx(2.0, abs=0.1)


def test_the_revisit_is_kept_until_blacklisted_then_the_next_then_none():
    g, reach, f = _room()
    r = _out_and_back()
    p = SelectionParams(revisit_goals=2, revisit_min_travel_m=5.0, revisit_spacing_m=3.0)
    first, _ = _goal(r, g, reach, f, p)
    assert first == (1.0, 1.0)
    assert _goal(r, g, reach, f, p)[0] == first            # kept while not blacklisted
    second, _ = _goal(r, g, reach, f, p, blacklist=[first])
    assert second == (4.0, 1.0)                             # 3 m on, the oldest there
    assert _goal(r, g, reach, f, p, blacklist=[first, second]) is None
    assert r.targets == (first, second)
    r.progress()                                            # a frontier was selectable
    third, _ = _goal(r, g, reach, f, p, blacklist=[first, second])
    assert third not in (first, second)                     # not at a blacklisted goal


def test_places_off_the_passable_cells_are_skipped():
    g, reach, f = _room()
    r = Revisits()
    r.add(0.1, 0.1)                              # in the wall: not passable
    for x in np.arange(2.0, 9.01, 0.5):
        r.add(float(x), 1.0)
    r.corrected()
    xy, _ = _goal(r, g, reach, f, SelectionParams(revisit_min_travel_m=5.0))
    assert xy == (2.0, 1.0)
    # a blacklisted frontier is left alone; so is one with a path
    r2 = Revisits()
    for x in np.arange(2.0, 9.01, 0.5):
        r2.add(float(x), 1.0)
    r2.corrected()
    args = (g, [f, f], np.array([np.inf, 2.0]), reach, np.array([True, False]), (),
            SelectionParams(revisit_min_travel_m=5.0))
    assert r2.goals(*args) is None and not r2.arm()
