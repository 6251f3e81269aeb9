"""The walls of the 2D (lidar) map, as the object pipeline uses them: depth points on
walls are dropped before clustering, and a post's overhang must lie over free cells."""

from __future__ import annotations

import math
from typing import Callable

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import FREE_THRESHOLD, GridMap
from explore_seg.core.objects.params import ObjectParams

#: Occupancy from which a map cell counts as occupied for the wall mask.
WALL_OCCUPIED_THRESHOLD = 65


class WallMask:
    """Wall cells of the 2D (lidar) map, grown by ``wall_margin_m``: see :func:`wall_mask`.

    The walls are computed on demand: :attr:`mask` (shape (H, W), bool) for the whole
    map, :meth:`on` only for a window around the points asked about (and kept for later
    questions inside it), with the same values as the whole map's (see
    :meth:`_window_walls`).

    Parameters
    ----------
    grid : GridMap
    mask : ndarray of bool, shape (H, W), optional
        The whole map's walls when already known.
    params : ObjectParams, optional
        Needed when ``mask`` is None.
    occupied_threshold : int
    """

    def __init__(self, grid: GridMap, mask: npt.NDArray[np.bool_] | None = None,
                 params: ObjectParams | None = None,
                 occupied_threshold: int = WALL_OCCUPIED_THRESHOLD) -> None:
        if mask is None and params is None:
            raise ValueError("WallMask needs the mask or the parameters to compute it")
        self.grid = grid
        self._mask = mask
        self._params = params
        self._threshold = occupied_threshold
        # Computed windows (r0, r1, c0, c1, walls there); shared by with_grid copies.
        self._windows: list[tuple[int, int, int, int, npt.NDArray[np.bool_]]] = []

    @property
    def mask(self) -> npt.NDArray[np.bool_]:
        """The whole map's wall cells, shape (H, W) bool (computed on first use)."""
        if self._mask is None:
            h, w = self.grid.shape
            self._mask = self._window_walls(0, h, 0, w)
        return self._mask

    def with_grid(self, grid: GridMap) -> "WallMask":
        """The same walls on ``grid``, a map with the same geometry and occupied cells
        (the walls depend on nothing else); what was computed is shared."""
        out = WallMask(grid, self._mask, self._params, self._threshold)
        out._windows = self._windows
        return out

    def free(self, points_xy: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
        """True for the points (map frame, shape (N, 2)) over cells the 2D map knows as
        free (the lidar saw through them); points outside the map are not."""
        return self._lookup(points_xy, lambda r, c: (self.grid.data[r, c] >= 0)
                            & (self.grid.data[r, c] < FREE_THRESHOLD))

    def on(self, points_xy: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
        """True for the points (map frame, shape (N, 2)) lying on a wall cell; points
        outside the map are not. Returns shape (N,) bool."""
        return self._lookup(points_xy, self._walls_at)

    def _walls_at(self, rows: npt.NDArray[np.intp], cols: npt.NDArray[np.intp]
                  ) -> npt.NDArray[np.bool_]:
        if self._mask is not None:
            return self._mask[rows, cols]
        q = (int(rows.min()), int(rows.max()) + 1, int(cols.min()), int(cols.max()) + 1)
        for r0, r1, c0, c1, walls in self._windows:
            if r0 <= q[0] and q[1] <= r1 and c0 <= q[2] and q[3] <= c1:
                return walls[rows - r0, cols - c0]
        # A little more than asked, so that the next frames' questions fall inside.
        h, w = self.grid.shape
        pad = _WINDOW_PAD_CELLS
        r0, r1 = max(0, q[0] - pad), min(h, q[1] + pad)
        c0, c1 = max(0, q[2] - pad), min(w, q[3] + pad)
        walls = self._window_walls(r0, r1, c0, c1)
        self._windows.append((r0, r1, c0, c1, walls))
        return walls[rows - r0, cols - c0]

    def _window_walls(self, r0: int, r1: int, c0: int, c1: int) -> npt.NDArray[np.bool_]:
        """:func:`wall_mask`'s cells in rows r0:r1, cols c0:c1, computed on a larger box.

        A cell's value depends on the occupied cells within the dilation radius ``r``
        and on whether their component is a wall. The box reaches ``r + E`` cells
        further (``E = ceil(wall_min_length_m / resolution) + 1``): a component lying
        inside it is seen whole (its extent exact); one crossing the box's edge inside
        the map and reaching within ``r`` of the window spans more than ``E`` cells of
        the box already, so it is a wall here as in the whole map. Dilation near the
        box's edge reads only cells farther than ``r`` from the window.
        """
        p = self._params
        assert p is not None
        grid = self.grid
        h, w = grid.shape
        res = grid.resolution_m
        r = int(round(p.wall_margin_m / res))
        ext = (int(math.ceil(p.wall_min_length_m / res)) + 1) if p.wall_min_length_m > 0 else 0
        R0, R1 = max(0, r0 - r - ext), min(h, r1 + r + ext)
        C0, C1 = max(0, c0 - r - ext), min(w, c1 + r + ext)
        occ = grid.data[R0:R1, C0:C1] >= self._threshold
        if p.wall_min_length_m > 0 and occ.any():
            _, comp, stats, _ = cv2.connectedComponentsWithStats(occ.astype(np.uint8),
                                                                 connectivity=8)
            side_cells = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
            is_wall = side_cells * res >= p.wall_min_length_m
            is_wall[0] = False                   # label 0: the unoccupied background
            occ = is_wall[comp]
        if r > 0 and occ.any():
            occ = cv2.dilate(occ.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)) > 0
        return np.ascontiguousarray(occ[r0 - R0:r1 - R0, c0 - C0:c1 - C0])

    def _lookup(self, points_xy: npt.NDArray[np.floating],
                cell_test: Callable[[npt.NDArray[np.intp], npt.NDArray[np.intp]],
                                    npt.NDArray[np.bool_]]) -> npt.NDArray[np.bool_]:
        """``cell_test(rows, cols)`` at the cells of the points inside the map, False
        for the others; shape (N,) bool."""
        pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
        out = np.zeros(len(pts), dtype=bool)
        if len(pts) == 0:
            return out
        r, c = self.grid.world_to_cells(pts[:, 0], pts[:, 1])
        ok = (r >= 0) & (r < self.grid.height) & (c >= 0) & (c < self.grid.width)
        if ok.any():
            out[ok] = cell_test(r[ok], c[ok])
        return out


#: Cells added on every side of the points' box when :meth:`WallMask.on` computes a
#: window (later frames from about the same place ask inside it).
_WINDOW_PAD_CELLS = 40


def wall_mask(grid: GridMap, params: ObjectParams,
              occupied_threshold: int = WALL_OCCUPIED_THRESHOLD) -> WallMask:
    """The walls of a 2D map: its long occupied structures, grown by ``wall_margin_m``.

    Occupied cells (``>= occupied_threshold``) form 8-connected components; those whose
    bounding box is at least ``params.wall_min_length_m`` long on one side are walls (and
    door jambs, large furniture seen as a long obstacle), smaller ones are the legs or
    bases of furniture the lidar cuts and are left out. The walls are then grown by
    ``params.wall_margin_m`` (a depth point on a wall face lies on or next to its cell).
    :func:`process_frame` drops depth points on them before clustering.

    Parameters
    ----------
    grid : GridMap
        The 2D (lidar / SLAM) map.
    params : ObjectParams
    occupied_threshold : int
        Cells at or above it are occupied.

    Returns
    -------
    WallMask
    """
    return WallMask(grid, None, params, occupied_threshold)
