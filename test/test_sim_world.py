"""World model: rasterisation rules of primitives into occupancy cells."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.grid import grid_from_ascii
from sim_bridge.world import Primitive
from sim_bridge.worlds import rasterize
from world_scenes import prim_box, tiny_world


def _cyl(x, y, r, z=(0.0, 1.0)):
    return Primitive("o", "table", "leg", "cylinder", x, y, 0.0, (r,), z[0], z[1])


@pytest.mark.parametrize("prim, expected", [
    # box edges exactly on cell borders: touching neighbours are not occupied
    (prim_box(0.2, 0.2, 0.2, 0.2), """
.....
.....
.##..
.##..
.....
"""),
    # box overlapping its neighbours by 0.5 mm: below the 1 mm rule
    (prim_box(0.2, 0.2, 0.201, 0.201), """
.....
.....
.##..
.##..
.....
"""),
    # overlap of 2 mm marks the neighbours
    (prim_box(0.2, 0.2, 0.204, 0.204), """
.....
####.
####.
####.
####.
"""),
    # thin leg at a cell centre: one cell
    (_cyl(0.25, 0.25, 0.02), """
.....
.....
..#..
.....
.....
"""),
    # box turned by 45 deg: a diamond
    (prim_box(0.25, 0.25, 0.12, 0.12, yaw=math.pi / 4), """
.....
..#..
.###.
..#..
.....
"""),
])
def test_rasterize_cell_rule(prim, expected):
    grid, _ = grid_from_ascii(expected, resolution_m=0.1)
    got = rasterize(tiny_world([prim]), 0.1, 0.17, 0.17)
    assert got.data.tolist() == grid.data.tolist()


@pytest.mark.parametrize("z, z_low, z_high, occupied", [
    ((0.0, 0.17), 0.17, 0.17, True),      # plane test is closed at zmax
    ((0.17, 1.0), 0.17, 0.17, True),      # ... and at zmin
    ((0.18, 1.0), 0.17, 0.17, False),
    ((0.5, 1.0), 0.0, 0.5, False),        # band test is open: a seat from 0.5 m is not in it
    ((0.45, 1.0), 0.0, 0.5, True),
    ((2.0, 2.5), 0.0, 1.5, False),        # lintel
])
def test_rasterize_height_filter(z, z_low, z_high, occupied):
    got = rasterize(tiny_world([prim_box(0.25, 0.25, 0.2, 0.2, z=z)]), 0.1, z_low, z_high)
    assert bool(got.data.any()) is occupied


def test_world_occupancy_method_matches_rasterize():
    w = tiny_world([prim_box(0.25, 0.25, 0.2, 0.2), _cyl(0.05, 0.45, 0.03)])
    assert np.array_equal(w.occupancy(0.05, 0.0, 0.5).data, rasterize(w, 0.05, 0.0, 0.5).data)


def test_rasterize_rejects_bad_band():
    with pytest.raises(ValueError, match="z_low <= z_high"):
        rasterize(tiny_world([]), 0.1, 0.5, 0.2)
