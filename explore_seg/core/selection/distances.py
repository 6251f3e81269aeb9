"""Path lengths robot -> frontier cPoints over passable space, one sweep per decision.

Known free space first; only when no cPoint is reachable that way (a doorway seen from
the side, its known strip narrower than the robot) through free-or-unknown space, as
Nav2 plans with ``allow_unknown``. :class:`PathGraphs` keeps both graphs of one map
version.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams, traversable_mask
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.block_graph import BlockGraph
from explore_seg.core.selection.params import SelectionParams


def frontier_distances(graph: BlockGraph, robot_rc: tuple[int, int],
                       frontiers: Sequence[Frontier],
                       params: SelectionParams = SelectionParams(),
                       fallback: Callable[[], BlockGraph] | None = None,
                       excluded: npt.NDArray[np.bool_] | None = None
                       ) -> npt.NDArray[np.float64]:
    """Path length (m) robot -> each cPoint, all from one sweep; inf when unreachable.

    A robot on a non-passable cell (inflated margin, map noise) starts from the nearest
    passable cell within ``start_search_radius_m`` (the straight hop is added); without
    one every distance is inf. cPoints that are not passable get inf.

    ``fallback`` builds a graph over an optimistic mask (free or unknown, see
    ``traversable_mask(..., allow_unknown=True)``). It is used only when no cPoint is
    reachable through known free space, leaving out the frontiers marked in ``excluded``
    (the goal manager's blacklist: a reachable but blacklisted frontier must not hide
    the others). A frontier seen through a doorway whose known free strip is narrower
    than the robot is then still a goal (the planner may cross unknown cells, as Nav2
    does with ``allow_unknown``) instead of ending exploration early. Those distances
    are multiplied by ``unknown_path_factor``.

    Returns
    -------
    ndarray of float64, shape (N,)
    """
    d = _frontier_distances(graph, robot_rc, frontiers, params)
    usable = np.isfinite(d)
    if excluded is not None:
        usable &= ~np.asarray(excluded, dtype=bool)
    if fallback is not None and len(d) and not usable.any():
        d = _frontier_distances(fallback(), robot_rc, frontiers, params) \
            * params.unknown_path_factor
    return d


def _frontier_distances(graph: BlockGraph, robot_rc: tuple[int, int],
                        frontiers: Sequence[Frontier], params: SelectionParams
                        ) -> npt.NDArray[np.float64]:
    n = len(frontiers)
    if n == 0:
        return np.zeros(0, dtype=np.float64)
    res = graph.resolution_m
    rad = metres_to_cells(params.start_search_radius_m, res)
    start = graph.nearest_passable(robot_rc, rad)
    if start is None:
        return np.full(n, np.inf)
    hop = math.hypot(start[0] - robot_rc[0], start[1] - robot_rc[1]) * res
    pts = np.asarray([f.point_rc for f in frontiers], dtype=np.int64)
    d = graph.distances(start, pts) + hop
    d[[not f.point_passable for f in frontiers]] = np.inf
    return d


class PathGraphs:
    """Path graphs of one map (and object layer) version, for :func:`frontier_distances`.

    The graph over known free space is built at once; the optimistic graph (free or
    unknown) only when a decision needs it, and then kept for this map version.

    Parameters
    ----------
    grid : GridMap
    extra_obstacles : ndarray of bool, shape (H, W), optional
        Object-layer obstacles aligned with ``grid``.
    frontier_params : FrontierParams
        Thresholds and robot radius of the passable masks.
    params : SelectionParams
        ``path_block_cells``, ``start_search_radius_m``, ``unknown_path_factor``.
    passable : ndarray of bool, optional
        The known-free passable mask when the caller already has it.
    """

    def __init__(self, grid: GridMap, extra_obstacles: npt.NDArray[np.bool_] | None,
                 frontier_params: FrontierParams, params: SelectionParams,
                 passable: npt.NDArray[np.bool_] | None = None) -> None:
        self._grid, self._extra, self._params = grid, extra_obstacles, params
        self._frontier_params = frontier_params
        if passable is None:
            passable = traversable_mask(grid, extra_obstacles, frontier_params)
        self.graph = BlockGraph(passable, grid.resolution_m, params.path_block_cells)
        self._fallback: BlockGraph | None = None

    def fallback(self) -> BlockGraph:
        """The graph over free-or-unknown cells (built on first use)."""
        if self._fallback is None:
            mask = traversable_mask(self._grid, self._extra, self._frontier_params,
                                    allow_unknown=True)
            self._fallback = BlockGraph(mask, self._grid.resolution_m,
                                        self._params.path_block_cells)
        return self._fallback

    def distances(self, robot_rc: tuple[int, int], frontiers: Sequence[Frontier],
                  excluded: npt.NDArray[np.bool_] | None = None
                  ) -> npt.NDArray[np.float64]:
        """:func:`frontier_distances` with the fallback through unknown space
        (``excluded``: e.g. :meth:`GoalManager.excluded`)."""
        return frontier_distances(self.graph, robot_rc, frontiers, self._params,
                                  self.fallback, excluded)
