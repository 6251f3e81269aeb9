"""Cleaning of an occupancy grid into free-space masks (DuDe spec shared/docs/dude.md §4).

Raw free cells, and the cleaned free space F: free cells grown into unknown space,
minus the obstacles (scan specks dropped) grown by the inflation radius. Small
free-standing objects (``small_object_max_m``: chair legs, castors, chairs) are not
inflated and count as free: rows and rings of chairs, closed by the inflation, would
otherwise wall off strips of a room.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.segmentation.furniture import (FillCache, fill_furniture,
                                                     furniture_cells,
                                                     furniture_cells_update,
                                                     furniture_reach_cells, open_disk)
from explore_seg.core.segmentation.labels import bbox, lookup_mask
from explore_seg.core.segmentation.params import SegmentationParams


#: Share of an occupied component's cells that must be thick for it to be a solid
#: furniture block (the rest: the opening's rounded-off corners, a few specks beside it).
_BLOCK_SOLID_SHARE = 0.7


def occupied_components(occ_u8: npt.NDArray[np.uint8]
                        ) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.int32],
                                   npt.NDArray[np.bool_]]:
    """8-connected components of the occupied cells: labels, OpenCV's stats, and a mask
    of removed components (none removed here)."""
    _n, lab, stats, _ = cv2.connectedComponentsWithStats(occ_u8, connectivity=8)
    return lab, stats, np.zeros(len(stats), dtype=bool)


def length_to_cells(length_m: float, res: float) -> int:
    return int(round(length_m / res))



def _square(r: int) -> npt.NDArray[np.uint8]:
    return np.ones((2 * r + 1, 2 * r + 1), dtype=np.uint8)


def clean_free_space(grid: GridMap, params: SegmentationParams
                     ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Raw free cells and the cleaned free-space mask F of a grid (DuDe spec
    shared/docs/dude.md §4).

    Parameters
    ----------
    grid : GridMap
    params : SegmentationParams

    Returns
    -------
    free_raw : ndarray of bool, shape (H, W)
        ``0 <= occupancy < free_max_occupancy``.
    free_clean : ndarray of bool, shape (H, W)
        Free cells grown by ``free_close_m`` into non-obstacle cells, minus the obstacles
        (occupancy > ``occupied_min_occupancy``, specks and small free-standing objects
        dropped) grown by ``obstacle_inflation_m``; the small objects' own cells count as
        free where the grown free space reaches them.
    """
    return clean_masks(grid.data, params, grid.resolution_m)


def clean_masks(data: npt.NDArray[np.int8], params: SegmentationParams, res: float,
                roi: tuple[slice, slice] | None = None
                ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """:func:`clean_free_space` of an occupancy array; ``roi`` (optional): the part of
    ``free_clean`` the caller uses (work outside it that cannot reach it is skipped,
    so free_clean is exact only there)."""
    st = clean_state(data, params, res, roi)
    return st.free_raw, st.free_clean


class CleanState(NamedTuple):
    """The masks of :func:`clean_state`, all of the grid's shape."""

    free_raw: npt.NDArray[np.bool_]
    free_clean: npt.NDArray[np.bool_]
    #: obstacles as inflated (specks and small objects removed), uint8
    occ: npt.NDArray[np.uint8]
    #: their furniture bulges (None when the furniture rule is off)
    bulge: npt.NDArray[np.bool_] | None
    #: the cells whose labels are published: the free cells, and the occupied cells the
    #: clutter fill and the small objects make room (free-standing furniture); the
    #: furniture fill's cells are not, as wall and furniture are one obstacle there
    shown: npt.NDArray[np.bool_]


def clean_state(data: npt.NDArray[np.int8], params: SegmentationParams, res: float,
                roi: tuple[slice, slice] | None = None,
                prev: tuple[npt.NDArray[np.uint8], npt.NDArray[np.bool_]] | None = None,
                fill_cache: FillCache | None = None, origin: tuple[int, int] = (0, 0)
                ) -> CleanState:
    """:func:`clean_masks` plus the published cells and what an incremental update keeps
    to redo less: the obstacles as inflated and their furniture bulges
    (:class:`CleanState`). ``prev``: those two of an
    earlier map in this array's geometry (cells it did not cover: obstacle value 2), so
    that the bulges' distance transforms run only around changed obstacles;
    ``fill_cache`` and ``origin``: the bulges' fills of that map (:class:`FillCache`) and
    this array's cell (0, 0) in the cache's reference cells."""
    free_raw = (data >= 0) & (data < params.free_max_occupancy)
    if data.size == 0:
        return CleanState(free_raw, free_raw.copy(), np.zeros(data.shape, np.uint8), None,
                          free_raw.copy())
    occ = data > params.occupied_min_occupancy
    occ_u8 = occ.astype(np.uint8)
    occ_cc = None
    speck_px = math.floor(params.obstacle_speck_area_m2 / (res * res) + 1e-6)
    if speck_px >= 1 and occ.any():
        n, lab, stats, _ = cv2.connectedComponentsWithStats(occ_u8, connectivity=8)
        small = stats[:, cv2.CC_STAT_AREA] <= speck_px
        small[0] = False
        if small.any():
            keep = (~small).astype(np.uint8)
            keep[0] = 0
            occ_u8 = np.take(keep, lab)      # the occupied cells less the specks
        # the components left in occ_u8 are these minus the specks
        occ_cc = (lab, stats, small)
    objects = None
    if params.small_object_max_m > 0 and occ.any():
        objects = _small_objects(occ_u8, occ_cc, params, res)
        if objects is not None:
            occ_u8 = np.where(objects, np.uint8(0), occ_u8)
    r_inf = length_to_cells(params.obstacle_inflation_m, res)
    obst = cv2.dilate(occ_u8, _square(r_inf)) if r_inf > 0 else occ_u8
    r_close = length_to_cells(params.free_close_m, res)
    grown = cv2.dilate(free_raw.astype(np.uint8), _square(r_close)) if r_close > 0 \
        else free_raw.astype(np.uint8)
    free_clean = (grown > 0) & (obst == 0)
    if objects is not None:
        # small free-standing objects are free space for the decomposition
        free_clean |= objects & (grown > 0) & (obst == 0)
    free_clean = fill_clutter_holes(free_clean, occ_u8, params, res, occ_cc)
    bulge = None
    if params.furniture_min_thickness_m > 0:
        bulge = (furniture_cells(occ_u8, params, res) if prev is None else
                 furniture_cells_update(occ_u8, params, res, prev[0], prev[1]))
    shown = free_raw | (free_clean & occ)
    filled = fill_furniture(free_clean, occ_u8, params, res, roi, bulge, fill_cache, origin)
    return CleanState(free_raw, filled, occ_u8, bulge, shown)


def _small_objects(occ_u8: npt.NDArray[np.uint8],
                   occ_cc: tuple[npt.NDArray[np.int32], npt.NDArray[np.int32],
                                 npt.NDArray[np.bool_]] | None,
                   params: SegmentationParams, res: float) -> npt.NDArray[np.bool_] | None:
    """Cells of the small free-standing objects of ``occ_u8`` (``small_object_max_m``),
    or None when there is none. An object whose inflation would touch a larger
    obstacle's is part of a row with it (a cabinet row, a broken wall) and is none."""
    lab, stats, gone = occ_cc if occ_cc is not None else occupied_components(occ_u8)
    diag = np.hypot(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
    obj = (diag <= params.small_object_max_m / res) & ~gone
    obj[0] = False
    if not obj.any():
        return None
    # the objects' cells, looked up only in the bounding box of their components
    r_near = 2 * length_to_cells(params.obstacle_inflation_m, res) + 1
    k = np.flatnonzero(obj)
    x, y = stats[k, cv2.CC_STAT_LEFT], stats[k, cv2.CC_STAT_TOP]
    x1, y1 = x + stats[k, cv2.CC_STAT_WIDTH], y + stats[k, cv2.CC_STAT_HEIGHT]
    h, w = occ_u8.shape
    inside = (slice(int(y.min()), int(y1.max())), slice(int(x.min()), int(x1.max())))
    objects = np.zeros(occ_u8.shape, dtype=bool)
    objects[inside] = lookup_mask(obj, lab[inside])
    box = (slice(max(0, inside[0].start - r_near), min(h, inside[0].stop + r_near)),
           slice(max(0, inside[1].start - r_near), min(w, inside[1].stop + r_near)))
    big = (occ_u8[box] > 0) & ~objects[box]
    near = cv2.dilate(big.view(np.uint8), _square(r_near)) > 0
    touch = near & objects[box]
    if touch.any():
        obj[lab[box][touch]] = False
        objects[box] &= obj[lab[box]]
    return objects if obj.any() else None


def fill_clutter_holes(free_clean: npt.NDArray[np.bool_], occ: npt.NDArray[np.uint8],
                       params: SegmentationParams, res: float,
                       occ_cc: tuple[npt.NDArray[np.int32], npt.NDArray[np.int32],
                                     npt.NDArray[np.bool_]] | None = None
                       ) -> npt.NDArray[np.bool_]:
    """``free_clean`` with its clutter holes filled.

    A hole of the cleaned free space (a component of its complement that does not reach
    the array border) is clutter when it is at most ``clutter_max_extent_m`` wide and
    high, at most ``clutter_max_area_m2`` large and holds no occupied component (8-
    connected, ``occ``) whose bounding-box diagonal exceeds ``clutter_max_object_m``:
    free-standing furniture seen as leg specks, castors, pedestals and panels, with the
    unknown cells around it. A wall piece between two doors is a hole too, but a long
    one. Clutter holes count as free space for the decomposition, so furniture does not
    cut rooms.

    ``occ_cc`` (optional): the 8-connected components of an occupied mask that ``occ``
    is with some whole components removed, as (labels, stats, removed).
    """
    ext = params.clutter_max_extent_m / res
    area = params.clutter_max_area_m2 / (res * res)
    if ext <= 0 or area <= 0 or free_clean.size == 0:
        return free_clean
    n, lab, stats, _ = cv2.connectedComponentsWithStats((~free_clean).astype(np.uint8),
                                                        connectivity=8)
    h, w = free_clean.shape
    x, y = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP]
    bw, bh = stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT]
    small = ((x > 0) & (y > 0) & (x + bw < w) & (y + bh < h)
             & (np.maximum(bw, bh) <= ext) & (stats[:, cv2.CC_STAT_AREA] <= area))
    small[0] = False
    if not small.any():
        return free_clean
    olab, ost, gone = occ_cc if occ_cc is not None else occupied_components(occ)
    diag = np.hypot(ost[:, cv2.CC_STAT_WIDTH], ost[:, cv2.CC_STAT_HEIGHT])
    big = (diag > params.clutter_max_object_m / res) & ~gone
    big[0] = False
    if big.any() and params.furniture_min_thickness_m > 0:
        big &= ~_thick_blocks(olab, ost, big, params, res)
    if big.any():
        small[lab[lookup_mask(big, olab)]] = False
    return free_clean | lookup_mask(small, lab)


def _thick_blocks(olab: npt.NDArray[np.int32], ost: npt.NDArray[np.int32],
                  big: npt.NDArray[np.bool_], params: SegmentationParams, res: float
                  ) -> npt.NDArray[np.bool_]:
    """Which of the ``big`` occupied components are solid furniture blocks: at most
    ``furniture_max_extent_m`` wide and high, and thick nearly all over (a disk of
    ``furniture_min_thickness_m`` fits round at least ``_BLOCK_SOLID_SHARE`` of their
    cells), unlike a wall, which is thin."""
    out = np.zeros(len(ost), dtype=bool)
    ext = params.furniture_max_extent_m / res
    d_min = params.furniture_min_thickness_m / res
    x, y = ost[:, cv2.CC_STAT_LEFT], ost[:, cv2.CC_STAT_TOP]
    bw, bh = ost[:, cv2.CC_STAT_WIDTH], ost[:, cv2.CC_STAT_HEIGHT]
    for k in np.flatnonzero(big & (np.maximum(bw, bh) <= ext) & (np.minimum(bw, bh) >= d_min)):
        m = olab[y[k]:y[k] + bh[k], x[k]:x[k] + bw[k]] == k
        pad = int(math.ceil(d_min)) + 2
        opened = open_disk(np.pad(m, pad), d_min)[pad:-pad, pad:-pad]
        out[k] = (opened & m).sum() >= _BLOCK_SOLID_SHARE * m.sum()
    return out


def clean_influence_cells(params: SegmentationParams, res: float) -> int:
    """How far (cells) a changed grid cell can change the cleaned mask."""
    speck = int(math.ceil(params.obstacle_speck_area_m2 / (res * res)))
    return max(length_to_cells(params.obstacle_inflation_m, res),
               length_to_cells(params.free_close_m, res),
               int(math.ceil(params.clutter_max_extent_m / res)) + 1,
               furniture_reach_cells(params, res),
               int(math.ceil(params.small_object_max_m / res))
               + length_to_cells(params.obstacle_inflation_m, res)) + speck + 2

