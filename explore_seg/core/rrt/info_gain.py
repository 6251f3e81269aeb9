"""Information gain of points: the unknown area around them (rrt_exploration's
``informationGain``: unknown cells whose centre lies within a radius of the point, times
the cell area)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap


def disc_offsets(radius_m: float, resolution_m: float) -> npt.NDArray[np.int64]:
    """(drow, dcol) of the cells whose centre lies within ``radius_m`` of a cell centre."""
    r = int(np.floor(radius_m / resolution_m))
    d = np.arange(-r, r + 1)
    dr, dc = np.meshgrid(d, d, indexing="ij")
    keep = (dr ** 2 + dc ** 2) * resolution_m ** 2 <= radius_m ** 2 + 1e-12
    return np.stack([dr[keep], dc[keep]], axis=1).astype(np.int64)


def unknown_within(grid: GridMap, rc: npt.ArrayLike, radius_m: float
                   ) -> tuple[npt.NDArray[np.int64], list[npt.NDArray[np.int64]]]:
    """Unknown cells within ``radius_m`` of each cell of ``rc``.

    Parameters
    ----------
    grid : GridMap
    rc : array_like of int, shape (M, 2)
        (row, col) of the points' cells (may lie outside the grid).
    radius_m : float

    Returns
    -------
    counts : ndarray of int64, shape (M,)
        Unknown cells per point (cells outside the grid do not count).
    cells : list of ndarray of int64, shape (K_i, 2)
        Those cells per point.
    """
    pts = np.asarray(rc, dtype=np.int64).reshape(-1, 2)
    off = disc_offsets(radius_m, grid.resolution_m)
    rows = pts[:, :1] + off[None, :, 0]
    cols = pts[:, 1:] + off[None, :, 1]
    inside = (rows >= 0) & (rows < grid.height) & (cols >= 0) & (cols < grid.width)
    unknown = np.zeros_like(inside)
    unknown[inside] = grid.data[rows[inside], cols[inside]] < 0
    cells = [np.stack([rows[i][unknown[i]], cols[i][unknown[i]]], axis=1)
             for i in range(len(pts))]
    return unknown.sum(axis=1).astype(np.int64), cells


def information_gain_m2(grid: GridMap, xy_m: npt.ArrayLike, radius_m: float
                        ) -> npt.NDArray[np.float64]:
    """Unknown area (m^2) within ``radius_m`` of each world point of ``xy_m`` (M, 2)."""
    xy = np.asarray(xy_m, dtype=np.float64).reshape(-1, 2)
    r, c = grid.world_to_cells(xy[:, 0], xy[:, 1])
    counts, _ = unknown_within(grid, np.stack([r, c], axis=1), radius_m)
    return counts * grid.resolution_m ** 2
