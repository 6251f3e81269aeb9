"""The navigation stand-in's Nav2-style inflation (sim_bridge.navigation.planner.cost_grid):
paths keep clearance where the room allows and still pass narrow doors."""

from __future__ import annotations

import numpy as np
import pytest

from sim_bridge.navigation.params import NavParams
from sim_bridge.navigation.planner import cost_grid, plan_path

RES = 0.05


def _wall_distance_m(blocked, cells):
    """Distance from each path cell centre to the nearest blocked cell's square."""
    br, bc = np.nonzero(blocked)
    out = []
    for r, c in cells:
        du = np.maximum(np.abs(bc - c) - 0.5, 0.0)
        dv = np.maximum(np.abs(br - r) - 0.5, 0.0)
        out.append(float(np.hypot(du, dv).min()) * RES)
    return np.asarray(out)


def _plan(blocked, start, goal, params=NavParams()):
    cost = cost_grid(blocked, None, RES, params)
    out = plan_path(cost, start, goal, RES, params.plan_window_margin_m)
    assert out is not None
    return out[0]


def test_corridor_path_keeps_clear_of_the_walls():
    """A 1.5 m corridor with a bend: the path keeps >= 0.1 m between the robot's disk and
    the walls everywhere, though a 0.22 m disk could pass 0.01 m from them."""
    blocked = np.ones((90, 120), bool)
    blocked[10:40, 0:110] = False                    # 1.5 m wide, along x ...
    blocked[10:80, 80:110] = False                   # ... then a 1.5 m leg along y
    cells = _plan(blocked, (13, 3), (70, 95))
    clearance = _wall_distance_m(blocked, cells) - NavParams().robot_radius_m
    # the start lies 0.03 m from the wall's disk on purpose: the path leaves it
    assert clearance[10:].min() >= 0.1 - 1e-9, clearance[10:].min()
    assert clearance[0] < 0.1


def test_a_0_8_m_door_still_passes():
    h, w = 60, 60
    blocked = np.zeros((h, w), bool)
    blocked[:, 28:32] = True                         # a wall across the room ...
    blocked[22:38, 28:32] = False                    # ... with a 0.8 m door (16 cells)
    cells = _plan(blocked, (30, 5), (30, 55))
    through = cells[(cells[:, 1] >= 28) & (cells[:, 1] < 32)]
    assert len(through) and np.all((through[:, 0] >= 22) & (through[:, 0] < 38))
    # the door's middle: 0.4 m from each jamb, 0.18 m clear of the disk
    clearance = _wall_distance_m(blocked, through) - NavParams().robot_radius_m
    assert clearance.min() >= 0.1


@pytest.mark.parametrize("width_m, passes", [(0.5, True), (0.4, False)])
def test_lethal_zone_is_the_inscribed_radius(width_m, passes):
    """Doors narrower than the robot's disk (plus the margin) are closed, wider ones open."""
    n = int(round(width_m / RES))
    blocked = np.zeros((40, 40), bool)
    blocked[:, 18:22] = True
    blocked[20 - n // 2:20 - n // 2 + n, 18:22] = False
    cost = cost_grid(blocked, None, RES, NavParams())
    out = plan_path(cost, (20, 3), (20, 36), RES, 3.0)
    assert (out is not None) == passes


def test_soft_margin_keeps_clear_where_it_can_and_still_passes_a_narrow_door():
    soft = NavParams(inflation_soft_margin_m=0.05, inflation_cost_weight=0.0)
    hard = NavParams(inflation_margin_m=0.05)
    # a door the robot just fits through: closed by a 0.05 m hard margin, open with the soft one
    blocked = np.zeros((40, 40), bool)
    blocked[:, 18:22] = True
    blocked[10:19, 18:22] = False                    # rows 10..18: 0.45 m
    assert plan_path(cost_grid(blocked, None, RES, hard), (14, 3), (14, 36), RES, 3.0) is None
    assert plan_path(cost_grid(blocked, None, RES, soft), (14, 3), (14, 36), RES, 3.0)
    # a post in the open: with the soft band the robot's disk stays off the post's cells,
    # with the bare lethal zone (cell centres only) the path grazes them
    blocked = np.zeros((40, 60), bool)
    blocked[19:21, 29:31] = True
    cells = _plan(blocked, (20, 3), (20, 56), soft)
    assert (_wall_distance_m(blocked, cells) - 0.22).min() >= 0.0
    cells = _plan(blocked, (20, 3), (20, 56), NavParams(inflation_cost_weight=0.0,
                                                         inflation_soft_margin_m=0.0,
                                                         inflation_edge_cost=0.0))
    assert (_wall_distance_m(blocked, cells) - 0.22).min() < 0.0


@pytest.mark.parametrize("start", [(24, 27), (23, 26)])
def test_edge_cost_keeps_the_disk_off_a_corner_cell_inside_the_soft_band(start):
    """A 0.45 m passage (rows 21..29) between a cabinet's top face (rows <= 20 from col 30)
    and a wall (rows >= 30): every cell of it lies in the soft band, and the cell-centre
    lethal zone (4.4 cells) lets the plan cut the cabinet's corner, where a 0.22 m disk
    overlaps the corner cell by 3 cm (house seed 17's contact with cabinet_2). The edge
    cost makes the plan keep the disk off every obstacle cell; the passage stays open."""
    blocked = np.zeros((50, 60), bool)
    blocked[:21, 30:] = True
    blocked[30:, :] = True
    goal = (25, 38)
    cells = _plan(blocked, start, goal)
    assert (_wall_distance_m(blocked, cells[1:]) - 0.22).min() >= 0.0
    bare = _plan(blocked, start, goal, NavParams(inflation_edge_cost=0.0))
    assert (_wall_distance_m(blocked, bare[1:]) - 0.22).min() < -0.025
