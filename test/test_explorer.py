"""The decision core (explore_seg.core.explorer.Explorer): detection, distances and the
strategies wired once, as the node and the lock step call it (incl. the paper's Fig. 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.explorer import (WARN_LABELS_SHAPE, WARN_LAYER_FRAME,
                                       WARN_ROBOT_BLOCKED, WARN_ROBOT_OUTSIDE, Explorer,
                                       detect_frontiers)
from explore_seg.core.frontiers import find_frontiers
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.selection import Action, GoalManager, PathGraphs, StepInputs
from selection_cases import BASE, RES, fig2, split_params


def pipeline(g: GridMap, robot_rc, params, labels=None, extra=None):
    """One Explorer step from ``robot_rc``: (frontiers, distances, selection)."""
    fp, sp = params
    layer = None if extra is None else g.with_data(np.where(extra, 100, 0).astype(np.int8))
    xy = g.cell_to_world(*robot_rc)
    out = Explorer(fp, sp).step(0.0, g, (xy[0], xy[1], 0.0), layer, labels)
    return out.frontiers, out.dist_m, out.selection


def chosen_size(strategy: str, with_labels: bool, block: int = 1) -> int:
    g, robot, labels = fig2()
    params = split_params(strategy=strategy, **{**BASE, "path_block_cells": block})
    fr, _, sel = pipeline(g, robot, params, labels if with_labels else None)
    assert sel.index is not None
    return fr[sel.index].size_cells


def test_fig2_frontiers_and_distances():
    g, robot, labels = fig2()
    fr, dist, sel = pipeline(g, robot, split_params(**BASE), labels)
    assert sorted(f.size_cells for f in fr) == [3, 11]
    small = next(i for i, f in enumerate(fr) if f.size_cells == 3)
    big = 1 - small
    assert fr[big].point_rc == (6, 21) and fr[small].point_rc == (10, 1)
    assert dist[big] == pytest.approx((7 + math.sqrt(2)) * RES)   # through the door
    assert dist[small] == pytest.approx((7 + 5 * math.sqrt(2)) * RES)
    assert sel.robot_region == 1 and sel.regions[small] == 1 and sel.regions[big] == 2
    assert sel.region_gain_active


@pytest.mark.parametrize("strategy,with_labels,size", [
    ("nearest", True, 11),         # switches rooms
    ("explore_lite", True, 11),
    ("paper", False, 11),          # without regions the big near frontier wins
    ("paper", True, 3),            # regionGain: finish room A first
])
def test_fig2_strategy_choice(strategy, with_labels, size):
    assert chosen_size(strategy, with_labels) == size


def test_fig2_paper_choice_holds_with_block_distances():
    assert chosen_size("paper", True, block=4) == 3
    assert chosen_size("nearest", True, block=4) == 11


def test_region_gain_off_without_labels_is_flagged():
    g, robot, _ = fig2()
    _, _, sel = pipeline(g, robot, split_params(**BASE), None)
    assert not sel.region_gain_active and sel.robot_region == 0



def test_dist_inf_when_object_blocks_the_corridor():
    g, marks = grid_from_ascii("""
    ##########
    #R......??
    ##########
    """, resolution_m=RES)
    params = split_params(robot_radius_m=0.0, min_group_size_cells=1, path_block_cells=1)
    fr, dist, _ = pipeline(g, marks["R"][0], params)
    assert len(fr) == 1 and dist[0] == pytest.approx(0.6)
    extra = np.zeros(g.shape, bool)
    extra[1, 4] = True
    fr, dist, sel = pipeline(g, marks["R"][0], params, extra=extra)
    assert len(fr) == 1 and np.isinf(dist[0]) and sel.index is None


def test_dist_inf_for_frontier_in_unreachable_pocket():
    g, marks = grid_from_ascii("""
    ##########
    #R..#..???
    #...#..???
    ##########
    """, resolution_m=RES)
    params = split_params(robot_radius_m=0.0, min_group_size_cells=1, path_block_cells=2)
    fr, dist, sel = pipeline(g, marks["R"][0], params)
    assert len(fr) == 1 and np.isinf(dist[0]) and sel.index is None


def test_robot_on_inflated_cell_starts_from_nearest_passable():
    g, _ = grid_from_ascii("""
    #####??
    #.....?
    #.....?
    #.....?
    #######
    """, resolution_m=RES)
    params = split_params(robot_radius_m=0.1, min_group_size_cells=1, path_block_cells=1)
    fr, dist, _ = pipeline(g, (3, 1), params)   # touching the corner walls
    assert len(fr) == 1 and np.isfinite(dist[0])
    far = split_params(robot_radius_m=0.1, min_group_size_cells=1, path_block_cells=1,
                       start_search_radius_m=0.0)
    fp, sp = far
    xy = g.cell_to_world(3, 1)
    out = Explorer(fp, sp).step(0.0, g, (xy[0], xy[1], 0.0))
    assert out.dist_m is None and out.action is Action.WAIT
    assert [k for k, _ in out.warnings] == [WARN_ROBOT_BLOCKED]


HIDDEN_POCKET = """
####################
#????...#.....?????#
#.......#.....?????#
#.......?.....?????#
#...R...?.....?????#
#.......?.....?????#
#.......#.....?????#
#.......#.....?????#
####################
"""


def test_blacklisted_reachable_frontier_does_not_hide_one_behind_unknown_cells():
    g, marks = grid_from_ascii(HIDDEN_POCKET, resolution_m=RES)
    robot = marks["R"][0]
    fp, sp = split_params(strategy="nearest", done_confirmations=1, blacklist_retries=0,
                          **{**BASE, "min_group_size_cells": 4})
    fr = find_frontiers(g, None, fp)
    top = [i for i, f in enumerate(fr) if f.centroid_rc[1] < 8]
    pocket = [i for i, f in enumerate(fr) if f.centroid_rc[1] > 12]
    assert len(fr) == 2 and len(top) == len(pocket) == 1
    graphs = PathGraphs(g, None, fp, sp)
    d = graphs.distances(robot, fr)
    assert np.isfinite(d[top[0]]) and np.isinf(d[pocket[0]])   # known space only
    x, y = g.cell_to_world(*robot)
    ex = Explorer(fp, sp)
    ex.manager.add_to_blacklist(fr[top[0]].point_xy_m)
    # Before the fix the reachable (blacklisted) F1 kept the fallback off: DONE at 0 %.
    out = ex.step(0.0, g, (x, y, 0.0))
    assert np.isfinite(out.dist_m[pocket[0]])
    assert out.action is Action.NEW_GOAL
    assert out.goal.xy_m == pytest.approx(fr[pocket[0]].point_xy_m)
    # Without the exclusion mask, the old behaviour: no candidate, DONE.
    m2 = GoalManager(sp)
    m2.add_to_blacklist(fr[top[0]].point_xy_m)
    assert m2.step(0.0, (x, y), g, fr, graphs.distances(robot, fr),
                   StepInputs(robot_rc=robot)).action is Action.DONE


# -------------------------------------------------------------- the decision API itself

CORRIDOR = """
##########
#R.......?
#........?
##########
"""


def _corridor():
    g, marks = grid_from_ascii(CORRIDOR, resolution_m=RES)
    x, y = g.cell_to_world(*marks["R"][0])
    fp, sp = split_params(strategy="nearest", robot_radius_m=0.0, min_group_size_cells=1)
    return g, (x, y, 0.0), Explorer(fp, sp)


def test_frontiers_and_paths_are_cached_per_map_and_layer_object():
    g, pose, ex = _corridor()
    first = ex.step(0.0, g, pose)
    assert first.detected and first.action is Action.NEW_GOAL and len(first.frontiers) == 1
    again = ex.step(1.0, g, pose)
    assert not again.detected and again.frontiers is first.frontiers
    assert again.action is Action.KEEP
    layer = g.with_data(np.zeros_like(g.data))
    assert ex.step(2.0, g, pose, layer).detected          # a new layer object
    # an equal map (a republished one) reuses the products; a changed one does not
    assert not ex.step(3.0, g.with_data(g.data.copy()), pose, layer).detected
    changed = g.data.copy()
    changed[1, 9] = 0                                    # a frontier cell seen free
    assert ex.step(4.0, g.with_data(changed), pose, layer).detected


def test_object_layer_blocks_and_a_layer_in_another_frame_is_ignored():
    g, pose, ex = _corridor()
    data = np.zeros_like(g.data)
    data[1:3, 5] = 100                                     # an object across the corridor
    out = ex.step(0.0, g, pose, g.with_data(data))
    assert out.selection.index is None and np.isinf(out.dist_m).all()
    other = GridMap(data, g.resolution_m, g.origin_xy_m, frame_id="odom")
    out = Explorer(ex.frontier_params, ex.selection_params).step(0.0, g, pose, other)
    assert out.action is Action.NEW_GOAL
    assert [k for k, _ in out.warnings] == [WARN_LAYER_FRAME]


def test_robot_outside_the_map_keeps_no_goal_and_warns():
    g, _, ex = _corridor()
    out = ex.step(0.0, g, (50.0, 50.0, 0.0))
    assert out.action is Action.WAIT and out.dist_m is None
    assert [k for k, _ in out.warnings] == [WARN_ROBOT_OUTSIDE]


def test_labels_of_another_shape_are_ignored_with_a_warning():
    g, pose, ex = _corridor()
    out = ex.step(0.0, g, pose, labels=np.ones((2, 2), np.int32))
    assert out.action is Action.NEW_GOAL
    assert [k for k, _ in out.warnings] == [WARN_LABELS_SHAPE]


def test_step_reports_blacklisting_and_done():
    g, marks = grid_from_ascii(CORRIDOR, resolution_m=RES)
    x, y = g.cell_to_world(*marks["R"][0])
    fp, sp = split_params(strategy="nearest", robot_radius_m=0.0, min_group_size_cells=1,
                          blacklist_retries=0, done_confirmations=3, turn_looks=0)
    ex = Explorer(fp, sp)
    assert ex.step(0.0, g, (x, y, 0.0)).action is Action.NEW_GOAL
    out = ex.step(sp.progress_timeout_s + 1.0, g, (x, y, 0.0))   # no progress: blacklisted
    assert out.blacklisted == 1 and "no progress" in out.reason
    assert out.action is Action.WAIT and ex.manager.blacklist_added == 1
    later = [ex.step(sp.progress_timeout_s + 2.0 + k, g, (x, y, 0.0)) for k in range(3)]
    assert [o.action for o in later] == [Action.WAIT, Action.DONE, Action.DONE]
    assert all(o.blacklisted == 0 for o in later) and ex.done


def test_switch_to_a_cheaper_frontier_is_reported():
    g, marks = grid_from_ascii("""
    ###########
    ?.........?
    ?.........?
    #.R.......#
    ###########
    """, resolution_m=RES)
    fp, sp = split_params(strategy="nearest", robot_radius_m=0.0, min_group_size_cells=1,
                          hysteresis_margin=0.0, goal_change_min_m=0.0)
    ex = Explorer(fp, sp)
    x, y = g.cell_to_world(*marks["R"][0])
    first = ex.step(0.0, g, (x, y, 0.0))
    assert first.action is Action.NEW_GOAL and not first.switched
    near_left = first.goal.xy_m
    # drive towards the right end: the right frontier becomes the nearer one
    x2, y2 = g.cell_to_world(2, 8)
    out = ex.step(1.0, g, (x2, y2, 0.0))
    assert out.action is Action.NEW_GOAL and out.goal.xy_m != near_left
    assert out.switched and out.blacklisted == 0


def test_detect_frontiers_is_what_the_explorer_sees():
    g, pose, ex = _corridor()
    det = detect_frontiers(g, None, ex.frontier_params)
    out = ex.step(0.0, g, pose)
    assert [f.point_rc for f in det.frontiers] == [f.point_rc for f in out.frontiers]
    assert det.passable.shape == g.shape and det.extra_obstacles is None
