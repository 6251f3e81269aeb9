"""Costs, strategies (incl. the paper's Fig. 2 case), hysteresis, blacklist, done."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.frontiers import Frontier, find_frontiers, traversable_mask
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.paths import BlockGraph
from explore_seg.core.selection import (Action, GoalManager, PathGraphs, SelectionParams,
                                        compute_costs, frontier_distances, goal_yaw, region_at,
                                        select_goal)

# Fig. 2 of the paper: the robot R in room A (cols 1..14) next to the door (col 15) into
# room B (cols 16..29). A small frontier (3 cells) is left at A's far left wall; a big one
# (11 cells) borders B's unexplored right half, nearer to the robot.
ROW_A = "?" + "." * 14 + "#" + "." * 6 + "?" * 8 + "#"
ROW = "#" + "." * 14 + "#" + "." * 6 + "?" * 8 + "#"
DOOR = "#" + "." * 14 + "." + "." * 6 + "?" * 8 + "#"
ROBOT = "#" + "." * 12 + "R." + "." + "." * 6 + "?" * 8 + "#"
WALL = "#" * 31
FIG2 = "\n".join([WALL, ROW_A, ROW_A, ROW_A, ROW, ROW, DOOR, ROBOT, DOOR, DOOR, ROW, ROW, WALL])
RES = 0.1
BASE = dict(robot_radius_m=0.1, min_group_size_cells=3, path_block_cells=1)


def fig2():
    g, marks = grid_from_ascii(FIG2, resolution_m=RES)
    labels = np.zeros(g.shape, np.int32)
    free = g.free_mask()
    labels[:, 1:15][free[:, 1:15]] = 1
    labels[:, 16:30][free[:, 16:30]] = 2
    return g, marks["R"][0], labels


def pipeline(g: GridMap, robot_rc, params: SelectionParams, labels=None, extra=None):
    fp = params.frontier_params()
    pas = traversable_mask(g, extra, fp)
    fr = find_frontiers(g, extra, fp, passable=pas)
    dist = frontier_distances(BlockGraph(pas, g.resolution_m, params.path_block_cells),
                              robot_rc, fr, params)
    return fr, dist, select_goal(fr, dist, labels, robot_rc, params)


def chosen_size(strategy: str, with_labels: bool, block: int = 1) -> int:
    g, robot, labels = fig2()
    params = SelectionParams(strategy=strategy, **{**BASE, "path_block_cells": block})
    fr, _, sel = pipeline(g, robot, params, labels if with_labels else None)
    assert sel.index is not None
    return fr[sel.index].size_cells


def test_fig2_frontiers_and_distances():
    g, robot, labels = fig2()
    fr, dist, sel = pipeline(g, robot, SelectionParams(**BASE), labels)
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
    _, _, sel = pipeline(g, robot, SelectionParams(**BASE), None)
    assert not sel.region_gain_active and sel.robot_region == 0


# ------------------------------------------------------------------------------ costs


def make_frontier(fid: int, cells, point_rc, grid: GridMap, passable: bool = True) -> Frontier:
    cells = np.asarray(cells, dtype=np.int64)
    cy, cx = cells.mean(axis=0)
    gx, gy = grid.cells_to_world(np.asarray([cy]), np.asarray([cx]))
    return Frontier(fid, len(cells), len(cells) * grid.resolution_m, tuple(point_rc),
                    grid.cell_to_world(*point_rc), passable, (float(cy), float(cx)),
                    (float(gx[0]), float(gy[0])), cells)


#: The default beta (the formulas below use it).
B = SelectionParams().beta


def two_frontiers(sizes=(10, 30)):
    g = GridMap(np.zeros((60, 60), np.int8), 0.05, (0.0, 0.0))
    f0 = make_frontier(0, [(5, c) for c in range(10, 10 + sizes[0])], (6, 12), g)
    f1 = make_frontier(1, [(50, c) for c in range(10, 10 + sizes[1])], (49, 20), g)
    labels = np.zeros(g.shape, np.int32)
    labels[:30] = 1
    labels[30:] = 2
    return g, [f0, f1], labels


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
    costs = compute_costs(fr + [f2], [1.0, 3.0, np.inf], labels, 1, SelectionParams())
    assert np.isinf(costs[2])
    # sizeGain counts every candidate (42 cells), distGain only the reachable ones
    assert costs[:2].tolist() == pytest.approx([0.25 + B * 42 / 10, 0.75 + B * 42 / 30 + 1])


def test_non_passable_cpoint_costs_inf():
    g, fr, labels = two_frontiers()
    blocked = make_frontier(1, fr[1].cells, fr[1].point_rc, g, passable=False)
    costs = compute_costs([fr[0], blocked], [1.0, 3.0], None, 0, SelectionParams())
    assert np.isfinite(costs[0]) and np.isinf(costs[1])


def test_frontier_without_region_counts_as_same_region():
    _, fr, labels = two_frontiers()
    labels[40:] = 0
    costs = compute_costs(fr, [1.0, 3.0], labels, 1, SelectionParams())
    assert costs[1] == pytest.approx(0.75 + B / 0.75)


def test_all_unreachable_selects_nothing():
    _, fr, labels = two_frontiers()
    sel = select_goal(fr, [np.inf, np.inf], labels, (1, 1), SelectionParams())
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
        compute_costs(fr, dist, labels, 1, SelectionParams())


def test_excluded_length_mismatch_raises():
    _, fr, _ = two_frontiers()
    with pytest.raises(ValueError, match="excluded has 1 entries"):
        select_goal(fr, [1.0, 2.0], None, (0, 0), excluded=np.array([True]))


def test_region_at_uses_nearest_labelled_cell():
    labels = np.zeros((5, 5), np.int32)
    labels[0, 0] = 3
    labels[4, 4] = 7
    assert region_at(labels, (0, 0), 0) == 3
    assert region_at(labels, (1, 1), 2) == 3
    assert region_at(labels, (2, 2), 1) == 0
    assert region_at(labels, (9, 9), 3) == 0


# ----------------------------------------------------------------- distances (dist=inf)


def test_dist_inf_when_object_blocks_the_corridor():
    g, marks = grid_from_ascii("""
    ##########
    #R......??
    ##########
    """, resolution_m=RES)
    params = SelectionParams(robot_radius_m=0.0, min_group_size_cells=1, path_block_cells=1)
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
    params = SelectionParams(robot_radius_m=0.0, min_group_size_cells=1, path_block_cells=2)
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
    params = SelectionParams(robot_radius_m=0.1, min_group_size_cells=1, path_block_cells=1)
    fr, dist, _ = pipeline(g, (3, 1), params)   # touching the corner walls
    assert len(fr) == 1 and np.isfinite(dist[0])
    far = SelectionParams(robot_radius_m=0.1, min_group_size_cells=1, path_block_cells=1,
                          start_search_radius_m=0.0)
    _, dist, _ = pipeline(g, (3, 1), far)
    assert np.isinf(dist[0])


# ------------------------------------------------------------------------ goal manager


def manager_world():
    g, fr, _ = two_frontiers()
    return g, fr


def test_new_goal_heads_to_the_unknown_side():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest"))
    res = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert res.action is Action.NEW_GOAL
    assert res.goal.xy_m == fr[0].point_xy_m
    # from the cPoint (6, 12) to the centroid (5, 14.5) of the group's cells
    assert res.goal.yaw_rad == pytest.approx(math.atan2(-1.0, 2.5))
    assert goal_yaw(fr[0], (1.0, 1.0)) == pytest.approx(res.goal.yaw_rad)


@pytest.mark.parametrize("new_dist,action", [(0.95, Action.KEEP), (0.8, Action.NEW_GOAL)])
def test_hysteresis(new_dist, action):
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", hysteresis_margin=0.1))
    first = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    res = m.step(1.0, (1.0, 1.0), g, fr, [1.0, new_dist])
    assert res.action is action
    assert (res.goal is first) == (action is Action.KEEP)


def test_no_progress_blacklists_goal():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0))
    assert m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal.xy_m == fr[0].point_xy_m
    assert m.step(20.0, (1.0, 1.0), g, fr, [1.0, 3.0]).action is Action.KEEP
    res = m.step(31.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert "no progress" in res.reason
    assert m.blacklist == (fr[0].point_xy_m,)


def test_progress_keeps_goal_alive():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0,
                                    goal_reached_tolerance_m=0.01))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    dx, dy = goal.xy_m[0] - 1.0, goal.xy_m[1] - 1.0
    ux, uy = dx / math.hypot(dx, dy), dy / math.hypot(dx, dy)
    for t in range(1, 50):   # 0.012 m/s toward the goal: 0.1 m of progress every 8.3 s
        pos = (1.0 + 0.012 * t * ux, 1.0 + 0.012 * t * uy)
        res = m.step(float(t), pos, g, fr, [1.0, 3.0])
        assert res.action is Action.KEEP
    assert m.blacklist == ()


def test_goal_reached_with_frontier_left_is_blacklisted_after_the_wait():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", arrival_wait_s=2.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    res = m.step(5.0, goal.xy_m, g, fr, [0.0, 2.0])
    assert res.action is Action.KEEP and "waiting" in res.reason
    res = m.step(7.0, goal.xy_m, g, fr, [0.0, 2.0])
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert m.blacklist == (goal.xy_m,)


def test_goal_reached_judged_at_once_on_a_newer_map():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", arrival_wait_s=100.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert m.step(5.0, goal.xy_m, g, fr, [0.0, 2.0]).action is Action.KEEP
    newer = GridMap(g.data, g.resolution_m, g.origin_xy_m, stamp_ns=10)
    res = m.step(5.5, goal.xy_m, newer, [fr[1]], [2.0])
    assert res.action is Action.NEW_GOAL and m.blacklist == ()


def test_goal_reached_and_frontier_cleared_is_not_blacklisted():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", arrival_wait_s=0.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    res = m.step(5.0, goal.xy_m, g, [fr[1]], [2.0])
    assert res.action is Action.NEW_GOAL and m.blacklist == ()


def test_goal_frontier_match_accounts_for_the_cpoint_gap():
    g, fr = manager_world()
    far = make_frontier(0, fr[0].cells, (25, 12), g)   # cPoint 1 m from its cells
    m = GoalManager(SelectionParams(strategy="nearest", frontier_match_radius_m=0.2))
    first = m.step(0.0, (1.0, 1.0), g, [far, fr[1]], [1.0, 3.0]).goal
    assert first.frontier_gap_m == pytest.approx(1.0)
    res = m.step(1.0, (1.0, 1.0), g, [far, fr[1]], [1.0, 3.0])
    assert res.action is Action.KEEP and res.goal is first


@pytest.mark.parametrize("change_min_m,action", [(0.3, Action.KEEP), (0.0, Action.NEW_GOAL)])
def test_new_goal_next_to_the_current_one_is_not_sent(change_min_m, action):
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", goal_change_min_m=change_min_m,
                                    frontier_match_radius_m=0.1))
    first = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    # the goal's frontier is gone; another one has its cPoint 0.11 m from the goal
    other = make_frontier(0, [(20, c) for c in range(10, 20)], (8, 13), g)
    res = m.step(1.0, (1.0, 1.0), g, [other, fr[1]], [0.9, 3.0])
    assert res.action is action and (res.goal is first) == (action is Action.KEEP)


def test_done_after_confirmations_and_final_until_reset():
    g, _ = manager_world()
    m = GoalManager(SelectionParams(done_confirmations=3))
    actions = [m.step(float(t), (1.0, 1.0), g, [], []).action for t in range(4)]
    assert actions == [Action.WAIT, Action.WAIT, Action.DONE, Action.DONE]
    m.reset()
    assert m.step(5.0, (1.0, 1.0), g, [], []).action is Action.WAIT


def test_all_frontiers_unreachable_is_done():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(done_confirmations=2))
    acts = [m.step(float(t), (1.0, 1.0), g, fr, [np.inf, np.inf]).action for t in range(2)]
    assert acts == [Action.WAIT, Action.DONE]


def test_missing_distances_do_not_count_towards_done():
    g, _ = manager_world()
    m = GoalManager(SelectionParams(done_confirmations=1))
    assert m.step(0.0, (1.0, 1.0), g, [], None).action is Action.WAIT
    assert m.step(1.0, (1.0, 1.0), g, [], []).action is Action.DONE


def test_return_to_start_then_done():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1,
                                    return_to_start=True))
    m.step(0.0, (0.5, 0.5), g, fr, [1.0, 3.0])
    res = m.step(1.0, (2.0, 2.0), g, [], [])
    assert res.action is Action.NEW_GOAL and res.goal.is_return
    assert res.goal.xy_m == (0.5, 0.5)
    assert m.step(2.0, (1.0, 1.0), g, [], []).action is Action.KEEP
    assert m.step(3.0, (0.55, 0.5), g, [], []).action is Action.DONE


def test_blacklist_is_bounded_and_excludes_nearby_cpoints():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", blacklist_max=2))
    for xy in [(9.0, 9.0), (8.0, 8.0), fr[0].point_xy_m]:
        m.add_to_blacklist(xy)
    assert m.blacklist == ((8.0, 8.0), fr[0].point_xy_m)
    res = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0])
    assert res.goal.xy_m == fr[1].point_xy_m


# ------------------------------------------------------------------------ parameters


@pytest.mark.parametrize("kwargs,match", [
    ({"strategy": "random"}, "strategy must be one of"),
    ({"pose_topic_type": "tf"}, "pose_topic_type must be one of"),
    ({"alpha": -1.0}, "alpha must be finite and >= 0"),
    ({"progress_timeout_s": 0.0}, "progress_timeout_s must be finite and > 0"),
    ({"path_block_cells": 5}, "path_block_cells must be in"),
    ({"blacklist_max": 0}, "blacklist_max must be >= 1"),
    ({"done_confirmations": 0}, "done_confirmations must be >= 1"),
    ({"min_group_size_cells": 0}, "min_group_size_cells must be >= 1"),
])
def test_params_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SelectionParams(**kwargs)


def test_frontier_params_mirror_selection_params():
    p = SelectionParams(min_group_size_cells=7, robot_radius_m=0.3)
    fp = p.frontier_params()
    assert (fp.min_group_size_cells, fp.robot_radius_m) == (7, 0.3)


@pytest.mark.parametrize("count,explored", [(3, False), (0, False), (3, True)])
def test_frontier_that_keeps_vanishing_and_coming_back_is_blacklisted(count, explored):
    # The near frontier (fr[0]) vanishes whenever the robot heads for it and comes back
    # when it heads for the far one (a wall edge flickering next to unknown space). With
    # ``explored`` its cells are known when it vanishes (cleared by sensing): not flicker.
    g, fr = manager_world()
    data = g.data.copy()
    data[fr[0].cells[:, 0], fr[0].cells[:, 1]] = -1
    g = g.with_data(data)
    gone = g.with_data(np.zeros_like(data)) if explored else g
    m = GoalManager(SelectionParams(strategy="nearest", flicker_vanish_count=count,
                                    hysteresis_margin=0.1))
    t, reasons = 0.0, []
    for _ in range(5):
        res = m.step(t, (1.0, 1.0), g, fr, [1.0, 3.0])
        reasons.append(res.reason)
        t += 1.0
        if res.goal is None or res.goal.xy_m != fr[0].point_xy_m:
            break
        res = m.step(t, (1.0, 1.0), gone, [fr[1]], [3.0])   # fr[0] gone
        reasons.append(res.reason)
        t += 1.0
        assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    if count and not explored:
        assert sum("vanished" in r for r in reasons) == 1, reasons
        assert fr[0].point_xy_m in m.blacklist
        res = m.step(t, (1.0, 1.0), g, fr, [1.0, 3.0])   # back again: not chosen
        assert res.goal.xy_m == fr[1].point_xy_m
    else:
        assert m.blacklist == () and not any("vanished" in r for r in reasons)


def test_frontier_that_vanishes_once_is_not_blacklisted():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest"))
    assert m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal.xy_m == fr[0].point_xy_m
    res = m.step(1.0, (1.0, 1.0), g, [fr[1]], [3.0])
    assert res.reason == "goal frontier gone or unreachable" and m.blacklist == ()
    assert m.step(2.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal.xy_m == fr[0].point_xy_m
    m.reset(clear_blacklist=True)
    with pytest.raises(ValueError, match="flicker_vanish_count"):
        SelectionParams(flicker_vanish_count=-1)


def test_goal_kept_while_its_frontier_is_undetected_but_unexplored():
    # A thin frontier seen at a grazing angle drops out of detection: drive on while its
    # cells are unknown; the progress timeout still bounds the wait.
    g, fr = manager_world()
    data = g.data.copy()
    data[fr[0].cells[:, 0], fr[0].cells[:, 1]] = -1
    g = g.with_data(data)
    m = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0))
    goal = m.step(0.0, (1.0, 1.0), g, [fr[0]], [1.0]).goal
    res = m.step(1.0, (1.0, 1.0), g, [], [])
    assert res.action is Action.KEEP and res.goal is goal and "still unknown" in res.reason
    res = m.step(2.0, (1.0, 1.0), g.with_data(np.zeros_like(data)), [], [])  # now seen
    assert res.action is Action.WAIT and m.goal is None
    m2 = GoalManager(SelectionParams(strategy="nearest", progress_timeout_s=30.0))
    m2.step(0.0, (1.0, 1.0), g, [fr[0]], [1.0])
    for t in range(1, 31):
        assert m2.step(float(t), (1.0, 1.0), g, [], []).action is Action.KEEP
    res = m2.step(31.0, (1.0, 1.0), g, [], [])
    assert res.action is not Action.KEEP and m2.goal is None


def test_blacklist_retried_once_before_done():
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", done_confirmations=2,
                                    blacklist_retries=1))
    m.add_to_blacklist((9.0, 9.0))           # nothing there now
    actions = [m.step(float(t), (1.0, 1.0), g, [], []) for t in range(6)]
    assert [a.action for a in actions[:2]] == [Action.WAIT, Action.WAIT]
    assert "blacklist cleared" in actions[1].reason and m.blacklist == ()
    assert actions[3].action is Action.DONE and m.done


# The robot's room (left) has a frontier F1 at its top; a doorway (rows 3-5 of the wall at
# col 8) is still unknown, so the pocket seen through it and its frontier F2 (col 14) are
# reachable only across unknown cells. The doorway's own 3 frontier cells are too few for
# a group.
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
    params = SelectionParams(strategy="nearest", done_confirmations=1, blacklist_retries=0,
                             **{**BASE, "min_group_size_cells": 4})
    fr = find_frontiers(g, None, params.frontier_params())
    top = [i for i, f in enumerate(fr) if f.centroid_rc[1] < 8]
    pocket = [i for i, f in enumerate(fr) if f.centroid_rc[1] > 12]
    assert len(fr) == 2 and len(top) == len(pocket) == 1
    graphs = PathGraphs(g, None, params)
    d = graphs.distances(robot, fr)
    assert np.isfinite(d[top[0]]) and np.isinf(d[pocket[0]])   # known space only
    m = GoalManager(params)
    m.add_to_blacklist(fr[top[0]].point_xy_m)
    xy = g.cells_to_world(*robot)
    # Before the fix the reachable (blacklisted) F1 kept the fallback off: DONE at 0 %.
    d = graphs.distances(robot, fr, m.excluded(fr))
    assert np.isfinite(d[pocket[0]])
    res = m.step(0.0, xy, g, fr, d, None, robot)
    assert res.action is Action.NEW_GOAL
    assert res.goal.xy_m == pytest.approx(fr[pocket[0]].point_xy_m)
    # Without the exclusion mask, the old behaviour: no candidate, DONE.
    m2 = GoalManager(params)
    m2.add_to_blacklist(fr[top[0]].point_xy_m)
    assert m2.step(0.0, xy, g, fr, graphs.distances(robot, fr), None, robot).action \
        is Action.DONE
