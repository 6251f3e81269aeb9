"""Incremental update of the cleaned masks (:class:`.cleaning.CleanState`) after a map
change, stage by stage, each only as far from the changed cells as that stage reaches.

A full cleaning (:func:`.cleaning.clean_state`) runs in four stages with growing reach:

1. base masks (specks, small objects, inflation, free growth: a few cells);
2. clutter holes (a hole is judged whole: up to ``clutter_max_extent_m``);
3. furniture bulges (two openings: :func:`.furniture.bulge_reach_cells`);
4. the furniture fill (a bulge's neighbourhood: :func:`.furniture.fill_window_cells`).

Recomputing all of them over the widest reach costs a window several times larger than
the change. Here each stage is redone in its own window from the stages before it, and
only where its inputs changed, so the update equals a full cleaning of the new map.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.cleaning import (CleanState, base_masks, base_reach_cells,
                                                    clutter_table)
from explore_seg.core.segmentation.furniture import (FillCache, bulge_reach_cells,
                                                     fill_furniture, fill_window_cells,
                                                     furniture_cells_update)
from explore_seg.core.segmentation.labels import bbox, lookup_mask
from explore_seg.core.segmentation.params import SegmentationParams

Box = tuple[slice, slice]


def grow(box: Box, margin: int, shape: tuple[int, int]) -> Box:
    """``box`` grown by ``margin`` cells on every side, clipped to ``shape``."""
    return (slice(max(0, box[0].start - margin), min(shape[0], box[0].stop + margin)),
            slice(max(0, box[1].start - margin), min(shape[1], box[1].stop + margin)))


def inner(box: Box, window: Box) -> Box:
    """``box`` (inside ``window``) in the window's own cells."""
    return (slice(box[0].start - window[0].start, box[0].stop - window[0].start),
            slice(box[1].start - window[1].start, box[1].stop - window[1].start))


def offset(box: Box | None, window: Box) -> Box | None:
    """``box`` in a window's own cells as cells of the whole array (None stays None)."""
    if box is None:
        return None
    return (slice(box[0].start + window[0].start, box[0].stop + window[0].start),
            slice(box[1].start + window[1].start, box[1].stop + window[1].start))


def union(a: Box | None, b: Box | None) -> Box | None:
    """Bounding box of two boxes (either may be None)."""
    if a is None or b is None:
        return a if b is None else b
    return (slice(min(a[0].start, b[0].start), max(a[0].stop, b[0].stop)),
            slice(min(a[1].start, b[1].start), max(a[1].stop, b[1].stop)))


def update_clean_state(st: CleanState, data: npt.NDArray[np.int8], changed: Box,
                       params: SegmentationParams, res: float, fill_cache: FillCache,
                       origin: tuple[int, int]) -> CleanState:
    """The cleaned masks of ``data`` from those of an earlier map (``st``, in this
    array's geometry and written in place) that differs from ``data`` only inside
    ``changed`` (cells ``st`` did not cover count as changed).

    ``fill_cache`` and ``origin``: the bulges' fills of the earlier map and this array's
    cell (0, 0) in the cache's reference cells. The result equals
    ``clean_state(data, params, res)``.
    """
    assert st.base is not None and st.clutter is not None
    shape = data.shape
    # 1. base masks: exact in b1 with r1 cells of context
    r1 = base_reach_cells(params, res)
    b1 = grow(changed, r1, shape)
    w1 = grow(b1, r1, shape)
    ib = inner(b1, w1)
    fr, occ_u8, base, _cc = base_masks(data[w1], params, res)
    occ_box = None
    if st.bulge is not None:
        # the old obstacles round the change, for the bulges' update
        occ_box = grow(b1, 2 * bulge_reach_cells(params, res) + 1, shape)
        occ_old = st.occ[occ_box].copy()
    # the furniture fill reads the obstacles, the clutter fill and the bulges
    diff = offset(bbox(occ_u8[ib] != st.occ[b1], 0), b1)
    st.free_raw[b1] = fr[ib]
    st.occ[b1] = occ_u8[ib]
    st.base[b1] = base[ib]
    # 2. clutter holes, then the published cells
    diff = union(diff, _update_clutter(st, data, b1, params, res))
    # 3. bulges
    if st.bulge is not None and occ_box is not None:
        diff = union(diff, _update_bulges(st, occ_box, occ_old, b1, params, res))
    # 4. furniture fill
    if st.bulge is None:
        return st._replace(free_clean=st.clutter)
    if diff is not None:
        _update_fill(st, diff, params, res, fill_cache, origin)
    return st


def _update_clutter(st: CleanState, data: npt.NDArray[np.int8], b1: Box,
                    params: SegmentationParams, res: float) -> Box | None:
    """Stage 2 of :func:`update_clean_state`, in place: the clutter fill and the
    published cells round ``b1`` (where the base masks were redone). Returns the
    bounding box of the cells whose clutter fill changed (None: none).

    A hole whose status can change meets ``b1`` (grown by a cell: a hole cut apart
    there touches it still) and, as a clutter hole, is at most ``clutter_max_extent_m``
    wide: it lies inside the window. A hole that meets ``b1`` and the window's edge is
    wider than that, as in the whole map; holes away from ``b1`` keep their status."""
    assert st.base is not None and st.clutter is not None
    shape = data.shape
    e = int(math.ceil(params.clutter_max_extent_m / res)) + 2
    w2 = grow(b1, e, shape)
    base = st.base[w2]
    new = base.copy()
    old = st.clutter[w2].copy()
    write = np.zeros(base.shape, dtype=bool)
    ib = inner(b1, w2)
    write[ib] = True
    if params.clutter_max_extent_m > 0 and params.clutter_max_area_m2 > 0:
        _n, lab, stats, _ = cv2.connectedComponentsWithStats((~base).astype(np.uint8),
                                                             connectivity=8)
        near = inner(grow(b1, 1, shape), w2)
        meet = np.zeros(len(stats), dtype=bool)
        meet[lab[near]] = True
        meet[0] = False
        write |= lookup_mask(meet, lab)
        table = clutter_table(lab, stats, st.occ[w2], params, res, only=meet, data=data[w2])
        if table is not None:
            new |= lookup_mask(table, lab)
    np.copyto(st.clutter[w2], new, where=write)
    st.shown[w2] = st.free_raw[w2] | (st.clutter[w2] & (data[w2] > params.occupied_min_occupancy))
    return offset(bbox(old != st.clutter[w2], 0), w2)


def _update_bulges(st: CleanState, window: Box, occ_old: npt.NDArray[np.uint8], b1: Box,
                   params: SegmentationParams, res: float) -> Box | None:
    """Stage 3 of :func:`update_clean_state`, in place: the furniture bulges, from the
    obstacles before (``occ_old``, over ``window``) and after the change (inside
    ``b1``). Returns the box of the cells whose bulge changed (None: none)."""
    assert st.bulge is not None
    shape = st.occ.shape
    out = grow(b1, bulge_reach_cells(params, res), shape)
    new = furniture_cells_update(st.occ[window], params, res, occ_old, st.bulge[window])
    io = inner(out, window)
    sub = new[io]
    changed = offset(bbox(sub != st.bulge[out], 0), out)
    st.bulge[out] = sub
    return changed


def _update_fill(st: CleanState, diff: Box, params: SegmentationParams, res: float,
                 fill_cache: FillCache, origin: tuple[int, int]) -> None:
    """Stage 4 of :func:`update_clean_state`, in place: the furniture fill wherever a
    change of its inputs inside ``diff`` can reach."""
    assert st.clutter is not None and st.bulge is not None
    shape = st.occ.shape
    reach, ctx = fill_window_cells(params, res)
    roi = grow(diff, reach, shape)
    if not st.bulge[roi].any():
        # no bulge whose neighbourhood meets the change, nor whose fill reaches it
        st.free_clean[diff] = st.clutter[diff]
        return
    w3 = grow(roi, ctx, shape)
    ir = inner(roi, w3)
    out = fill_furniture(st.clutter[w3], st.occ[w3], params, res, ir, st.bulge[w3],
                         fill_cache, (w3[0].start + origin[0], w3[1].start + origin[1]))
    st.free_clean[roi] = out[ir]
