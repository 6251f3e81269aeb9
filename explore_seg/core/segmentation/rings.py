"""Rings and notches of a one-piece free-space mask (DuDe spec shared/docs/dude.md §5-§7).

The outer ring and the hole rings are traced and simplified; notches are the boundary
vertices deeper than tau below the convex hull (outer ring: pocket tree, §6) or the
extreme points and deep vertices of structural holes (§7).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.params import DudeSettings
from explore_seg.core.segmentation.polygon import (dp_keep, dp_keep_list, hull_indices,
                                                   hull_indices_list, point_segment_dists,
                                                   seg_dist_xy,
                                                   signed_area)


@dataclass
class Ring:
    pts: npt.NDArray[np.float64]          # (n, 2) simplified, oriented (interior left)
    raw: npt.NDArray[np.int32]            # OpenCV contour (for filling)
    is_hole: bool
    arc: npt.NDArray[np.float64] = field(init=False)   # arc length at each vertex
    perimeter: float = field(init=False)

    def __post_init__(self) -> None:
        nxt = np.concatenate([self.pts[1:], self.pts[:1]])
        seg = np.hypot(nxt[:, 0] - self.pts[:, 0], nxt[:, 1] - self.pts[:, 1])
        self.arc = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
        self.perimeter = float(seg.sum())


@dataclass
class Notch:
    ring: int
    idx: int
    pt: npt.NDArray[np.float64]
    conc: float
    p: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    n: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    a_n: float = 0.0
    interior: float = 0.0


def _simplify_ring(contour: npt.NDArray[np.int32], eps: float, want_positive: bool
                   ) -> npt.NDArray[np.float64] | None:
    raw = contour.reshape(-1, 2)
    pts = raw
    if eps > 0 and len(raw) > 3:
        approx = cv2.approxPolyDP(contour, eps, True).reshape(-1, 2)
        if len(approx) >= 3 and abs(cv2.contourArea(approx)) > 0:
            pts = approx
    if len(pts) < 3:
        return None
    pts = pts.astype(np.float64)
    # drop consecutive duplicates
    prev = np.concatenate([pts[-1:], pts[:-1]])
    keep = (pts[:, 0] != prev[:, 0]) | (pts[:, 1] != prev[:, 1])
    pts = pts[keep]
    if len(pts) < 3:
        return None
    area = signed_area(pts)
    if area == 0:
        return None
    if (area > 0) != want_positive:
        pts = pts[::-1].copy()
    return pts


def trace_rings(mask: npt.NDArray[np.uint8], st: DudeSettings
                 ) -> tuple[Ring | None, list[Ring]]:
    """Outer ring (largest top-level contour) and hole rings of a one-piece mask."""
    contours, hier = cv2.findContours(mask, cv2.RETR_CCOMP, cv2.CHAIN_APPROX_SIMPLE)
    if hier is None or not contours:
        return None, []
    hier = hier[0]
    tops = [i for i in range(len(contours)) if hier[i][3] < 0]
    if not tops:
        return None, []
    top = max(tops, key=lambda i: abs(cv2.contourArea(contours[i])))
    pts = _simplify_ring(contours[top], st.simplify_eps_px, True)
    if pts is None:
        return None, []
    outer = Ring(pts, contours[top], False)
    holes: list[Ring] = []
    child = hier[top][2]
    guard = 0
    while child >= 0 and guard < len(contours):
        guard += 1
        c = contours[child]
        if abs(cv2.contourArea(c)) > st.min_hole_area_px:
            hp = _simplify_ring(c, st.simplify_eps_px, False)
            if hp is not None:
                holes.append(Ring(hp, c, True))
        child = hier[child][0]
    return outer, holes


# ------------------------------------------------------------------- notches: outer ring


def _pocket_candidates(pts: list[list[float]], tau: float, depth: int, max_depth: int
                       ) -> tuple[list[int], list[int]]:
    """Notch candidates (chain indices) of one pocket chain and its nested dents.

    ``pts`` is the pocket chain from one bridge end to the other (integer ``[x, y]``
    points). Its convex hull gives the chain's extreme points (own candidates,
    simplified with 0.75 tau). Between two consecutive hull vertices the free space
    bulges into the pocket; the hull of such a bulge has its own dents, which are
    searched recursively (simplified pocket tree: nested hulls instead of a cut search
    inside the pocket). An own candidate is a shallow bump and dropped when it lies
    within tau/2 of the segment joining its neighbours among the chain ends, kids'
    bridge ends, kids' notches and own candidates (§6.3.6).

    Returns
    -------
    notches : list of int
        Chain indices of the candidates kept at this level and below, ascending.
    bridge_ends : list of int
        Chain indices of the bridge ends of the dents that produced candidates.
    """
    m = len(pts)
    if m < 3 or depth > max_depth:
        return [], []
    h = _with_ends(hull_indices_list(pts), m)
    own = [h[k] for k in dp_keep_list([pts[i] for i in h], 0.75 * tau) if 0 < h[k] < m - 1]
    kid_notches: list[int] = []
    kid_ends: list[int] = []
    for a, b in zip(h[:-1], h[1:]):
        if b - a < 2:
            continue
        bulge = pts[a:b + 1]
        hb = _with_ends(hull_indices_list(bulge), len(bulge))
        for c, d in zip(hb[:-1], hb[1:]):
            if d - c < 2:
                continue
            lo, hi = a + c, a + d
            sub, sub_ends = _pocket_candidates(pts[lo:hi + 1], tau, depth + 1, max_depth)
            if sub:
                kid_notches.extend(lo + k for k in sub)
                kid_ends.extend([lo, hi] + [lo + k for k in sub_ends])
    walk = sorted(set([0, m - 1] + kid_ends + kid_notches + own))
    pos = {k: i for i, k in enumerate(walk)}
    kept = []
    half_tau = 0.5 * tau
    for k in own:
        i = pos[k]
        if i == 0 or i == len(walk) - 1:
            continue
        (px, py), (ax, ay), (bx, by) = pts[k], pts[walk[i - 1]], pts[walk[i + 1]]
        if seg_dist_xy(px, py, ax, ay, bx, by) > half_tau:
            kept.append(k)
    return sorted(set(kept + kid_notches)), list(set(kid_ends))


def _with_ends(h: list[int], m: int) -> list[int]:
    """Sorted hull indices ``h`` with the chain ends 0 and m - 1 added."""
    if not h or h[0] != 0:
        h = [0] + h
    if h[-1] != m - 1:
        h = h + [m - 1]
    return h


def outer_features(ring: Ring, tau: float, max_depth: int
                    ) -> tuple[list[tuple[int, float]], list[int]]:
    """Notches ``(index, concavity)`` and feature indices of the outer ring (§6)."""
    pts = ring.pts
    n = len(pts)
    hull = hull_indices(pts).tolist()
    if len(hull) < 3:
        return [], list(range(n))
    plist = pts.tolist()
    feats: set[int] = set(hull)
    nh = len(hull)
    cands: list[tuple[int, int, int]] = []      # (vertex, bridge end a, bridge end b)
    for k in range(nh):
        a = hull[k]
        b = hull[(k + 1) % nh]
        gap = (b - a) % n
        if gap < 2:
            continue
        chain = plist[a:a + gap + 1] if a + gap < n else plist[a:] + plist[:a + gap + 1 - n]
        cand, ends = _pocket_candidates(chain, tau, 0, max_depth)
        feats.update((a + i) % n for i in ends)
        cands += [((a + c) % n, a, b) for c in cand]
    if not cands:
        return [], sorted(feats)
    idx = np.array(cands, dtype=np.intp)
    conc = point_segment_dists(pts[idx[:, 0]], pts[idx[:, 1]], pts[idx[:, 2]]).tolist()
    notches: list[tuple[int, float]] = []
    for (i, _a, _b), c in zip(cands, conc):
        if c >= tau:
            notches.append((i, c))
            feats.add(i)
    return notches, sorted(feats)


# ------------------------------------------------------------------------ notches: holes


def hole_features(ring: Ring, tau: float
                   ) -> tuple[bool, list[tuple[int, float]], list[int]]:
    """Noise test and notches of one hole (§7; every hole treated as nearly convex).

    Returns
    -------
    structural : bool
        False when the hole is noise (``min(D, W) < tau``).
    notches : list of (index, concavity)
    features : list of int
    """
    pts = ring.pts
    h = hull_indices(pts)
    hp = pts[h]
    diff = hp[:, None, :] - hp[None, :, :]
    d2 = np.einsum("ijk,ijk->ij", diff, diff)
    i1, i2 = np.unravel_index(int(np.argmax(d2)), d2.shape)
    m1, m2 = int(h[i1]), int(h[i2])
    diam = math.sqrt(float(d2[i1, i2]))
    if diam <= 0:
        return False, [], []
    a, b = pts[m1], pts[m2]
    ab = (b - a) / diam
    off = (pts - a) @ np.array([-ab[1], ab[0]])
    width = 2.0 * float(np.max(np.abs(off)))
    if min(diam, width) < tau:
        return False, [], []
    n = len(pts)
    notches = [(m1, diam), (m2, diam)]
    feats = {m1, m2}
    for s, e in ((m1, m2), (m2, m1)):
        gap = (e - s) % n
        idx = (s + np.arange(gap + 1)) % n
        for k in dp_keep(pts[idx], tau)[1:-1]:
            j = int(idx[k])
            feats.add(j)
            dist = abs(float(off[j]))
            if dist > tau:
                notches.append((j, dist))
    return True, notches, sorted(feats)

