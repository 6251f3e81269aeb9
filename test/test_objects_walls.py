"""The 2D map's walls as the object pipeline uses them (explore_seg.core.objects.walls)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.objects import ObjectParams, wall_mask
from explore_seg.core.objects import walls as walls_mod
from objects_scene import desk_at_wall_map, table_parts


def test_wall_mask_holds_walls_grown_but_not_furniture_legs():
    desk = table_parts((2.3, 0.0), 1.2, 0.6, 0.75, yaw=math.pi / 2)
    grid = desk_at_wall_map(desk, 2.7)
    walls = wall_mask(grid, ObjectParams())
    legs = np.array([c[:2] for c, _, _ in desk[1:]])
    assert grid.data[grid.world_to_cells(legs[:, 0], legs[:, 1])].min() == 100
    assert not walls.on(legs).any()                    # legs are short: kept
    # the wall and one margin cell (0.05 m) on either side; beyond that free
    on = walls.on(np.array([[2.7, 0.0], [2.62, 1.5], [2.78, -1.5], [2.55, 0.0], [4.5, 0.0]]))
    assert on.tolist() == [True, True, True, False, False]
    every = wall_mask(grid, ObjectParams(wall_min_length_m=0.0, wall_margin_m=0.0))
    assert every.on(legs).all()
    assert every.mask.sum() == (grid.data == 100).sum()


def _random_map(rng: np.random.Generator, h: int, w: int) -> GridMap:
    """Free space with wall lines of all lengths (some crossing the whole map) and specks."""
    data = np.zeros((h, w), np.int8)
    data[rng.random((h, w)) < 0.3] = -1
    data[rng.random((h, w)) < 0.01] = 100
    for _ in range(12):
        r, c = int(rng.integers(0, h)), int(rng.integers(0, w))
        n = int(rng.integers(1, 200))
        if rng.random() < 0.5:
            data[r, c:c + n] = 100
        else:
            data[r:r + n, c] = 100
    return GridMap(data, 0.05, (-1.0, 2.0))


def test_walls_asked_about_points_equal_the_whole_maps():
    rng = np.random.default_rng(4)
    for i in range(30):
        grid = _random_map(rng, int(rng.integers(40, 260)), int(rng.integers(40, 260)))
        params = ObjectParams(wall_min_length_m=float(rng.choice([0.0, 0.3, 0.5, 2.0])),
                              wall_margin_m=float(rng.choice([0.0, 0.05, 0.12])))
        whole = wall_mask(grid, params).mask
        lazy = wall_mask(grid, params)
        for _ in range(4):
            # points in a random box (some outside the map), as one camera frame's
            c = rng.uniform(-1.5, 1.5 + grid.width * 0.05, 2) + np.array([-1.0, 2.0])
            c[1] = rng.uniform(1.5, 2.5 + grid.height * 0.05)
            pts = c + rng.uniform(-2.0, 2.0, (500, 2)) * rng.uniform(0.1, 1.0)
            r, cc = grid.world_to_cells(pts[:, 0], pts[:, 1])
            ok = (r >= 0) & (r < grid.height) & (cc >= 0) & (cc < grid.width)
            want = np.zeros(len(pts), bool)
            want[ok] = whole[r[ok], cc[ok]]
            np.testing.assert_array_equal(lazy.on(pts), want)
        assert lazy._mask is None                 # only windows were computed
        # a copy for a map with the same occupied cells shares what was computed
        same = lazy.with_grid(grid.with_data(grid.data.copy()))
        assert same._windows is lazy._windows
        np.testing.assert_array_equal(same.mask, whole)


@pytest.mark.parametrize("length_cells", [59, 60, 61, 62])
def test_a_wall_reaching_far_out_of_the_window_is_judged_by_its_whole_length(
        length_cells, monkeypatch):
    # No padding: the window is the asked points' box and the margin the walls need.
    monkeypatch.setattr(walls_mod, "_WINDOW_PAD_CELLS", 0)
    data = np.zeros((40, 200), np.int8)
    data[20, 10:10 + length_cells] = 100            # 2.95 .. 3.1 m long
    grid = GridMap(data, 0.05, (0.0, 0.0))
    params = ObjectParams(wall_min_length_m=3.0, wall_margin_m=0.05)
    end = np.array([[10.5 * 0.05, 20.5 * 0.05]])   # the wall's first cell only
    assert wall_mask(grid, params).on(end)[0] == (length_cells * 0.05 >= 3.0)
    assert wall_mask(grid, params).on(end)[0] == wall_mask(grid, params).mask[20, 10]
