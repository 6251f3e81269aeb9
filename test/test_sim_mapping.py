"""Simulator mapping: the scan mapper's cells and the map an engine builds on a tour."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.mapping import MappingParams, ScanMapper
from sim_scenes import box, chair, cyl, room_world


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
    m.integrate_scan((0.0, 0.0, math.pi), np.array([2.75], np.float32), 0.0, 0.1, 5.0)
    m.integrate_scan((0.0, 0.0, math.pi / 2), np.array([2.4], np.float32), 0.0, 0.1, 5.0)
    g1 = m.grid()
    assert g0.origin_xy_m == pytest.approx((-1.0, -1.0))
    assert g1.origin_xy_m == pytest.approx((-3.0, -1.0))      # two 1 m chunks to the west
    assert g1.shape == (g0.height + 40, g0.width + 40)
    assert g1.data[g1.world_to_cell(*wall_xy)] == 100
    assert int((g1.data == 100).sum()) == 3
    assert g1.data[g1.world_to_cell(-2.75 + 0.01, 0.01)] == 100
    assert g1.data[g1.world_to_cell(0.01, 2.4 + 0.01)] == 100


@pytest.mark.parametrize("range_max", [0.91, 0.94])
def test_free_space_never_reaches_the_border(range_max):
    # A beam without return whose end (and so its last free sample) lies in the map's
    # last cell: the map grows, so an unknown cell lies beyond and a frontier is there.
    from explore_seg.core.frontiers import FrontierParams, detect_frontier_cells
    m = ScanMapper((0.0, 0.0), MappingParams(resolution_m=0.1, initial_size_m=2.0,
                                             grow_chunk_m=1.0))
    m.integrate_scan((0.05, 0.05, 0.0), np.array([np.inf], np.float32), 0.0, 0.1, range_max)
    g = m.grid()
    edge = np.concatenate([g.data[0], g.data[-1], g.data[:, 0], g.data[:, -1]])
    assert not (edge == 0).any()
    r, c = g.world_to_cell(0.05, 0.05)
    last = int(np.flatnonzero(g.data[r] == 0).max())
    assert g.data[r, last + 1] == -1
    front = detect_frontier_cells(g, params=FrontierParams(min_group_size_cells=1))
    assert front[r, last + 1]


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


def test_published_grid_equals_the_log_odds_thresholded_after_random_scans_and_growth():
    """The trinary map kept cell by cell equals the one rebuilt from the log-odds."""
    rng = np.random.default_rng(3)
    p = MappingParams(initial_size_m=2.0, grow_chunk_m=1.0)
    m = ScanMapper((0.0, 0.0), p)
    for k in range(40):
        pose = (float(rng.uniform(-1, 1)), float(rng.uniform(-1, 1)), float(rng.uniform(-3, 3)))
        ranges = rng.uniform(0.2, 4.0, 90)
        ranges[rng.random(90) < 0.2] = np.inf
        m.integrate_scan(pose, ranges, -math.pi, 2 * math.pi / 90, 3.5, 0.1)
        g = m.grid(k)
        lo = m.log_odds
        ref = np.full(lo.shape, -1, np.int8)
        observed = m._observed
        ref[observed] = 0
        ref[observed & (lo > p.occupied_threshold_log_odds)] = 100
        assert np.array_equal(g.data, ref)
    assert m.shape[0] > 40 and (g.data == 100).any() and (g.data == 0).any()
