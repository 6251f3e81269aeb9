"""Furniture standing against walls: obstacle protrusions that are filled for the
decomposition so that they do not cut rooms.

The clutter fill of :mod:`.cleaning` handles free-standing furniture (holes of the
cleaned free space). Furniture pushed against a wall is no hole: it is a thick bulge
of the wall's obstacle component (a pillar, a shelf, a desk, a row of chairs whose
inflated footprints touch the wall). Walls are thin; the space outside the building
and large blocks (a courtyard, a stairwell) are deep. A bulge is the part of the
obstacles that a disk of ``furniture_min_thickness_m`` fits in but a disk of
``furniture_max_thickness_m`` does not (two morphological openings). A bulge is
filled (the cells its inflation took count as free space for the decomposition) when
it is at most ``furniture_max_extent_m`` wide and high and one free area lies along its
footprint: the free space less every passage up to a door wide (``max_door_width_m``),
so a thick wall piece between two rooms is never opened, even beside a door. Where a
bulge takes a junction of thick walls along (a pillar at a T-junction), only its cells
farther than half ``furniture_min_thickness_m`` from the thin walls are tried next.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.labels import bbox
from explore_seg.core.segmentation.params import SegmentationParams


def open_disk(mask: npt.NDArray[np.bool_], d_cells: float,
          dist: npt.NDArray[np.float32] | None = None) -> npt.NDArray[np.bool_]:
    """Morphological opening of ``mask`` by a disk of diameter ``d_cells``, by two
    distance transforms (their cost does not grow with the disk). ``dist``: the
    distance transform of ``mask``, when the caller has it. OpenCV's transform counts
    the array's outside as part of ``mask``."""
    r = 0.5 * d_cells
    if dist is None:
        dist = cv2.distanceTransform(mask.view(np.uint8), cv2.DIST_L2, 3)
    core = dist > r
    box = bbox(core, int(math.ceil(r)) + 2)
    if box is None:
        return core
    out = np.zeros(core.shape, dtype=bool)
    sub = core[box]
    # the array's outside is no core here: pad so that OpenCV does not count it
    pad = np.pad(~sub, 1, constant_values=True)
    back = cv2.distanceTransform(pad.view(np.uint8), cv2.DIST_L2, 3)[1:-1, 1:-1]
    out[box] = back <= r
    return out


def furniture_cells(occ: npt.NDArray[np.uint8], params: SegmentationParams, res: float
                    ) -> npt.NDArray[np.bool_]:
    """Obstacle cells of wall-standing furniture bulges (see the module docstring).

    Parameters
    ----------
    occ : ndarray of uint8, shape (H, W)
        1 on the obstacle cells (scan specks already removed); the array's outside
        counts as obstacle (unknown beyond the map).
    params : SegmentationParams
    res : float
        Metres per cell.

    Returns
    -------
    ndarray of bool, shape (H, W)
        True on the cells of the bulges; all False when the rule is disabled.
    """
    out = np.zeros(occ.shape, dtype=bool)
    d_min = params.furniture_min_thickness_m / res
    d_max = params.furniture_max_thickness_m / res
    if d_min < 2 or d_max <= d_min or not occ.any():
        return out
    o = occ > 0
    dist = cv2.distanceTransform(o.view(np.uint8), cv2.DIST_L2, 3)
    if not (dist > 0.5 * d_min).any():
        return out                    # thin walls only
    cand = open_disk(o, d_min, dist) & ~open_disk(o, d_max, dist)
    # opened again so that the rounded-off corners of deep blocks (slivers thinner
    # than d_min) are no bulges; only around the candidates
    m = int(math.ceil(d_min)) + 2
    box = bbox(cand, m)
    if box is None:
        return out
    out[box] = open_disk(np.pad(cand[box], m), d_min)[m:-m, m:-m]
    return out


def furniture_cells_update(occ: npt.NDArray[np.uint8], params: SegmentationParams,
                           res: float, occ_prev: npt.NDArray[np.uint8],
                           bulge_prev: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
    """:func:`furniture_cells` of ``occ``, given those of ``occ_prev`` (``bulge_prev``):
    the distance transforms run only around the cells where the two differ.

    A cell's bulge depends on the obstacles within :func:`bulge_reach_cells` of it, so
    it is recomputed (with that much context) within that distance of a changed cell
    and copied elsewhere. The result equals ``furniture_cells(occ)`` wherever
    ``bulge_prev`` equals ``furniture_cells(occ_prev)``.
    """
    changed = occ != occ_prev
    box = bbox(changed, bulge_reach_cells(params, res))
    if box is None:
        return bulge_prev.copy()
    d = bulge_reach_cells(params, res)
    h, w = occ.shape
    ctx = (slice(max(0, box[0].start - d), min(h, box[0].stop + d)),
           slice(max(0, box[1].start - d), min(w, box[1].stop + d)))
    if (ctx[0].stop - ctx[0].start) * (ctx[1].stop - ctx[1].start) >= 0.8 * occ.size:
        return furniture_cells(occ, params, res)
    out = bulge_prev.copy()
    sub = furniture_cells(occ[ctx], params, res)
    out[box] = sub[box[0].start - ctx[0].start:box[0].stop - ctx[0].start,
                   box[1].start - ctx[1].start:box[1].stop - ctx[1].start]
    return out


def bulge_reach_cells(params: SegmentationParams, res: float) -> int:
    """How far (cells) a changed obstacle cell can change :func:`furniture_cells`: the
    two openings see the obstacles within their disks' diameters (the chamfer distance
    transform underestimates a distance by at most 4.5 %), plus a few cells."""
    d_min = params.furniture_min_thickness_m / res
    d_max = params.furniture_max_thickness_m / res
    return int(math.ceil(1.1 * (d_max + d_min))) + 4


def fill_furniture(free_clean: npt.NDArray[np.bool_], occ: npt.NDArray[np.uint8],
                   params: SegmentationParams, res: float,
                   roi: tuple[slice, slice] | None = None,
                   bulge: npt.NDArray[np.bool_] | None = None,
                   cache: FillCache | None = None,
                   origin: tuple[int, int] = (0, 0)) -> npt.NDArray[np.bool_]:
    """``free_clean`` with the footprints of wall-standing furniture filled.

    Parameters
    ----------
    free_clean : ndarray of bool, shape (H, W)
        Cleaned free space.
    occ : ndarray of uint8, shape (H, W)
        Obstacle cells (specks removed), as inflated into ``free_clean``.
    params : SegmentationParams
    res : float
    roi : (slice, slice), optional
        The part of the result the caller uses: bulges whose fill cannot reach it are
        not tested (their fill is left out).
    bulge : ndarray of bool, shape (H, W), optional
        :func:`furniture_cells` of ``occ``, when the caller has it.
    cache : FillCache, optional
        The fills of the previous call, replaced by this call's.
    origin : (int, int)
        The cell (0, 0) of these arrays in the cache's reference cells.

    Returns
    -------
    ndarray of bool, shape (H, W)
        ``free_clean`` plus, for every bulge (:func:`furniture_cells`) at most
        ``furniture_max_extent_m`` wide and high that stands in one free area, the
        cells its inflation took from the free space.
    """
    if params.furniture_min_thickness_m <= 0:
        return free_clean
    if bulge is None:
        bulge = furniture_cells(occ, params, res)
    if not bulge.any():
        return free_clean
    ext = params.furniture_max_extent_m / res
    r_inf = int(round(params.obstacle_inflation_m / res))
    k_inf = np.ones((2 * r_inf + 1, 2 * r_inf + 1), np.uint8)
    r_door = _door_cells(params, res)
    # a bulge where thick walls meet (a pillar at a T-junction) takes the junction
    # along: its cells within half furniture_min_thickness_m of the thin walls keep the
    # walls closed when the whole bulge would open them
    occ_b = occ > 0
    half_min = 0.5 * params.furniture_min_thickness_m / res
    r_c = int(math.ceil(0.25 * params.furniture_min_thickness_m / res))
    # a bulge's fill lies within the corner dilation and the inflation of its box
    reach = r_c + r_inf + 1
    # components of the bulges, in the bulges' bounding box; with a roi, only within
    # reach of it plus the widest bulge filled (a component cut off there is wider
    # than that, as it is whole)
    bb = bbox(bulge, 0)
    assert bb is not None
    if roi is not None:
        g = reach + int(math.ceil(ext)) + 1
        bb = (slice(max(bb[0].start, roi[0].start - g), min(bb[0].stop, roi[0].stop + g)),
              slice(max(bb[1].start, roi[1].start - g), min(bb[1].stop, roi[1].stop + g)))
        if bb[0].start >= bb[0].stop or bb[1].start >= bb[1].stop:
            return free_clean
    lab = np.zeros(occ.shape, dtype=np.int32)
    n, lab[bb], stats, _ = cv2.connectedComponentsWithStats(bulge[bb].view(np.uint8),
                                                            connectivity=8)
    stats[:, 0] += bb[1].start
    stats[:, 1] += bb[0].start
    h, w = occ.shape
    m = int(round(params.furniture_max_thickness_m / res)) + r_inf + r_door + 4
    k_corner = np.ones((2 * r_c + 1, 2 * r_c + 1), np.uint8)
    out = free_clean.copy()
    seen = {}
    if cache is not None:
        seen, cache.fills = cache.fills, {}
    for k in range(1, n):
        x, y, bw, bh, _area = (int(v) for v in stats[k])
        if max(bw, bh) > ext:
            continue
        if roi is not None and (y + bh + reach <= roi[0].start or y - reach >= roi[0].stop
                                or x + bw + reach <= roi[1].start
                                or x - reach >= roi[1].stop):
            continue
        box = (slice(max(0, y - m), min(h, y + bh + m)),
               slice(max(0, x - m), min(w, x + bw + m)))
        blob = lab[box] == k
        inputs = (blob, occ_b[box], free_clean[box], bulge[box])
        key = (box[0].start + origin[0], box[0].stop + origin[0],
               box[1].start + origin[1], box[1].stop + origin[1])
        hit = seen.get(key)
        if hit is not None and all(np.array_equal(a, b) for a, b in zip(hit[0], inputs)):
            fill = hit[1]
            if cache is not None:
                cache.fills[key] = hit
        else:
            fill = _bulge_fill(*inputs, k_corner, k_inf, r_door, half_min)
            if cache is not None:
                cache.fills[key] = (tuple(a.copy() for a in inputs), fill)
        if fill is not None:
            out[box] |= fill
    return out


class FillCache:
    """The fills of the bulges of an earlier :func:`fill_furniture` call, with the
    inputs each was computed from, keyed by the bulge's neighbourhood in cells of a
    fixed reference (a bulge whose neighbourhood did not change is not tested again;
    an incremental update keeps one)."""

    def __init__(self) -> None:
        self.fills: dict[tuple[int, int, int, int],
                         tuple[tuple[npt.NDArray[np.bool_], ...],
                               npt.NDArray[np.bool_] | None]] = {}


def _bulge_fill(blob: npt.NDArray[np.bool_], occ: npt.NDArray[np.bool_],
                free_clean: npt.NDArray[np.bool_], bulge: npt.NDArray[np.bool_],
                k_corner: npt.NDArray[np.uint8], k_inf: npt.NDArray[np.uint8],
                r_door: int, half_min: float) -> npt.NDArray[np.bool_] | None:
    """The fill of one bulge ``blob`` (arrays: the bulge's neighbourhood), or None."""
    # the opening rounds the bulge's corners off: the occupied cells near it are the
    # furniture's footprint
    whole = (cv2.dilate(blob.view(np.uint8), k_corner) > 0) & occ
    fill = _footprint(whole, occ, free_clean, k_inf, r_door)
    if fill is None:
        thin = occ & ~bulge
        to_thin = cv2.distanceTransform((~thin).view(np.uint8), cv2.DIST_L2, 3)
        fill = _footprint(blob & (to_thin > half_min), occ, free_clean, k_inf, r_door)
    return fill


def _footprint(cells: npt.NDArray[np.bool_], occ: npt.NDArray[np.bool_],
               free_clean: npt.NDArray[np.bool_], k_inf: npt.NDArray[np.uint8],
               r_door: int) -> npt.NDArray[np.bool_] | None:
    """The cells that obstacle ``cells`` alone keep out of the free space (their
    inflation less the other obstacles'), or None when nothing or when they stand
    between two free areas (a wall).

    The free areas are the cleaned free space less every passage up to a door wide
    (eroded by ``r_door`` cells); around the filled footprint there must be exactly one of them:
    furniture stands in one room, a wall piece between two, even when a door next to
    it joins them."""
    if not cells.any():
        return None
    grown = cv2.dilate(cells.view(np.uint8), k_inf) > 0
    keep = cv2.dilate((occ & ~cells).view(np.uint8), k_inf) > 0
    fill = grown & ~keep & ~free_clean
    if not fill.any():
        return None
    k_door = np.ones((2 * r_door + 1, 2 * r_door + 1), np.uint8)
    areas = cv2.erode(free_clean.view(np.uint8), k_door, borderValue=0)
    k_band = np.ones((2 * r_door + 5, 2 * r_door + 5), np.uint8)
    band = (cv2.dilate(fill.view(np.uint8), k_band) > 0) & (areas > 0)
    if cv2.connectedComponents(band.view(np.uint8), connectivity=8)[0] != 2:
        return None
    return fill


def _door_cells(params: SegmentationParams, res: float) -> int:
    """Half the widest door in the cleaned free space (the door less the inflation on
    both sides), plus one cell (cells)."""
    return int(math.ceil((0.5 * params.max_door_width_m - params.obstacle_inflation_m)
                         / res)) + 1


def furniture_reach_cells(params: SegmentationParams, res: float) -> int:
    """How far (cells) a changed obstacle cell can change the furniture fill.

    The bulges at a cell depend on the obstacles within the two openings' disks
    (``furniture_max_thickness_m`` then ``furniture_min_thickness_m``); a bulge's fill
    lies within its extent (at most ``furniture_max_extent_m``), the corner dilation and
    the inflation of any of its cells. The one-free-area test sees the free space (the
    inflation) through the door erosion and the contact band, again anywhere along the
    bulge. The larger of the two paths, plus two cells."""
    if params.furniture_min_thickness_m <= 0:
        return 0
    d_min = int(math.ceil(params.furniture_min_thickness_m / res))
    d_max = int(math.ceil(params.furniture_max_thickness_m / res))
    ext = int(math.ceil(params.furniture_max_extent_m / res))
    r_inf = int(round(params.obstacle_inflation_m / res))
    r_c = int(math.ceil(0.25 * params.furniture_min_thickness_m / res))
    r_door = _door_cells(params, res)
    shape = d_max + d_min + ext + r_c + r_inf
    areas = 2 * r_inf + 2 * r_door + 2 + ext + r_c
    return max(shape, areas) + 2


def fill_window_cells(params: SegmentationParams, res: float) -> tuple[int, int]:
    """(how far (cells) a change of :func:`fill_furniture`'s inputs can change its
    result, how much context beyond a ``roi`` it reads for an exact result there).

    A bulge's fill reads the inputs in its bounding box grown by the neighbourhood
    margin, depends on its whole component (at most ``furniture_max_extent_m``), and
    lies within the corner dilation and the inflation of it; with a ``roi``, the bulges
    within that reach plus the widest bulge are tested, each with its neighbourhood."""
    r_inf = int(round(params.obstacle_inflation_m / res))
    r_c = int(math.ceil(0.25 * params.furniture_min_thickness_m / res))
    reach = r_c + r_inf + 1
    ext = int(math.ceil(params.furniture_max_extent_m / res))
    m = int(round(params.furniture_max_thickness_m / res)) + r_inf + _door_cells(params, res) + 4
    return m + ext + reach + 2, reach + ext + 1 + m + 1
