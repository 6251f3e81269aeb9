"""Simulator engine: collisions, mapping, navigation stand-in, metrics, rendering.

Worlds are hand-built from a few primitives (``room_world``) except for the navigation
run across the generated ``small_house``. Everything runs in lock step (no ROS).
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest
from PIL import Image

from explore_seg.core.grid import GridMap, grid_from_ascii
from sim_bridge import worlds
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.mapping import MappingParams, ScanMapper
from sim_bridge.metrics import CollisionEvent, CoverageReference, SimMetrics
from sim_bridge.navigation import (NavParams, NavState, cost_distance_field, cost_grid,
                                   plan_path)
from sim_bridge.render import GifWriter, Overlays, render_map, render_map_png
from sim_bridge.world import Primitive, World

WALL_T = 0.15
WALL_H = 2.5


def box(obj: str, cls: str, part: str, x: float, y: float, sx: float, sy: float,
        zmin: float, zmax: float) -> Primitive:
    return Primitive(obj, cls, part, "box", x, y, 0.0, (sx, sy), zmin, zmax)


def cyl(obj: str, cls: str, part: str, x: float, y: float, r: float, zmin: float,
        zmax: float) -> Primitive:
    return Primitive(obj, cls, part, "cylinder", x, y, 0.0, (r,), zmin, zmax)


def walls_around(x0: float, y0: float, x1: float, y1: float, name: str = "wall"
                 ) -> list[Primitive]:
    """Four wall boxes whose inner faces are the rectangle's sides."""
    t = WALL_T
    w, h = x1 - x0, y1 - y0
    return [box(f"{name}_s", "wall", "wall", (x0 + x1) / 2, y0 - t / 2, w + 2 * t, t, 0, WALL_H),
            box(f"{name}_n", "wall", "wall", (x0 + x1) / 2, y1 + t / 2, w + 2 * t, t, 0, WALL_H),
            box(f"{name}_w", "wall", "wall", x0 - t / 2, (y0 + y1) / 2, t, h, 0, WALL_H),
            box(f"{name}_e", "wall", "wall", x1 + t / 2, (y0 + y1) / 2, t, h, 0, WALL_H)]


def room_world(extra: list[Primitive], size=(6.0, 4.0), start=(1.0, 2.0, 0.0)) -> World:
    w, h = size
    return World(name="room", bounds=(-0.5, -0.5, w + 0.5, h + 0.5), start_pose=start,
                 primitives=walls_around(0.0, 0.0, w, h) + list(extra))


def chair(x: float, y: float) -> list[Primitive]:
    """Seat 0.5 x 0.5 m at 0.42-0.47 m on four 0.02 m legs, backrest on the +x side."""
    legs = [cyl("chair_1", "chair", "leg", x + dx, y + dy, 0.02, 0.0, 0.42)
            for dx in (-0.23, 0.23) for dy in (-0.23, 0.23)]
    return legs + [box("chair_1", "chair", "seat", x, y, 0.5, 0.5, 0.42, 0.47),
                   box("chair_1", "chair", "back", x + 0.23, y, 0.04, 0.5, 0.47, 0.9)]


def desk(x: float, y: float) -> list[Primitive]:
    """Top 0.6 (x) x 1.2 (y) m at 0.72-0.75 m on four 0.05 m legs."""
    legs = [box("desk_1", "table", "leg", x + dx, y + dy, 0.05, 0.05, 0.0, 0.72)
            for dx in (-0.275, 0.275) for dy in (-0.575, 0.575)]
    return legs + [box("desk_1", "table", "top", x, y, 0.6, 1.2, 0.72, 0.75)]


def bench(x: float, y: float) -> list[Primitive]:
    """Seat 0.5 x 1.6 m at 0.42-0.47 m on legs 1.5 m apart: planners see a free lane."""
    legs = [cyl("bench_1", "chair", "leg", x + dx, y + dy, 0.02, 0.0, 0.42)
            for dx in (-0.2, 0.2) for dy in (-0.75, 0.75)]
    return legs + [box("bench_1", "chair", "seat", x, y, 0.5, 1.6, 0.42, 0.47)]


def shelf(x: float, y: float) -> list[Primitive]:
    """A board at 1.5-1.6 m on two posts outside the robot's lane (above robot height)."""
    return [box("shelf_1", "cabinet", "post", x, y - 0.6, 0.05, 0.05, 0.0, 1.6),
            box("shelf_1", "cabinet", "post", x, y + 0.6, 0.05, 0.05, 0.0, 1.6),
            box("shelf_1", "cabinet", "shelf", x, y, 0.4, 1.25, 1.5, 1.6)]


FAST = dict(compute_coverage=False, lidar_noise_std_m=0.0)


# ------------------------------------------------------------------ collisions


@pytest.mark.parametrize("parts, obj, part, contact_x", [
    (chair(3.0, 2.0), "chair_1", "seat", 3.0 - 0.25 - 0.22),
    (desk(3.0, 2.0), "desk_1", "top", 3.0 - 0.3 - 0.22),
])
def test_driving_into_a_part_above_the_scan_plane_is_one_collision_at_contact(
        parts, obj, part, contact_x):
    eng = SimEngine(room_world(parts), SimParams(**FAST))
    eng.step(0.1)
    # The lidar at 0.17 m sees between the legs: nothing ahead for more than 2 m.
    ahead = eng.latest_scan.ranges[eng.scan_geometry.num_beams // 2]
    assert ahead > 2.0
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(12.0)
    assert eng.metrics.n_collisions == 1
    ev = eng.metrics.collisions[0]
    assert (ev.object, ev.part) == (obj, part)
    step_m = 0.26 * eng.params.physics_dt_s
    assert contact_x - step_m - 1e-6 <= ev.x_m <= contact_x
    assert ev.y_m == pytest.approx(2.0, abs=1e-6)
    # Stopped: the command was zeroed; the robot backed off 0.15 m and stays there.
    x_stop = eng.pose[0]
    assert x_stop == pytest.approx(ev.x_m - 0.15, abs=0.1 * eng.params.physics_dt_s + 1e-6)
    eng.step(2.0)
    assert eng.pose[0] == x_stop and eng.velocity[0] == 0.0


def test_part_above_robot_height_is_no_collision():
    eng = SimEngine(room_world(shelf(3.0, 2.0)), SimParams(**FAST))
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(12.0)
    assert eng.metrics.n_collisions == 0
    assert eng.pose[0] > 3.5


def test_pushing_on_counts_once_and_backing_off_then_again_counts_twice():
    eng = SimEngine(room_world([]), SimParams(collision_backup_m=0.0, **FAST))
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(25.0)
    assert eng.metrics.n_collisions == 1
    assert eng.pose[0] == pytest.approx(6.0 - 0.22, abs=0.26 * 0.02 + 1e-6)
    eng.set_cmd_vel(0.26, 0.0)        # pushes again while touching: same contact
    eng.step(2.0)
    assert eng.metrics.n_collisions == 1 and eng.in_contact
    eng.set_cmd_vel(-0.2, 0.0)
    eng.step(1.0)
    assert not eng.in_contact
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(3.0)
    assert eng.metrics.n_collisions == 2


def test_automatic_back_off_makes_the_next_push_a_new_contact():
    eng = SimEngine(room_world([]), SimParams(collision_backup_m=0.15, **FAST))
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(25.0)
    assert eng.metrics.n_collisions == 1 and not eng.backing_up
    assert eng.pose[0] == pytest.approx(6.0 - 0.22 - 0.15, abs=0.01)
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(3.0)
    assert eng.metrics.n_collisions == 2


@pytest.mark.parametrize("retries", [0, 2])
def test_collision_aborts_the_active_goal_after_the_retries(retries):
    eng = SimEngine(room_world(bench(3.0, 2.0)),
                    SimParams(nav_collision_retries=retries, **FAST))
    eng.step(0.1)
    eng.set_goal(5.0, 2.0, 0.0)       # straight under the seat the lidar cannot see
    eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, 120.0)
    assert eng.nav_status.state is NavState.ABORTED
    assert "collision with bench_1" in eng.nav_status.reason
    # Every retry backs off, replans the same lane and bumps into the seat again.
    assert eng.metrics.n_collisions == retries + 1 and eng.metrics.goals_aborted == 1
    for ev in eng.metrics.collisions:
        assert ev.x_m == pytest.approx(3.0 - 0.25 - 0.22, abs=0.01)


def test_after_a_collision_with_retries_left_the_goal_stays_active_and_is_replanned():
    eng = SimEngine(room_world(bench(3.0, 2.0)), SimParams(nav_collision_retries=1, **FAST))
    eng.step(0.1)
    eng.set_goal(5.0, 2.0, 0.0)
    eng.run_until(lambda e: e.metrics.n_collisions == 1, 60.0)
    plans = eng.navigator.plan_count
    assert eng.nav_status.state is NavState.ACTIVE and eng.backing_up
    eng.run_until(lambda e: not e.backing_up, 10.0)
    eng.step(0.5)
    assert eng.navigator.plan_count > plans              # replanned from the new pose
    assert eng.nav_status.state is NavState.ACTIVE and eng.velocity[0] > 0.0


# --------------------------------------------------------------------- mapping


def test_mapper_marks_hit_occupied_and_ray_free_with_literal_cells():
    m = ScanMapper((0.0, 0.0), MappingParams(resolution_m=0.1, initial_size_m=2.0,
                                             grow_chunk_m=1.0))
    m.integrate_scan((0.05, 0.05, 0.0), np.array([0.52], np.float32), 0.0, 0.1, 3.0)
    g = m.grid()
    r, c0 = g.world_to_cell(0.05, 0.05)
    assert g.data[r, c0:c0 + 7].tolist() == [0, 0, 0, 0, 0, 100, -1]
    assert int((g.data >= 0).sum()) == 6


def test_mapper_no_return_carves_to_range_max_and_ignores_nan_and_too_close():
    m = ScanMapper((0.0, 0.0), MappingParams(resolution_m=0.1, initial_size_m=2.0,
                                             grow_chunk_m=1.0))
    ranges = np.array([np.inf, np.nan, -np.inf], np.float32)
    m.integrate_scan((0.05, 0.05, 0.0), ranges, 0.0, math.pi / 2, 1.0, 0.12)
    g = m.grid()
    r, c = g.world_to_cell(0.05, 0.05)
    assert g.data[r, c:c + 11].tolist() == [0] * 11     # +x: free up to x = 1.05 m
    assert (g.data[r, c + 11:] == -1).all()
    assert (g.data[r + 1:, c] == -1).all()               # +y (NaN): untouched
    assert (g.data[r, :c] == -1).all()                   # -x (too close): untouched
    assert not (g.data == 100).any()


def test_map_grows_in_chunks_and_a_wall_keeps_its_world_position():
    res = 0.05
    m = ScanMapper((0.0, 0.0), MappingParams(resolution_m=res, initial_size_m=2.0,
                                             grow_chunk_m=1.0))
    m.integrate_scan((0.0, 0.0, 0.0), np.array([0.8], np.float32), 0.0, 0.1, 5.0)
    g0 = m.grid()
    wall = np.argwhere(g0.data == 100)
    assert len(wall) == 1
    wall_xy = g0.cell_to_world(*wall[0])
    # A long beam to -x and one to +y make the map grow on those sides.
    m.integrate_scan((0.0, 0.0, math.pi), np.array([3.0], np.float32), 0.0, 0.1, 5.0)
    m.integrate_scan((0.0, 0.0, math.pi / 2), np.array([2.4], np.float32), 0.0, 0.1, 5.0)
    g1 = m.grid()
    assert g0.origin_xy_m == pytest.approx((-1.0, -1.0))
    assert g1.origin_xy_m == pytest.approx((-3.0, -1.0))      # two 1 m chunks to the west
    assert g1.shape == (g0.height + 40, g0.width + 40)
    assert g1.data[g1.world_to_cell(*wall_xy)] == 100
    assert int((g1.data == 100).sum()) == 3
    assert g1.data[g1.world_to_cell(-3.0 + 0.01, 0.01)] == 100
    assert g1.data[g1.world_to_cell(0.01, 2.4 + 0.01)] == 100


def _scripted_tour(eng: SimEngine, legs: list[tuple[float, float, float]]) -> None:
    for v, w, dur in legs:
        eng.set_cmd_vel(v, w)
        eng.step(dur)


def test_scripted_tour_map_converges_to_ground_truth():
    parts = (chair(4.0, 1.0) + [box("cab", "cabinet", "body", 2.5, 3.4, 0.8, 0.4, 0.0, 1.0),
                                cyl("bin", "other", "body", 4.8, 3.0, 0.2, 0.0, 0.6)])
    world = room_world(parts)
    eng = SimEngine(world, SimParams(lidar_noise_std_m=0.01, compute_coverage=True))
    turn = 2 * math.pi / 1.0
    _scripted_tour(eng, [(0.0, 1.0, turn), (0.26, 0.0, 7.0), (0.0, 1.0, turn),
                         (0.0, -1.0, math.pi / 2), (0.26, 0.0, 3.0), (0.0, 1.0, turn)])
    assert eng.metrics.n_collisions == 0
    grid = eng.map
    truth = eng.ground_truth.as_map("lidar").resample_to(grid, fill=-1)
    seen = (grid.data >= 0) & (truth >= 0)
    assert seen.sum() > 0.9 * eng.ground_truth.inside.sum()
    # A hit on a surface lying on a cell border may land in either cell: a mapped
    # obstacle agrees when the truth has one within one cell; a mapped free cell
    # agrees when the truth cell is free.
    occ, gt_occ = grid.data >= 65, truth >= 65
    near_gt = cv2.dilate(gt_occ.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    agree = np.where(occ, near_gt, ~gt_occ)
    assert agree[seen].mean() >= 0.95
    assert near_gt[occ].mean() >= 0.98                  # obstacles where they are
    assert (~gt_occ[seen & ~occ]).mean() >= 0.98        # free space never on obstacles
    # Inner wall faces (truth wall cells next to the inside) are mapped within one cell.
    inside = eng.ground_truth.inside
    gt_occ = eng.ground_truth.lidar.data >= 65
    near_inside = cv2.dilate(inside.astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    faces = eng.ground_truth.lidar.with_data(
        np.where(gt_occ & near_inside, 100, 0).astype(np.int8)).resample_to(grid, fill=0) == 100
    mapped = cv2.dilate((grid.data >= 65).astype(np.uint8), np.ones((3, 3), np.uint8)) > 0
    assert mapped[faces].mean() >= 0.9
    assert eng.metrics.coverage_pct >= 90.0


# ------------------------------------------------------------------ navigation


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


# ------------------------------------------------------------ planner pieces


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


# --------------------------------------------------------------------- metrics


def test_coverage_counts_inside_cells_known_free_in_a_shifted_map():
    truth, _ = grid_from_ascii("""
    ######
    #....#
    #....#
    ######
    """, resolution_m=0.1)
    inside = truth.free_mask()
    ref = CoverageReference(inside, truth)
    mdata, _ = grid_from_ascii("""
    ???????
    ??..#.?
    ???????
    ??????.
    """, resolution_m=0.1)
    # origin (-0.1, -0.1): map cell (r, c) lies on truth cell (r - 1, c - 1), so map row 2
    # covers inside row 1: 3 of the 8 inside cells known free, 4 known.
    shifted = GridMap(mdata.data, 0.1, (-0.1, -0.1))
    assert ref.coverage(shifted) == pytest.approx((37.5, 50.0))
    off_lattice = GridMap(mdata.data, 0.1, (-0.1 + 0.01, -0.1 + 0.01))   # general path
    assert ref.coverage(off_lattice) == pytest.approx((37.5, 50.0))


def test_metrics_json_and_diagnostics(tmp_path):
    m = SimMetrics(None, history_max=4)
    m.add_distance(1.5)
    m.add_collision(CollisionEvent(2.0, 1.0, 2.0, "chair_1", "chair", "seat"))
    m.goal_received()
    m.goal_aborted("collision with chair_1 (seat)")
    out = m.to_json(tmp_path / "a" / "m.json")
    d = json.loads(out.read_text())
    assert d["collisions"] == 1 and d["path_length_m"] == 1.5 and d["coverage_pct"] is None
    assert d["collision_events"][0]["object"] == "chair_1"
    assert d["abort_reasons"] == {"collision with": 1}
    diag = dict(m.to_diagnostics())
    assert diag["collisions"] == "1" and diag["goals_aborted"] == "1"
    assert "chair_1/seat" in diag["last_collision"]


def test_coverage_history_stays_bounded():
    truth, _ = grid_from_ascii("....\n....")
    gt = type("GT", (), {"inside": truth.free_mask(), "lidar": truth})()
    m = SimMetrics(gt, history_max=8)
    for k in range(100):
        m.update_coverage(truth, float(k))
    hist = m.coverage_history
    assert len(hist) < 8 and hist[0][0] == 0.0 and hist[-1][0] > 80.0
    assert all(c == 100.0 for _, c in hist)


# ------------------------------------------------------------------- rendering


def test_render_map_colours_and_overlays(tmp_path):
    grid, _ = grid_from_ascii("""
    ?????
    ?...#
    ?...#
    """, resolution_m=0.1)
    img = render_map(grid, Overlays(collisions=[(0.25, 0.15)]), scale=10)
    assert img.shape == (30, 50, 3)
    assert tuple(img[5, 5]) == (160, 160, 160)             # unknown, top-left
    assert tuple(img[25, 45]) == (0, 0, 0)                 # occupied, bottom-right
    assert tuple(img[15, 15]) == (255, 255, 255)           # free
    red = (img[..., 0] > 200) & (img[..., 1] < 50) & (img[..., 2] < 50)
    ys, xs = np.nonzero(red)
    assert abs(xs.mean() - 25) < 2 and abs(ys.mean() - 15) < 2
    with pytest.raises(ValueError, match="regions shape"):
        render_map(grid, Overlays(regions=np.zeros((2, 2), np.int32)))
    with pytest.raises(ValueError, match="frontier mask shape"):
        render_map(grid, Overlays(frontiers=np.zeros((2, 2), bool)))
    with pytest.raises(ValueError, match="frontiers must be"):
        render_map(grid, Overlays(frontiers=np.zeros((4, 3))))
    pts = render_map(grid, Overlays(frontiers=np.array([[0.15, 0.25]])), scale=10)
    mask = np.zeros(grid.shape, bool)
    mask[2, 1] = True                                    # the same cell as a mask
    cells = render_map(grid, Overlays(frontiers=mask), scale=10)
    magenta = (255, 0, 200)
    assert tuple(pts[5, 15]) == magenta and tuple(cells[5, 15]) == magenta
    path = render_map_png(tmp_path / "m.png", grid, scale=4)
    assert Image.open(path).size == (20, 12)


def test_gif_writer_keeps_at_most_max_frames(tmp_path):
    w = GifWriter(tmp_path / "run.gif", every=1, max_frames=6, max_side_px=32)
    for k in range(50):
        w.add(np.full((64, 40, 3), k * 5, np.uint8))
    assert 3 <= len(w) < 6
    out = w.write()
    with Image.open(out) as im:
        assert im.n_frames == len(w) and max(im.size) <= 32
    with pytest.raises(ValueError, match="no frames"):
        GifWriter(tmp_path / "x.gif").write()



def test_pursuit_arc_check_rejects_a_lookahead_point_around_an_obstacle_corner():
    """The lookahead point is taken only if the arc to it stays out of the lethal zone."""
    from sim_bridge.navigation import Navigator

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
    # Straight on along the lane, or around the corner with room: clear.
    assert nav._arc_clear(pose, np.array([1.7, 1.25]))
    assert nav._arc_clear(pose, np.array([2.1, 1.62]))

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
