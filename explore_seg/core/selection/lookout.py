"""Lookout goals: look at a frontier the robot cannot drive to.

A frontier can lie beyond a passage narrower than the robot (a niche, a corridor's far
end seen through its mouth): its cPoint has no path, yet a robot standing at the right
spot would see the unknown space behind it. Without another reachable frontier,
exploration would end there ("no path") with that space unseen.

When a decision has no selectable frontier (every one without a path, or blacklisted),
:func:`lookouts` gives each unreachable, non-blacklisted frontier a **lookout**: the
reachable cell from which the robot sees the most unknown area (``view_gain``, a
``sensor_range_m`` 360-degree sensor) among lattice cells (every ``viewpoint_step_m``)
that

* lie within ``sensor_range_m`` of one of the frontier's cells, and
* see at least one of its cells: the straight line between them crosses no occupied cell
  (sampled every half cell on the full-resolution map).

Lookouts that see less than ``min_gain_m2`` of unknown area are not goals. Among those
within ``1 - viewpoint_gain_tolerance`` of the best view, the closest (path length) wins.
The frontier is returned with its cPoint moved to the lookout, so the goal manager
sends, judges (arrival, then "frontier still there?") and blacklists the lookout as any
other goal: one look per lookout, then exploration ends as before.

Examples
--------
>>> import numpy as np
>>> from explore_seg.core.block_graph import BlockGraph
>>> from explore_seg.core.frontiers import Frontier
>>> data = np.full((60, 60), 100, dtype=np.int8)   # 3 x 3 m at 0.05 m, all walls
>>> data[5:30, 5:55] = 0                             # a room
>>> data[30:50, 28:32] = 0                           # a 0.2 m wide corridor down
>>> data[50:55, 28:32] = -1                          # its unknown end
>>> g = GridMap(data, 0.05, (0.0, 0.0))
>>> passable = np.zeros((60, 60), bool); passable[10:25, 10:50] = True
>>> f = Frontier(1, 4, 0.2, (49, 30), g.cell_to_world(49, 30), True, (49.0, 29.5),
...              g.cell_to_world(49, 29.5),
...              np.array([[49, 28], [49, 29], [49, 30], [49, 31]]))
>>> graph = BlockGraph(passable, 0.05, 1)
>>> reach = Reach(graph, (15, 15), passable)
>>> new, d = lookouts(g, [f], np.array([np.inf]), reach,
...                   SelectionParams(sensor_range_m=3.0, min_gain_m2=0.01), 65)
>>> new[0].point_rc, round(float(d[0]), 2)      # in line with the corridor
((12, 30), 0.81)
>>> new, d = lookouts(g, [f], np.array([np.inf]), reach,
...                   SelectionParams(sensor_range_m=3.0, min_gain_m2=1.0), 65)
>>> new[0].point_rc, float(d[0])                # too little to see: unchanged
((49, 30), inf)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.block_graph import BlockGraph
from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.viewpoints import (candidate_cells, coarse_codes,
                                                   pick_viewpoint, view_gain)

#: Frontier cells per group whose visibility is tested (evenly spread over the group).
MAX_TARGET_CELLS = 16


def sees_any(blocked: npt.NDArray[np.bool_], origins_rc: npt.NDArray[np.int64],
             targets_rc: npt.NDArray[np.int64], range_cells: float
             ) -> npt.NDArray[np.bool_]:
    """For each origin: is any target within ``range_cells`` with a line of sight (no
    ``blocked`` cell on the segment, sampled every half cell; the end cells included)?

    Examples
    --------
    >>> b = np.zeros((5, 9), bool); b[:, 4] = True; b[0, 4] = False
    >>> sees_any(b, np.array([[2, 1], [0, 1]]), np.array([[2, 7], [0, 7]]), 10.0).tolist()
    [False, True]
    """
    o = np.asarray(origins_rc, dtype=np.float64).reshape(-1, 2)
    t = np.asarray(targets_rc, dtype=np.float64).reshape(-1, 2)
    seen = np.zeros(len(o), dtype=bool)
    h, w = blocked.shape
    for tr, tc in t:                    # one target at a time: (O, samples) arrays
        dr, dc = tr - o[:, 0], tc - o[:, 1]
        length = np.hypot(dr, dc)
        near = ~seen & (length <= range_cells)
        if not near.any():
            continue
        n = max(2, int(math.ceil(float(length[near].max()) * 2.0)) + 1)
        s = np.linspace(0.0, 1.0, n)
        r = np.clip(np.rint(o[near, 0, None] + s[None, :] * dr[near, None]).astype(np.int64),
                    0, h - 1)
        c = np.clip(np.rint(o[near, 1, None] + s[None, :] * dc[near, None]).astype(np.int64),
                    0, w - 1)
        seen[np.flatnonzero(near)[~blocked[r, c].any(axis=1)]] = True
    return seen


@dataclass(frozen=True, eq=False)
class Reach:
    """Where the robot can drive: path lengths from its start cell on a passable graph."""

    #: The passable graph the distances were computed on.
    graph: BlockGraph
    #: The robot's passable start cell.
    start_rc: tuple[int, int]
    #: Passable cells (lookout candidates), shape (H, W).
    passable: npt.NDArray[np.bool_]
    #: Added to every path length (the robot's hop to ``start_rc``), metres.
    hop_m: float = 0.0


def lookouts(grid: GridMap, frontiers: Sequence[Frontier], dist_m: npt.NDArray[np.float64],
             reach: Reach, params: SelectionParams, occupied_threshold: int,
             excluded: npt.NDArray[np.bool_] | None = None
             ) -> tuple[list[Frontier], npt.NDArray[np.float64]]:
    """The frontiers with a lookout instead of their unreachable cPoint (module docstring).

    Parameters
    ----------
    grid : GridMap
    frontiers : sequence of Frontier
    dist_m : ndarray of float64, shape (N,)
        Path lengths robot -> cPoints (inf: no path).
    reach : Reach
        The graph, start cell and passable cells the distances were computed on.
    params : SelectionParams
        ``sensor_range_m``, ``viewpoint_step_m``, ``gain_rays``, ``min_gain_m2``,
        ``viewpoint_gain_tolerance``.
    occupied_threshold : int
        Map values >= this block the view.
    excluded : ndarray of bool, shape (N,), optional
        Blacklisted frontiers (left as they are).

    Returns
    -------
    (list of Frontier, ndarray of float64)
        Same order; an unreachable frontier with a lookout has ``point_rc`` /
        ``point_xy_m`` there and ``point_passable`` True, and its distance is the path
        length to the lookout. The others are unchanged.
    """
    out = list(frontiers)
    d_out = np.asarray(dist_m, dtype=np.float64).copy()
    todo = [i for i, f in enumerate(frontiers)
            if not np.isfinite(d_out[i]) and not (excluded is not None and excluded[i])]
    if not todo:
        return out, d_out
    res = grid.resolution_m
    radius = metres_to_cells(params.sensor_range_m, res)
    step = max(1, metres_to_cells(params.viewpoint_step_m, res))
    blocked = grid.data >= occupied_threshold
    codes = coarse_codes(grid, occupied_threshold)
    cands = [candidate_cells(frontiers[i].cells, frontiers[i].point_rc, reach.passable,
                             radius, step)[1:] for i in todo]
    counts = [len(c) for c in cands]
    if not sum(counts):
        return out, d_out
    # One Dijkstra sweep for the candidates of every frontier.
    dist_all = reach.graph.distances(reach.start_rc, np.concatenate(cands)) + reach.hop_m
    bounds = np.concatenate([[0], np.cumsum(counts)])
    for j, i in enumerate(todo):
        f = frontiers[i]
        cand, d = cands[j], dist_all[bounds[j]:bounds[j + 1]]
        reach = np.isfinite(d)
        cand, d = cand[reach], d[reach]
        if len(cand) == 0:
            continue
        cells = f.cells
        if len(cells) > MAX_TARGET_CELLS:
            cells = cells[np.linspace(0, len(cells) - 1, MAX_TARGET_CELLS).astype(np.int64)]
        see = sees_any(blocked, cand, cells, float(radius))
        cand, d = cand[see], d[see]
        if len(cand) == 0:
            continue
        gain = view_gain(grid, cand, params.sensor_range_m, params.gain_rays,
                         occupied_threshold, codes)
        d = np.where(gain >= params.min_gain_m2, d, np.inf)
        k = pick_viewpoint(gain, d, params.viewpoint_gain_tolerance)
        if k is None:
            continue
        r, c = int(cand[k, 0]), int(cand[k, 1])
        out[i] = replace(f, point_rc=(r, c), point_xy_m=grid.cell_to_world(r, c),
                         point_passable=True)
        d_out[i] = float(d[k])
    return out, d_out


__all__ = ["MAX_TARGET_CELLS", "Reach", "lookouts", "sees_any"]
