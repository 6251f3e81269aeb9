"""SweptPath: the floor the robot's body has covered (core/swept.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.swept import SweptPath


def _grid(h: int = 40, w: int = 60, res: float = 0.05,
          origin: tuple[float, float] = (0.0, 0.0)) -> GridMap:
    return GridMap(np.zeros((h, w), np.int8), res, origin)


def _cell_centres(g: GridMap) -> tuple[np.ndarray, np.ndarray]:
    rr, cc = np.mgrid[0:g.height, 0:g.width]
    return g.cells_to_world(rr, cc)


def test_mask_is_every_cell_within_the_radius_of_the_driven_segment():
    g = _grid()
    sp = SweptPath(spacing_m=0.05)
    for x in np.arange(0.5, 2.5001, 0.01):
        sp.add(float(x), 1.0)
    m = sp.mask(g, 0.22)
    x, y = _cell_centres(g)
    # Distance of each cell centre to the segment (0.5, 1) - (2.5, 1).
    dx = np.maximum(np.maximum(0.5 - x, x - 2.5), 0.0)
    d = np.hypot(dx, y - 1.0)
    assert m[d <= 0.22 - g.resolution_m].all()          # inside: all swept
    assert not m[d > 0.22 + g.resolution_m].any()       # outside: none
    assert m.sum() > 0


def test_positions_closer_than_the_spacing_are_not_kept_and_nan_is_ignored():
    sp = SweptPath(spacing_m=0.1)
    assert sp.add(0.0, 0.0)
    assert not sp.add(0.05, 0.0)
    assert sp.add(0.1, 0.0)
    assert not sp.add(math.nan, 0.0)
    assert len(sp) == 2


def test_a_pose_jump_leaves_no_corridor_between_the_two_places():
    g = _grid()
    sp = SweptPath(spacing_m=0.05, max_gap_m=0.5)
    sp.add(0.5, 1.0)
    sp.add(2.5, 1.0)               # 2 m jump (relocalisation)
    m = sp.mask(g, 0.1)
    r, c = g.world_to_cell(1.5, 1.0)
    assert not m[r, c]
    assert m[g.world_to_cell(0.5, 1.0)] and m[g.world_to_cell(2.5, 1.0)]


def test_memory_is_bounded_and_the_newest_position_is_kept():
    sp = SweptPath(spacing_m=0.01, max_points=100)
    for i in range(1000):
        sp.add(0.02 * i, 0.0)
    assert len(sp) < 100
    assert sp.points()[-1, 0] == pytest.approx(0.02 * 999)
    # The corridor is still continuous over the thinned points.
    g = _grid(h=20, w=420, origin=(-0.5, -0.5))
    m = sp.mask(g, 0.1)
    row = g.world_to_cell(0.0, 0.0)[0]
    c0, c1 = g.world_to_cell(0.0, 0.0)[1], g.world_to_cell(19.9, 0.0)[1]
    assert m[row, c0:c1 + 1].all()


def test_mask_follows_the_grid_geometry_when_the_map_grows():
    sp = SweptPath()
    for x in np.arange(0.0, 1.0, 0.05):
        sp.add(float(x), 0.0)
    small = _grid(h=20, w=40, origin=(-0.5, -0.5))
    big = _grid(h=60, w=80, origin=(-1.5, -1.5))
    ms, mb = sp.mask(small, 0.15), sp.mask(big, 0.15)
    assert ms.sum() == mb.sum() > 0                   # the same world cells
    xs, ys = _cell_centres(small)
    xb, yb = _cell_centres(big)
    assert np.allclose(sorted(xs[ms]), sorted(xb[mb]))
    assert np.allclose(sorted(ys[ms]), sorted(yb[mb]))


def test_empty_path_or_zero_radius_gives_an_empty_mask_and_bad_values_raise():
    g = _grid()
    assert not SweptPath().mask(g, 0.3).any()
    sp = SweptPath()
    sp.add(1.0, 1.0)
    assert not sp.mask(g, 0.0).any()
    with pytest.raises(ValueError):
        sp.mask(g, -0.1)
    with pytest.raises(ValueError):
        SweptPath(spacing_m=0.0)
    with pytest.raises(ValueError):
        SweptPath(max_points=1)
