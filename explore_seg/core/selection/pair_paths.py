"""Path lengths between viewpoints, kept across decisions (the ``routed`` tour's matrix).

A tour needs the path length between every pair of viewpoints. One Dijkstra sweep per
viewpoint over the whole map's path graph costs time in proportion to the explored area
and the number of viewpoints (on a 2,000 m^2 office floor about 0.8 ms per viewpoint:
70 ms for 90 viewpoints, every decision). Between two decisions most viewpoints stay
where they were: the map changes near the robot only (on that floor about 4 of 65
viewpoints are new at a decision). So, as FUEL updates the connection
costs of changed frontier clusters only, :class:`PairPaths` keeps the lengths between
viewpoints that stayed (same cell in world coordinates) and sweeps only from

- the viewpoints that are new (not in the last matrix), and
- the ``refresh_rows`` viewpoints whose lengths are the oldest (round robin), so every
  kept length is recomputed within ``n / refresh_rows`` decisions.

A kept length is the one of the map it was computed on: a shortcut found since then is
missed, a path blocked since then still counted, for at most that many decisions (the
robot -> viewpoint lengths, which decide the next goal's cost most, are always fresh: the
caller computes them per decision). ``refresh_rows`` at or above the number of
viewpoints recomputes every length at every decision (exact, slower on large maps).

Examples
--------
>>> import numpy as np
>>> from explore_seg.core.block_graph import BlockGraph
>>> from explore_seg.core.grid import GridMap
>>> grid = GridMap(np.zeros((20, 40), np.int8), 0.1)
>>> graph = BlockGraph(np.ones((20, 40), bool), 0.1, 1)
>>> cache = PairPaths(refresh_rows=0)
>>> pts = np.array([[10, 2], [10, 20], [10, 37]])
>>> d = cache.matrix(graph, grid, pts)
>>> round(float(d[0, 2]), 2), cache.swept
(3.5, 3)
>>> d2 = cache.matrix(graph, grid, pts[[2, 0]])      # both kept: no sweep
>>> round(float(d2[1, 0]), 2), cache.swept
(3.5, 0)
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from explore_seg.core.block_graph import BlockGraph
from explore_seg.core.grid import GridMap


class PairPaths:
    """Viewpoint-to-viewpoint path lengths kept across decisions (module docstring).

    Parameters
    ----------
    refresh_rows : int
        Kept viewpoints whose lengths are recomputed per call (the oldest first), >= 0.

    Attributes
    ----------
    swept : int
        Viewpoints swept from in the last :meth:`matrix` call.
    """

    def __init__(self, refresh_rows: int = 8) -> None:
        if refresh_rows < 0:
            raise ValueError(f"refresh_rows must be >= 0, got {refresh_rows}")
        self._refresh = int(refresh_rows)
        self.reset()

    def reset(self) -> None:
        """Forget every kept length (a new map)."""
        self._index: dict[tuple[float, float], int] = {}
        self._d = np.zeros((0, 0))
        self._stamp = np.zeros(0, dtype=np.int64)
        self._calls = 0
        self._frame: tuple[str, float] | None = None
        self.swept = 0

    def matrix(self, graph: BlockGraph, grid: GridMap, cells_rc: npt.ArrayLike
               ) -> npt.NDArray[np.float64]:
        """Path lengths between all pairs of ``cells_rc`` (see
        :meth:`BlockGraph.distance_matrix`; kept lengths where the module docstring says).

        Parameters
        ----------
        graph : BlockGraph
            The path graph of ``grid``'s current version.
        grid : GridMap
            For the cells' world positions (the keys that survive map growth).
        cells_rc : array_like of int, shape (N, 2)

        Returns
        -------
        ndarray of float64, shape (N, N)
            0 on the diagonal, inf between unconnected cells.
        """
        rc = np.asarray(cells_rc, dtype=np.int64).reshape(-1, 2)
        frame = (grid.frame_id, float(grid.resolution_m))
        if frame != self._frame:
            self.reset()
            self._frame = frame
        self._calls += 1
        n = rc.shape[0]
        xs, ys = grid.cells_to_world(rc[:, 0], rc[:, 1])
        keys = [(round(float(x), 4), round(float(y), 4)) for x, y in zip(xs, ys)]
        pos = np.asarray([self._index.get(k, -1) for k in keys], dtype=np.int64)
        fresh = pos < 0
        kept = np.flatnonzero(~fresh)
        if self._refresh and kept.size:
            oldest = kept[np.argsort(self._stamp[pos[kept]], kind="stable")[:self._refresh]]
            fresh[oldest] = True
        out = np.zeros((n, n))
        old = np.flatnonzero(~fresh)
        if old.size:
            out[np.ix_(old, old)] = self._d[np.ix_(pos[old], pos[old])]
        new = np.flatnonzero(fresh)
        if new.size:
            rows = graph.distance_rows(rc[new], rc)
            out[:, new] = rows.T
            out[new, :] = rows
        np.fill_diagonal(out, 0.0)
        stamp = np.where(fresh, self._calls,
                         self._stamp[np.maximum(pos, 0)] if len(self._stamp) else 0)
        self._index = {k: i for i, k in enumerate(keys)}
        self._d, self._stamp = out.copy(), np.asarray(stamp, dtype=np.int64)
        self.swept = int(new.size)
        return out


__all__ = ["PairPaths"]
