"""The walls of the 2D (lidar) map, as the object pipeline uses them: depth points on
walls are dropped before clustering, and a post's overhang must lie over free cells."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import FREE_THRESHOLD, GridMap
from explore_seg.core.objects.params import ObjectParams

#: Occupancy from which a map cell counts as occupied for the wall mask.
WALL_OCCUPIED_THRESHOLD = 65


@dataclass(frozen=True)
class WallMask:
    """Wall cells of the 2D (lidar) map, grown by ``wall_margin_m``: see :func:`wall_mask`.

    ``mask`` has ``grid``'s shape (H, W), bool.
    """

    grid: GridMap
    mask: npt.NDArray[np.bool_]

    def free(self, points_xy: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
        """True for the points (map frame, shape (N, 2)) over cells the 2D map knows as
        free (the lidar saw through them); points outside the map are not."""
        return self._lookup(points_xy, lambda r, c: (self.grid.data[r, c] >= 0)
                            & (self.grid.data[r, c] < FREE_THRESHOLD))

    def on(self, points_xy: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
        """True for the points (map frame, shape (N, 2)) lying on a wall cell; points
        outside the map are not. Returns shape (N,) bool."""
        return self._lookup(points_xy, lambda r, c: self.mask[r, c])

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
        out[ok] = cell_test(r[ok], c[ok])
        return out


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
    occ = grid.data >= occupied_threshold
    if params.wall_min_length_m > 0 and occ.any():
        _, comp, stats, _ = cv2.connectedComponentsWithStats(occ.astype(np.uint8),
                                                             connectivity=8)
        side_cells = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
        is_wall = side_cells * grid.resolution_m >= params.wall_min_length_m
        is_wall[0] = False                       # label 0: the unoccupied background
        occ = is_wall[comp]
    r = int(round(params.wall_margin_m / grid.resolution_m))
    if r > 0 and occ.any():
        occ = cv2.dilate(occ.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)) > 0
    return WallMask(grid, occ)
