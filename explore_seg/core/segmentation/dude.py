"""Dual-Space Decomposition (DuDe) of a free-space mask into nearly convex pieces.

Polygon stage of the room segmentation (DuDe spec shared/docs/dude.md §5-§9), with the
raster shortcut of §9.5: the cuts chosen for a piece are drawn into its mask as
4-connected lines of "wall" cells, the mask is split into its 4-connected components, and
every component is decomposed again until it yields no cut.

All geometry here is in pixel units of the cropped mask: points are ``(x, y) = (col,
row)`` pixel centres, treated as a right-handed plane (the outer ring has positive
shoelace area, holes negative), so the interior of the free space lies on the left of
every ring. Nothing here knows about metres or maps; :mod:`.incremental` converts.

Simplifications with respect to the library the spec describes (each one documented at
the function doing it):

* pocket tree: nested hulls of the pocket chains instead of a recursive cut search
  inside each pocket (:mod:`.rings`);
* holes: every structural hole is treated as nearly convex (§7.2), so L/U-shaped
  islands get the extreme-point notches only (:func:`.rings.hole_features`);
* candidates: instead of the edges of a constrained Delaunay triangulation, every cut
  from a notch to another notch, to a ring vertex or to the foot of the perpendicular
  on a ring edge that stays inside the free space (raster test) is a candidate; the
  far end of a cut therefore need not be a polygon vertex, which lets a door jamb be
  cut straight across to a flat wall. Non-crossing is enforced in the choice;
* choice: the greedy version recommended in §8.3 instead of the knapsack table.
"""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.cuts import choose_cuts, cut_sets, wedge
from explore_seg.core.segmentation.params import DudeSettings
from explore_seg.core.segmentation.rings import (Notch, Ring, hole_features, outer_features,
                                                 trace_rings)


def find_cuts(mask: npt.NDArray[np.uint8], st: DudeSettings
              ) -> list[tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]:
    """One round of DuDe on a mask holding one connected piece (§6-§9).

    Parameters
    ----------
    mask : ndarray of uint8, shape (H, W)
        1 on the piece's cells, 0 elsewhere; the piece must not touch the array border.
    st : DudeSettings

    Returns
    -------
    list of (p0, p1)
        Cuts as pairs of ``(x, y)`` float points; empty when the piece is convex enough.
    """
    tau = st.tau_px
    outer, holes = trace_rings(mask, st)
    if outer is None:
        return []
    rings = [outer]
    feats_per_ring: list[list[int]] = []
    raw_notches: list[tuple[int, int, float]] = []
    onotch, ofeat = outer_features(outer, tau, st.max_pocket_depth)
    feats_per_ring.append(ofeat)
    raw_notches += [(0, i, c) for i, c in onotch]
    noise: list[Ring] = []
    for hole in holes:
        structural, hn, hf = hole_features(hole, tau)
        if not structural:
            noise.append(hole)
            continue
        ri = len(rings)
        rings.append(hole)
        feats_per_ring.append(hf)
        raw_notches += [(ri, i, c) for i, c in hn]
    notches: list[Notch] = []
    for ri, i, c in raw_notches:
        nt = Notch(ri, i, rings[ri].pts[i].copy(), c)
        if wedge(nt, rings[ri], feats_per_ring[ri]):
            notches.append(nt)
    if not notches:
        return []
    vis = mask.astype(bool)
    if noise:
        filled = mask.copy()
        cv2.drawContours(filled, [h.raw for h in noise], -1, 1, thickness=cv2.FILLED)
        vis = filled.astype(bool)
    inner = cv2.erode(vis.astype(np.uint8), cv2.getStructuringElement(cv2.MORPH_CROSS,
                                                                      (3, 3)))
    border = vis & ~inner.astype(bool)
    sets = cut_sets(notches, rings, vis, border, st)
    if not sets:
        return []
    return choose_cuts(sets)


def _draw_cut(mask: npt.NDArray[np.uint8], a: npt.NDArray[np.float64],
              b: npt.NDArray[np.float64]) -> None:
    """Draw a cut as a 4-connected line of 0 cells, extended 1.5 px past both ends."""
    d = b - a
    length = float(np.hypot(d[0], d[1]))
    if length < 1e-9:
        return
    ext = d / length * 1.5
    p0 = np.rint(a - ext).astype(int)
    p1 = np.rint(b + ext).astype(int)
    cv2.line(mask, (int(p0[0]), int(p0[1])), (int(p1[0]), int(p1[1])), 0, 1, cv2.LINE_4)


def decompose_mask(mask: npt.NDArray[np.bool_], st: DudeSettings
                   ) -> tuple[npt.NDArray[np.int32], int]:
    """Decompose a free-space mask into nearly convex pieces (raster shortcut, §9.5).

    Parameters
    ----------
    mask : ndarray of bool, shape (H, W)
        Cleaned free space.
    st : DudeSettings

    Returns
    -------
    pieces : ndarray of int32, shape (H, W)
        0 outside the pieces and on cut lines, 1..n a piece.
    n : int
        Number of pieces.

    Raises
    ------
    ValueError
        When ``mask`` is not 2D.
    """
    mask = np.asarray(mask)
    if mask.ndim != 2:
        raise ValueError(f"mask must be 2D, got shape {mask.shape}")
    out = np.zeros(mask.shape, dtype=np.int32)
    if mask.size == 0 or not mask.any():
        return out, 0
    src = mask.astype(np.uint8)
    ncomp, lab, stats, _ = cv2.connectedComponentsWithStats(src, connectivity=4)
    # queue of (piece mask crop, x0, y0, round) in full-image coordinates
    queue: list[tuple[npt.NDArray[np.bool_], int, int, int]] = []
    for k in range(1, ncomp):
        x, y, w, h, _a = (int(v) for v in stats[k])
        queue.append((lab[y:y + h, x:x + w] == k, x, y, 0))
    n_out = 0
    processed = 0
    while queue and processed < st.max_pieces:
        processed += 1
        piece, x, y, rnd = queue.pop()
        h, w = piece.shape
        crop = np.zeros((h + 2, w + 2), dtype=np.uint8)
        crop[1:-1, 1:-1] = piece
        cuts = []
        if int(piece.sum()) >= st.min_component_px and rnd < st.max_rounds:
            cuts = find_cuts(crop, st)
        if cuts:
            before = crop.copy()
            for a, b in cuts:
                _draw_cut(crop, a, b)
            crop[0, :] = crop[-1, :] = 0
            crop[:, 0] = crop[:, -1] = 0
            if np.array_equal(before, crop):
                cuts = []
        if not cuts:
            n_out += 1
            out[y:y + h, x:x + w][piece] = n_out
            continue
        nc, sl, sst, _ = cv2.connectedComponentsWithStats(crop, connectivity=4)
        for c in range(1, nc):
            cx, cy, cw, ch, _a = (int(v) for v in sst[c])
            queue.append((sl[cy:cy + ch, cx:cx + cw] == c, x + cx - 1, y + cy - 1, rnd + 1))
    # whatever is left after the safety bound becomes pieces as is
    for piece, x, y, _rnd in queue:
        n_out += 1
        h, w = piece.shape
        out[y:y + h, x:x + w][piece] = n_out
    return out, n_out
