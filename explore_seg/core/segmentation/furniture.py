"""Furniture standing against walls: obstacle protrusions that are filled for the
decomposition so that they do not cut rooms (issue #53).

The clutter fill of :mod:`.cleaning` handles free-standing furniture (holes of the
cleaned free space). Furniture pushed against a wall is no hole: it is a thick bulge
of the wall's obstacle component (a pillar, a shelf, a desk, a row of chairs whose
inflated footprints touch the wall). Walls are thin; the space outside the building
and large blocks (a courtyard, a stairwell) are deep. A bulge is the part of the
obstacles that a disk of ``furniture_min_thickness_m`` fits in but a disk of
``furniture_max_thickness_m`` does not (two morphological openings). A bulge is
filled (its cells count as free space for the decomposition) when it is at most
``furniture_max_extent_m`` wide and high and the free space along its filled footprint
is one stretch (furniture in front of a wall), so a thick wall piece between two free
areas is never opened.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.params import SegmentationParams


def _open(mask: npt.NDArray[np.bool_], d_cells: int,
          dist: npt.NDArray[np.float32] | None = None) -> npt.NDArray[np.bool_]:
    """Morphological opening of ``mask`` by a disk of diameter ``d_cells``, by two
    distance transforms (their cost does not grow with the disk). ``dist``: the
    distance transform of ``mask``, when the caller has it."""
    r = 0.5 * d_cells
    if dist is None:
        dist = cv2.distanceTransform(mask.view(np.uint8), cv2.DIST_L2, 3)
    core = dist > r
    back = cv2.distanceTransform((~core).view(np.uint8), cv2.DIST_L2, 3)
    return back <= r


def furniture_cells(occ: npt.NDArray[np.uint8], params: SegmentationParams, res: float
                    ) -> npt.NDArray[np.bool_]:
    """Obstacle cells of wall-standing furniture bulges (see the module docstring).

    Parameters
    ----------
    occ : ndarray of uint8, shape (H, W)
        1 on the obstacle cells (scan specks already removed).
    params : SegmentationParams
    res : float
        Metres per cell.

    Returns
    -------
    ndarray of bool, shape (H, W)
        True on the cells of the bulges, less the cells within half
        ``furniture_min_thickness_m`` of the thin walls (where walls meet, those keep
        the walls closed); all False when the rule is disabled.
    """
    d_min = params.furniture_min_thickness_m / res
    d_max = params.furniture_max_thickness_m / res
    if d_min < 2 or d_max <= d_min or not occ.any():
        return np.zeros(occ.shape, dtype=bool)
    # the array border counts as obstacle (unknown outside the map)
    # no obstacle thicker than d_min (thin walls only): no bulge, one distance transform
    inner = cv2.distanceTransform((occ > 0).view(np.uint8), cv2.DIST_L2, 3)
    if not (inner > 0.5 * d_min).any():
        return np.zeros(occ.shape, dtype=bool)
    pad = int(d_max) + 2
    o = np.pad(occ > 0, pad, constant_values=True)
    dist = cv2.distanceTransform(o.view(np.uint8), cv2.DIST_L2, 3)
    thick = _open(o, d_min, dist)
    deep = _open(o, d_max, dist)
    # bulges: thick but not deep, opened again so that the rounded-off corners of deep
    # blocks (slivers thinner than d_min) are no bulges
    bulge = _open(thick & ~deep, d_min)[pad:-pad, pad:-pad]
    if not bulge.any():
        return bulge
    rest = (occ > 0) & ~bulge
    to_rest = cv2.distanceTransform((~rest).view(np.uint8), cv2.DIST_L2, 3)
    return bulge & (to_rest > 0.5 * d_min)


def fill_furniture(free_clean: npt.NDArray[np.bool_], occ: npt.NDArray[np.uint8],
                   params: SegmentationParams, res: float) -> npt.NDArray[np.bool_]:
    """``free_clean`` with the footprints of wall-standing furniture filled.

    Parameters
    ----------
    free_clean : ndarray of bool, shape (H, W)
        Cleaned free space.
    occ : ndarray of uint8, shape (H, W)
        Obstacle cells (specks removed), as inflated into ``free_clean``.
    params : SegmentationParams
    res : float

    Returns
    -------
    ndarray of bool, shape (H, W)
        ``free_clean`` plus, for every bulge (:func:`furniture_cells`) at most
        ``furniture_max_extent_m`` wide and high whose filled footprint borders the free
        space along one stretch, the cells the bulge's inflation took from it.
    """
    bulge = furniture_cells(occ, params, res)
    if not bulge.any():
        return free_clean
    ext = params.furniture_max_extent_m / res
    r_inf = int(round(params.obstacle_inflation_m / res))
    rest = ((occ > 0) & ~bulge).view(np.uint8)
    k_inf = np.ones((2 * r_inf + 1, 2 * r_inf + 1), np.uint8)
    n, lab, stats, _ = cv2.connectedComponentsWithStats(bulge.astype(np.uint8),
                                                        connectivity=8)
    h, w = occ.shape
    m = int(round(params.furniture_max_thickness_m / res)) + r_inf + 2
    out = free_clean.copy()
    for k in range(1, n):
        x, y, bw, bh, area = (int(v) for v in stats[k])
        if max(bw, bh) > ext:
            continue
        r0, r1 = max(0, y - m), min(h, y + bh + m)
        c0, c1 = max(0, x - m), min(w, x + bw + m)
        blob = lab[r0:r1, c0:c1] == k
        # cells the blob's inflation alone took from the free space
        grown = cv2.dilate(blob.astype(np.uint8), k_inf) > 0
        keep = cv2.dilate(rest[r0:r1, c0:c1], k_inf) > 0
        fill = grown & ~keep & ~free_clean[r0:r1, c0:c1]
        if not fill.any():
            continue
        # the free cells along the filled footprint: one stretch for furniture in
        # front of a wall, two or more for a wall piece between two free areas
        fu8 = fill.astype(np.uint8)
        contact = (cv2.dilate(fu8, np.ones((3, 3), np.uint8)) > 0) & ~fill \
            & free_clean[r0:r1, c0:c1]
        if cv2.connectedComponents(contact.astype(np.uint8), connectivity=8)[0] != 2:
            continue
        out[r0:r1, c0:c1] |= fill
    return out


def furniture_reach_cells(params: SegmentationParams, res: float) -> int:
    """How far (cells) a changed obstacle cell can change the furniture fill: the deep
    opening's disk, the second opening and the shave, the largest bulge, its inflation
    and the contact ring."""
    if params.furniture_min_thickness_m <= 0:
        return 0
    d_min = int(math.ceil(params.furniture_min_thickness_m / res))
    d_max = int(math.ceil(params.furniture_max_thickness_m / res))
    ext = int(math.ceil(params.furniture_max_extent_m / res))
    r_inf = int(round(params.obstacle_inflation_m / res))
    return d_max + 2 * d_min + ext + r_inf + 4
