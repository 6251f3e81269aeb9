"""The navigation stand-in's costmap, rebuilt only where the map changed.

Nav2's layered costmap updates the bounds its layers touched since the last cycle; this
does the same for :func:`~sim_bridge.navigation.planner.cost_grid`. A cell's cost depends
only on the obstacle and unknown cells within :func:`influence_cells` of it (the lethal
disk, the inflation band, the soft margin, the edge kernel), so after a map update the
cells within that reach of a changed cell are recomputed from a window that holds their
whole neighbourhood, and every other cell keeps its cost. The distance transform under
the inflation band is exact (OpenCV's ``DIST_MASK_PRECISE`` gives the float32 square root
of the exact squared distance, the same in a window as on the whole map), so the result
equals a whole-map ``cost_grid`` bit for bit (``test_nav_costmap.py`` checks it on map
sequences of lock-step runs); on the 60 x 40 m office floor, where the robot changes a
few square metres of a 2,500 m^2 map between plans, that is most of the costmap's time.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from sim_bridge.navigation.params import NavParams
from sim_bridge.navigation.planner import cost_grid

#: Side of the tiles in which changed cells are collected into windows (cells).
TILE_CELLS = 16

#: Above this share of the map's cells in windows, the whole map is rebuilt instead.
WHOLE_MAP_SHARE = 0.5


def influence_cells(params: NavParams, resolution_m: float) -> int:
    """Cells within which an obstacle or unknown cell changes another cell's cost (the
    largest of the inflation radius, the soft margin's and the edge kernel's reach, with
    two cells to spare)."""
    reach_m = max(params.inflation_radius_m,
                  params.lethal_radius_m + params.inflation_soft_margin_m,
                  params.lethal_radius_m + resolution_m)
    return int(math.ceil(reach_m / resolution_m)) + 2


class CostGridCache:
    """:func:`~sim_bridge.navigation.planner.cost_grid` of the latest masks, updated in
    windows around the cells that changed since the previous call (see the module doc)."""

    def __init__(self) -> None:
        self._key: tuple | None = None
        self._blocked: npt.NDArray[np.bool_] | None = None
        self._unknown: npt.NDArray[np.bool_] | None = None
        self._cost: npt.NDArray[np.float64] | None = None
        #: Cells recomputed by the last call (for tests and profiles).
        self.last_recomputed_cells = 0

    def cost(self, blocked: npt.NDArray[np.bool_], unknown: npt.NDArray[np.bool_] | None,
             resolution_m: float, params: NavParams, geometry: tuple = ()
             ) -> npt.NDArray[np.float64]:
        """The costmap of these masks, as ``cost_grid(blocked, unknown, resolution_m,
        params)`` would give it; a new array the caller may change.

        ``geometry`` is anything else that identifies the map's frame (its origin): a
        different value, shape, resolution or ``params`` rebuilds the whole map. The masks
        are kept (not copied) for the next call's comparison: do not change them afterwards.
        """
        key = (blocked.shape, float(resolution_m), unknown is None, params, geometry)
        reach = influence_cells(params, resolution_m)
        windows = None
        if key == self._key:
            changed = blocked != self._blocked
            if unknown is not None:
                changed |= unknown != self._unknown
            windows = _windows(changed, reach)
        if windows is None:
            self._cost = cost_grid(blocked, unknown, resolution_m, params)
            self.last_recomputed_cells = blocked.size
        else:
            self.last_recomputed_cells = 0
            h, w = blocked.shape
            for r0, r1, c0, c1 in windows:
                a0, a1 = max(0, r0 - reach), min(h, r1 + reach)
                b0, b1 = max(0, c0 - reach), min(w, c1 + reach)
                part = cost_grid(blocked[a0:a1, b0:b1],
                                 None if unknown is None else unknown[a0:a1, b0:b1],
                                 resolution_m, params)
                assert self._cost is not None
                self._cost[r0:r1, c0:c1] = part[r0 - a0:r1 - a0, c0 - b0:c1 - b0]
                self.last_recomputed_cells += (r1 - r0) * (c1 - c0)
        self._key, self._blocked, self._unknown = key, blocked, unknown
        assert self._cost is not None
        return self._cost.copy()


def _windows(changed: npt.NDArray[np.bool_], reach: int
             ) -> list[tuple[int, int, int, int]] | None:
    """Boxes (r0, r1, c0, c1) that hold every cell within ``reach`` of a changed cell:
    changed tiles grown by the reach, one box per connected group of them; None when
    they cover more than :data:`WHOLE_MAP_SHARE` of the map (rebuild it whole)."""
    h, w = changed.shape
    t = TILE_CELLS
    th, tw = -(-h // t), -(-w // t)
    pad = np.zeros((th * t, tw * t), dtype=bool)
    pad[:h, :w] = changed
    tiles = pad.reshape(th, t, tw, t).any(axis=(1, 3))
    if not tiles.any():
        return []
    grow = -(-reach // t)
    tiles = ndimage.binary_dilation(tiles, np.ones((2 * grow + 1, 2 * grow + 1), bool))
    labels, _ = ndimage.label(tiles, np.ones((3, 3), bool))
    boxes = []
    for sl in ndimage.find_objects(labels):
        boxes.append((sl[0].start * t, min(h, sl[0].stop * t),
                      sl[1].start * t, min(w, sl[1].stop * t)))
    if sum((r1 - r0) * (c1 - c0) for r0, r1, c0, c1 in boxes) > WHOLE_MAP_SHARE * h * w:
        return None
    return boxes
