"""Path distances: exact field vs an independent Dijkstra, block approximation bounds."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.block_graph import BlockGraph, block_distances
from explore_seg.core.paths import (cost_distance_field, distance_field, extract_path, inflate,
                                    path_length_m)

RES = 0.05


def reference_field(passable: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """Plain Dijkstra, 8 moves, no corner cutting, start forced passable (cells)."""
    pas = passable.copy()
    pas[start] = True
    return reference_cost_field(np.where(pas, 1.0, np.inf), start, 1.0)


def reference_cost_field(cost: np.ndarray, start: tuple[int, int], res: float) -> np.ndarray:
    """Plain heapq Dijkstra on per-metre cell costs: a move costs its length times the
    mean of its two cells' costs; inf cells impassable; no corner cutting."""
    pas = np.isfinite(cost)
    h, w = cost.shape
    dist = np.full((h, w), np.inf)
    dist[start] = 0.0
    heap = [(0.0, start)]
    while heap:
        d, (r, c) = heapq.heappop(heap)
        if d > dist[r, c]:
            continue
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if (dr == 0 and dc == 0) or not (0 <= rr < h and 0 <= cc < w) or not pas[rr, cc]:
                    continue
                if dr and dc and not (pas[r + dr, c] and pas[r, c + dc]):
                    continue
                step = (math.sqrt(2.0) if dr and dc else 1.0) * res
                nd = d + step * 0.5 * (cost[r, c] + cost[rr, cc])
                if nd < dist[rr, cc]:
                    dist[rr, cc] = nd
                    heapq.heappush(heap, (nd, (rr, cc)))
    return dist


def random_passable(seed: int, shape=(40, 50), density=0.3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.random(shape) > density


def maze_passable(seed: int, size=120, room=30) -> np.ndarray:
    """Rooms with one-cell walls, random doors and box clutter."""
    rng = np.random.default_rng(seed)
    occ = np.zeros((size, size), bool)
    for k in range(0, size, room):
        occ[k, :] = True
        occ[:, k] = True
    for i in range(0, size, room):
        for j in range(0, size, room):
            d = rng.integers(2, room - 8)
            occ[i + d:i + d + 6, j] = False
            d = rng.integers(2, room - 8)
            occ[i, j + d:j + d + 6] = False
    for _ in range(30):
        r, c = rng.integers(0, size - 6, 2)
        occ[r:r + rng.integers(1, 6), c:c + rng.integers(1, 6)] = True
    return ~inflate(occ, 2.0, 1.0)


def test_distance_field_corridor_literal():
    g, m = grid_from_ascii("""
    #######
    #S...G#
    #######
    """, resolution_m=RES)
    d = distance_field(g.free_mask(), m["S"][0], RES)
    assert d[1, 1:6].tolist() == pytest.approx([0.0, 0.05, 0.10, 0.15, 0.20])
    assert np.isinf(d[0]).all()


def test_distance_field_no_corner_cutting():
    g, m = grid_from_ascii("""
    ..G
    .#.
    S..
    """, resolution_m=1.0)
    d = distance_field(g.free_mask(), m["S"][0], 1.0)
    # every diagonal would touch the centre wall: four straight moves around it
    assert d[m["G"][0]] == pytest.approx(4.0)


def test_distance_field_diagonal_between_two_walls_blocked():
    g, m = grid_from_ascii("""
    #G
    S#
    """, resolution_m=1.0)
    d = distance_field(g.free_mask(), m["S"][0], 1.0)
    assert np.isinf(d[m["G"][0]])


def test_distance_field_start_on_blocked_cell_is_passable():
    g, _ = grid_from_ascii("""
    ...
    .#.
    ...
    """, resolution_m=1.0)
    d = distance_field(g.free_mask(), (1, 1), 1.0)
    assert d[1, 1] == 0.0
    assert d[1, 2] == pytest.approx(1.0)


def test_distance_field_start_outside_raises():
    with pytest.raises(ValueError, match="outside grid"):
        distance_field(np.ones((3, 3), bool), (3, 0), 1.0)


def test_distance_field_bad_resolution_raises():
    with pytest.raises(ValueError, match="resolution_m"):
        distance_field(np.ones((3, 3), bool), (0, 0), 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_distance_field_matches_reference_on_random_grids(seed):
    pas = random_passable(seed)
    start = tuple(int(v) for v in np.argwhere(pas)[seed * 7])
    np.testing.assert_allclose(distance_field(pas, start, RES),
                               reference_field(pas, start) * RES, rtol=1e-12)


@pytest.mark.parametrize("seed", range(4))
def test_cost_distance_field_matches_reference_on_random_costs(seed):
    """Weighted field (the navigation's planner) against a plain Dijkstra, passable cells
    touching every border of the grid included."""
    rng = np.random.default_rng(100 + seed)
    shape = (23 + seed, 31 - seed)
    cost = 1.0 + 4.0 * rng.random(shape)
    blocked = rng.random(shape) < 0.25
    start = (shape[0] // 2, shape[1] // 2)
    blocked[start[0] - 1:start[0] + 2, start[1] - 1:start[1] + 2] = False
    cost[blocked] = np.inf
    got = cost_distance_field(cost, start, RES)
    want = reference_cost_field(cost, start, RES)
    assert np.isfinite(want).sum() > 100
    np.testing.assert_array_equal(np.isinf(got), np.isinf(want))
    np.testing.assert_allclose(got[np.isfinite(want)], want[np.isfinite(want)], rtol=1e-12)


@pytest.mark.parametrize("seed", range(3))
def test_cost_distance_field_limit_drops_only_costlier_cells(seed):
    """With a limit, cells costlier than it are inf and every other cell keeps its exact
    value (the planner's pruned search relies on both)."""
    rng = np.random.default_rng(200 + seed)
    shape = (30, 27)
    cost = 1.0 + 3.0 * rng.random(shape)
    cost[rng.random(shape) < 0.2] = np.inf
    start = (15, 13)
    cost[start] = 1.0
    full = cost_distance_field(cost, start, RES)
    limit = float(np.median(full[np.isfinite(full)]))
    got = cost_distance_field(cost, start, RES, limit)
    keep = full <= limit
    assert 10 < keep.sum() < np.isfinite(full).sum()
    np.testing.assert_array_equal(got[keep], full[keep])
    assert np.isinf(got[~keep]).all()


@pytest.mark.parametrize("seed", range(4))
def test_path_length_at_least_straight_line(seed):
    pas = random_passable(seed, density=0.25)
    cells = np.argwhere(pas)
    start = tuple(int(v) for v in cells[0])
    d = distance_field(pas, start, RES)
    finite = np.argwhere(np.isfinite(d))
    straight = np.hypot(finite[:, 0] - start[0], finite[:, 1] - start[1]) * RES
    assert (d[finite[:, 0], finite[:, 1]] >= straight - 1e-9).all()


def test_extract_path_follows_field():
    g, m = grid_from_ascii("""
    #######
    #S.#.G#
    #.....#
    #######
    """, resolution_m=RES)
    d = distance_field(g.free_mask(), m["S"][0], RES)
    path = extract_path(d, m["G"][0])
    assert tuple(path[0]) == m["S"][0] and tuple(path[-1]) == m["G"][0]
    assert path_length_m(path, RES) == pytest.approx(d[m["G"][0]])


def test_extract_path_unreachable_raises():
    d = np.array([[0.0, np.inf]])
    with pytest.raises(ValueError, match="unreachable"):
        extract_path(d, (0, 1))


# ---------------------------------------------------------------- block approximation


def targets_of(pas: np.ndarray, seed: int, n: int = 60) -> np.ndarray:
    rng = np.random.default_rng(seed)
    cells = np.argwhere(pas)
    return cells[rng.choice(len(cells), size=min(n, len(cells)), replace=False)]


@pytest.mark.parametrize("k", [2, 3, 4])
@pytest.mark.parametrize("maker,seed", [(random_passable, 0), (random_passable, 1),
                                        (maze_passable, 0), (maze_passable, 1)])
def test_block_distances_reachability_and_error_bound(maker, seed, k):
    pas = maker(seed)
    start = tuple(int(v) for v in targets_of(pas, seed + 100, 1)[0])
    tg = targets_of(pas, seed)
    exact = distance_field(pas, start, RES)[tg[:, 0], tg[:, 1]]
    approx = block_distances(pas, start, tg, RES, k)
    assert (np.isfinite(approx) == np.isfinite(exact)).all()
    fin = np.isfinite(exact)
    straight = np.hypot(tg[:, 0] - start[0], tg[:, 1] - start[1]) * RES
    assert (approx[fin] >= straight[fin] - 1e-9).all()
    assert (np.abs(approx[fin] - exact[fin]) <= 0.2 * exact[fin] + 2 * k * RES).all()


@pytest.mark.parametrize("seed", range(3))
def test_block_cells_1_is_exact(seed):
    pas = random_passable(seed)
    start = tuple(int(v) for v in targets_of(pas, seed + 5, 1)[0])
    tg = targets_of(pas, seed)
    np.testing.assert_allclose(block_distances(pas, start, tg, RES, 1),
                               distance_field(pas, start, RES)[tg[:, 0], tg[:, 1]])


def test_block_distances_open_room_is_straight_line():
    pas = np.ones((40, 40), bool)
    # k = 3: cells (1, 1), (1, 31), (31, 31) are centres of full blocks
    d = block_distances(pas, (1, 1), [[1, 31], [31, 31], [1, 1]], 1.0, 3)
    assert d.tolist() == pytest.approx([30.0, 30.0 * math.sqrt(2.0), 0.0])


def test_block_distances_wall_without_door_literal():
    g, m = grid_from_ascii("""
    ........
    ........
    ########
    ........
    S......T
    """, resolution_m=1.0)
    pas = g.free_mask()
    d_closed = block_distances(pas, m["S"][0], [[4, 0], m["T"][0]], 1.0, 2)
    # S and T sit at corners of 2x2 blocks: half a diagonal off each block centre
    assert np.isinf(d_closed[0]) and d_closed[1] == pytest.approx(6.0 + math.sqrt(2.0))


def test_block_distances_unreachable_pocket_and_blocked_target_are_inf():
    g, m = grid_from_ascii("""
    .....###
    .S...#P#
    .....###
    ....#...
    """, resolution_m=1.0)
    pas = g.free_mask()
    d = block_distances(pas, m["S"][0], [m["P"][0], (0, 4)], 1.0, 2)
    assert np.isinf(d[0]) and np.isinf(d[1])


def test_block_graph_start_not_passable_gives_inf():
    pas = np.ones((8, 8), bool)
    pas[3, 3] = False
    graph = BlockGraph(pas, 1.0, 2)
    assert np.isinf(graph.distances((3, 3), [[0, 0]])).all()
    assert graph.nearest_passable((3, 3), 1) in {(2, 3), (3, 2), (3, 4), (4, 3)}


def test_block_graph_empty_mask():
    graph = BlockGraph(np.zeros((5, 5), bool), 1.0, 4)
    assert graph.num_nodes == 0
    assert np.isinf(graph.distances((0, 0), [[1, 1]])).all()


@pytest.mark.parametrize("k", [0, 5])
def test_block_cells_out_of_range_raises(k):
    with pytest.raises(ValueError, match="block_cells"):
        block_distances(np.ones((4, 4), bool), (0, 0), [[1, 1]], 1.0, k)


def test_block_targets_shape_raises():
    with pytest.raises(ValueError, match=r"shape \(N, 2\)"):
        block_distances(np.ones((4, 4), bool), (0, 0), [1, 2, 3], 1.0, 2)


def test_block_graph_non_2d_raises():
    with pytest.raises(ValueError, match="2D"):
        BlockGraph(np.ones(4, bool), 1.0, 2)


def test_inflate_radius_literal():
    m = np.zeros((7, 7), bool)
    m[3, 3] = True
    assert int(inflate(m, 0.1, 0.05).sum()) == 13
    assert inflate(m, 0.04, 0.05).sum() == 1


@pytest.mark.parametrize("radius_m", [0.1, 0.22, 0.25, 0.3, 0.37, 1.62, 2.13])
def test_inflate_takes_every_cell_whose_centre_is_within_the_metric_radius(radius_m,
                                                                           monkeypatch):
    """A cell is inflated exactly when its centre lies within ``radius_m`` of a blocked
    cell's centre, not within the radius rounded down to whole cells (at 0.22 m and
    0.05 m a cell 4.12 cells = 0.206 m away is inflated: the robot would touch it), and
    the distance-transform branch of large radii gives the same cells."""
    import explore_seg.core.paths as paths_module
    res = 0.05
    rng = np.random.default_rng(int(radius_m * 100))
    blocked = rng.random((90, 90)) < 0.004
    rr, cc = np.nonzero(blocked)
    yy, xx = np.mgrid[0:90, 0:90]
    d = np.min(np.hypot(yy[..., None] - rr, xx[..., None] - cc), axis=-1) * res
    expected = d <= radius_m + 1e-9
    assert np.array_equal(inflate(blocked, radius_m, res), expected)
    monkeypatch.setattr(paths_module, "_MAX_KERNEL_RADIUS_CELLS", 0)
    assert np.array_equal(inflate(blocked, radius_m, res), expected)


def test_inflate_by_the_robot_radius_covers_the_cells_the_robot_would_touch():
    """0.22 m at 0.05 m is 4.4 cells: the offsets (4, 1) and (3, 3), 0.206 and 0.212 m
    away, are inflated; (4, 2), 0.224 m away, is not."""
    one = np.zeros((11, 11), bool)
    one[5, 5] = True
    out = inflate(one, 0.22, 0.05)
    assert out[5 + 4, 5 + 1] and out[5 + 3, 5 + 3] and not out[5 + 4, 5 + 2]
    assert int(out.sum()) == 61


def test_inflate_negative_radius_raises():
    with pytest.raises(ValueError, match="radius_m"):
        inflate(np.zeros((3, 3), bool), -1.0, 0.05)
