"""The rrt_exploration baseline: RRT frontier points, mean shift, revenue, determinism,
parameters, and the decision core running it (Umari & Mukhopadhyay 2017)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import Frontier, FrontierParams, traversable_mask
from explore_seg.core.grid import GridMap
from explore_seg.core.rrt import (CellClasses, RrtFrontierDetector, RrtParams, RrtTree,
                                  information_gain_m2, mean_shift, walk_edge)
from explore_seg.core.rrt.tree import FREE, OBSTACLE, UNKNOWN
from explore_seg.core.selection import Action, SelectionParams, compute_costs

RES = 0.05
FP = FrontierParams(robot_radius_m=0.1)


def half_known(wall_x_m: float | None = None, size_m=(6.0, 4.0)) -> GridMap:
    """A walled 6 x 4 m box: x < 3 m known free, x >= 3 m unknown. With ``wall_x_m`` a
    closed wall at that x (the known part then is a closed room)."""
    w, h = int(size_m[0] / RES), int(size_m[1] / RES)
    data = np.zeros((h, w), np.int8)
    data[:, int(3.0 / RES):] = -1
    data[0, :] = data[-1, :] = 100
    data[:, 0] = data[:, -1] = 100
    if wall_x_m is not None:
        data[:, int(wall_x_m / RES) - 1:int(wall_x_m / RES) + 1] = 100
    return GridMap(data, RES, (0.0, 0.0))


def test_walk_edge_classifies_free_obstacle_and_unknown_edges():
    cells = CellClasses.from_grid(half_known(wall_x_m=2.0), 65)
    assert walk_edge((0.5, 2.0), (1.5, 2.0), cells)[0] == FREE
    assert walk_edge((0.5, 2.0), (2.5, 2.0), cells)[0] == OBSTACLE      # through the wall
    cells = CellClasses.from_grid(half_known(), 65)
    status, point = walk_edge((2.0, 2.0), (4.0, 2.0), cells)
    assert status == UNKNOWN
    assert 3.0 <= point[0] < 3.0 + RES        # where the edge entered unknown space
    assert point[1] == pytest.approx(2.0)


def test_tree_grows_only_through_free_space():
    cells = CellClasses.from_grid(half_known(wall_x_m=2.0), 65)
    tree = RrtTree((1.0, 2.0), 1.0)
    rng = np.random.default_rng(0)
    for x, y in rng.uniform((0, 0), (6, 4), (400, 2)):
        tree.extend((x, y), cells)
    v = tree.vertices
    assert len(v) > 20
    assert (v[:, 0] < 2.0).all()               # never past the wall
    assert np.hypot(*np.diff(v[:2], axis=0).T) <= 1.0 + 1e-9


def test_rrt_finds_frontier_points_on_the_boundary_of_the_known_space():
    grid = half_known()
    det = RrtFrontierDetector(RrtParams(iterations_per_step=300), FP)
    pts = det.grow(grid, (1.0, 2.0))
    assert len(pts) >= 5 and det.points_found == len(pts)
    r, c = grid.world_to_cells(pts[:, 0], pts[:, 1])
    assert (grid.data[r, c] == -1).all()                    # each point in unknown space
    free_nb = np.zeros(len(r), bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            free_nb |= grid.data[r + dr, c + dc] == 0
    assert free_nb.all()                                    # ... next to known free space
    assert np.ptp(pts[:, 1]) > 1.0                          # spread along the boundary


def test_no_frontier_points_in_a_closed_room():
    det = RrtFrontierDetector(RrtParams(iterations_per_step=300), FP)
    grid = half_known(wall_x_m=2.0)
    assert len(det.grow(grid, (1.0, 2.0))) == 0
    passable = traversable_mask(grid, None, FP)
    assert det.update(grid, (1.0, 2.0), passable) == []


def test_mean_shift_merges_nearby_points_and_keeps_far_ones_apart():
    rng = np.random.default_rng(1)
    a = rng.normal((1.0, 1.0), 0.03, (20, 2))
    b = rng.normal((3.0, 1.0), 0.03, (8, 2))
    centres, counts = mean_shift(np.vstack([a, b]), 0.3)
    assert counts.tolist() == [20, 8]                       # biggest cluster first
    assert centres[0] == pytest.approx(a.mean(axis=0), abs=1e-9)
    assert centres[1] == pytest.approx(b.mean(axis=0), abs=1e-9)
    line = np.column_stack([np.arange(5) * 1.0, np.zeros(5)])   # 1 m apart
    assert len(mean_shift(line, 0.3)[0]) == 5
    assert len(mean_shift(np.zeros((0, 2)), 0.3)[0]) == 0
    with pytest.raises(ValueError, match="bandwidth"):
        mean_shift(line, 0.0)


def test_filter_collapses_points_to_centres_and_drops_explored_ones():
    grid = half_known()
    passable = traversable_mask(grid, None, FP)
    det = RrtFrontierDetector(RrtParams(), FP)
    boundary = np.column_stack([np.full(10, 3.01), np.linspace(1.0, 1.1, 10)])
    known = np.array([[1.0, 2.0]])          # deep in explored space: no information
    kept = det.filter(grid, np.vstack([boundary, known]), passable)
    assert len(kept) == 1
    assert kept[0] == pytest.approx(boundary.mean(axis=0))
    (f,) = det.candidates(grid, passable)
    assert f.point_passable and grid.data[f.point_rc] == 0
    assert f.info_gain_m2 == pytest.approx(f.size_cells * RES * RES)
    assert f.info_gain_m2 == pytest.approx(information_gain_m2(grid, kept, 1.0)[0])
    # about half of the 1 m disc around a boundary point is unknown
    assert 0.35 * math.pi < f.info_gain_m2 < 0.65 * math.pi


def _cands(gains, dists):
    fs = [Frontier(i, 10, 0.5, (0, i), (0.0, float(i)), True, (0.0, float(i)),
                   (0.0, float(i)), np.zeros((10, 2), np.int64), info_gain_m2=g)
          for i, g in enumerate(gains)]
    return fs, np.asarray(dists, float)


def test_revenue_ordering():
    sp = SelectionParams(strategy="rrt_exploration")   # info_multiplier 3, radius 3, gain 2
    fs, d = _cands([1.0, 2.0], [5.0, 5.0])
    c = compute_costs(fs, d, None, 0, sp)
    assert c.tolist() == pytest.approx([5.0 - 3.0, 5.0 - 6.0])     # more gain wins
    fs, d = _cands([1.0, 1.0], [4.0, 6.0])
    assert np.argmin(compute_costs(fs, d, None, 0, sp)) == 0        # nearer wins
    # hysteresis: within 3 m the gain counts twice, so a near small gain beats a far
    # big one that would win without it
    fs, d = _cands([1.0, 1.5], [2.5, 3.5])
    c = compute_costs(fs, d, None, 0, sp)
    assert c.tolist() == pytest.approx([2.5 - 6.0, 3.5 - 4.5])
    assert np.argmin(compute_costs(fs, d, None, 0, SelectionParams(
        strategy="rrt_exploration", hysteresis_gain=1.0))) == 1
    fs, d = _cands([1.0, float("nan")], [5.0, np.inf])
    c = compute_costs(fs, d, None, 0, sp)
    assert c[0] == pytest.approx(2.0) and c[1] == np.inf


def _run(seed: int, steps: int = 6) -> list[np.ndarray]:
    grid = half_known()
    passable = traversable_mask(grid, None, FP)
    det = RrtFrontierDetector(RrtParams(seed=seed, iterations_per_step=50), FP)
    return [np.array([f.centroid_xy_m for f in det.update(grid, (1.0, 2.0), passable)])
            for _ in range(steps)]


def test_same_seed_same_points_other_seed_other_points():
    a, b, c = _run(3), _run(3), _run(4)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not all(x.shape == y.shape and np.allclose(x, y) for x, y in zip(a, c))


@pytest.mark.parametrize("kwargs, match", [
    ({"global_eta_m": 0.0}, "global_eta_m"), ({"local_eta_m": math.inf}, "local_eta_m"),
    ({"info_radius_m": -1.0}, "info_radius_m"), ({"cluster_bandwidth_m": 0.0}, "bandwidth"),
    ({"min_info_gain_m2": -0.1}, "min_info_gain_m2"), ({"iterations_per_step": 0}, "iter"),
    ({"seed": -1}, "seed"),
])
def test_rrt_params_are_validated(kwargs, match):
    with pytest.raises(ValueError, match=match):
        RrtParams(**kwargs)


@pytest.mark.parametrize("name", ["info_multiplier", "hysteresis_radius_m", "hysteresis_gain"])
def test_assigner_params_are_validated(name):
    with pytest.raises(ValueError, match=name):
        SelectionParams(strategy="rrt_exploration", **{name: -1.0})


def test_explorer_runs_rrt_exploration_and_sends_a_goal_at_the_boundary():
    grid = half_known()
    ex = Explorer(FP, SelectionParams(strategy="rrt_exploration"), RrtParams(seed=1))
    out = ex.step(0.0, grid, (1.0, 2.0, 0.0))
    assert out.action is Action.NEW_GOAL and out.detected
    assert out.frontiers and all(f.info_gain_m2 > 0 for f in out.frontiers)
    gx, gy = out.goal.xy_m
    assert 2.0 < gx < 3.0 and grid.data[grid.world_to_cell(gx, gy)] == 0
    assert ex.rrt_detector is not None and ex.rrt_detector.points_found > 0
    # the trees grow at every step, also on the same map
    found = ex.rrt_detector.points_found
    assert ex.step(1.0, grid, (1.0, 2.0, 0.0)).detected
    assert ex.rrt_detector.points_found > found
    ex.set_params(rrt=RrtParams(seed=2))
    assert ex.rrt_detector is None and ex.rrt_params.seed == 2


def test_explorer_finishes_a_closed_room():
    grid = half_known(wall_x_m=2.0)
    ex = Explorer(FP, SelectionParams(strategy="rrt_exploration", done_confirmations=2),
                  RrtParams(iterations_per_step=50))
    actions = [ex.step(float(t), grid, (1.0, 2.0, 0.0)).action for t in range(3)]
    assert actions[-1] is Action.DONE


def test_lockstep_runs_rrt_exploration_deterministically():
    from sim_bridge.lockstep import STRATEGY_SPECS, LockstepParams, run_exploration
    from sim_bridge.worlds import default_world, ground_truth

    spec = STRATEGY_SPECS["rrt_exploration"]
    assert spec.selection == "rrt_exploration" and not spec.use_objects \
        and not spec.use_regions
    w = default_world("small_house")
    gt = ground_truth(w)
    a, b = (run_exploration(w, "rrt_exploration", 3, params=LockstepParams(max_sim_time_s=25.0),
                            ground_truth=gt)
            for _ in range(2))
    assert a.goals_sent >= 1 and a.coverage_pct > 10.0
    da, db = a.to_dict(), b.to_dict()
    for d in (da, db):
        d.pop("wall_time_s")
        d.pop("timings_ms")
    assert da == db


def test_mean_shift_equals_scikit_learn_on_the_filter_point_sets():
    """scikit-learn's MeanShift (which the original rrt_exploration uses) is the reference:
    the same centres, in the same order, on the point sets the filter clusters in a
    lock-step run (bench/bench_libraries.py records them)."""
    pytest.importorskip("sklearn")
    from bench.bench_libraries import mean_shift_sklearn, record_mean_shift_calls
    calls = record_mean_shift_calls("small_house", [0], 25.0)
    assert len(calls) >= 10
    merged = 0
    for args, kwargs in calls:
        centres, _ = mean_shift(*args, **kwargs)
        ref = mean_shift_sklearn(*args, **kwargs)
        assert centres.shape == ref.shape
        np.testing.assert_allclose(centres, ref, rtol=0.0, atol=1e-9)
        merged += len(centres) < len(args[0])
    assert merged > 0                        # some calls merge points into one centre
