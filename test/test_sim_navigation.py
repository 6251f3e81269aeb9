"""Navigation stand-in: planner pieces, goals across worlds, pursuit around corners."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from explore_seg.core.grid import GridMap, grid_from_ascii
from sim_bridge import worlds
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.navigation import pursuit as pursuit_module
from sim_bridge.navigation import (NavParams, NavState, Navigator, cost_distance_field,
                                   cost_grid, plan_path)
from sim_bridge.world import World
from sim_scenes import FAST, WALL_H, WALL_T, box, room_world, walls_around


def _clear_goal_far_from_start(eng: SimEngine, clearance_m: float = 0.6):
    gt = eng.ground_truth
    free = (gt.inside & (gt.footprint_tall.data < 65)).astype(np.uint8)
    clear = cv2.distanceTransform(free, cv2.DIST_L2, 5) * gt.resolution_m >= clearance_m
    rows, cols = np.nonzero(clear)
    xs, ys = gt.lidar.cells_to_world(rows, cols)
    sx, sy, _ = eng.pose
    i = int(np.argmax(np.hypot(xs - sx, ys - sy)))
    return float(xs[i]), float(ys[i])


def test_goal_across_the_small_house_is_reached_without_collision():
    eng = SimEngine(worlds.default_world("small_house"), SimParams())
    eng.step(0.2)
    gx, gy = _clear_goal_far_from_start(eng)
    straight = math.hypot(gx - eng.pose[0], gy - eng.pose[1])
    assert straight > 5.0
    eng.set_goal(gx, gy, 1.0)
    eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, 300.0)
    assert eng.nav_status.state is NavState.SUCCEEDED, eng.nav_status.reason
    assert math.hypot(eng.pose[0] - gx, eng.pose[1] - gy) <= 0.25
    assert abs(math.remainder(eng.pose[2] - 1.0, 2 * math.pi)) <= 0.25
    assert eng.metrics.n_collisions == 0
    assert eng.metrics.path_length_m >= straight - 0.25
    assert eng.metrics.goals_reached == 1


def closed_room_world() -> World:
    """A 6 x 4 m room holding a closed 1.6 x 1.6 m box room (no door)."""
    return room_world(walls_around(3.6, 1.2, 5.2, 2.8, name="closet"))


def test_goal_inside_a_closed_room_is_aborted_without_unknown_space():
    eng = SimEngine(closed_room_world(), SimParams(nav_allow_unknown=False, **FAST))
    eng.step(0.2)
    eng.set_goal(4.4, 2.0, 0.0)
    eng.step(0.1)
    assert eng.nav_status.state is NavState.ABORTED
    assert "no path" in eng.nav_status.reason


def test_goal_inside_a_closed_room_is_aborted_once_its_walls_are_seen():
    eng = SimEngine(closed_room_world(), SimParams(**FAST))
    eng.step(0.2)
    eng.set_goal(4.4, 2.0, 0.0)
    eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, 240.0)
    assert eng.nav_status.state is NavState.ABORTED
    assert eng.metrics.n_collisions == 0


@pytest.mark.parametrize("goal, match", [
    ((math.nan, 1.0, 0.0), "finite"),
    ((1.0, 1.0, math.inf), "finite"),
    ((100.0, 1.0, 0.0), "outside the map"),
])
def test_bad_goals_are_rejected_and_the_sim_keeps_running(goal, match):
    eng = SimEngine(room_world([]), SimParams(**FAST))
    eng.step(0.2)
    with pytest.raises(ValueError, match=match):
        eng.set_goal(*goal)
    assert eng.metrics.goals_rejected == 1 and eng.metrics.goals_received == 0
    assert eng.nav_status.state is NavState.IDLE
    t = eng.time_s
    eng.step(0.5)
    assert eng.time_s == pytest.approx(t + 0.5)


def test_costmap_layer_blocks_the_direct_route():
    eng = SimEngine(room_world([]), SimParams(**FAST))
    eng.step(0.3)
    base = eng.map
    layer = np.zeros(base.shape, np.int8)
    r0, c0 = base.world_to_cell(3.0, 0.0)
    r1, _ = base.world_to_cell(3.0, 3.0)
    layer[r0:r1 + 1, c0:c0 + 2] = 100                    # a fence from y = 0 to 3 m
    eng.add_costmap_layer("object_costmap", base.with_data(layer))
    eng.set_goal(5.0, 1.0, 0.0)
    eng.step(0.1)
    plan = eng.plan
    assert len(plan) > 2
    assert plan[:, 1].max() > 3.0 + 0.2                  # goes round the end of the fence
    eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, 120.0)
    assert eng.nav_status.state is NavState.SUCCEEDED


def test_cost_grid_lethal_zone_and_decay():
    grid, _ = grid_from_ascii("""
    ...........
    .....#.....
    ...........
    """, resolution_m=0.1)
    p = NavParams(robot_radius_m=0.1, inflation_margin_m=0.0, inflation_radius_m=0.4,
                  inflation_cost_weight=2.0, inflation_cost_scale=10.0)
    cost = cost_grid(grid.occupied_mask(), None, 0.1, p)
    row = cost[1]
    assert np.isinf(row[4:7]).all() and np.isfinite(row[:4]).all()
    assert row[3] == pytest.approx(1 + 2.0 * math.exp(-10.0 * 0.1))
    assert row[2] == pytest.approx(1 + 2.0 * math.exp(-10.0 * 0.2))
    assert row[0] == row[1] == 1.0                       # at/after inflation_radius


def test_unknown_cost_makes_the_planner_prefer_known_space():
    grid, marks = grid_from_ascii("""
    ...............
    .?????????????.
    .?????????????.
    S?????????????G
    """, resolution_m=0.1)
    p = NavParams(robot_radius_m=0.01, inflation_margin_m=0.0, inflation_radius_m=0.01,
                  unknown_cost=4.0)
    cost = cost_grid(grid.occupied_mask(), grid.unknown_mask(), 0.1, p)
    cells, c = plan_path(cost, marks["S"][0], marks["G"][0], 0.1, 1.0)
    assert cells[:, 0].max() == 3                          # detours along the known top row
    cheap = NavParams(robot_radius_m=0.01, inflation_margin_m=0.0, inflation_radius_m=0.01,
                      unknown_cost=0.0)
    cost0 = cost_grid(grid.occupied_mask(), grid.unknown_mask(), 0.1, cheap)
    cells0, c0 = plan_path(cost0, marks["S"][0], marks["G"][0], 0.1, 1.0)
    assert (cells0[:, 0] == 0).all() and c0 == pytest.approx(1.4)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_windowed_plan_equals_full_grid_field_on_random_grids(seed):
    rng = np.random.default_rng(seed)
    cost = np.where(rng.random((40, 60)) < 0.25, np.inf, 1.0 + rng.random((40, 60)))
    cost[5, 5] = cost[35, 55] = 1.0
    full = cost_distance_field(cost, (5, 5), 0.1)[35, 55]
    found = plan_path(cost, (5, 5), (35, 55), 0.1, 0.5)
    if not np.isfinite(full):
        assert found is None
    else:
        cells, c = found
        assert c == pytest.approx(full)
        assert c >= 0.1 * math.hypot(30, 50) - 1e-9
        assert tuple(cells[0]) == (5, 5) and tuple(cells[-1]) == (35, 55)
        assert np.isfinite(cost[cells[1:-1, 0], cells[1:-1, 1]]).all()


def test_pursuit_arc_check_rejects_a_lookahead_point_around_an_obstacle_corner():
    """The lookahead point is taken only if the arc to it stays out of the lethal zone."""
    res = 0.05
    blocked = np.zeros((60, 60), bool)
    blocked[30:, :30] = True              # x < 1.5 and y > 1.5: a corner at (1.5, 1.5)
    grid = GridMap(np.where(blocked, 100, 0).astype(np.int8), res, (0.0, 0.0))
    nav = Navigator(NavParams())
    assert nav._arc_clear((1.3, 1.25, 0.0), np.array([1.7, 1.62]))   # no plan yet: no check
    nav._plan_cost = cost_grid(blocked, None, res, nav.params)
    nav._plan_grid = grid
    pose = (1.3, 1.25, 0.0)               # 0.25 m below the block, heading +x
    # Around the corner: the arc passes ~0.1 m from it (robot radius 0.22).
    assert not nav._arc_clear(pose, np.array([1.7, 1.62]))
    # Straight on along the lane, or around the corner with room (0.26 m): clear.
    assert nav._arc_clear(pose, np.array([1.7, 1.25]))
    assert nav._arc_clear(pose, np.array([2.6, 1.55]))
    # 0.225 m from the corner's edge: out of the lethal zone (cell centres), refused by
    # the edge check (0.22 + 0.02 m), taken without it.
    assert not nav._arc_clear(pose, np.array([2.1, 1.62]))
    nav.params = NavParams(arc_check_edges=False)
    assert nav._arc_clear(pose, np.array([2.1, 1.62]))


def test_pursuit_arc_keeps_clear_of_the_cell_edges_with_arc_check_edges():
    """The lethal zone is judged at cell centres, half a cell diagonal closer than the
    obstacle cells' edges: an arc the lethal check lets within 0.235 m of a wall's edge is
    refused with arc_check_edges (0.22 + 0.02 m), one at 0.24 m is taken, and a robot
    already closer may drive on at its clearance or away, not closer."""
    res = 0.05
    blocked = np.zeros((60, 60), bool)
    blocked[30:, :] = True                # a wall whose edge is the line y = 1.5
    grid = GridMap(np.where(blocked, 100, 0).astype(np.int8), res, (0.0, 0.0))
    plain = Navigator(NavParams(arc_check_edges=False))
    edges = Navigator(NavParams(arc_check_edges=True, arc_clearance_m=0.02))
    for nav in (plain, edges):
        nav._plan_cost = cost_grid(blocked, None, res, nav.params)
        nav._plan_grid = grid
    pose = (1.0, 1.24, 0.0)               # 0.26 m from the edge, heading +x
    closer = np.array([1.5, 1.265])       # the arc ends 0.235 m from the edge
    assert plain._arc_clear(pose, closer)
    assert not edges._arc_clear(pose, closer)
    assert edges._arc_clear(pose, np.array([1.5, 1.26]))
    assert edges._arc_clear(pose, np.array([1.5, 1.1]))
    tight = (1.0, 1.29, 0.0)              # 0.21 m from the edge (after a contact)
    assert edges._arc_clear(tight, np.array([1.5, 1.29]))
    assert edges._arc_clear(tight, np.array([1.5, 1.2]))
    assert not edges._arc_clear(tight, np.array([1.5, 1.3]))
    assert plain._arc_clear(tight, np.array([1.5, 1.3]))


@pytest.mark.parametrize("seed", range(3))
def test_arc_edge_check_shortcut_by_inflation_cost_agrees_with_the_exact_check(seed,
                                                                               monkeypatch):
    """Arcs the inflation cost shows to be far from every obstacle skip the exact edge
    distances: on random clutter the answers are those of the exact check alone."""
    rng = np.random.default_rng(seed)
    res = 0.05
    blocked = rng.random((80, 80)) < 0.01
    blocked[:, :2] = blocked[:, -2:] = blocked[:2, :] = blocked[-2:, :] = True
    grid = GridMap(np.where(blocked, 100, 0).astype(np.int8), res, (0.0, 0.0))
    nav = Navigator(NavParams(arc_check_edges=True))
    nav._plan_cost = cost_grid(blocked, None, res, nav.params)
    nav._plan_grid = grid
    cases = [((float(x), float(y), float(t)), np.array([x + 0.4 * np.cos(t + a),
                                                         y + 0.4 * np.sin(t + a)]))
             for x, y, t, a in zip(rng.uniform(0.6, 3.4, 400), rng.uniform(0.6, 3.4, 400),
                                   rng.uniform(-np.pi, np.pi, 400),
                                   rng.uniform(-0.7, 0.7, 400))]
    fast = [nav._arc_clear(pose, tgt) for pose, tgt in cases]
    monkeypatch.setattr(pursuit_module, "edge_safe_cost", lambda params, res: None)
    exact = [nav._arc_clear(pose, tgt) for pose, tgt in cases]
    assert fast == exact
    assert 0 < sum(exact) < len(exact)


def _door_world(door_lo: float, door_hi: float, start) -> World:
    """A 6 x 4 m room split at x = 3 by a wall with a door between door_lo and door_hi."""
    t = WALL_T
    return room_world([box("split_a", "wall", "wall", 3.0, door_lo / 2, t, door_lo, 0, WALL_H),
                       box("split_b", "wall", "wall", 3.0, (door_hi + 4.0) / 2, t,
                           4.0 - door_hi, 0, WALL_H)], start=start)


@pytest.mark.parametrize("start, goal", [((1.2, 0.6, 0.0), (4.8, 0.6)),
                                         ((1.5, 3.6, -0.5), (4.5, 0.5))])
def test_robot_passes_a_door_at_a_sharp_angle_clear_of_its_jambs(start, goal):
    """Through a 0.8 m door entered and left at sharp angles: no contact, and the robot's
    centre keeps more than its radius from every jamb corner."""
    eng = SimEngine(_door_world(2.6, 3.4, start), SimParams(nav_collision_retries=0, **FAST))
    eng.run_until(lambda e: e.latest_scan is not None, 1.0)
    eng.set_goal(goal[0], goal[1], 0.0)
    eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, 120.0)
    assert eng.nav_status.state is NavState.SUCCEEDED
    xy = eng.trail
    jambs = np.array([[3.0 - WALL_T / 2, 2.6], [3.0 + WALL_T / 2, 2.6],
                      [3.0 - WALL_T / 2, 3.4], [3.0 + WALL_T / 2, 3.4]])
    d = np.hypot(xy[:, None, 0] - jambs[None, :, 0], xy[:, None, 1] - jambs[None, :, 1])
    assert eng.metrics.n_collisions == 0
    assert float(d.min()) > 0.22


def _navigator_on(blocked: np.ndarray, res: float = 0.05) -> tuple[Navigator, GridMap]:
    """A navigator whose current plan was made on a map of these obstacle cells."""
    grid = GridMap(np.where(blocked, 100, 0).astype(np.int8), res, (0.0, 0.0))
    nav = Navigator(NavParams())
    nav._plan_cost = cost_grid(blocked, None, res, nav.params)
    nav._plan_grid = grid
    return nav, grid


def test_pursuit_turns_in_place_when_no_arc_from_its_heading_keeps_clear():
    """A robot 0.23 m from a wall's edge, heading 0.6 rad towards it, with its plan
    running along the wall: every arc from that heading first closes in on the wall, so
    the controller turns in place towards the plan (the footprint does not move) instead
    of driving the nearest arc unchecked; once it faces along the wall it drives on."""
    res = 0.05
    blocked = np.zeros((60, 80), bool)
    blocked[30:, :] = True                # a wall whose edge is the line y = 1.5
    nav, grid = _navigator_on(blocked, res)
    xs = np.arange(1.0, 3.0, res)
    nav._plan_xy = np.column_stack([xs, np.full(len(xs), 1.27)])
    nav._plan_index = 0
    pose = (1.0, 1.27, 0.6)
    assert not any(nav._arc_clear(pose, nav._plan_xy[k]) for k in range(1, 12))
    v, w = nav._pursue(pose, 2.0)
    assert v == 0.0 and w < 0.0
    v, w = nav._pursue((1.0, 1.27, 0.0), 2.0)
    assert v > 0.0


def test_pursuit_never_drives_an_unchecked_arc_when_no_straight_line_is_clear_either():
    """A robot 0.20 m from a wall's edge (inside the margin) whose plan runs closer to the
    wall: no arc from its heading and no straight line to a plan point keeps its
    clearance, so it turns in place to face the next plan point and then waits (zero
    command); it never drives. (The old fallback drove the arc to that point: eb/corner,
    paper_noseg seed 9 touched a wall corner so.)"""
    res = 0.05
    blocked = np.zeros((60, 80), bool)
    blocked[30:, :] = True                # a wall whose edge is the line y = 1.5
    nav, grid = _navigator_on(blocked, res)
    xs = np.arange(1.0, 3.0, res)
    nav._plan_xy = np.column_stack([xs, np.minimum(1.30 + (xs - 1.0), 1.34)])
    nav._plan_index = 0
    heading = math.atan2(nav._plan_xy[1, 1] - 1.30, nav._plan_xy[1, 0] - 1.0)
    assert not any(nav._arc_clear((1.0, 1.30, math.atan2(p[1] - 1.30, p[0] - 1.0)), p)
                   for p in nav._plan_xy[1:12])          # no straight line keeps clear
    for yaw in (heading - 0.3, heading):
        assert not any(nav._arc_clear((1.0, 1.30, yaw), nav._plan_xy[k]) for k in range(1, 12))
    v, w = nav._pursue((1.0, 1.30, heading - 0.3), 2.0)
    assert v == 0.0 and w > 0.0                       # turns to face the plan
    nav._plan_index = 0
    assert nav._pursue((1.0, 1.30, heading), 2.0) == (0.0, 0.0)   # facing it: waits


def test_a_plan_from_inside_the_margin_leads_out_of_it_not_closer():
    """A robot 0.2 m from a wall (inside the 0.22 m lethal disk) near the wall's corner,
    with its goal around that corner: the plan's cells never come closer to an obstacle
    cell than the start's (it leaves the margin first, instead of cutting the corner
    through it, as the plan that led eb/corner paper_noseg seed 9 into a wall corner did)
    and it reaches the goal."""
    res = 0.05
    blocked = np.zeros((80, 80), bool)
    blocked[40:, :40] = True              # x < 2 and y > 2: a corner at (2, 2)
    grid = GridMap(np.where(blocked, 100, 0).astype(np.int8), res, (0.0, 0.0))
    near = cv2.distanceTransform((~blocked).astype(np.uint8), cv2.DIST_L2,
                                 cv2.DIST_MASK_PRECISE) * res
    nav = Navigator(NavParams())
    nav.set_map(grid, 1)
    pose = (1.975, 1.8, 0.0)              # 0.2 m below the wall's last cell
    start_near = near[grid.world_to_cell(pose[0], pose[1])]
    assert start_near < nav.params.lethal_radius_m
    nav.set_goal(2.3, 2.6, 0.0, 0.0, pose)
    nav.update(pose, 0.0)
    assert nav.status.state is NavState.ACTIVE
    plan = nav.plan_xy
    assert np.hypot(*(plan[-1] - [2.3, 2.6])) <= 0.1
    r, c = grid.world_to_cells(plan[1:, 0], plan[1:, 1])
    assert (near[r, c] >= start_near - 1e-9).all()


def test_pursuit_drives_through_a_passage_only_a_little_wider_than_the_robot():
    """A passage whose free cells keep 0.225 m from both walls' cell edges (the robot
    radius is 0.22, the arc check wants 0.02 more) that narrows just ahead of the robot:
    no arc keeps 0.24 m (nor the robot's 0.23 m now), so the controller drives the arc
    that keeps the robot radius instead of waiting in front of the passage (the map's
    obstacle cells hold the true walls, so the robot cannot touch them)."""
    res = 0.05
    blocked = np.zeros((60, 80), bool)
    blocked[30:, :] = True                # upper wall: edge at y = 1.5
    blocked[:21, 22:] = True              # lower wall from x = 1.1: edge at y = 1.05
    nav, grid = _navigator_on(blocked, res)
    xs = np.arange(1.0, 3.5, res)
    nav._plan_xy = np.column_stack([xs, np.full(len(xs), 1.275)])
    pose = (1.0, 1.27, 0.0)
    assert np.isfinite(nav._plan_cost[grid.world_to_cells(xs, np.full(len(xs), 1.275))]).all()
    assert not any(nav._arc_clear(pose, nav._plan_xy[k]) for k in range(1, 12))
    nav._plan_index = 0
    v, w = nav._pursue(pose, 2.0)
    assert v > 0.0
