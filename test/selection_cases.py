"""Shared cases of the selection and explorer tests: the paper's Fig. 2 world and
hand-made frontiers (not a test module)."""

from __future__ import annotations

import dataclasses

import numpy as np

from explore_seg.core.frontiers import Frontier, FrontierParams
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.selection import SelectionParams

# Fig. 2 of the paper: the robot R in room A (cols 1..14) next to the door (col 15) into
# room B (cols 16..29). A small frontier (3 cells) is left at A's far left wall; a big one
# (11 cells) borders B's unexplored right half, nearer to the robot.
ROW_A = "?" + "." * 14 + "#" + "." * 6 + "?" * 8 + "#"
ROW = "#" + "." * 14 + "#" + "." * 6 + "?" * 8 + "#"
DOOR = "#" + "." * 14 + "." + "." * 6 + "?" * 8 + "#"
ROBOT = "#" + "." * 12 + "R." + "." + "." * 6 + "?" * 8 + "#"
WALL = "#" * 31
FIG2 = "\n".join([WALL, ROW_A, ROW_A, ROW_A, ROW, ROW, DOOR, ROBOT, DOOR, DOOR, ROW, ROW, WALL])
RES = 0.1
BASE = dict(robot_radius_m=0.1, min_group_size_cells=3, path_block_cells=1)


def fig2():
    g, marks = grid_from_ascii(FIG2, resolution_m=RES)
    labels = np.zeros(g.shape, np.int32)
    free = g.free_mask()
    labels[:, 1:15][free[:, 1:15]] = 1
    labels[:, 16:30][free[:, 16:30]] = 2
    return g, marks["R"][0], labels


_FRONTIER_FIELDS = {f.name for f in dataclasses.fields(FrontierParams)}


def split_params(**kw) -> tuple[FrontierParams, SelectionParams]:
    """(FrontierParams, SelectionParams) from one set of keyword arguments (the paper's
    strategy unless ``strategy`` is given: these are the paper's cases)."""
    fkw = {k: v for k, v in kw.items() if k in _FRONTIER_FIELDS}
    skw = {"strategy": "paper", **{k: v for k, v in kw.items() if k not in _FRONTIER_FIELDS}}
    return FrontierParams(**fkw), SelectionParams(**skw)


def make_frontier(fid: int, cells, point_rc, grid: GridMap, passable: bool = True) -> Frontier:
    cells = np.asarray(cells, dtype=np.int64)
    cy, cx = cells.mean(axis=0)
    gx, gy = grid.cells_to_world(np.asarray([cy]), np.asarray([cx]))
    return Frontier(fid, len(cells), len(cells) * grid.resolution_m, tuple(point_rc),
                    grid.cell_to_world(*point_rc), passable, (float(cy), float(cx)),
                    (float(gx[0]), float(gy[0])), cells)


#: The default beta (the formulas below use it).
B = SelectionParams().beta


def two_frontiers(sizes=(10, 30)):
    g = GridMap(np.zeros((60, 60), np.int8), 0.05, (0.0, 0.0))
    f0 = make_frontier(0, [(5, c) for c in range(10, 10 + sizes[0])], (6, 12), g)
    f1 = make_frontier(1, [(50, c) for c in range(10, 10 + sizes[1])], (49, 20), g)
    labels = np.zeros(g.shape, np.int32)
    labels[:30] = 1
    labels[30:] = 2
    return g, [f0, f1], labels



def manager_world():
    g, fr, _ = two_frontiers()
    return g, fr
