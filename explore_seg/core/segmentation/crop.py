"""The crop an update works on: the known cells' bounding box grown by a margin that no
cleaning or labelling step reaches across, snapped outward to :data:`CROP_CHUNK_CELLS`."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.segmentation.cleaning import clean_influence_cells, length_to_cells
from explore_seg.core.segmentation.params import SegmentationParams

#: The crop's edges are snapped outward to multiples of this many cells, so that it
#: moves only now and then while the known area grows (a move recleans the new strip).
CROP_CHUNK_CELLS = 64


def crop_margin_cells(params: SegmentationParams, res: float) -> int:
    """Unknown cells kept around the known ones: beyond the reach of the cleaning (free
    space grows by ``free_close_m``; clutter holes, specks) and of the gap filling and
    work-area boxes of an update, so the crop's edge changes no label."""
    p = params
    fill = 2 * (length_to_cells(p.obstacle_inflation_m, res)
                + length_to_cells(p.free_close_m, res)) + 4
    return clean_influence_cells(p, res) + fill + p.inc_touch_cells + 4


def known_crop(data: npt.NDArray[np.int8], margin: int, chunk: int = CROP_CHUNK_CELLS
               ) -> tuple[slice, slice] | None:
    """(rows, cols) of the known (not -1) cells' bounding box grown by ``margin`` and
    snapped outward to multiples of ``chunk`` (clipped to the array); None when no cell
    is known.

    >>> d = np.full((300, 200), -1, np.int8); d[100:110, 150:160] = 0
    >>> known_crop(d, 5)
    (slice(64, 128, None), slice(128, 192, None))
    """
    # max >= 0 <=> a known cell (values -1..100): no temporary of the grid's size
    rows = np.flatnonzero(data.max(axis=1) >= 0)
    if rows.size == 0:
        return None
    cols = np.flatnonzero(data[rows[0]:rows[-1] + 1].max(axis=0) >= 0)
    h, w = data.shape

    def span(lo: int, hi: int, n: int) -> slice:
        return slice(max(0, (lo - margin) // chunk * chunk),
                     min(n, -(-(hi + margin) // chunk) * chunk))
    return span(int(rows[0]), int(rows[-1]) + 1, h), span(int(cols[0]), int(cols[-1]) + 1, w)


def crop_grid(grid: GridMap, box: tuple[slice, slice]) -> GridMap:
    """The part ``box`` of ``grid`` as a grid of its own (origin at its first cell's
    corner; the data is a view)."""
    r0, c0 = box[0].start, box[1].start
    x, y = grid.cells_to_world(np.array([r0 - 0.5]), np.array([c0 - 0.5]))
    return GridMap(grid.data[box], grid.resolution_m, (float(x[0]), float(y[0])),
                   grid.origin_yaw_rad, grid.frame_id, grid.stamp_ns)
