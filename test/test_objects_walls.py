"""The 2D map's walls as the object pipeline uses them (explore_seg.core.objects.walls)."""

from __future__ import annotations

import math

import numpy as np

from explore_seg.core.objects import ObjectParams, wall_mask
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
