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


def clean_masks(data: npt.NDArray[np.int8], params: SegmentationParams, res: float
                ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """:func:`clean_free_space` of an occupancy array."""
    st = clean_state(data, params, res)
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
    #: the cleaned free space before the clutter and furniture fills
    base: npt.NDArray[np.bool_] | None = None
    #: ``base`` with the clutter holes filled (``free_clean`` less the furniture fill)
    clutter: npt.NDArray[np.bool_] | None = None


OccComponents = tuple[npt.NDArray[np.int32], npt.NDArray[np.int32], npt.NDArray[np.bool_]]


def base_masks(data: npt.NDArray[np.int8], params: SegmentationParams, res: float
               ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.uint8], npt.NDArray[np.bool_],
                          OccComponents | None]:
    """The first stage of :func:`clean_state`: raw free cells, the obstacles less specks
    and small objects (uint8), the cleaned free space before the fills, and the occupied
    components the clutter fill reads (None: it labels the obstacles itself). A cell's
    values depend on the grid within :func:`base_reach_cells` of it."""
    free_raw = (data >= 0) & (data < params.free_max_occupancy)
    occ = data > params.occupied_min_occupancy
    occ_u8 = occ.astype(np.uint8)
    occ_cc = None
    speck_px = math.floor(params.obstacle_speck_area_m2 / (res * res) + 1e-6)
    if speck_px >= 1 and occ.any():
        occ_u8, occ_cc = _drop_specks(occ_u8, speck_px)
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
    return free_raw, occ_u8, free_clean, occ_cc


def _drop_specks(occ_u8: npt.NDArray[np.uint8], speck_px: int
                 ) -> tuple[npt.NDArray[np.uint8], OccComponents]:
    """The obstacles less the components of at most ``speck_px`` cells, and the
    components of ``occ_u8`` with those marked removed."""
    n, lab, stats, _ = cv2.connectedComponentsWithStats(occ_u8, connectivity=8)
    small = stats[:, cv2.CC_STAT_AREA] <= speck_px
    small[0] = False
    if small.any():
        keep = (~small).astype(np.uint8)
        keep[0] = 0
        occ_u8 = np.take(keep, lab)      # the occupied cells less the specks
    return occ_u8, (lab, stats, small)


def clutter_components(data: npt.NDArray[np.int8], occ_u8: npt.NDArray[np.uint8],
                       params: SegmentationParams, res: float) -> OccComponents | None:
    """The occupied components :func:`base_masks` hands the clutter fill, from the grid
    and its result (for a window of the grid: components cut by the window's edge lie in
    holes that reach it)."""
    occ = data > params.occupied_min_occupancy
    speck_px = math.floor(params.obstacle_speck_area_m2 / (res * res) + 1e-6)
    if speck_px >= 1 and occ.any():
        return _drop_specks(occ.view(np.uint8), speck_px)[1]
    return None


def base_reach_cells(params: SegmentationParams, res: float) -> int:
    """How far (cells) a changed grid cell can change :func:`base_masks`: a speck is
    judged whole; so is a small object, with the obstacles (specks dropped) near it, so a
    change that joins one object to a wall changes the objects near that one; and an
    obstacle's change reaches as far as the inflation, a free cell's as the growth."""
    speck = int(math.ceil(params.obstacle_speck_area_m2 / (res * res)))
    r_inf = length_to_cells(params.obstacle_inflation_m, res)
    obj = 0
    if params.small_object_max_m > 0:
        obj = 2 * int(math.ceil(params.small_object_max_m / res)) + 2 * r_inf + 1
    return speck + obj + max(r_inf, length_to_cells(params.free_close_m, res)) + 2


def clean_state(data: npt.NDArray[np.int8], params: SegmentationParams, res: float,
                fill_cache: FillCache | None = None) -> CleanState:
    """:func:`clean_masks` plus the published cells and what an incremental update keeps
    to redo less (:class:`CleanState`): the obstacles as inflated, their furniture
    bulges, the cleaned free space before the fills and after the clutter fill.
    ``fill_cache``: the bulges' fills, kept for a later update (:class:`FillCache`)."""
    if data.size == 0:
        free_raw = np.zeros(data.shape, dtype=bool)
        return CleanState(free_raw, free_raw.copy(), np.zeros(data.shape, np.uint8), None,
                          free_raw.copy(), free_raw.copy(), free_raw.copy())
    free_raw, occ_u8, base, occ_cc = base_masks(data, params, res)
    clutter = fill_clutter_holes(base, occ_u8, params, res, occ_cc)
    bulge = None
    if params.furniture_min_thickness_m > 0:
        bulge = furniture_cells(occ_u8, params, res)
    if clutter is base:
        clutter = base.copy()          # an update writes the two apart
    shown = free_raw | (clutter & (data > params.occupied_min_occupancy))
    filled = fill_furniture(clutter, occ_u8, params, res, None, bulge, fill_cache)
    if filled is clutter and bulge is not None:
        filled = clutter.copy()
    return CleanState(free_raw, filled, occ_u8, bulge, shown, base, clutter)


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
                       occ_cc: OccComponents | None = None) -> npt.NDArray[np.bool_]:
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
    if params.clutter_max_extent_m <= 0 or params.clutter_max_area_m2 <= 0 \
            or free_clean.size == 0:
        return free_clean
    _n, lab, stats, _ = cv2.connectedComponentsWithStats((~free_clean).astype(np.uint8),
                                                         connectivity=8)
    small = clutter_table(lab, stats, occ, params, res, occ_cc)
    if small is None:
        return free_clean
    return free_clean | lookup_mask(small, lab)


def clutter_table(lab: npt.NDArray[np.int32], stats: npt.NDArray[np.int32],
                  occ: npt.NDArray[np.uint8], params: SegmentationParams, res: float,
                  occ_cc: OccComponents | None = None,
                  only: npt.NDArray[np.bool_] | None = None,
                  data: npt.NDArray[np.int8] | None = None) -> npt.NDArray[np.bool_] | None:
    """Which components of the cleaned free space's complement (``lab``, ``stats``:
    OpenCV's 8-connected labelling) are clutter holes (:func:`fill_clutter_holes`), or
    None when none is.

    ``only`` (optional): the components to judge (the others are no clutter here).
    ``data`` (optional, instead of ``occ_cc``): the grid the obstacles come from; the
    occupied components are then labelled only round the holes judged (an occupied
    component lies in one hole)."""
    ext = params.clutter_max_extent_m / res
    area = params.clutter_max_area_m2 / (res * res)
    h, w = lab.shape
    x, y = stats[:, cv2.CC_STAT_LEFT], stats[:, cv2.CC_STAT_TOP]
    bw, bh = stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT]
    small = ((x > 0) & (y > 0) & (x + bw < w) & (y + bh < h)
             & (np.maximum(bw, bh) <= ext) & (stats[:, cv2.CC_STAT_AREA] <= area))
    small[0] = False
    if only is not None:
        small &= only
    if not small.any():
        return None
    if data is not None:
        k = np.flatnonzero(small)
        box = (slice(max(0, int(y[k].min()) - 1), min(h, int((y[k] + bh[k]).max()) + 1)),
               slice(max(0, int(x[k].min()) - 1), min(w, int((x[k] + bw[k]).max()) + 1)))
        lab, occ = lab[box], occ[box]
        occ_cc = clutter_components(data[box], occ, params, res)
    olab, ost, gone = occ_cc if occ_cc is not None else occupied_components(occ)
    diag = np.hypot(ost[:, cv2.CC_STAT_WIDTH], ost[:, cv2.CC_STAT_HEIGHT])
    big = (diag > params.clutter_max_object_m / res) & ~gone
    big[0] = False
    if big.any() and params.furniture_min_thickness_m > 0:
        big &= ~_thick_blocks(olab, ost, big, params, res)
    if big.any():
        small[lab[lookup_mask(big, olab)]] = False
    return small if small.any() else None


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

