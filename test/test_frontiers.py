"""Frontier cells, groups and cPoints on ASCII grids and seeded random grids."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.frontiers import (FrontierParams, detect_frontier_cells, find_frontiers,
                                        group_frontiers, obstacle_mask, split_frontiers,
                                        traversable_mask)
from explore_seg.core.grid import GridMap, grid_from_ascii

P1 = FrontierParams(min_group_size_cells=1, robot_radius_m=0.0)


def cells_of(mask: np.ndarray) -> list[tuple[int, int]]:
    return [tuple(int(v) for v in rc) for rc in np.argwhere(mask)]


# ------------------------------------------------------------------------- detection


def test_detect_unknown_cells_next_to_free():
    g, _ = grid_from_ascii("""
    ?????
    ?...?
    ?.#.?
    ?????
    """)
    # rows listed bottom-up: row 0 is the last text line
    assert cells_of(detect_frontier_cells(g)) == [
        (0, 1), (0, 3), (1, 0), (1, 4), (2, 0), (2, 4), (3, 1), (3, 2), (3, 3)]


@pytest.mark.parametrize("conn,expected", [(4, []), (8, [(0, 1)])])
def test_diagonal_free_neighbour_depends_on_connectivity(conn, expected):
    g, _ = grid_from_ascii("""
    .#
    #?
    """)
    params = FrontierParams(free_neighbour_connectivity=conn)
    assert cells_of(detect_frontier_cells(g, params=params)) == expected


def test_uncertain_cells_are_neither_free_nor_unknown():
    g, _ = grid_from_ascii("""
    ???
    ...
    """)
    data = g.data.copy()
    data[0, 1] = 50  # between the free and occupied thresholds
    g2 = g.with_data(data)
    assert cells_of(detect_frontier_cells(g2)) == [(1, 0), (1, 2)]


def test_object_layer_closes_frontier():
    g, _ = grid_from_ascii("""
    ????
    ....
    """)
    extra = np.zeros(g.shape, bool)
    extra[1, 0:2] = True        # unknown cells covered by an object
    extra[0, 3] = True          # a free cell occupied by an object
    assert cells_of(detect_frontier_cells(g, extra)) == [(1, 2)]


@pytest.mark.parametrize("text", ["""
    ???
    ???
    """, """
    ...
    .#.
    """, """
    ###
    ?#?
    """])
def test_no_frontier_without_free_and_unknown_contact(text):
    g, _ = grid_from_ascii(text)
    assert not detect_frontier_cells(g).any()
    assert find_frontiers(g, params=P1) == []


def test_extra_layer_shape_mismatch_raises():
    g, _ = grid_from_ascii("..?")
    with pytest.raises(ValueError, match="extra_obstacles has shape"):
        detect_frontier_cells(g, np.zeros((2, 2), bool))


def test_frontier_mask_shape_mismatch_raises():
    g, _ = grid_from_ascii("..?")
    with pytest.raises(ValueError, match="frontier_mask has shape"):
        group_frontiers(g, np.zeros((2, 2), bool))


# -------------------------------------------------------------------------- grouping


def test_groups_sizes_ids_and_min_size():
    g, _ = grid_from_ascii("""
    ??????#??
    ......#..
    ......#..
    """)
    fr = find_frontiers(g, params=P1)
    assert [(f.id, f.size_cells) for f in fr] == [(0, 6), (1, 2)]
    assert [f.id for f in find_frontiers(g, params=FrontierParams(
        min_group_size_cells=3, robot_radius_m=0.0))] == [0]


@pytest.mark.parametrize("conn,sizes", [(8, [2]), (4, [1, 1])])
def test_group_connectivity(conn, sizes):
    g, _ = grid_from_ascii("""
    #?#
    ?.#
    ###
    """)
    params = FrontierParams(min_group_size_cells=1, robot_radius_m=0.0, group_connectivity=conn)
    assert [f.size_cells for f in find_frontiers(g, params=params)] == sizes


def test_cpoint_is_free_reachable_cell_next_to_group():
    g, _ = grid_from_ascii("""
    ??????
    ......
    ......
    ......
    """, resolution_m=0.1)
    (f,) = find_frontiers(g, params=FrontierParams(min_group_size_cells=3, robot_radius_m=0.0))
    assert f.point_rc == (2, 2) and f.point_passable
    assert f.centroid_rc == pytest.approx((3.0, 2.5))
    assert f.point_xy_m == pytest.approx(g.cell_to_world(2, 2))
    assert f.length_m == pytest.approx(0.6)


def test_cpoint_avoids_inflated_walls():
    g, _ = grid_from_ascii("""
    #??##
    #...#
    #...#
    #...#
    #####
    """, resolution_m=0.1)
    params = FrontierParams(min_group_size_cells=2, robot_radius_m=0.1)
    (f,) = find_frontiers(g, params=params)
    pas = traversable_mask(g, None, params)
    assert not pas[3, 1]          # the free cell below the group touches the wall
    assert f.point_passable and pas[f.point_rc]
    assert f.point_rc == (3, 2)


def test_cpoint_never_behind_a_thin_wall():
    g, _ = grid_from_ascii("""
    ....#..
    ....#..
    ...?#..
    ....#..
    ....#..
    """)
    passable = np.zeros(g.shape, bool)
    passable[2, 5] = True   # 2 cells away but behind the wall
    passable[2, 0] = True   # 3 cells away, in line of sight
    (f,) = group_frontiers(g, detect_frontier_cells(g), P1, passable=passable)
    assert f.point_rc == (2, 0)


def test_cpoint_not_passable_when_no_room_for_the_robot():
    g, _ = grid_from_ascii("""
    #?#
    #.#
    #.#
    ###
    """, resolution_m=0.1)
    params = FrontierParams(min_group_size_cells=1, robot_radius_m=0.2,
                            cpoint_search_radius_m=0.5)
    (f,) = find_frontiers(g, params=params)
    assert not f.point_passable
    assert f.point_rc == (3, 1)   # the group cell itself, flagged


def test_cpoint_leaves_inflated_object():
    g, _ = grid_from_ascii("""
    ?????????
    .........
    .........
    .........
    .........
    .........
    """, resolution_m=0.1)
    extra = np.zeros(g.shape, bool)
    extra[3, 3:6] = True          # an object one cell below the frontier's free row
    params = FrontierParams(min_group_size_cells=3, robot_radius_m=0.1)
    (f,) = find_frontiers(g, extra, params)
    assert f.size_cells == 9
    assert f.point_passable and traversable_mask(g, extra, params)[f.point_rc]
    assert f.point_rc == (4, 2)   # (4, 3..5) lie in the object's inflated margin


# ------------------------------------------------------------------------ invariants


def random_grid(seed: int, shape=(60, 70)) -> GridMap:
    rng = np.random.default_rng(seed)
    known = np.zeros(shape, bool)
    for _ in range(12):  # known blobs
        r, c = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        rad = rng.integers(3, 15)
        yy, xx = np.ogrid[:shape[0], :shape[1]]
        known |= (yy - r) ** 2 + (xx - c) ** 2 <= rad * rad
    data = np.full(shape, -1, np.int8)
    vals = np.where(rng.random(shape) < 0.12, 100, 0).astype(np.int8)
    data[known] = vals[known]
    return GridMap(data, 0.05, (1.0, -2.0))


def reference_frontier(g: GridMap) -> np.ndarray:
    free, unk = g.free_mask(), g.unknown_mask()
    out = np.zeros(g.shape, bool)
    h, w = g.shape
    for r in range(h):
        for c in range(w):
            if unk[r, c]:
                out[r, c] = any(0 <= r + dr < h and 0 <= c + dc < w and free[r + dr, c + dc]
                                for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)))
    return out


@pytest.mark.parametrize("seed", range(5))
def test_random_grid_invariants(seed):
    g = random_grid(seed)
    params = FrontierParams(min_group_size_cells=4, robot_radius_m=0.1)
    mask = detect_frontier_cells(g, params=params)
    np.testing.assert_array_equal(mask, reference_frontier(g))
    fr = group_frontiers(g, mask, params)
    assert [f.id for f in fr] == list(range(len(fr)))
    seen = np.zeros(g.shape, int)
    for f in fr:
        assert f.size_cells == len(f.cells) >= params.min_group_size_cells
        seen[f.cells[:, 0], f.cells[:, 1]] += 1
    assert seen.max(initial=0) <= 1                     # groups are disjoint
    assert not (seen.astype(bool) & ~mask).any()        # and made of frontier cells
    small = FrontierParams(min_group_size_cells=1, robot_radius_m=0.1)
    assert sum(f.size_cells for f in group_frontiers(g, mask, small)) == int(mask.sum())
    pas = traversable_mask(g, None, params)
    occ = obstacle_mask(g, None, params)
    for f in fr:
        if f.point_passable:
            assert pas[f.point_rc] and g.free_mask()[f.point_rc] and not occ[f.point_rc]


# ------------------------------------------------------------------------ parameters


@pytest.mark.parametrize("kwargs,match", [
    ({"free_threshold": -1}, "free_threshold must be in"),
    ({"occupied_threshold": 102}, "occupied_threshold must be in"),
    ({"free_threshold": 70, "occupied_threshold": 60}, "must be <= occupied_threshold"),
    ({"min_group_size_cells": 0}, "min_group_size_cells"),
    ({"group_connectivity": 6}, "group_connectivity must be 4 or 8"),
    ({"robot_radius_m": -0.1}, "robot_radius_m"),
    ({"cpoint_search_radius_m": float("nan")}, "cpoint_search_radius_m"),
])
def test_params_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        FrontierParams(**kwargs)


# ------------------------------------------------------------------------- split


def _extent_m(cells: np.ndarray, res: float) -> float:
    """Extent of cells along their principal axis (m)."""
    c = cells.astype(float) - cells.mean(axis=0)
    if len(c) < 2:
        return 0.0
    axis = np.linalg.eigh(c.T @ c)[1][:, -1]
    p = c @ axis
    return float(p.max() - p.min()) * res


@pytest.mark.parametrize("max_m", [1.0, 3.0, 4.9])
def test_split_long_groups_into_parts_with_their_own_cpoints(max_m):
    # A 10 m corridor side (unknown above row 10) and an L-shaped 2 x 2 m corner of
    # unknown space in the corridor's far side: every part is at most max_m long, the
    # parts partition the group's cells, each has a passable cPoint next to its cells.
    res = 0.05
    data = np.zeros((60, 200), dtype=np.int8)
    data[:10] = -1
    data[40:, 160:] = -1
    g = GridMap(data, res, (0.0, 0.0))
    p = FrontierParams(robot_radius_m=0.1)
    fs = find_frontiers(g, params=p)
    assert [f.size_cells for f in fs] == [200, 59]
    parts = split_frontiers(g, fs, max_m, p)
    assert [f.id for f in parts] == list(range(len(parts)))
    assert len(parts) > len(fs)
    assert sum(f.size_cells for f in parts) == sum(f.size_cells for f in fs)
    every = np.concatenate([f.cells for f in parts])
    assert len({tuple(c) for c in every}) == len(every)
    assert {tuple(c) for c in every} == {tuple(c) for f in fs for c in f.cells}
    for f in parts:
        assert _extent_m(f.cells, res) <= max_m
        assert f.point_passable and traversable_mask(g, None, p)[f.point_rc]
        d = np.hypot(*(f.cells - np.asarray(f.point_rc)).T).min() * res
        assert d <= p.cpoint_search_radius_m
        assert f.length_m == pytest.approx(f.size_cells * res)


def test_split_keeps_short_groups_and_is_off_at_zero():
    g, _ = grid_from_ascii("""
    ??????
    ......
    ......
    """, resolution_m=0.1)
    fs = find_frontiers(g, params=P1)
    assert split_frontiers(g, fs, 1.0, P1)[0] is fs[0]        # 0.5 m long: kept
    assert split_frontiers(g, fs, 0.0, P1) == fs
    fine = split_frontiers(g, fs, 0.2, P1)                    # 0.5 m: 2 parts of 0.2 m
    assert [f.size_cells for f in fine] == [3, 3]
    assert all(_extent_m(f.cells, 0.1) <= 0.2 for f in fine)


def _same_frontiers(a, b) -> bool:
    return len(a) == len(b) and all(
        x.point_rc == y.point_rc and x.point_passable == y.point_passable
        and x.size_cells == y.size_cells and np.array_equal(x.cells, y.cells)
        and x.centroid_rc == y.centroid_rc for x, y in zip(a, b))


@pytest.mark.parametrize("seed", range(4))
def test_cpoint_cache_gives_the_frontiers_of_a_fresh_detection_as_the_map_changes(seed):
    """A map revealed window by window (obstacles, objects and unknown space changing
    locally, the map growing once): find_frontiers and split_frontiers with a FrontierCache
    equal those without, map after map, and the cache is used where the map stayed."""
    from explore_seg.core.frontiers import FrontierCache, split_frontiers, traversable_mask
    rng = np.random.default_rng(seed)
    truth = np.where(rng.random((120, 160)) < 0.03, 100, 0).astype(np.int8)
    truth[40:42, 10:150] = 100
    seen = np.full(truth.shape, -1, np.int8)
    p = FrontierParams(robot_radius_m=0.1, cpoint_search_radius_m=0.5)
    cache = FrontierCache()
    for step in range(14):
        r, c = rng.integers(0, 100), rng.integers(0, 140)
        seen[r:r + 30, c:c + 30] = truth[r:r + 30, c:c + 30]
        data = seen if step < 9 else np.pad(seen, ((0, 8), (4, 0)), constant_values=-1)
        grid = GridMap(data.copy(), 0.1, (0.0, 0.0) if step < 9 else (-0.4, 0.0))
        extra = np.zeros(grid.shape, bool)
        extra[60:64, 70:75] = step % 3 == 0
        pas = traversable_mask(grid, extra, p)
        cache.start(grid)
        got = find_frontiers(grid, extra, p, passable=pas, cache=cache)
        want = find_frontiers(grid, extra, p, passable=pas)
        assert _same_frontiers(got, want)
        assert _same_frontiers(split_frontiers(grid, got, 1.0, p, extra, pas, cache),
                               split_frontiers(grid, want, 1.0, p, extra, pas))
    assert cache.hits > 0 and cache.misses > 0


@pytest.mark.parametrize("change", ["passable", "extra", "occupied"])
def test_cpoint_cache_sees_a_change_of_any_of_its_inputs_near_the_cpoint(change):
    """The cPoint moves when, near it, only the passable mask, only the extra layer or
    only the map's occupied cells change (the other inputs given as before): the cache
    must give the moved cPoint, not the kept one."""
    from explore_seg.core.frontiers import FrontierCache, traversable_mask
    g, _ = grid_from_ascii("""
    ????????????????????
    ????????????????????
    ....................
    ....................
    ....................
    ....................
    ....................
    ....................
    """, resolution_m=0.1)
    p = FrontierParams(robot_radius_m=0.0, cpoint_search_radius_m=0.6,
                       min_group_size_cells=3)
    pas = traversable_mask(g, None, p)
    pas[4:6] = False                  # the cPoint lies 3 rows below the frontier (row 6)
    cache = FrontierCache()
    cache.start(g)
    (before,) = find_frontiers(g, None, p, passable=pas, cache=cache)
    r, c = before.point_rc
    assert r == 3
    grid2, pas2, extra2 = g, pas.copy(), None
    if change == "passable":
        pas2[r, c] = False
    elif change == "extra":           # on the line of sight, not next to the frontier
        extra2 = np.zeros(g.shape, bool)
        extra2[r + 1, c] = True
    else:
        data = g.data.copy()
        data[r + 1, c] = 100
        grid2 = GridMap(data, 0.1, (0.0, 0.0))
    cache.start(grid2)
    got = find_frontiers(grid2, extra2, p, passable=pas2, cache=cache)
    want = find_frontiers(grid2, extra2, p, passable=pas2)
    assert before.point_rc not in [f.point_rc for f in want]
    assert _same_frontiers(got, want)
