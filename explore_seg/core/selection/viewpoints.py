"""Viewpoints of frontier groups: where the robot would see the most unknown space.

For each frontier group, candidate poses are passable cells on a lattice (every
``viewpoint_step_m``) within ``viewpoint_radius_m`` of the group's cells, plus the group's
cPoint. The **gain** of a candidate is the unknown area (m^2) a 360-degree range sensor
of range ``sensor_range_m`` would see from it on the current map: ``gain_rays`` rays are
cast on a map coarsened to twice the cell size (a coarse cell is occupied when any of its
cells is, unknown when any is and none is occupied; outside the map blocks); unknown
cells let the ray through, an occupied cell stops it, and each unknown sample counts
its area element ``r * dtheta * dr``, so the sum estimates the visible unknown area
rather than the number of ray hits. All candidates of all groups are cast at once
(numpy fancy indexing over a ``(candidates, rays, steps)`` array).

The viewpoint of a group is its reachable candidate of highest gain; among candidates
within ``1 - viewpoint_gain_tolerance`` of that gain, the one with the shortest path from
the robot (seeing nearly as much from closer saves driving). A group without a
reachable candidate keeps its cPoint.

Examples
--------
>>> import numpy as np
>>> data = np.full((40, 100), -1, dtype=np.int8)     # 2 x 5 m at 0.05 m, unknown
>>> data[:, :50] = 0                                   # the left half is free
>>> g = GridMap(data, 0.05, (0.0, 0.0))
>>> gain = view_gain(g, np.array([[20, 5], [20, 48]]), range_m=3.0, rays=16)
>>> bool(gain[1] > gain[0] > 0)
True
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap

#: Coarsening factor of the ray-casting map (cells per coarse cell side).
COARSEN = 2
_FREE, _UNKNOWN, _BLOCKED = 0, 1, 2


def coarse_codes(grid: GridMap, occupied_threshold: int = 65, factor: int = COARSEN
                 ) -> npt.NDArray[np.uint8]:
    """The map coarsened by ``factor``: 0 free, 1 unknown, 2 occupied (any cell decides,
    occupied before unknown).

    Returns
    -------
    ndarray of uint8, shape (ceil(H / factor), ceil(W / factor))
    """
    d = grid.data
    h, w = d.shape
    hc, wc = -(-h // factor), -(-w // factor)
    pad = np.full((hc * factor, wc * factor), -1, dtype=np.int16)
    pad[:h, :w] = d
    occ = (pad >= occupied_threshold).reshape(hc, factor, wc, factor).any(axis=(1, 3))
    unk = (pad < 0).reshape(hc, factor, wc, factor).any(axis=(1, 3))
    out = np.where(occ, _BLOCKED, np.where(unk, _UNKNOWN, _FREE)).astype(np.uint8)
    return out


def view_gain(grid: GridMap, cells_rc: npt.ArrayLike, range_m: float = 5.0,
              rays: int = 24, occupied_threshold: int = 65,
              codes: npt.NDArray[np.uint8] | None = None) -> npt.NDArray[np.float64]:
    """Unknown area (m^2) visible within ``range_m`` from each cell (module docstring).

    Parameters
    ----------
    grid : GridMap
    cells_rc : array_like of int, shape (C, 2)
        Sensor positions (row, col) in ``grid``.
    range_m : float
        Sensor range, > 0.
    rays : int
        Rays over 360 degrees, >= 4.
    occupied_threshold : int
        Map values >= this stop a ray.
    codes : ndarray of uint8, optional
        :func:`coarse_codes` of ``grid`` (computed when None).

    Returns
    -------
    ndarray of float64, shape (C,)

    Raises
    ------
    ValueError
        On a bad range, ray count or cell array.
    """
    if not (math.isfinite(range_m) and range_m > 0):
        raise ValueError(f"range_m must be finite and > 0, got {range_m}")
    if rays < 4:
        raise ValueError(f"rays must be >= 4, got {rays}")
    rc = np.asarray(cells_rc, dtype=np.int64).reshape(-1, 2)
    if rc.shape[0] == 0:
        return np.zeros(0)
    if codes is None:
        codes = coarse_codes(grid, occupied_threshold)
    cell_m = grid.resolution_m * COARSEN
    steps = max(1, int(math.ceil(range_m / cell_m)))
    r = (np.arange(steps) + 1.0) * cell_m                           # (S,) metres
    theta = np.arange(rays) * (2.0 * math.pi / rays)
    dr = np.rint(np.sin(theta)[:, None] * r[None, :] / cell_m).astype(np.int64)  # (K, S)
    dc = np.rint(np.cos(theta)[:, None] * r[None, :] / cell_m).astype(np.int64)
    # Pad the coarse map with blocking cells so no ray leaves it; flat indices.
    pad = steps + 1
    hc, wc = codes.shape
    padded = np.full((hc + 2 * pad, wc + 2 * pad), _BLOCKED, dtype=np.uint8)
    padded[pad:pad + hc, pad:pad + wc] = codes
    wp = wc + 2 * pad
    orow = np.clip(np.floor((rc[:, 0] + 0.5) / COARSEN).astype(np.int64), -1, hc) + pad
    ocol = np.clip(np.floor((rc[:, 1] + 0.5) / COARSEN).astype(np.int64), -1, wc) + pad
    flat = (orow * wp + ocol)[:, None] + (dr * wp + dc).ravel()[None, :]   # (C, K*S)
    code = padded.ravel()[flat].reshape(rc.shape[0], rays, steps)
    blocked = code == _BLOCKED
    first = np.where(blocked.any(axis=2), blocked.argmax(axis=2), steps)   # (C, K)
    visible = np.arange(steps)[None, None, :] < first[:, :, None]
    weight = r * (2.0 * math.pi / rays) * cell_m                    # area per sample
    return ((visible & (code == _UNKNOWN)) * weight[None, None, :]).sum(axis=(1, 2))


def candidate_cells(frontier_cells: npt.NDArray[np.int64], cpoint_rc: tuple[int, int],
                    passable: npt.NDArray[np.bool_], radius_cells: int, step_cells: int,
                    max_frontier_cells: int = 64) -> npt.NDArray[np.int64]:
    """Passable lattice cells within ``radius_cells`` of a group's cells, cPoint first.

    The lattice is global (rows and columns divisible by ``step_cells``), so the
    candidates of a group do not move when the group grows.

    Returns
    -------
    ndarray of int64, shape (C, 2)
    """
    h, w = passable.shape
    cells = frontier_cells
    if len(cells) > max_frontier_cells:
        cells = cells[np.linspace(0, len(cells) - 1, max_frontier_cells).astype(np.int64)]
    r0 = max(0, int(cells[:, 0].min()) - radius_cells)
    r1 = min(h - 1, int(cells[:, 0].max()) + radius_cells)
    c0 = max(0, int(cells[:, 1].min()) - radius_cells)
    c1 = min(w - 1, int(cells[:, 1].max()) + radius_cells)
    rows = np.arange(-(-r0 // step_cells) * step_cells, r1 + 1, step_cells)
    cols = np.arange(-(-c0 // step_cells) * step_cells, c1 + 1, step_cells)
    first = np.asarray([cpoint_rc], dtype=np.int64)
    if rows.size == 0 or cols.size == 0:
        return first
    gr, gc = np.meshgrid(rows, cols, indexing="ij")
    gr, gc = gr.ravel(), gc.ravel()
    ok = passable[gr, gc]
    gr, gc = gr[ok], gc[ok]
    if gr.size == 0:
        return first
    d2 = ((gr[:, None] - cells[None, :, 0]) ** 2
          + (gc[:, None] - cells[None, :, 1]) ** 2).min(axis=1)
    near = d2 <= radius_cells * radius_cells
    return np.concatenate([first, np.stack([gr[near], gc[near]], axis=1)]).astype(np.int64)


def pick_viewpoint(gain_m2: npt.NDArray[np.float64], dist_m: npt.NDArray[np.float64],
                   tolerance: float) -> int | None:
    """Index of the viewpoint among candidates: highest gain among the reachable ones,
    then the closest within ``1 - tolerance`` of it; None when none is reachable.

    Examples
    --------
    >>> pick_viewpoint(np.array([10.0, 9.5, 4.0]), np.array([6.0, 2.0, 1.0]), 0.1)
    1
    """
    reach = np.isfinite(dist_m)
    if not reach.any():
        return None
    g = np.where(reach, gain_m2, -np.inf)
    best = float(g.max())
    good = reach & (gain_m2 >= best * (1.0 - tolerance))
    return int(np.argmin(np.where(good, dist_m, np.inf)))


__all__ = ["COARSEN", "candidate_cells", "coarse_codes", "pick_viewpoint", "view_gain"]
