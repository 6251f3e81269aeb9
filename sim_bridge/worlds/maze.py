"""Procedural mazes: a perfect maze of wall boxes with a few loops."""

from __future__ import annotations

from typing import Any

import numpy as np

from explore_seg.core.grid import metres_to_cells
from sim_bridge.world import Primitive, World
from sim_bridge.worlds.walls import Wall, bounds_around

def generate_maze(seed: int, size_m: tuple[float, float] = (40.0, 40.0), cell_m: float = 2.0,
                  **opts: Any) -> World:
    """A seeded maze of wall boxes on a grid of ``cell_m`` cells.

    A perfect maze (depth-first backtracker) whose interior walls are then removed with
    probability ``loop_prob`` to make a few loops. Walls are ``wall_thickness_m`` thick
    and ``wall_height_m`` high; collinear wall pieces are merged into one box. The start
    is the centre of the middle cell.

    Parameters
    ----------
    seed : int
    size_m : tuple of float
        Outer size (m); the maze has ``floor(size / cell_m)`` cells per axis (>= 2).
    cell_m : float
        Cell pitch (m): corridors are ``cell_m - wall_thickness_m`` wide.
    **opts
        ``wall_thickness_m`` (0.15), ``wall_height_m`` (2.5), ``loop_prob`` (0.05),
        ``margin_m`` (0.5).

    Returns
    -------
    World
        ``room_labels`` is None.

    Raises
    ------
    ValueError
        On a bad size, cell, option name or value.
    """
    known = {"wall_thickness_m": 0.15, "wall_height_m": 2.5, "loop_prob": 0.05, "margin_m": 0.5}
    unknown = sorted(set(opts) - set(known))
    if unknown:
        raise ValueError(f"unknown generate_maze option '{unknown[0]}' (known: {sorted(known)})")
    o = dict(known, **opts)
    t = float(o["wall_thickness_m"])
    if not 0 < t < cell_m - 0.5:
        raise ValueError(f"need 0 < wall_thickness_m < cell_m - 0.5, got {t} for cell {cell_m}")
    if not 0 <= float(o["loop_prob"]) <= 1:
        raise ValueError(f"loop_prob must be in [0, 1], got {o['loop_prob']}")
    nx, ny = (metres_to_cells(float(v), cell_m) for v in size_m)
    if nx < 2 or ny < 2:
        raise ValueError(f"size_m {size_m} holds fewer than 2x2 cells of {cell_m} m")
    rng = np.random.default_rng(seed)
    # walls: east[i, j] between cell (i, j) and (i+1, j); north[i, j] between (i, j), (i, j+1)
    east = np.ones((nx, ny), bool)
    north = np.ones((nx, ny), bool)
    seen = np.zeros((nx, ny), bool)
    stack = [(int(rng.integers(nx)), int(rng.integers(ny)))]
    seen[stack[0]] = True
    while stack:
        i, j = stack[-1]
        nbrs = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                if 0 <= i + di < nx and 0 <= j + dj < ny and not seen[i + di, j + dj]]
        if not nbrs:
            stack.pop()
            continue
        a, b = nbrs[int(rng.integers(len(nbrs)))]
        if a != i:
            east[min(a, i), j] = False
        else:
            north[i, min(b, j)] = False
        seen[a, b] = True
        stack.append((a, b))
    loops = rng.random((2, nx, ny)) < float(o["loop_prob"])
    east[:-1] &= ~loops[0][:-1]
    north[:, :-1] &= ~loops[1][:, :-1]
    x0, y0 = -nx * cell_m / 2, -ny * cell_m / 2
    walls: list[Wall] = [Wall(x0, y0, -x0, y0), Wall(x0, y0, x0, -y0)]
    # vertical lines x = x0 + (i+1) cell: runs of east[i, :]
    for i in range(nx):
        edges = np.flatnonzero(np.diff(np.concatenate(([0], east[i].astype(np.int8), [0]))))
        for a, b in zip(edges[0::2], edges[1::2]):
            xl = x0 + (i + 1) * cell_m
            walls.append(Wall(xl, y0 + a * cell_m, xl, y0 + b * cell_m))
    for j in range(ny):
        edges = np.flatnonzero(np.diff(np.concatenate(([0], north[:, j].astype(np.int8), [0]))))
        for a, b in zip(edges[0::2], edges[1::2]):
            yl = y0 + (j + 1) * cell_m
            walls.append(Wall(x0 + a * cell_m, yl, x0 + b * cell_m, yl))
    prims: list[Primitive] = []
    for k, w in enumerate(walls):
        prims.extend(w.boxes(f"wall_{k}", t, float(o["wall_height_m"]), None))
    start = (x0 + (nx // 2 + 0.5) * cell_m, y0 + (ny // 2 + 0.5) * cell_m, 0.0)
    bounds = bounds_around(x0 - t / 2, y0 - t / 2, -x0 + t / 2, -y0 + t / 2,
                            float(o["margin_m"]))
    return World(name=f"maze_s{seed}", bounds=bounds, start_pose=start, primitives=prims,
                 description=f"generated maze seed={seed} {nx}x{ny} cells of {cell_m} m")
