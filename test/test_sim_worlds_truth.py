"""Ground truth: the explorable region (4-connected flood fill) and trinary maps."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.grid import grid_from_ascii
from sim_bridge.world import World
from sim_bridge.worlds import flood_inside, ground_truth
from world_scenes import prim_box, tiny_world


def test_ground_truth_inside_is_flood_fill_from_start():
    # a closed 1 x 1 m room (walls 0.1 m) inside 2 x 2 m bounds, start in it
    walls = [prim_box(0.5, 0.05, 1.0, 0.1), prim_box(0.5, 0.95, 1.0, 0.1),
             prim_box(0.05, 0.5, 0.1, 1.0), prim_box(0.95, 0.5, 0.1, 1.0)]
    w = World("room", (-0.5, -0.5, 1.5, 1.5), (0.5, 0.5, 0.0), walls)
    gt = ground_truth(w, 0.1)
    assert gt.inside.sum() == 64                    # 8 x 8 interior cells
    assert gt.free_area_m2 == pytest.approx(0.64)
    m = gt.as_map("lidar").data
    assert (m == 0).sum() == 64 and (m == 100).sum() == 100 - 64
    assert (m == -1).sum() == 400 - 100


def test_flood_inside_is_4_connected():
    grid, marks = grid_from_ascii("""
    ..#..
    .S#..
    ##.#.
    ...#.
    """)
    inside = flood_inside(grid.free_mask(), marks["S"][0])
    want, _ = grid_from_ascii("""
    ##...
    ##...
    .....
    .....
    """)
    assert inside.tolist() == (want.data == 100).tolist()


def test_flood_inside_rejects_blocked_start():
    with pytest.raises(ValueError, match="occupied"):
        flood_inside(np.zeros((3, 3), bool), (1, 1))


def test_flood_inside_rejects_start_outside():
    with pytest.raises(ValueError, match="outside"):
        flood_inside(np.ones((3, 3), bool), (5, 1))


def test_as_map_rejects_unknown_raster():
    gt = ground_truth(tiny_world([prim_box(0.35, 0.35, 0.1, 0.1)]), 0.1)
    with pytest.raises(ValueError, match="which must be one of"):
        gt.as_map("ceiling")
