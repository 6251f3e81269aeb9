"""Approach goals (explore_seg.core.selection.blockage): a doorway closed only by map
speckle (lone occupied cells from scans mapped at a noisy pose) does not end exploration;
the robot drives up to it and looks first."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.selection import Action, NavOutcome
from explore_seg.core.selection.blockage import speckle_cells
from selection_cases import split_params

# Room A (robot R) and room B joined by a 0.7 m doorway (robot radius 0.2 m: passable)
# in which one speckle cell (*) stands; room B opens onto unknown space (a frontier).
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


def _scene(text: str = DOORWAY, **kw):
    g, marks = grid_from_ascii(text.replace("*", "#"), resolution_m=0.1)
    params = dict(strategy="nearest", robot_radius_m=0.2, min_group_size_cells=1,
                  path_block_cells=1, blacklist_retries=0, done_confirmations=1,
                  turn_looks=0)   # the look alone (turn looks: test_turn_look.py)
    params.update(kw)
    fp, sp = split_params(**params)
    x, y = g.cell_to_world(*marks["R"][0])
    return g, (x, y, 0.0), Explorer(fp, sp), sp


def test_the_speckle_cell_walls_the_robot_in():
    g, pose, ex, _ = _scene(speckle_max_cells=0)
    out = ex.step(0.0, g, pose)
    assert len(out.frontiers) >= 1 and np.isinf(out.dist_m).all()
    assert out.action is Action.DONE


def _look(ex, g, pose):
    """The first goal (the frontier itself: the navigator decides) is aborted by the
    navigator with no path on the map either; the next goal is the look."""
    first = ex.step(0.0, g, pose)
    assert first.action is Action.NEW_GOAL
    assert first.goal.rc == ex._frontiers[0].point_rc      # the frontier's own cPoint
    assert ex.report_navigation(NavOutcome.ABORTED, first.goal)
    return ex.step(0.5, g, pose)


def test_walled_in_by_speckle_the_navigator_tries_then_the_robot_approaches_the_doorway():
    g, pose, ex, _ = _scene()
    out = _look(ex, g, pose)
    assert out.action is Action.NEW_GOAL and out.blacklisted == 0
    r, c = out.goal.rc
    assert ex._det.passable[r, c]                     # on the robot's side, reachable
    door = np.argwhere(speckle_cells(g.data >= 65, 2))
    assert len(door) == 1
    dr, dc = door[0]
    assert r > dr                                     # room A's side (rows grow upward)
    # where the path meets the speckle: next to it, within the inflation (0.2 m) + a cell
    assert np.hypot(r - dr, c - dc) * g.resolution_m <= 0.2 + 2 * g.resolution_m + 1e-9
    assert np.isfinite(out.dist_m).any()


def test_an_approach_that_did_not_clear_the_speckle_is_blacklisted_once_then_done():
    g, pose, ex, sp = _scene()
    goal = _look(ex, g, pose).goal
    at = (goal.xy_m[0], goal.xy_m[1], goal.yaw_rad)
    assert ex.step(1.0, g, at).action is Action.KEEP   # arrived: wait for a newer map
    judged = ex.step(1.0 + sp.arrival_wait_s + 0.1, g, at)   # map unchanged
    assert judged.blacklisted == 1
    assert judged.action is Action.DONE


def test_once_the_look_cleared_the_speckle_the_frontier_beyond_is_a_goal():
    g, pose, ex, sp = _scene()
    goal = _look(ex, g, pose).goal
    at = (goal.xy_m[0], goal.xy_m[1], goal.yaw_rad)
    clear, _ = grid_from_ascii(DOORWAY.replace("*", "."), resolution_m=0.1)
    out = ex.step(1.0 + sp.arrival_wait_s + 0.1, clear, at)
    assert out.action in (Action.NEW_GOAL, Action.KEEP)
    assert np.isfinite(out.dist_m).all()


def test_a_piece_larger_than_speckle_max_cells_gets_no_approach():
    """Three cells in a row (a real obstacle: a chair's seat edge, a box) close the
    doorway as far as the explorer knows: DONE as before."""
    g, pose, ex, _ = _scene(DOORWAY.replace("####...*...####", "####..***..####"))
    assert ex.step(0.0, g, pose).action is Action.DONE


def test_speckle_cells_counts_8_connected_pieces():
    occ = np.zeros((6, 8), bool)
    occ[1, 1] = True                      # lone cell
    occ[3, 3] = occ[4, 4] = True          # diagonal pair: one piece of 2
    occ[0:3, 6] = True                    # a piece of 3
    assert speckle_cells(occ, 0).sum() == 0
    assert np.argwhere(speckle_cells(occ, 1)).tolist() == [[1, 1]]
    assert speckle_cells(occ, 2).sum() == 3
    assert speckle_cells(occ, 3).sum() == 6
    with pytest.raises(ValueError, match="max_cells must be >= 0, got -1"):
        speckle_cells(occ, -1)
    with pytest.raises(ValueError, match="occupied must be 2-D"):
        speckle_cells(occ[0], 1)


# Room A (robot R) reaches room B around the right end of their wall; the straight way
# down leads through a 0.3 m gap in that wall (narrower than the robot: radius 0.2 m),
# then room B's 0.3 m doorway to room C and its unknown space. Map noise narrows a
# doorway like these (ragged wall edges joined to the wall: no speckle).
DETOUR = """
########################
#......................#
#......................#
#.........R............#
#......................#
#......................#
#......................#
#########...######.....#
#......................#
#......................#
#......................#
#......................#
#......................#
#########...############
#......................#
#......................#
#??????????????????????#
########################
"""


def test_a_passage_narrowed_below_the_robot_width_gets_an_approach_at_its_near_side():
    """On the relaxed map (robot radius approach_radius_m, 0.15 m by default) both gaps
    are open; the approach is the last reachable cell of that path (room B above its
    doorway), not where the path first leaves the robot's reach (the gap next to it)."""
    g, pose, ex, sp = _scene(DETOUR)
    assert sp.approach_radius_m < 0.2
    out = _look(ex, g, pose)
    assert out.action is Action.NEW_GOAL
    r, c = out.goal.rc
    assert ex._det.passable[r, c]
    door_r = g.height - 1 - DETOUR.strip("\n").split("\n").index("#########...############")
    assert r == door_r + 1 and 9 <= c <= 11            # next to room B's doorway
    assert out.dist_m[0] > 2.0                           # the way around, through room B


def test_at_the_robot_radius_only_speckle_opens_a_passage():
    g, pose, ex, _ = _scene(DETOUR, approach_radius_m=0.2)
    assert ex.step(0.0, g, pose).action is Action.DONE


def test_a_doorway_closed_by_an_object_layer_box_gets_an_approach():
    """A box of the object layer (depth points of a wall mapped at a drifted pose) closes
    the doorway: the navigator tries the frontier, then the robot drives up to the box to
    look (the layer clears a box its camera sees through), instead of ending."""
    text = DOORWAY.replace("*", ".")
    g, pose, ex, _ = _scene(text, approach_keeps_objects=False)
    row = int(np.flatnonzero((g.data == 0).sum(axis=1) == 7)[0])    # the doorway's row
    data = np.zeros_like(g.data)
    data[row, :] = 100
    layer = g.with_data(data)
    first = ex.step(0.0, g, pose, layer)
    assert first.action is Action.NEW_GOAL and first.goal.rc == ex._frontiers[0].point_rc
    assert ex.report_navigation(NavOutcome.ABORTED, first.goal)
    look = ex.step(0.5, g, pose, layer)
    assert look.action is Action.NEW_GOAL and look.blacklisted == 0
    r, _ = look.goal.rc
    assert ex._det.passable[look.goal.rc] and 0 < r - row <= 4   # room A's side, at the box
    _, _, keeps, _ = _scene(text, approach_keeps_objects=True)
    assert keeps.step(0.0, g, pose, layer).action is Action.DONE


# DOORWAY with its doorway walled up: walls mapped again at a pose that drifted by a
# door's width close the doorway the robot came in through (no speckle: a solid wall).
WALLED = DOORWAY.replace("####...*...####", "###############")


def _walk_in(ex, g_open, pose):
    """The robot drives from room B (below) through the doorway to R, one decision every
    0.1 m on the open map; returns the decision time after the walk."""
    door = DOORWAY.strip("\n").split("\n").index("####...*...####")
    g, marks = grid_from_ascii(DOORWAY.replace("*", "."), resolution_m=0.1)
    door_r = g.height - 1 - door
    dx, _ = g.cell_to_world(door_r, 7)
    x0, y0 = dx, g.cell_to_world(door_r - 3, 7)[1]
    t = 0.0
    pts = [(x0, y0 + 0.1 * k) for k in range(int(round((pose[1] - y0) / 0.1)) + 1)]
    pts += [(x0 + (pose[0] - x0) * k / 10, pose[1]) for k in range(1, 11)]
    for x, y in pts:
        ex.step(t, g_open, (x, y, 0.0))
        t += 0.1
    ex.reset(clear_blacklist=False)           # its goal gone (a resume), its path kept
    return t


def test_a_doorway_the_robot_drove_through_gets_an_approach_however_the_map_closed_it():
    """Drift doubled the doorway's walls in the map after the robot drove through it:
    the robot's own path is passable on the relaxed map, so the frontier beyond gets an
    approach (its cPoint: the navigator decides) instead of DONE."""
    open_map, _ = grid_from_ascii(DOORWAY.replace("*", "."), resolution_m=0.1)
    g, pose, ex, _ = _scene(WALLED)
    t = _walk_in(ex, open_map, pose)
    out = ex.step(t, g, pose)
    assert out.action in (Action.NEW_GOAL, Action.KEEP), out.reason
    assert out.goal is not None and out.goal.rc == ex._frontiers[0].point_rc
    assert np.isfinite(out.dist_m).any()


def test_without_the_trail_or_after_a_correction_the_walled_doorway_ends_exploration():
    open_map, _ = grid_from_ascii(DOORWAY.replace("*", "."), resolution_m=0.1)
    g, pose, ex, _ = _scene(WALLED, approach_trail_radius_m=0.0)
    t = _walk_in(ex, open_map, pose)
    assert ex.step(t, g, pose).action is Action.DONE
    # the path was recorded at uncorrected poses: a correction forgets it
    g, pose, ex, _ = _scene(WALLED)
    t = _walk_in(ex, open_map, pose)
    ex.map_corrected(t)
    assert ex.step(t, g, pose).action is Action.DONE
    # a (re)start forgets it too
    g, pose, ex, _ = _scene(WALLED)
    t = _walk_in(ex, open_map, pose)
    ex.reset(clear_blacklist=True)
    assert ex.step(t, g, pose).action is Action.DONE


def test_a_robot_that_never_drove_through_the_wall_gets_no_approach_through_it():
    """The trail opens only where the robot was: standing in room A of the walled map,
    it has no way out."""
    g, pose, ex, _ = _scene(WALLED)
    for k in range(5):
        ex.step(0.1 * k, g, (pose[0] + 0.1 * k, pose[1], 0.0))
    assert ex.step(1.0, g, pose).action is Action.DONE


def _shut_doorway_maps():
    """Room A (the robot's, below), a 0.2 m wall with a 1 m doorway, room B (0.5 m deep)
    and unknown space beyond it; the second map has the doorway shut by a wall that
    drift mapped into it. 0.05 m cells, rows grow upward."""
    data = np.zeros((120, 100), np.int8)
    data[0, :] = data[:, 0] = data[:, 99] = 100
    data[60:64, :] = 100
    data[74:, 1:99] = -1
    opened = data.copy()
    opened[60:64, 40:60] = 0
    return (GridMap(opened, 0.05, (0.0, 0.0)), GridMap(data, 0.05, (0.0, 0.0)))


def _routed(**kw):
    params = dict(strategy="routed", robot_radius_m=0.2, min_group_size_cells=1,
                  path_block_cells=1, blacklist_retries=0, done_confirmations=1,
                  turn_looks=0, viewpoint_radius_m=1.5)
    params.update(kw)
    return Explorer(*split_params(**params))


def _walk_up(ex, g, x, rows):
    for k, r in enumerate(rows):
        ex.step(0.1 * k, g, (x, (r + 0.5) * 0.05, 0.0))
    ex.reset(clear_blacklist=False)


def test_routed_a_group_seen_only_from_beyond_a_shut_doorway_counts_as_unreachable():
    """Room B's frontier is seen from room B alone (unreachable on the shut map); from
    room A a viewpoint sees nothing through the wall. The group keeps its own cPoint with
    no path (so the explorer seeks a way to it) instead of a zero-view viewpoint in room A
    that drops it from the tour."""
    _, shut = _shut_doorway_maps()
    pose = (2.5, 1.0, 0.0)
    out = _routed().step(0.0, shut, pose)
    assert len(out.frontiers) >= 1 and np.isinf(out.dist_m).all()
    assert all(f.point_rc[0] >= 64 for f in out.frontiers)          # room B: its cPoints
    old = _routed(blocked_views_unreachable=False).step(0.0, shut, pose)
    assert np.isfinite(old.dist_m).any()
    assert all(f.point_rc[0] < 60 for f, d in zip(old.frontiers, old.dist_m)
               if np.isfinite(d))                                 # viewpoints in room A
    assert old.action is Action.DONE


def test_routed_the_robot_goes_back_through_the_shut_doorway_it_came_in_by():
    opened, shut = _shut_doorway_maps()
    ex = _routed()
    _walk_up(ex, opened, 2.5, range(69, 19, -2))
    out = ex.step(10.0, shut, (2.5, 1.0, 0.0))
    assert out.action is Action.NEW_GOAL, out.reason
    assert out.goal.rc[0] >= 64                                   # beyond the doorway
    old = _routed(blocked_views_unreachable=False)
    _walk_up(old, opened, 2.5, range(69, 19, -2))
    assert old.step(10.0, shut, (2.5, 1.0, 0.0)).action is Action.DONE
