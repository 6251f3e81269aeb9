"""GoalManager: hysteresis, progress, arrival, blacklist, flicker, done, return to start."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.selection import Action, GoalManager, SelectionParams, StepInputs, \
    goal_yaw
from selection_cases import make_frontier, manager_world


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
    g.data[5, 10:20] = -1          # fr[0]'s cells stay unknown: the visit revealed nothing
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
    newer = GridMap(g.data, g.resolution_m, g.origin_xy_m, stamp_ns=5_200_000_000)
    res = m.step(5.5, goal.xy_m, newer, [fr[1]], [2.0])
    assert res.action is Action.NEW_GOAL and m.blacklist == ()


def _stamped(g):
    """The map ``g`` as published at ``t_s`` (a function of ``t_s``)."""
    return lambda t_s: GridMap(g.data, g.resolution_m, g.origin_xy_m,
                               stamp_ns=round(t_s * 1e9))


def test_goal_reached_is_not_judged_on_a_newer_map_stamped_before_the_arrival():
    # A map renewed every 5 s: the one published after the arrival map (stamp 3 s) but
    # stamped before the arrival (5 s) does not show the view from the goal.
    g, fr = manager_world()
    g.data[5, 10:20] = -1          # fr[0] remains on the maps of before the arrival
    stamped = _stamped(g)
    m = GoalManager(SelectionParams(strategy="nearest", arrival_wait_s=7.0))
    goal = m.step(0.0, (1.0, 1.0), stamped(0.0), fr, [1.0, 3.0]).goal
    res = m.step(5.0, goal.xy_m, stamped(3.0), fr, [0.0, 2.0])
    assert res.action is Action.KEEP and "waiting" in res.reason
    res = m.step(5.5, goal.xy_m, stamped(4.0), fr, [0.0, 2.0])   # newer, before arrival
    assert res.action is Action.KEEP and "waiting" in res.reason
    res = m.step(9.0, goal.xy_m, stamped(4.0), fr, [0.0, 2.0])   # 4 s: past the old 2 s
    assert res.action is Action.KEEP and m.blacklist == ()
    res = m.step(9.5, goal.xy_m, stamped(8.0), [fr[1]], [2.0])   # shows the arrival
    assert res.action is Action.NEW_GOAL and res.reason == "goal reached"
    assert m.blacklist == ()


def test_goal_reached_waits_for_a_map_showing_it_at_most_arrival_wait_s():
    # No map after the arrival (the map's clock is another one, its publisher stopped):
    # the frontier is judged on the map at hand after arrival_wait_s.
    g, fr = manager_world()
    g.data[5, 10:20] = -1
    m = GoalManager(SelectionParams(strategy="nearest", arrival_wait_s=7.0))
    goal = m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal
    assert m.step(5.0, goal.xy_m, g, fr, [0.0, 2.0]).action is Action.KEEP
    assert m.step(11.9, goal.xy_m, g, fr, [0.0, 2.0]).action is Action.KEEP
    res = m.step(12.0, goal.xy_m, g, fr, [0.0, 2.0])
    assert res.action is Action.NEW_GOAL and m.blacklist == (goal.xy_m,)
    assert res.reason == "goal reached but its frontier remains: blacklisted"


def test_goal_reached_with_maps_of_every_scan_is_judged_at_the_next_decision():
    # A map stamped at the arrival itself is the arrival's: the next one (the scan from the
    # goal) is judged, at the next decision as before.
    g, fr = manager_world()
    stamped = _stamped(g)
    m = GoalManager(SelectionParams(strategy="nearest"))
    goal = m.step(0.0, (1.0, 1.0), stamped(0.0), fr, [1.0, 3.0]).goal
    res = m.step(5.0, goal.xy_m, stamped(5.0), fr, [0.0, 2.0])
    assert res.action is Action.KEEP and "waiting" in res.reason
    res = m.step(5.5, goal.xy_m, stamped(5.5), [fr[1]], [2.0])
    assert res.action is Action.NEW_GOAL and res.reason == "goal reached"


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


@pytest.mark.parametrize("n_frontiers,dist,excluded,reason", [
    (0, [], None, "no frontier left"),
    (2, [np.inf, np.inf], None, "no selectable frontier (2 left: 2 without a path)"),
    (2, [1.0, np.inf], [True, False],
     "no selectable frontier (2 left: 1 without a path, 1 blacklisted)"),
])
def test_done_reason_names_the_frontiers_left(n_frontiers, dist, excluded, reason):
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1, turn_looks=0))
    known = StepInputs(excluded=None if excluded is None else np.asarray(excluded))
    res = m.step(0.0, (1.0, 1.0), g, fr[:n_frontiers], dist, known)
    assert res.action is Action.DONE and res.reason == reason


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
    assert res.reason == "goal frontier gone" and m.blacklist == ()
    assert m.step(2.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal.xy_m == fr[0].point_xy_m
    m.reset(clear_blacklist=True)
    with pytest.raises(ValueError, match="flicker_vanish_count"):
        SelectionParams(flicker_vanish_count=-1)


def test_goal_whose_frontier_is_still_there_but_not_selectable_says_so():
    # Routed leaves a view out of the tour (a leftover while a bigger view remains): the
    # frontier is still mapped, its cost inf; the switch must not claim it is gone.
    g, fr = manager_world()
    m = GoalManager(SelectionParams(strategy="nearest"))
    assert m.step(0.0, (1.0, 1.0), g, fr, [1.0, 3.0]).goal.xy_m == fr[0].point_xy_m
    res = m.step(1.0, (1.0, 1.0), g, fr, [math.inf, 3.0])
    assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
    assert res.reason.startswith("goal frontier no longer selectable") and m.blacklist == ()


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


@pytest.mark.parametrize("revealed_cells,far_cells,retried",
                         [(0, 0, False), (3, 0, False), (4, 0, True), (3, 20, False)])
def test_a_blacklist_retry_that_revealed_space_does_not_count(revealed_cells, far_cells,
                                                              retried):
    # 0.5 m cells: retry_reveal_m2 = 1 m^2 is 4 cells become known during the retry,
    # within retry_reveal_radius_m (2 m) of the retried goal at (9, 9); cells known far
    # from it (a loop-closure re-render redrawing the map elsewhere) reveal nothing
    g, _ = manager_world()
    g = GridMap(g.data.copy(), 0.5)
    g.data[17:19, 16:22] = -1                                  # 12 unknown cells near it
    g.data[:2, :10] = -1                                       # 20 unknown cells far away
    unknown = np.argwhere(g.data[:, 12:] < 0) + [0, 12]
    far = np.argwhere(g.data[:, :12] < 0)
    m = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1,
                                    blacklist_retries=1, retry_reveal_m2=1.0))
    m.add_to_blacklist((9.0, 9.0))
    first = m.step(0.0, (1.0, 1.0), g, [], [])
    assert "blacklist cleared" in first.reason                 # the counted retry
    r, c = unknown[:revealed_cells].T
    g.data[r, c] = 0                                           # what the retry revealed
    g.data[tuple(far[:far_cells].T)] = 0                       # and a re-render elsewhere
    m.add_to_blacklist((9.0, 9.0))                             # its goal failed again
    second = m.step(1.0, (1.0, 1.0), g, [], [])
    assert ("blacklist cleared" in second.reason) is retried
    assert (second.action is Action.DONE) is not retried
    if retried:                  # the free retry revealed nothing: its count is spent
        m.add_to_blacklist((9.0, 9.0))
        assert m.step(2.0, (1.0, 1.0), g, [], []).action is Action.DONE
    whole = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1,
                                        blacklist_retries=1, retry_reveal_radius_m=0.0))
    whole.add_to_blacklist((9.0, 9.0))
    g.data[:2, :10] = -1
    whole.step(0.0, (1.0, 1.0), g, [], [])
    g.data[:2, :10] = 0                                        # known anywhere counts
    whole.add_to_blacklist((9.0, 9.0))
    assert "blacklist cleared" in whole.step(1.0, (1.0, 1.0), g, [], []).reason
    off = GoalManager(SelectionParams(strategy="nearest", done_confirmations=1,
                                      blacklist_retries=1, retry_reveal_m2=0.0))
    off.add_to_blacklist((9.0, 9.0))
    off.step(0.0, (1.0, 1.0), g, [], [])
    g.data[g.data < 0] = 0
    off.add_to_blacklist((9.0, 9.0))
    assert off.step(1.0, (1.0, 1.0), g, [], []).action is Action.DONE


# The robot's room (left) has a frontier F1 at its top; a doorway (rows 3-5 of the wall at
# col 8) is still unknown, so the pocket seen through it and its frontier F2 (col 14) are
# reachable only across unknown cells. The doorway's own 3 frontier cells are too few for
# a group.

def test_blacklist_added_counts_entries_past_the_bound():
    m = GoalManager(SelectionParams(blacklist_max=2))
    for k in range(5):
        m.add_to_blacklist((float(k), 0.0))
    assert m.blacklist_added == 5 and m.blacklist == ((3.0, 0.0), (4.0, 0.0))
    m.reset(clear_blacklist=True)
    assert m.blacklist == () and m.blacklist_added == 5


@pytest.mark.parametrize("strategy,handover_m,reached", [
    ("routed", 1.0, True), ("routed", 0.0, False), ("nearest", 1.0, False)])
def test_routed_goal_counts_as_reached_within_handover_m(strategy, handover_m, reached):
    g, fr = manager_world()
    g.data[5, 10:20] = -1          # fr[0]'s cells stay unknown: the visit revealed nothing
    m = GoalManager(SelectionParams(strategy=strategy, handover_m=handover_m,
                                    arrival_wait_s=0.0))
    cost = np.array([1.0, 3.0])
    goal = m.step(0.0, (0.6, 2.0), g, fr, cost, StepInputs(tour_cost_m=cost)).goal
    assert goal.xy_m == fr[0].point_xy_m
    near = (goal.xy_m[0] + 0.8, goal.xy_m[1])     # 0.8 m away, the frontier still there
    res = m.step(1.0, near, g, fr, [0.8, 2.0], StepInputs(tour_cost_m=np.array([0.8, 2.0])))
    if reached:
        assert res.action is Action.NEW_GOAL and res.goal.xy_m == fr[1].point_xy_m
        assert "frontier remains" in res.reason and m.blacklist == (goal.xy_m,)
    else:
        assert res.action is Action.KEEP and res.goal is goal and m.blacklist == ()


@pytest.mark.parametrize("strategy,fraction,revealed,blacklisted", [
    ("routed", 0.5, True, False), ("routed", 0.5, False, True), ("routed", 0.0, True, True),
    ("routed", None, True, False), ("nearest", 0.5, True, True), ("paper", None, True, True)])
def test_reached_goal_whose_frontier_moved_on_is_not_blacklisted(strategy, fraction, revealed,
                                                                  blacklisted):
    """A corridor longer than the sensor range: at the goal, the frontier it was chosen
    for is revealed and a new one lies just beyond it (within the match radius). That is
    where the space goes on, not a frontier the robot failed to clear: with
    reached_unknown_fraction > 0 (default 0.5) routed keeps it selectable; 0 and every
    other strategy (explore_lite's and the paper's rule) blacklist it."""
    g = GridMap(np.zeros((60, 60), np.int8), 0.05, (0.0, 0.0))
    g.data[:6] = -1
    f0 = make_frontier(0, [(5, c) for c in range(10, 20)], (6, 12), g)
    far = make_frontier(1, [(50, c) for c in range(10, 40)], (49, 20), g)
    g.data[50, 10:40] = -1
    extra = {} if fraction is None else {"reached_unknown_fraction": fraction}
    m = GoalManager(SelectionParams(strategy=strategy, arrival_wait_s=0.0, **extra))
    goal = m.step(0.0, (1.0, 2.0), g, [f0, far], [1.0, 3.0],
                  StepInputs(tour_cost_m=np.array([1.0, 3.0]))).goal
    assert goal.xy_m == f0.point_xy_m
    after = GridMap(g.data.copy(), 0.05, (0.0, 0.0))
    if revealed:
        after.data[3:6] = 0                               # rows 3-5 seen: free
    on = make_frontier(0, [(2, c) for c in range(10, 20)], (3, 12), after)
    res = m.step(1.0, goal.xy_m, after, [on, far], [0.15, 2.5],
                 StepInputs(tour_cost_m=np.array([0.15, 2.5])))
    assert m.blacklist == ((goal.xy_m,) if blacklisted else ())
    if blacklisted:
        assert "frontier remains" in res.reason
        assert res.action is Action.NEW_GOAL and res.goal.xy_m == far.point_xy_m
    else:
        assert "revealed" in res.reason
        assert res.action is Action.NEW_GOAL and res.goal.xy_m == on.point_xy_m


@pytest.mark.parametrize("limit,blacklisted", [(2, True), (3, False), (0, False)])
def test_revealed_arrivals_in_one_area_are_limited(limit, blacklisted):
    """A small leftover re-chosen after each revealed arrival (the frontier recedes by a
    row per visit): the arrival that brings an area's count to revealed_arrivals_max
    blacklists every goal of the area, as a plain reached-but-remains goal is."""
    g = GridMap(np.zeros((60, 60), np.int8), 0.05, (0.0, 0.0))
    g.data[:6] = -1
    f0 = make_frontier(0, [(5, c) for c in range(10, 20)], (6, 12), g)
    far = make_frontier(1, [(50, c) for c in range(10, 40)], (49, 20), g)
    g.data[50, 10:40] = -1
    m = GoalManager(SelectionParams(strategy="routed", arrival_wait_s=0.0,
                                    reached_unknown_fraction=0.5,
                                    revealed_arrivals_max=limit))
    first = m.step(0.0, (1.0, 2.0), g, [f0, far], [1.0, 3.0],
                   StepInputs(tour_cost_m=np.array([1.0, 3.0]))).goal
    g1 = GridMap(g.data.copy(), 0.05, (0.0, 0.0))
    g1.data[3:6] = 0                                      # rows 3-5 revealed
    on1 = make_frontier(0, [(2, c) for c in range(10, 20)], (3, 12), g1)
    second = m.step(1.0, first.xy_m, g1, [on1, far], [0.15, 2.5],
                    StepInputs(tour_cost_m=np.array([0.15, 2.5]))).goal
    assert second.xy_m == on1.point_xy_m and m.blacklist == ()
    g2 = GridMap(g1.data.copy(), 0.05, (0.0, 0.0))
    g2.data[1:3] = 0                                      # rows 1-2 revealed
    on2 = make_frontier(0, [(0, c) for c in range(10, 20)], (1, 12), g2)
    res = m.step(2.0, second.xy_m, g2, [on2, far], [0.1, 2.4],
                 StepInputs(tour_cost_m=np.array([0.1, 2.4])))
    assert res.action is Action.NEW_GOAL
    if blacklisted:
        assert "area blacklisted" in res.reason and res.goal.xy_m == far.point_xy_m
        assert set(m.blacklist) == {first.xy_m, second.xy_m}
        assert m.blacklist_added == 2
    else:
        assert "revealed" in res.reason and res.goal.xy_m == on2.point_xy_m
        assert m.blacklist == ()
