"""The navigation stand-in's layer mask, cached per layer set and map geometry, equals
resampling every layer anew: after a layer changes, after the map grows, and in windows."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.paths import inflate
from sim_bridge.navigation import NavParams, Navigator


def _fresh(nav: Navigator, grid: GridMap, window=None) -> tuple[np.ndarray, np.ndarray]:
    """_obstacles without the cache (every layer resampled onto the window now)."""
    r0, r1, c0, c1 = window if window is not None else (0, grid.height, 0, grid.width)
    data = grid.data[r0:r1, c0:c1]
    blocked = (data >= nav.params.occupied_threshold) | nav._resampled_layers(
        grid, (r0, r1, c0, c1))
    return blocked, data < 0


def _layer(rng: np.random.Generator, grid: GridMap, shift_cells: tuple[float, float],
           shape: tuple[int, int]) -> GridMap:
    data = np.where(rng.random(shape) < 0.1, 100, 0).astype(np.int8)
    res = grid.resolution_m
    origin = (grid.origin_xy_m[0] + shift_cells[0] * res,
              grid.origin_xy_m[1] + shift_cells[1] * res)
    return GridMap(data, res, origin, 0.0, grid.frame_id)


@pytest.mark.parametrize("shift", [(0, 0), (3, -2), (0.5, 0.25)])   # last: off the lattice
def test_cached_layer_mask_equals_fresh_resampling(shift):
    rng = np.random.default_rng(0)
    data = np.where(rng.random((60, 70)) < 0.05, 100, np.where(rng.random((60, 70)) < 0.3,
                                                               -1, 0)).astype(np.int8)
    grid = GridMap(data, 0.05, (1.0, -2.0))
    nav = Navigator(NavParams())
    nav.set_map(grid, 1)
    nav.set_layer("objects", _layer(rng, grid, shift, (50, 55)))
    for window in (None, (5, 30, 10, 60), (0, 60, 0, 70), (40, 60, 50, 70)):
        for got, want in zip(nav._obstacles(grid, window), _fresh(nav, grid, window)):
            np.testing.assert_array_equal(got, want)
    # a new layer object: the cached mask must not be used
    nav.set_layer("objects", _layer(rng, grid, shift, (50, 55)))
    for window in (None, (5, 30, 10, 60)):
        np.testing.assert_array_equal(nav._obstacles(grid, window)[0],
                                      _fresh(nav, grid, window)[0])
    # same shape, origin moved by whole cells
    moved = GridMap(data, 0.05, (1.0 + 3 * 0.05, -2.0 - 2 * 0.05))
    for window in (None, (0, 20, 0, 20)):
        np.testing.assert_array_equal(nav._obstacles(moved, window)[0],
                                      _fresh(nav, moved, window)[0])
    # a grown map (new geometry) with the same layer
    big = GridMap(np.pad(data, ((4, 0), (0, 8)), constant_values=-1), 0.05,
                  (1.0, -2.0 - 4 * 0.05))
    for window in (None, (0, 20, 0, 20)):
        np.testing.assert_array_equal(nav._obstacles(big, window)[0],
                                      _fresh(nav, big, window)[0])
    # the layer removed
    nav.set_layer("objects", None)
    np.testing.assert_array_equal(nav._obstacles(grid)[0], data >= nav.params.occupied_threshold)


def _plan_blocked_by_inflating(nav: Navigator, grid: GridMap) -> bool:
    """The blocked-plan test as inflating the plan's window (the reference)."""
    pts = nav._plan_xy[nav._plan_index + 1:]
    rows, cols = grid.world_to_cells(pts[:, 0], pts[:, 1])
    if not ((rows >= 0) & (rows < grid.height) & (cols >= 0) & (cols < grid.width)).all():
        return True
    rad = int(np.ceil(nav.params.lethal_radius_m / grid.resolution_m))
    r0, r1 = max(0, rows.min() - rad), min(grid.height, rows.max() + rad + 1)
    c0, c1 = max(0, cols.min() - rad), min(grid.width, cols.max() + rad + 1)
    blocked = _fresh(nav, grid, (r0, r1, c0, c1))[0]
    lethal = inflate(blocked, nav.params.lethal_radius_m, grid.resolution_m)
    return bool(lethal[rows - r0, cols - c0].any())


@pytest.mark.parametrize("margin", [0.0, 0.1, 2.0])     # 2.0: beyond the disk kernels
def test_plan_blocked_equals_inflating_the_window(margin):
    rng = np.random.default_rng(1)
    nav = Navigator(NavParams(inflation_margin_m=margin,
                              inflation_radius_m=max(0.6, 0.22 + margin)))
    seen = set()
    for _ in range(60):
        density = rng.uniform(0.0, 0.004) / (1.0 + 100.0 * margin ** 2)
        data = np.where(rng.random((80, 90)) < density, 100, 0).astype(np.int8)
        grid = GridMap(data, 0.05, (0.3, -1.1))
        nav.set_map(grid, 1)
        nav.set_layer("objects", _layer(rng, grid, (0, 0), (80, 90)) if rng.random() < 0.3
                      else None)
        # a random walk of plan points, sometimes leaving the map
        xy = np.cumsum(rng.normal(0.0, 0.08, (int(rng.integers(2, 80)), 2)), axis=0)
        xy += np.array([0.3 + rng.uniform(0.5, 4.0), -1.1 + rng.uniform(0.5, 3.5)])
        nav._plan_xy = xy
        nav._plan_index = int(rng.integers(0, len(xy) - 1))
        want = _plan_blocked_by_inflating(nav, grid)
        assert nav._plan_blocked() == want
        seen.add(want)
    assert seen == {True, False}
