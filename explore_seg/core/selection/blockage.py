"""Approach goals: drive up to a passage closed only by map speckle and look at it.

A map built from noisy scans holds **speckle**: single occupied cells (or pairs) where a
scan mapped at a wrong pose put a hit that no other scan confirmed. Inflated by the robot
radius, one such cell closes a doorway. A robot that drove through a doorway and then
mapped speckle into it is walled in: every frontier beyond has no path, and exploration
would end ("no path") with the rest of the building unseen. The sensor removes speckle
where it sees through it (every beam that passes lowers a cell's occupancy), most
surely from close by, where a heading error moves a hit least.

Drift narrows doorways too: a wall mapped twice a few centimetres apart, ragged edges
joined to the wall (no speckle), leave a passage narrower than the robot in the map.
Larger drift closes them: walls mapped again at a pose that drifted by a door's width
shut the doorway the robot came in through. Where the robot's centre was, it could be:
its own path (``RelaxedMap.trail``) is passable on the relaxed map, so the frontiers
beyond such a doorway get an approach and the navigator, which plans on its own map and
live scans, decides whether to pass.

When a decision has no selectable frontier, :func:`approaches` judges reachability once
more on a relaxed map: without speckle (occupied 8-connected pieces of at most
``speckle_max_cells`` cells taken as free), for a robot of radius ``approach_radius_m``
(smaller than the real one). Each unreachable frontier that this map reaches gets an
**approach**, in two steps:

1. its own cPoint, marked passable: the navigator (Nav2) decides. Its planner may pass
   where this map's graph does not (a doorway passable only diagonally, a margin it
   plans through), and a goal it cannot reach ends "no path" at once;
2. once the navigator aborted a goal there while the map had no path either
   (:meth:`~explore_seg.core.selection.goals.GoalManager.aborted_near`), a **look**:
   the last cell of the relaxed path (from the robot) that the robot reaches on the
   real map, i.e. where the blockage beyond it begins. The frontier is returned with its
   cPoint moved there, so the goal manager sends, judges (arrival, then "frontier still
   there?") and blacklists it as any other goal: one look per blocked passage (per
   blacklist retry), then exploration ends as before. When the look cleared the noise,
   the frontiers beyond have a path again and exploration goes on.

Examples
--------
>>> from explore_seg.core.grid import grid_from_ascii
>>> g, _ = grid_from_ascii('''
... #####
... #.?.#
... #...#
... #...#
... #...#
... #.#.#
... #...#
... #...#
... #...#
... #####
... ''', resolution_m=1.0)
>>> speck = speckle_cells(g.data >= 65, 1)     # the lone cell in the middle, no wall
>>> [g.cell_to_world(int(r), int(c)) for r, c in np.argwhere(speck)]
[(2.5, 4.5)]
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams, traversable_mask
from explore_seg.core.grid import GridMap
from explore_seg.core.paths import distance_field, extract_path
from explore_seg.core.selection.lookout import Reach


def speckle_cells(occupied: npt.NDArray[np.bool_], max_cells: int) -> npt.NDArray[np.bool_]:
    """Occupied cells in 8-connected occupied pieces of at most ``max_cells`` cells.

    Parameters
    ----------
    occupied : ndarray of bool, shape (H, W)
    max_cells : int
        Largest piece counted as speckle; 0 = none.

    Returns
    -------
    ndarray of bool, shape (H, W)

    Raises
    ------
    ValueError
        When ``max_cells`` < 0 or ``occupied`` is not 2-D.

    Examples
    --------
    >>> occ = np.zeros((4, 6), bool); occ[1, 1] = True; occ[1:3, 3:5] = True
    >>> speckle_cells(occ, 1).astype(int).tolist()
    [[0, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]]
    >>> int(speckle_cells(occ, 4).sum())
    5
    """
    occ = np.asarray(occupied, dtype=bool)
    if occ.ndim != 2:
        raise ValueError(f"occupied must be 2-D, got shape {occ.shape}")
    if max_cells < 0:
        raise ValueError(f"max_cells must be >= 0, got {max_cells}")
    if max_cells == 0 or not occ.any():
        return np.zeros(occ.shape, dtype=bool)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(occ.astype(np.uint8),
                                                           connectivity=8)
    small = stats[:, cv2.CC_STAT_AREA] <= max_cells
    small[0] = False                       # background
    return small[labels]


def despeckled(grid: GridMap, params: FrontierParams, max_cells: int) -> GridMap:
    """``grid`` with its speckle (:func:`speckle_cells` of the occupied cells, values >=
    ``params.occupied_threshold``) set free (0)."""
    speck = speckle_cells(grid.data >= params.occupied_threshold, max_cells)
    data = grid.data.copy()
    data[speck] = 0
    return replace(grid, data=data)


@dataclass(frozen=True, eq=False)
class RelaxedMap:
    """How :func:`approaches` relaxes the map (module docstring)."""

    #: ``occupied_threshold``, ``free_threshold`` and ``robot_radius_m`` of the relaxed
    #: map: a radius below the robot's opens passages that noise narrowed to more than
    #: twice it.
    params: FrontierParams
    #: Occupied pieces of at most this many cells are speckle; 0: no approaches.
    max_cells: int
    #: Obstacles besides the map (the object layer), kept; shape (H, W).
    extra_obstacles: npt.NDArray[np.bool_] | None = None
    #: Cells passable whatever the map says: the robot's own path (where its centre
    #: was); shape (H, W).
    trail: npt.NDArray[np.bool_] | None = None


def approaches(grid: GridMap, frontiers: Sequence[Frontier], dist_m: npt.NDArray[np.float64],
               reach: Reach, relaxed: RelaxedMap,
               excluded: npt.NDArray[np.bool_] | None = None,
               through: npt.NDArray[np.bool_] | None = None
               ) -> tuple[list[Frontier], npt.NDArray[np.float64]]:
    """The frontiers with an approach instead of their unreachable cPoint (module
    docstring).

    Parameters
    ----------
    grid : GridMap
    frontiers : sequence of Frontier
    dist_m : ndarray of float64, shape (N,)
        Path lengths robot -> cPoints (inf: no path).
    reach : Reach
        The graph, start cell and passable cells the distances were computed on.
    relaxed : RelaxedMap
    excluded : ndarray of bool, shape (N,), optional
        Blacklisted frontiers (left as they are).
    through : ndarray of bool, shape (N,), optional
        Frontiers whose approach is their own cPoint (marked passable, at the relaxed
        path's length): the navigator, whose planner may pass where this map's graph
        does not, decides; the others get the look point. Default: none.

    Returns
    -------
    (list of Frontier, ndarray of float64)
        Same order; an unreachable frontier with an approach has ``point_rc`` /
        ``point_xy_m`` there and ``point_passable`` True, and its distance is the path
        length to the approach. The others are unchanged.
    """
    out = list(frontiers)
    d_out = np.asarray(dist_m, dtype=np.float64).copy()
    todo = [i for i in range(len(frontiers))
            if not np.isfinite(d_out[i]) and not (excluded is not None and excluded[i])]
    if not todo or relaxed.max_cells <= 0:
        return out, d_out
    clean = traversable_mask(despeckled(grid, relaxed.params, relaxed.max_cells),
                             relaxed.extra_obstacles, relaxed.params)
    clean |= reach.passable
    if relaxed.trail is not None:
        clean |= relaxed.trail
    field = distance_field(clean, reach.start_rc, grid.resolution_m)
    paths: dict[int, npt.NDArray[np.int64]] = {}
    for i in todo:
        r, c = frontiers[i].point_rc
        if grid.in_bounds(r, c) and np.isfinite(field[r, c]):
            paths[i] = extract_path(field, (r, c))
    if not paths:
        return out, d_out
    # A relaxed path may leave the robot's reach and come back (it cuts corners the robot
    # radius keeps the robot from): the approach is the last cell of the path that the
    # robot reaches, where the blockage beyond it begins.
    d_all = reach.graph.distances(reach.start_rc, np.concatenate(list(paths.values())))
    at = 0
    for i, path in paths.items():
        d_path = d_all[at:at + len(path)]
        at += len(path)
        reached = np.isfinite(d_path)
        reached[0] = True                  # the start cell (the robot may stand on a margin)
        if reached.all():
            continue
        k = int(np.flatnonzero(reached)[-1])
        if not np.isfinite(d_path[k]):
            continue
        if through is not None and through[i]:
            fr, fc = frontiers[i].point_rc
            out[i] = replace(frontiers[i], point_passable=True)
            d_out[i] = max(float(d_path[k]), float(field[fr, fc])) + reach.hop_m
            continue
        r, c = int(path[k, 0]), int(path[k, 1])
        out[i] = replace(frontiers[i], point_rc=(r, c), point_xy_m=grid.cell_to_world(r, c),
                         point_passable=True)
        d_out[i] = float(d_path[k]) + reach.hop_m
    return out, d_out


__all__ = ["RelaxedMap", "approaches", "despeckled", "speckle_cells"]
