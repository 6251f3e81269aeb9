"""The ``routed`` strategy: viewpoint gain, tours (greedy, 2-opt, Or-opt), tour costs,
hysteresis through the decision core, and the pairwise path lengths it uses."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from explore_seg.core.block_graph import BlockGraph
from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import GridMap
from explore_seg.core.selection import STRATEGIES, Action, SelectionParams, compute_costs
from explore_seg.core.selection.tour import (front_costs, greedy_order, improve, solve_tour,
                                             tour_length)
from explore_seg.core.selection.pair_paths import PairPaths
from explore_seg.core.selection.viewpoints import (GainCache, candidate_cells,
                                                   pick_viewpoint, view_gain)
from selection_cases import two_frontiers

RES = 0.05


def _grid(data: np.ndarray) -> GridMap:
    return GridMap(np.asarray(data, dtype=np.int8), RES, (0.0, 0.0))


def _dist_matrix(xy: np.ndarray) -> np.ndarray:
    return np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])


# ------------------------------------------------------------------------- viewpoint gain

def test_gain_is_the_visible_unknown_area():
    # 6 x 6 m free square, a 4 m unknown strip east of it: a sensor at the border sees a
    # half disc of unknown space (pi * r^2 / 2), one 3 m inside sees less.
    data = np.zeros((120, 200), dtype=np.int8)
    data[:, 120:] = -1
    g = _grid(data)
    gain = view_gain(g, np.array([[60, 119], [60, 59]]), range_m=2.0, rays=72)
    assert gain[0] == pytest.approx(np.pi * 2.0 ** 2 / 2, rel=0.15)
    assert 0 <= gain[1] < 0.05 * gain[0]


def test_walls_block_the_view():
    data = np.zeros((100, 200), dtype=np.int8)
    data[:, 120:] = -1
    data[:, 100:102] = 100                       # a wall between the sensor and the unknown
    g = _grid(data)
    gain = view_gain(g, np.array([[50, 95], [50, 110]]), range_m=3.0, rays=48)
    assert gain[0] == 0.0
    assert gain[1] > 1.0


def _exploring_maps(shifts):
    """A map that is revealed disc by disc around a moving robot and grows towards negative
    x / y by ``shifts`` cells (row, col) per step: the sequence a mapper publishes."""
    rng = np.random.default_rng(7)
    world = np.where(rng.random((140, 160)) < 0.03, 100, 0).astype(np.int8)
    world[70, 20:140] = 100                                  # a wall with a gap
    world[70, 80:90] = 0
    known = np.zeros(world.shape, dtype=bool)
    rr, cc = np.mgrid[0:140, 0:160]
    off = np.array([20, 20])                                 # world cell of the map's (0, 0)
    grids = []
    for k, (sr, sc) in enumerate(shifts):
        centre = (50 + 7 * k, 40 + 11 * k)
        known |= (rr - centre[0]) ** 2 + (cc - centre[1]) ** 2 < 25 ** 2
        off = off - (sr, sc)
        data = np.where(known, world, -1)[off[0]:, off[1]:]
        origin = (float(off[1]) * RES, float(off[0]) * RES)
        grids.append((GridMap(np.ascontiguousarray(data), RES, origin), off.copy()))
    return grids


@pytest.mark.parametrize("shifts", [[(0, 0)] * 8, [(0, 0), (4, 2), (0, 6), (2, 2), (0, 0),
                                                    (8, 0), (2, 4), (0, 0)],
                                    [(0, 0), (3, 0), (1, 1), (0, 0), (5, 3), (0, 0), (1, 0),
                                     (0, 0)]])
def test_kept_gains_equal_a_full_cast_as_the_map_grows(shifts):
    # Even shifts keep the coarse lattice (gains kept), odd ones do not (cast again):
    # either way every gain equals view_gain's on the same map, and a map that changed
    # near the robot only is cast again near the robot only.
    cache = GainCache(range_m=1.5, rays=24)
    rng = np.random.default_rng(1)
    casts = []
    maps = _exploring_maps(shifts)
    g0, off0 = maps[0]
    first = np.argwhere(g0.data == 0)
    fixed = first[rng.choice(len(first), 150, replace=False)] + off0    # world cells
    for g, off in maps:
        free = np.argwhere(g.data == 0)
        cells = np.vstack([fixed - off, free[rng.choice(len(free), 150, replace=False)]])
        got = cache.gains(g, cells)
        np.testing.assert_array_equal(got, view_gain(g, cells, 1.5, 24))
        casts.append(cache.cast)
        again = cache.gains(g, cells)                        # same map: nothing cast
        assert cache.cast == 0
        np.testing.assert_array_equal(again, got)
    if all(r % 2 == 0 and c % 2 == 0 for r, c in shifts):
        # The first disc lies far behind the robot at the end: its gains are kept.
        assert casts[-1] <= 150


def test_view_gain_rejects_bad_arguments():
    g = _grid(np.zeros((10, 10)))
    with pytest.raises(ValueError, match="range_m"):
        view_gain(g, [[1, 1]], range_m=0.0)
    with pytest.raises(ValueError, match="rays"):
        view_gain(g, [[1, 1]], rays=2)


def test_viewpoint_is_the_best_view_and_then_the_closest():
    assert pick_viewpoint(np.array([5.0, 10.0, 9.5]), np.array([1.0, 8.0, 3.0]), 0.1) == 2
    assert pick_viewpoint(np.array([5.0, 10.0, 9.5]), np.array([1.0, 8.0, 3.0]), 0.0) == 1
    assert pick_viewpoint(np.array([5.0, 10.0]), np.array([1.0, np.inf]), 0.1) == 0
    assert pick_viewpoint(np.array([5.0]), np.array([np.inf]), 0.1) is None


def test_candidates_are_passable_near_the_frontier_and_start_with_the_cpoint():
    pas = np.zeros((60, 60), dtype=bool)
    pas[:, :30] = True
    cells = np.array([[30, 30], [31, 30], [32, 30]])
    c = candidate_cells(cells, (31, 29), pas, radius_cells=10, step_cells=5)
    assert tuple(c[0]) == (31, 29)
    assert pas[c[1:, 0], c[1:, 1]].all()
    d = np.hypot(c[1:, None, 0] - cells[None, :, 0], c[1:, None, 1] - cells[None, :, 1]).min(1)
    assert (d <= 10).all() and len(c) > 5
    assert (c[1:] % 5 == 0).all()                # on the global lattice


# ---------------------------------------------------------------------------------- tours

def test_known_instance_is_solved_to_its_optimum():
    # Robot at 0 on a line, points at 1, -1.5, 3: greedy goes 1, 3, -1.5 (7.5 m), the
    # optimum goes -1.5, 1, 3 (6 m).
    x = np.array([0.0, 1.0, -1.5, 3.0])
    cost = np.abs(x[:, None] - x[None, :])
    cost[:, 0] = 0.0
    assert greedy_order(cost).tolist() == [1, 3, 2]
    assert tour_length(cost, greedy_order(cost)) == pytest.approx(7.5)
    t = solve_tour(cost)
    assert t.order.tolist() == [2, 1, 3]
    assert t.length_m == pytest.approx(6.0)


@pytest.mark.parametrize("seed", range(30))
def test_improvement_is_never_worse_than_greedy_and_small_tours_are_near_optimal(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 8))
    cost = _dist_matrix(rng.uniform(0, 10, (n, 2))) * rng.uniform(1.0, 1.3, (n, n))
    cost[:, 0] = 0.0
    np.fill_diagonal(cost, 0.0)
    greedy = greedy_order(cost)
    t = solve_tour(cost)
    assert sorted(t.order.tolist()) == list(range(1, n))
    assert t.length_m == pytest.approx(tour_length(cost, t.order))
    assert t.length_m <= tour_length(cost, greedy) + 1e-9
    best = min(tour_length(cost, p) for p in itertools.permutations(range(1, n)))
    assert t.length_m <= 1.1 * best + 1e-9


def test_fixed_first_and_front_costs():
    rng = np.random.default_rng(7)
    cost = _dist_matrix(rng.uniform(0, 10, (7, 2)))
    cost[:, 0] = 0.0
    t = solve_tour(cost)
    front = front_costs(cost, t)
    assert front[t.order[0]] == pytest.approx(t.length_m)
    for j in range(1, 7):
        moved = [j] + [k for k in t.order if k != j]
        assert front[j] == pytest.approx(tour_length(cost, moved))
        own = solve_tour(cost, first=j)
        assert own.order[0] == j and own.length_m <= front[j] + 1e-9
    assert improve(cost, t.order).tolist() == t.order.tolist()     # a local optimum


def test_solve_tour_rejects_bad_matrices():
    with pytest.raises(ValueError, match="square"):
        solve_tour(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="finite"):
        solve_tour(np.array([[0.0, np.inf], [0.0, 0.0]]))
    with pytest.raises(ValueError, match="first"):
        solve_tour(np.zeros((3, 3)), first=0)
    assert solve_tour(np.zeros((1, 1))).order.size == 0


# ------------------------------------------------------------------ pairwise path lengths

@pytest.mark.parametrize("k", [1, 4])
def test_distance_matrix_matches_single_sweeps(k):
    rng = np.random.default_rng(3)
    pas = rng.random((50, 70)) > 0.25
    g = BlockGraph(pas, RES, k)
    cells = np.vstack([np.argwhere(pas)[rng.choice(int(pas.sum()), 8, replace=False)],
                       np.argwhere(~pas)[:1]])
    m = g.distance_matrix(cells)
    for i, c in enumerate(cells):
        d = g.distances(tuple(c), cells)
        d[i] = 0.0
        np.testing.assert_allclose(m[i], d)


def test_distance_rows_are_the_matrix_rows():
    rng = np.random.default_rng(5)
    pas = rng.random((40, 60)) > 0.25
    for k in (1, 3):
        g = BlockGraph(pas, RES, k)
        cells = np.argwhere(pas)[rng.choice(int(pas.sum()), 10, replace=False)]
        m = g.distance_matrix(cells)
        rows = g.distance_rows(cells[[7, 2]], cells)
        np.fill_diagonal(m, np.inf)                          # rows keep i -> i as swept
        for r, i in enumerate((7, 2)):
            np.testing.assert_array_equal(np.delete(rows[r], i), np.delete(m[i], i))
        assert g.distance_rows(np.zeros((0, 2)), cells).shape == (0, 10)


def test_distances_keep_the_robot_sweep_for_the_next_call():
    rng = np.random.default_rng(6)
    pas = rng.random((60, 80)) > 0.25
    g = BlockGraph(pas, RES, 4)
    cells = np.argwhere(pas)[rng.choice(int(pas.sum()), 11, replace=False)]
    rows = g.distance_rows(cells[:2], cells)
    first = g.distances(tuple(cells[0]), cells)
    np.testing.assert_allclose(np.delete(first, 0), np.delete(rows[0], 0))
    first[:] = -1.0                              # the caller's array, not the kept sweep
    for _ in range(2):                           # kept, then another start, then back
        np.testing.assert_allclose(np.delete(g.distances(tuple(cells[0]), cells), 0),
                                   np.delete(rows[0], 0))
        np.testing.assert_allclose(np.delete(g.distances(tuple(cells[1]), cells), 1),
                                   np.delete(rows[1], 1))


def _grid_graph(pas: np.ndarray) -> tuple[GridMap, BlockGraph]:
    data = np.where(pas, 0, 100).astype(np.int8)
    return GridMap(data, RES, (1.0, -2.0)), BlockGraph(pas, RES, 4)


def test_pair_paths_sweep_new_viewpoints_and_refresh_the_oldest():
    rng = np.random.default_rng(2)
    pas = rng.random((60, 80)) > 0.2
    grid, graph = _grid_graph(pas)
    cells = np.argwhere(pas)[rng.choice(int(pas.sum()), 12, replace=False)]
    exact = graph.distance_matrix(cells)
    cache = PairPaths(refresh_rows=2)
    np.testing.assert_array_equal(cache.matrix(graph, grid, cells), exact)
    assert cache.swept == 12
    # The next decision: 3 viewpoints gone, 2 new, the rest kept (2 of them refreshed).
    new = np.argwhere(pas)[rng.choice(int(pas.sum()), 2, replace=False)]
    now = np.vstack([cells[3:][::-1], new])
    m = cache.matrix(graph, grid, now)
    assert cache.swept == 2 + 2
    np.testing.assert_allclose(m, graph.distance_matrix(now), rtol=1e-12)
    # A wall across the map: kept lengths stay as they were until refreshed, every
    # length is the new map's within ceil(n / refresh_rows) decisions.
    walled = pas.copy()
    walled[:, 40] = False
    walled[30, 40] = True
    grid2, graph2 = _grid_graph(walled)
    target = graph2.distance_matrix(now)
    first = cache.matrix(graph2, grid2, now)
    assert not np.allclose(first, target)
    for _ in range(int(np.ceil(len(now) / 2)) - 1):
        last = cache.matrix(graph2, grid2, now)
    np.testing.assert_allclose(last, target, rtol=1e-12)


def test_pair_paths_with_enough_refresh_rows_are_exact_every_time():
    rng = np.random.default_rng(4)
    pas = rng.random((50, 50)) > 0.2
    grid, graph = _grid_graph(pas)
    cache = PairPaths(refresh_rows=1000)
    for _ in range(3):
        cells = np.argwhere(pas)[rng.choice(int(pas.sum()), 9, replace=False)]
        np.testing.assert_array_equal(cache.matrix(graph, grid, cells),
                                      graph.distance_matrix(cells))
    # Keys are world positions: a grown map (new origin) keeps them; a new frame does not.
    grown = GridMap(np.pad(grid.data, ((4, 0), (8, 0))), RES,
                    (grid.origin_xy_m[0] - 8 * RES, grid.origin_xy_m[1] - 4 * RES))
    cache = PairPaths(refresh_rows=0)
    cache.matrix(graph, grid, cells)
    cache.matrix(BlockGraph(np.pad(pas, ((4, 0), (8, 0))), RES, 4), grown, cells + [4, 8])
    assert cache.swept == 0
    cache.matrix(graph, GridMap(grid.data, RES, grid.origin_xy_m, frame_id="odom"), cells)
    assert cache.swept == 9
    with pytest.raises(ValueError, match="refresh_rows"):
        PairPaths(-1)


# ------------------------------------------------------- the strategy in the decision core

def test_routed_is_a_strategy_and_needs_tour_costs():
    assert "routed" in STRATEGIES
    _, fr, labels = two_frontiers()
    with pytest.raises(ValueError, match="tour costs"):
        compute_costs(fr, [1.0, 3.0], labels, 1, SelectionParams(strategy="routed"))
    costs = compute_costs(fr, [1.0, 3.0], labels, 1, SelectionParams(strategy="routed"),
                          tour_cost_m=np.array([7.0, 5.0]))
    assert costs.tolist() == [7.0, 5.0]


def _two_rooms() -> tuple[GridMap, tuple[float, float, float]]:
    """A 12 x 4 m known corridor with unknown space at both ends and one side room."""
    data = np.full((120, 300), -1, dtype=np.int8)
    data[40:80, 30:270] = 0
    data[38:40, 30:270] = 100
    data[80:82, 30:270] = 100
    data[38:40, 140:160] = 0                     # a doorway north
    g = _grid(data)
    x, y = g.cell_to_world(60, 100)
    return g, (x, y, 0.0)


def test_routed_step_sends_a_viewpoint_goal_with_a_tour():
    g, pose = _two_rooms()
    fp = FrontierParams(robot_radius_m=0.1)
    ex = Explorer(fp, SelectionParams(strategy="routed"))
    out = ex.step(0.0, g, pose)
    assert out.action is Action.NEW_GOAL
    assert out.tour is not None and len(out.tour.order) == 3
    assert out.selection.index == out.tour.order[0]
    assert out.tour.gain_m2[out.selection.index] > 0
    f = out.frontiers[out.selection.index]
    assert f.point_passable and g.data[f.point_rc] == 0
    assert out.goal.xy_m == f.point_xy_m
    assert 0 < out.route_s <= out.select_s
    # costs are tour lengths minus the weighted gain
    w = SelectionParams().gain_weight_m_per_m2
    i = out.selection.index
    assert out.selection.costs[i] == pytest.approx(out.tour.length_m - w * out.tour.gain_m2[i])
    # without the gain term: the chosen one is the tour's length, no other is cheaper
    plain = Explorer(fp, SelectionParams(strategy="routed", gain_weight_m_per_m2=0.0))
    out = plain.step(0.0, g, pose)
    fin = out.selection.costs[np.isfinite(out.selection.costs)]
    assert out.selection.costs[out.selection.index] == pytest.approx(out.tour.length_m)
    assert fin.min() == pytest.approx(out.tour.length_m)


def test_no_goal_flip_on_a_tiny_map_change():
    g, pose = _two_rooms()
    fp = FrontierParams(robot_radius_m=0.1)
    ex = Explorer(fp, SelectionParams(strategy="routed"))
    first = ex.step(0.0, g, pose)
    assert first.action is Action.NEW_GOAL
    for k in range(5):
        data = g.data.copy()
        data[60 + k, 30 + k] = 100               # a speck of noise at the west end
        data[40, 200 + k] = 0
        g = g.with_data(data)
        out = ex.step(1.0 + k, g, pose)
        assert out.action is Action.KEEP, out.reason
        assert out.goal == first.goal


def test_kept_path_lengths_are_forgotten_on_reset_and_clock_jumps():
    g, pose = _two_rooms()
    ex = Explorer(FrontierParams(robot_radius_m=0.1),
                  SelectionParams(strategy="routed", tour_refresh_rows=0))
    n = len(ex.step(0.0, g, pose).tour.order)
    assert n == 3
    data = g.data.copy()
    data[40, 200] = 100                          # a new map version, same viewpoints
    g = g.with_data(data)
    assert ex.step(1.0, g, pose).tour.swept == 0
    ex.clock_jumped(0.0)
    assert ex.step(0.5, g, pose).tour.swept == n
    assert ex.step(1.5, g.with_data(g.data.copy()), pose).tour.swept == 0
    ex.reset()
    assert ex.step(2.0, g, pose).tour.swept == n


def test_a_frontier_that_reveals_nothing_is_not_chased():
    # A room fully known but for a speck of unknown cells walled off except one free
    # neighbour: nearest sends a goal there, routed finishes (its view gains < min_gain).
    data = np.zeros((80, 80), dtype=np.int8)
    data[0:2, :] = data[-2:, :] = data[:, 0:2] = data[:, -2:] = 100
    data[30:36, 60:72] = 100
    data[32:34, 62:70] = -1                      # 16 unknown cells inside a box ...
    data[33, 60:62] = 0                          # ... with a slit towards the room
    data[33, 62] = -1
    g = _grid(data)
    x, y = g.cell_to_world(40, 20)
    fp = FrontierParams(robot_radius_m=0.05, min_group_size_cells=1)
    near = Explorer(fp, SelectionParams(strategy="nearest")).step(0.0, g, (x, y, 0.0))
    assert near.action is Action.NEW_GOAL
    ex = Explorer(fp, SelectionParams(strategy="routed", done_confirmations=2))
    outs = [ex.step(float(k), g, (x, y, 0.0)) for k in range(3)]
    assert outs[0].tour is not None and outs[0].tour.gain_m2.max() < 0.25
    assert [o.action for o in outs[:2]] == [Action.WAIT, Action.DONE]


def test_routed_splits_a_long_frontier_into_tour_stops():
    # A 10 m corridor whose whole north side is unknown: one frontier group. With
    # frontier_split_m (default 3 m) its parts are separate viewpoints, toured from the
    # robot's end; the other strategies (paper's Alg. 1) keep the group whole.
    data = np.zeros((40, 200), dtype=np.int8)
    data[:10] = -1
    data[-2:] = 100
    g = _grid(data)
    x, y = g.cell_to_world(30, 10)
    fp = FrontierParams(robot_radius_m=0.1)
    whole = Explorer(fp, SelectionParams(strategy="routed", frontier_split_m=0.0))
    assert len(whole.step(0.0, g, (x, y, 0.0)).frontiers) == 1
    out = Explorer(fp, SelectionParams(strategy="routed")).step(0.0, g, (x, y, 0.0))
    assert SelectionParams().frontier_split_m == 3.0
    assert len(out.frontiers) == 4 and len(out.tour.order) == 4
    cols = [float(out.frontiers[i].centroid_rc[1]) for i in out.tour.order]
    assert cols == sorted(cols)                   # west to east, from the robot's end
    assert out.goal.xy_m == out.frontiers[out.tour.order[0]].point_xy_m
    paper = Explorer(fp, SelectionParams(strategy="paper", frontier_split_m=3.0))
    assert len(paper.step(0.0, g, (x, y, 0.0)).frontiers) == 1


def _niche_and_hall() -> tuple[GridMap, tuple[float, float, float]]:
    """A known 10 x 2 m corridor; a 1 x 1 m unknown niche in its wall next to the robot
    (a small view) and a large unknown hall behind its far end (a big view)."""
    data = np.full((140, 260), 100, dtype=np.int8)
    data[60:100, 10:210] = 0                      # the corridor
    data[40:60, 40:60] = -1                       # the niche, open to the corridor
    data[20:120, 210:255] = -1                    # the hall, open at the corridor's end
    g = _grid(data)
    x, y = g.cell_to_world(80, 30)
    return g, (x, y, 0.0)


def test_leftovers_wait_while_a_bigger_view_remains_and_are_visited_last():
    g, pose = _niche_and_hall()
    fp = FrontierParams(robot_radius_m=0.1, min_group_size_cells=1)
    old = Explorer(fp, SelectionParams(strategy="routed", leftover_gain_m2=0.0)).step(
        0.0, g, pose)
    assert len(old.tour.order) == 2
    small, big = sorted(old.tour.order, key=lambda i: old.tour.gain_m2[i])
    assert old.tour.gain_m2[small] < 2.0 <= old.tour.gain_m2[big]
    assert old.selection.index == small           # on the way: the tour takes it first
    new = Explorer(fp, SelectionParams(strategy="routed")).step(0.0, g, pose)
    assert SelectionParams().leftover_gain_m2 == 2.0
    assert new.tour.order.tolist() == [big] and new.selection.index == big
    assert not np.isfinite(new.selection.costs[small])
    # once the hall is known, the niche is the goal: leftovers are visited, not dropped
    data = g.data.copy()
    data[20:120, 210:255] = 0
    data[20:22, 210:255] = data[118:120, 210:255] = data[20:120, 253:255] = 100
    late = Explorer(fp, SelectionParams(strategy="routed")).step(0.0, g.with_data(data), pose)
    assert late.action is Action.NEW_GOAL
    assert late.tour.order.tolist() == [0] and late.tour.gain_m2[0] < 2.0


def test_a_ragged_map_edge_is_not_a_leftover():
    # A hall whose east end is where the lidar's max-range beams ended: a ragged frontier
    # of 100 cells at the map's edge that sees almost nothing (the map, and so the view,
    # ends there), and a 2 x 2 m niche 7 m behind the robot. As a leftover the edge waits
    # and the robot turns round for the niche; a frontier of 3 m or more is never one.
    data = np.full((140, 260), 100, dtype=np.int8)
    data[40:80, 10:259] = 0
    data[40:80, 259] = -1
    data[40:80:2, 255:259] = -1                   # the ragged end of the beams
    data[80:118, 20:60] = -1                      # the niche, open to the hall
    g = _grid(data)
    x, y = g.cell_to_world(60, 200)
    fp = FrontierParams(robot_radius_m=0.1, min_group_size_cells=1)
    old = Explorer(fp, SelectionParams(strategy="routed", leftover_max_length_m=0.0)).step(
        0.0, g, (x, y, 0.0))
    edge = next(i for i, f in enumerate(old.frontiers) if f.point_rc[1] > 200)
    niche = 1 - edge
    assert old.frontiers[edge].size_cells * g.resolution_m >= 3.0
    assert old.tour.gain_m2[edge] < 2.0 <= old.tour.gain_m2[niche]
    assert old.tour.order.tolist() == [niche]     # the edge waits: the robot turns round
    new = Explorer(fp, SelectionParams(strategy="routed")).step(0.0, g, (x, y, 0.0))
    assert SelectionParams().leftover_max_length_m == 3.0
    assert new.tour.order.tolist() == [edge, niche] and new.selection.index == edge


def test_region_switch_finishes_the_robots_region_unless_the_other_is_on_the_way():
    # A 12 m corridor, unknown at both ends; the robot 3.5 m from the west end, whose
    # last 2.5 m are another region. West first, then east, is the shorter tour, but it
    # changes region twice; east first changes once. region_switch_m is added per change.
    data = np.full((120, 300), -1, dtype=np.int8)
    data[40:80, 30:270] = 0
    data[38:40, 30:270] = data[80:82, 30:270] = 100
    g = _grid(data)
    x, y = g.cell_to_world(60, 100)
    labels = np.zeros(data.shape, dtype=np.int32)
    labels[38:82, 30:80], labels[38:82, 80:270] = 2, 1
    fp = FrontierParams(robot_radius_m=0.1)

    def tour(**kw):
        out = Explorer(fp, SelectionParams(strategy="routed", **kw)).step(
            0.0, g, (x, y, 0.0), labels=labels)
        xs = [out.frontiers[i].point_xy_m[0] for i in out.tour.order]
        return xs, out.tour.length_m, out.frontiers[out.selection.index].point_xy_m[0]

    (w0, e0), plain, first = tour(region_switch_m=0.0)
    assert w0 < x < e0 and first == w0                  # the shorter tour: west first
    assert SelectionParams().region_switch_m == 1.0
    xs, length, first = tour()                          # the default: 2 x 1 m more, still
    assert xs == [w0, e0] and first == w0 and length == pytest.approx(plain + 2.0)
    xs, length, first = tour(region_switch_m=8.0)       # the detour is worth less: east
    assert xs == [e0, w0] and first == e0 and length < plain + 2 * 8.0
