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

:class:`GainCache` keeps the gains between map versions: a gain depends only on the coarse
map within ``range_m`` of its coarse cell, so after a map update only the gains of coarse
cells with a changed coarse cell within that window are cast again (exactly the values a
full cast gives; the map may grow, its origin moving by whole coarse cells).

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
    return _coarse_block(grid.data, occupied_threshold, factor)


def _coarse_block(d: npt.NDArray[np.int8], occupied_threshold: int, factor: int = COARSEN
                  ) -> npt.NDArray[np.uint8]:
    """:func:`coarse_codes` of a block of map cells (a partial last block counts its
    missing cells as unknown)."""
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


def _window_any(mask: npt.NDArray[np.bool_], radius: int) -> npt.NDArray[np.bool_]:
    """True where ``mask`` has a True cell within Chebyshev distance ``radius``
    (integral image: O(H W) whatever the radius)."""
    h, w = mask.shape
    s = np.zeros((h + 1, w + 1), dtype=np.int64)
    s[1:, 1:] = np.cumsum(np.cumsum(mask, axis=0, dtype=np.int64), axis=1)
    r0 = np.clip(np.arange(h) - radius, 0, h)
    r1 = np.clip(np.arange(h) + radius + 1, 0, h)
    c0 = np.clip(np.arange(w) - radius, 0, w)
    c1 = np.clip(np.arange(w) + radius + 1, 0, w)
    box = (s[r1][:, c1] - s[r0][:, c1] - s[r1][:, c0] + s[r0][:, c0])
    return box > 0


class GainCache:
    """:func:`view_gain` kept across map versions (module docstring).

    Parameters
    ----------
    range_m, rays, occupied_threshold : see :func:`view_gain`

    Attributes
    ----------
    cast : int
        Coarse cells cast in the last :meth:`gains` call (the rest came from the cache).

    Examples
    --------
    >>> data = np.full((40, 100), -1, dtype=np.int8)
    >>> data[:, :50] = 0
    >>> cache = GainCache(1.0, 16)
    >>> cells = np.array([[20, 5], [20, 48]])
    >>> g1 = cache.gains(GridMap(data, 0.05, (0.0, 0.0)), cells)
    >>> data2 = data.copy(); data2[:, 50:60] = 0          # the map grows on the right
    >>> g2 = cache.gains(GridMap(data2, 0.05, (0.0, 0.0)), cells)
    >>> bool(g2[0] == g1[0] and g2[1] < g1[1]), cache.cast   # only the near one is cast
    (True, 1)
    """

    def __init__(self, range_m: float = 5.0, rays: int = 24, occupied_threshold: int = 65
                 ) -> None:
        self._range, self._rays, self._thr = float(range_m), int(rays), int(occupied_threshold)
        self.reset()

    def reset(self) -> None:
        """Forget every kept gain."""
        self._grid: GridMap | None = None
        self._codes: npt.NDArray[np.uint8] | None = None
        self._gain: npt.NDArray[np.float64] | None = None       # per coarse cell, NaN: none
        self.cast = 0

    def _steps(self, resolution_m: float) -> int:
        return max(1, int(math.ceil(self._range / (resolution_m * COARSEN))))

    def _update(self, grid: GridMap) -> None:
        if grid is self._grid:
            return
        old, old_codes, old_gain = self._grid, self._codes, self._gain
        if (old is not None and old_codes is not None and old_gain is not None
                and old.shape == grid.shape and old.origin_xy_m == grid.origin_xy_m
                and _coarse_shift(old, grid) == (0, 0)):
            self._update_in_place(grid, old, old_codes, old_gain)
            return
        codes = coarse_codes(grid, self._thr)
        gain = np.full(codes.shape, np.nan)
        shift = None if old is None else _coarse_shift(old, grid)
        if shift is not None and old_codes is not None and old_gain is not None:
            dr, dc = shift
            oh, ow = old_codes.shape
            h, w = codes.shape
            if 0 <= dr and 0 <= dc and dr + oh <= h and dc + ow <= w:
                # Old map in the new frame; outside it the old cast saw blocking cells.
                prev = np.full(codes.shape, _BLOCKED, dtype=np.uint8)
                prev[dr:dr + oh, dc:dc + ow] = old_codes
                gain[dr:dr + oh, dc:dc + ow] = old_gain
                stale = _window_any(prev != codes, self._steps(grid.resolution_m))
                gain[stale] = np.nan
        self._grid, self._codes, self._gain = grid, codes, gain

    def _update_in_place(self, grid: GridMap, old: GridMap, codes: npt.NDArray[np.uint8],
                         gain: npt.NDArray[np.float64]) -> None:
        """Same geometry: coarse codes and gains change only around the changed cells
        (their bounding box, plus the sensor range for the gains)."""
        diff = grid.data != old.data
        rows, cols = np.flatnonzero(diff.any(axis=1)), np.flatnonzero(diff.any(axis=0))
        self._grid = grid
        if rows.size == 0:
            return
        f = COARSEN
        r0, r1 = int(rows[0]) // f, int(rows[-1]) // f + 1          # coarse, exclusive end
        c0, c1 = int(cols[0]) // f, int(cols[-1]) // f + 1
        block = _coarse_block(grid.data[r0 * f:r1 * f, c0 * f:c1 * f], self._thr, f)
        changed = block != codes[r0:r1, c0:c1]
        codes[r0:r1, c0:c1] = block                 # the cache's own arrays
        if not changed.any():
            return
        rad = self._steps(grid.resolution_m)
        h, w = codes.shape
        a0, a1 = max(0, r0 - rad), min(h, r1 + rad)
        b0, b1 = max(0, c0 - rad), min(w, c1 + rad)
        mask = np.zeros((a1 - a0, b1 - b0), dtype=bool)
        mask[r0 - a0:r1 - a0, c0 - b0:c1 - b0] = changed
        gain[a0:a1, b0:b1][_window_any(mask, rad)] = np.nan

    def gains(self, grid: GridMap, cells_rc: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """:func:`view_gain` of ``cells_rc`` on ``grid`` (cast only where the cache has no
        valid value).

        Returns
        -------
        ndarray of float64, shape (C,)
        """
        rc = np.asarray(cells_rc, dtype=np.int64).reshape(-1, 2)
        self._update(grid)
        assert self._codes is not None and self._gain is not None
        self.cast = 0
        if rc.shape[0] == 0:
            return np.zeros(0)
        h, w = self._codes.shape
        cr = np.clip(rc[:, 0] // COARSEN, 0, h - 1)
        cc = np.clip(rc[:, 1] // COARSEN, 0, w - 1)
        inside = (rc[:, 0] >= 0) & (rc[:, 1] >= 0) & (rc[:, 0] < grid.shape[0]) & (
            rc[:, 1] < grid.shape[1])
        if not inside.all():
            # Off-map cells are not cached (the caller's candidates are on the map).
            return view_gain(grid, rc, self._range, self._rays, self._thr, self._codes)
        flat = cr * w + cc
        todo = np.unique(flat[np.isnan(self._gain.ravel()[flat])])
        if todo.size:
            ur, uc = np.divmod(todo, w)
            self._gain.ravel()[todo] = view_gain(
                grid, np.stack([ur * COARSEN, uc * COARSEN], axis=1), self._range,
                self._rays, self._thr, self._codes)
            self.cast = int(todo.size)
        return self._gain.ravel()[flat].copy()


def _coarse_shift(old: GridMap, new: GridMap) -> tuple[int, int] | None:
    """Offset (rows, cols) of ``old``'s coarse cell (0, 0) in ``new``'s coarse grid; None
    when the grids do not share the coarse lattice (resolution, rotation, frame, an origin
    moved by a fraction of a coarse cell)."""
    if (old.resolution_m != new.resolution_m or old.origin_yaw_rad != new.origin_yaw_rad
            or old.frame_id != new.frame_id):
        return None
    step = new.resolution_m * COARSEN
    fr = (old.origin_xy_m[1] - new.origin_xy_m[1]) / step
    fc = (old.origin_xy_m[0] - new.origin_xy_m[0]) / step
    dr, dc = round(fr), round(fc)
    if abs(fr - dr) > 1e-6 or abs(fc - dc) > 1e-6:
        return None
    return int(dr), int(dc)


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


__all__ = ["COARSEN", "GainCache", "candidate_cells", "coarse_codes", "pick_viewpoint",
           "view_gain"]
