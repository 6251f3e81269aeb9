"""Dual-Space Decomposition (DuDe) of a free-space mask into nearly convex pieces.

Polygon stage of the room segmentation (DuDe spec shared/docs/dude.md §5-§9), with the raster shortcut of
§9.5: the cuts chosen for a piece are drawn into its mask as 4-connected lines of
"wall" cells, the mask is split into its 4-connected components, and every component is
decomposed again until it yields no cut.

All geometry here is in pixel units of the cropped mask: points are ``(x, y) = (col,
row)`` pixel centres, treated as a right-handed plane (the outer ring has positive
shoelace area, holes negative), so the interior of the free space lies on the left of
every ring. Nothing here knows about metres or maps; :mod:`.segmentation` converts.

Simplifications with respect to the library the spec describes (each one documented at
the function doing it):

* pocket tree: nested hulls of the pocket chains instead of a recursive cut search
  inside each pocket (:func:`_pocket_candidates`);
* holes: every structural hole is treated as nearly convex (§7.2), so L/U-shaped
  islands get the extreme-point notches only (:func:`_hole_features`);
* candidates: instead of the edges of a constrained Delaunay triangulation, every cut
  from a notch to another notch, to a ring vertex or to the foot of the perpendicular
  on a ring edge that stays inside the free space (raster test) is a candidate; the
  far end of a cut therefore need not be a polygon vertex, which lets a door jamb be
  cut straight across to a flat wall. Non-crossing is enforced in the choice;
* choice: the greedy version recommended in §8.3 instead of the knapsack table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

_TWO_PI = 2.0 * math.pi
#: Angular slack (rad) when testing whether a cut direction lies inside a wedge.
_ANGLE_EPS = 1e-6
#: Points closer than this to a convex hull edge are on the hull (px).
_HULL_TOL_PX = 0.5
#: Sample spacing (px) of the raster visibility test of a cut.
_SAMPLE_STEP_PX = 0.5
#: A cut whose interior samples are on the piece border for more than this fraction
#: runs along the boundary and separates nothing.
_MAX_BORDER_FRACTION = 0.5


@dataclass(frozen=True)
class DudeSettings:
    """Pixel-unit settings of the decomposition (built by :mod:`.segmentation`).

    Parameters
    ----------
    tau_px : float
        Maximum concavity tau, in pixels (> 0).
    simplify_eps_px : float
        Douglas-Peucker tolerance applied to every traced ring (>= 0).
    min_hole_area_px : float
        Holes (obstacle islands) of at most this area are ignored entirely.
    min_component_px : int
        Components smaller than this are final pieces without decomposition.
    max_rounds : int
        Bound on the decomposition rounds of one piece (>= 1).
    max_tip_candidates : int
        For every notch, at most this many nearest plain boundary points are tested as
        far ends of a cut.
    max_notch_candidates : int
        For every notch, at most this many nearest other notches are tested.
    sliver_factor : float
        A cut whose ends are within ``sliver_factor * tau`` of each other along their
        ring is a sliver cut and is not used (§9.2).
    max_pocket_depth : int
        Bound on the nesting depth of the pocket tree.
    max_pieces : int
        Bound on the number of pieces processed for one mask (safety net).
    """

    tau_px: float
    simplify_eps_px: float = 1.5
    min_hole_area_px: float = 5.0
    min_component_px: int = 400
    max_rounds: int = 16
    max_tip_candidates: int = 24
    max_notch_candidates: int = 16
    sliver_factor: float = 2.0
    max_pocket_depth: int = 6
    max_pieces: int = 20000

    def __post_init__(self) -> None:
        if not (math.isfinite(self.tau_px) and self.tau_px > 0):
            raise ValueError(f"tau_px must be finite and > 0, got {self.tau_px}")
        if not self.simplify_eps_px >= 0:
            raise ValueError(f"simplify_eps_px must be >= 0, got {self.simplify_eps_px}")
        if self.max_rounds < 1:
            raise ValueError(f"max_rounds must be >= 1, got {self.max_rounds}")


# ----------------------------------------------------------------------------- geometry


def _signed_area(pts: npt.NDArray[np.float64]) -> float:
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _point_segment_dist(p: npt.NDArray[np.float64], a: npt.NDArray[np.float64],
                        b: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Distances of points ``p`` (N, 2) (or one point) to the segment a-b."""
    p = np.atleast_2d(p)
    ab = b - a
    den = float(ab @ ab)
    if den <= 1e-12:
        return np.hypot(p[:, 0] - a[0], p[:, 1] - a[1])
    t = np.clip(((p - a) @ ab) / den, 0.0, 1.0)
    q = a + t[:, None] * ab
    return np.hypot(p[:, 0] - q[:, 0], p[:, 1] - q[:, 1])


def _seg_dist(p: npt.NDArray[np.float64], a: npt.NDArray[np.float64],
              b: npt.NDArray[np.float64]) -> float:
    return float(_point_segment_dist(p, a, b)[0])


def _dp_keep(pts: npt.NDArray[np.float64], eps: float) -> npt.NDArray[np.intp]:
    """Douglas-Peucker on an open polyline; indices of the kept vertices (ends kept)."""
    n = len(pts)
    if n <= 2:
        return np.arange(n)
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        d = _point_segment_dist(pts[i + 1:j], pts[i], pts[j])
        k = int(np.argmax(d))
        if d[k] > eps:
            m = i + 1 + k
            keep[m] = True
            stack.append((i, m))
            stack.append((m, j))
    return np.flatnonzero(keep)


def _hull_indices(pts: npt.NDArray[np.float64], tol: float = _HULL_TOL_PX
                  ) -> npt.NDArray[np.intp]:
    """Indices of the points on the convex hull boundary of ``pts``, sorted ascending.

    Points within ``tol`` of a hull edge count as on the hull, so collinear runs (the
    straight outer wall of a row of rooms) do not merge several pockets into one.
    """
    n = len(pts)
    if n < 3:
        return np.arange(n)
    h = np.asarray(cv2.convexHull(pts.astype(np.float32).reshape(-1, 1, 2),
                                  returnPoints=False)).ravel()
    if len(h) < 3:
        return np.unique(h)
    a = pts[h]
    b = np.roll(a, -1, axis=0)
    ab = b - a
    den = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12)
    ap = pts[:, None, :] - a[None, :, :]                       # (n, nh, 2)
    t = np.clip(np.einsum("ijk,jk->ij", ap, ab) / den, 0.0, 1.0)
    q = a[None, :, :] + t[..., None] * ab[None, :, :]
    d = np.hypot(pts[:, None, 0] - q[..., 0], pts[:, None, 1] - q[..., 1]).min(axis=1)
    on = d <= tol
    on[h] = True
    return np.flatnonzero(on)


def _crosses_any(a0: npt.NDArray[np.float64], a1: npt.NDArray[np.float64],
                 b0: npt.NDArray[np.float64], b1: npt.NDArray[np.float64]) -> bool:
    """True when segment a0-a1 properly crosses one of the segments b0-b1 (K, 2).

    Segments sharing an end point do not count as crossing.
    """
    shared = (np.all(np.abs(b0 - a0) < 1e-9, axis=1) | np.all(np.abs(b0 - a1) < 1e-9, axis=1)
              | np.all(np.abs(b1 - a0) < 1e-9, axis=1) | np.all(np.abs(b1 - a1) < 1e-9, axis=1))

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) \
            - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0])

    d1, d2 = orient(b0, b1, a0), orient(b0, b1, a1)
    d3, d4 = orient(a0, a1, b0), orient(a0, a1, b1)
    return bool(np.any((d1 * d2 < 0) & (d3 * d4 < 0) & ~shared))


# -------------------------------------------------------------------------------- rings


@dataclass
class _Ring:
    pts: npt.NDArray[np.float64]          # (n, 2) simplified, oriented (interior left)
    raw: npt.NDArray[np.int32]            # OpenCV contour (for filling)
    is_hole: bool
    arc: npt.NDArray[np.float64] = field(init=False)   # arc length at each vertex
    perimeter: float = field(init=False)

    def __post_init__(self) -> None:
        seg = np.hypot(*(np.roll(self.pts, -1, axis=0) - self.pts).T)
        self.arc = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
        self.perimeter = float(seg.sum())


@dataclass
class _Notch:
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
    keep = np.any(pts != np.roll(pts, 1, axis=0), axis=1)
    pts = pts[keep]
    if len(pts) < 3:
        return None
    area = _signed_area(pts)
    if area == 0:
        return None
    if (area > 0) != want_positive:
        pts = pts[::-1].copy()
    return pts


def _trace_rings(mask: npt.NDArray[np.uint8], st: DudeSettings
                 ) -> tuple[_Ring | None, list[_Ring]]:
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
    outer = _Ring(pts, contours[top], False)
    holes: list[_Ring] = []
    child = hier[top][2]
    guard = 0
    while child >= 0 and guard < len(contours):
        guard += 1
        c = contours[child]
        if abs(cv2.contourArea(c)) > st.min_hole_area_px:
            hp = _simplify_ring(c, st.simplify_eps_px, False)
            if hp is not None:
                holes.append(_Ring(hp, c, True))
        child = hier[child][0]
    return outer, holes


# ------------------------------------------------------------------- notches: outer ring


def _pocket_candidates(pts: npt.NDArray[np.float64], ring_idx: npt.NDArray[np.intp],
                       tau: float, depth: int, max_depth: int
                       ) -> tuple[list[int], list[int]]:
    """Notch candidates (ring indices) of one pocket chain and its nested dents.

    ``pts`` is the pocket chain from one bridge end to the other. Its convex hull gives
    the chain's extreme points (own candidates, simplified with 0.75 tau). Between two
    consecutive hull vertices the free space bulges into the pocket; the hull of such a
    bulge has its own dents, which are searched recursively (simplified pocket tree:
    nested hulls instead of a cut search inside the pocket). An own candidate is a
    shallow bump and dropped when it lies within tau/2 of the segment joining its
    neighbours among the chain ends, kids' bridge ends, kids' notches and own
    candidates (§6.3.6).

    Returns
    -------
    notches : list of int
        Ring indices of the candidates kept at this level and below.
    bridge_ends : list of int
        Ring indices of the bridge ends of the dents that produced candidates.
    """
    m = len(pts)
    if m < 3 or depth > max_depth:
        return [], []
    h = _hull_indices(pts)
    h = np.union1d(h, [0, m - 1])
    hk = _dp_keep(pts[h], 0.75 * tau)
    own = [int(h[k]) for k in hk if 0 < h[k] < m - 1]
    kid_notches: list[int] = []      # local chain indices
    kid_ends: list[int] = []
    for a, b in zip(h[:-1], h[1:]):
        if b - a < 2:
            continue
        bulge = pts[a:b + 1]
        hb = np.union1d(_hull_indices(bulge), [0, len(bulge) - 1])
        for c, d in zip(hb[:-1], hb[1:]):
            if d - c < 2:
                continue
            lo, hi = a + c, a + d
            sub, sub_ends = _pocket_candidates(pts[lo:hi + 1], np.arange(lo, hi + 1),
                                               tau, depth + 1, max_depth)
            if sub:
                kid_notches.extend(sub)
                kid_ends.extend([lo, hi] + sub_ends)
    walk = sorted(set([0, m - 1] + kid_ends + kid_notches + own))
    pos = {k: i for i, k in enumerate(walk)}
    kept = []
    for k in own:
        i = pos[k]
        if i == 0 or i == len(walk) - 1:
            continue
        if _seg_dist(pts[k], pts[walk[i - 1]], pts[walk[i + 1]]) > 0.5 * tau:
            kept.append(k)
    local = sorted(set(kept + kid_notches))
    return ([int(ring_idx[k]) for k in local],
            [int(ring_idx[k]) for k in set(kid_ends)])


def _outer_features(ring: _Ring, tau: float, max_depth: int
                    ) -> tuple[list[tuple[int, float]], list[int]]:
    """Notches ``(index, concavity)`` and feature indices of the outer ring (§6)."""
    pts = ring.pts
    n = len(pts)
    hull = _hull_indices(pts)
    if len(hull) < 3:
        return [], list(range(n))
    notches: list[tuple[int, float]] = []
    feats: set[int] = set(int(i) for i in hull)
    nh = len(hull)
    for k in range(nh):
        a = int(hull[k])
        b = int(hull[(k + 1) % nh])
        gap = (b - a) % n
        if gap < 2:
            continue
        chain_idx = (a + np.arange(gap + 1)) % n
        chain = pts[chain_idx]
        cand, ends = _pocket_candidates(chain, chain_idx, tau, 0, max_depth)
        feats.update(ends)
        for i in cand:
            conc = _seg_dist(pts[i], pts[a], pts[b])
            if conc >= tau:
                notches.append((i, conc))
                feats.add(i)
    return notches, sorted(feats)


# ------------------------------------------------------------------------ notches: holes


def _hole_features(ring: _Ring, tau: float
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
    h = _hull_indices(pts)
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
        for k in _dp_keep(pts[idx], tau)[1:-1]:
            j = int(idx[k])
            feats.add(j)
            dist = abs(float(off[j]))
            if dist > tau:
                notches.append((j, dist))
    return True, notches, sorted(feats)


# ------------------------------------------------------------------------- cut support


def _wedge(notch: _Notch, ring: _Ring, feats: list[int]) -> bool:
    """Set the feature wedge p-v-n of a notch; False when it is not reflex."""
    n = len(ring.pts)
    if len(feats) >= 3:
        arr = np.asarray(feats)
        pos = int(np.searchsorted(arr, notch.idx))
        nxt = int(arr[(pos + 1) % len(arr)]) if pos < len(arr) and arr[pos] == notch.idx \
            else int(arr[pos % len(arr)])
        prv = int(arr[pos - 1])
    else:
        nxt, prv = (notch.idx + 1) % n, (notch.idx - 1) % n
    notch.p = ring.pts[prv]
    notch.n = ring.pts[nxt]
    dn = notch.n - notch.pt
    dp = notch.p - notch.pt
    notch.a_n = math.atan2(dn[1], dn[0])
    notch.interior = (math.atan2(dp[1], dp[0]) - notch.a_n) % _TWO_PI
    return notch.interior > math.pi + _ANGLE_EPS


def _resolves(v: _Notch, ends: list[npt.NDArray[np.float64]], tau: float) -> bool:
    """True when cuts from ``v`` to ``ends`` (one or two points) resolve ``v`` (§8.2)."""
    rel = []
    for u in ends:
        d = u - v.pt
        w = (math.atan2(d[1], d[0]) - v.a_n) % _TWO_PI
        if w <= _ANGLE_EPS or w >= v.interior - _ANGLE_EPS:
            return False
        rel.append((w, u))
    rel.sort(key=lambda t: t[0])
    bounds = [(0.0, v.n)] + rel + [(v.interior, v.p)]
    for (w0, q0), (w1, q1) in zip(bounds[:-1], bounds[1:]):
        if w1 - w0 >= math.pi and _seg_dist(v.pt, q0, q1) > tau:
            return False
    return True


def _segments_clear(vis: npt.NDArray[np.bool_], border: npt.NDArray[np.bool_],
                    p0: npt.NDArray[np.float64], p1: npt.NDArray[np.float64],
                    min_len: float) -> npt.NDArray[np.bool_]:
    """Raster test of segments p0-p1 (N, 2): inside ``vis`` and not along its border."""
    n = len(p0)
    if n == 0:
        return np.zeros(0, dtype=bool)
    d = p1 - p0
    length = np.hypot(d[:, 0], d[:, 1])
    ns = np.maximum(2, np.ceil(length / _SAMPLE_STEP_PX).astype(np.int64))
    seg = np.repeat(np.arange(n), ns)
    start = np.cumsum(ns) - ns
    k = np.arange(int(ns.sum())) - np.repeat(start, ns)
    t = (k + 0.5) / ns[seg]
    xy = p0[seg] + t[:, None] * d[seg]
    c = np.clip(np.rint(xy[:, 0]).astype(np.int64), 0, vis.shape[1] - 1)
    r = np.clip(np.rint(xy[:, 1]).astype(np.int64), 0, vis.shape[0] - 1)
    outside = np.bincount(seg, weights=~vis[r, c], minlength=n)
    onb = np.bincount(seg, weights=border[r, c], minlength=n) / ns
    return (outside == 0) & (onb <= _MAX_BORDER_FRACTION) & (length >= min_len)


@dataclass
class _End:
    pt: npt.NDArray[np.float64]
    ring: int
    arc: float                 # arc position on its ring
    notch: int                 # index into the notch list, -1 for a plain point
    length: float = 0.0


@dataclass
class _CutSet:
    owner: int
    cuts: list[tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]
    resolves: set[int]
    weight: float
    far: set[int] = field(default_factory=set)     # notches at the far ends


class _Boundary:
    """All ring vertices and edges of a piece in flat arrays (built once per round)."""

    def __init__(self, rings: list[_Ring]) -> None:
        self.pts = np.concatenate([r.pts for r in rings])
        self.ring = np.concatenate([np.full(len(r.pts), k) for k, r in enumerate(rings)])
        self.idx = np.concatenate([np.arange(len(r.pts)) for r in rings])
        self.arc = np.concatenate([r.arc for r in rings])
        self.size = np.concatenate([np.full(len(r.pts), len(r.pts)) for r in rings])
        nxt = np.concatenate([np.roll(r.pts, -1, axis=0) for r in rings])
        self.ab = nxt - self.pts
        self.den = np.einsum("ij,ij->i", self.ab, self.ab)
        self.len = np.sqrt(self.den)
        self.perimeter = np.array([r.perimeter for r in rings])


def _far_ends(v: _Notch, vi: int, notches: list[_Notch], rings: list[_Ring],
              bd: _Boundary, st: DudeSettings) -> tuple[list[_End], list[_End]]:
    """Candidate far ends of cuts from notch ``v``: other notches and plain points.

    Plain points are the ring vertices and the feet of the perpendiculars from ``v`` on
    the ring edges that face it; the ``max_tip_candidates`` nearest are returned. Ends
    whose cut would be a sliver cut (§9.2) are skipped.
    """
    tau = st.tau_px
    per = float(rings[v.ring].perimeter)
    va = float(rings[v.ring].arc[v.idx])
    limit = st.sliver_factor * tau

    def not_sliver(ring: npt.NDArray[np.intp], arc: npt.NDArray[np.float64]
                   ) -> npt.NDArray[np.bool_]:
        dd = np.abs(arc - va) % per if per > 0 else np.zeros_like(arc)
        return (ring != v.ring) | (np.minimum(dd, per - dd) > limit)

    notch_ends = []
    for j, u in enumerate(notches):
        if j == vi or (u.ring == v.ring and u.idx == v.idx):
            continue
        notch_ends.append(_End(u.pt, u.ring, float(rings[u.ring].arc[u.idx]), j,
                               float(np.hypot(*(u.pt - v.pt)))))
    notch_ends.sort(key=lambda e: e.length)
    notch_ends = [e for e in notch_ends[:st.max_notch_candidates]
                  if not_sliver(np.array([e.ring]), np.array([e.arc]))[0]]
    # ring vertices, not v itself nor its ring neighbours
    same = bd.ring == v.ring
    near_v = same & (((bd.idx - v.idx) % bd.size <= 1) | ((v.idx - bd.idx) % bd.size <= 1))
    # perpendicular feet on edges facing v (v on the interior = left side)
    rel = v.pt - bd.pts
    ok = bd.den > 1e-12
    t = np.where(ok, np.einsum("ij,ij->i", rel, bd.ab) / np.where(ok, bd.den, 1.0), -1.0)
    cross = bd.ab[:, 0] * rel[:, 1] - bd.ab[:, 1] * rel[:, 0]
    own_edge = same & ((bd.idx == v.idx) | ((bd.idx + 1) % bd.size == v.idx))
    sel = ok & (t > 0.0) & (t < 1.0) & (cross > 0) & ~own_edge
    P = np.concatenate([bd.pts[~near_v], bd.pts[sel] + t[sel, None] * bd.ab[sel]])
    R = np.concatenate([bd.ring[~near_v], bd.ring[sel]])
    A = np.concatenate([bd.arc[~near_v], bd.arc[sel] + t[sel] * bd.len[sel]])
    L = np.hypot(P[:, 0] - v.pt[0], P[:, 1] - v.pt[1])
    keep = (L >= 1.0) & not_sliver(R, A)
    P, R, A, L = P[keep], R[keep], A[keep], L[keep]
    k = st.max_tip_candidates
    if len(L) > k:
        part = np.argpartition(L, k)[:k]
        P, R, A, L = P[part], R[part], A[part], L[part]
    order = np.argsort(L, kind="stable")
    tips = [_End(P[i], int(R[i]), float(A[i]), -1, float(L[i])) for i in order]
    return notch_ends, tips


def _cut_sets(notches: list[_Notch], rings: list[_Ring], vis: npt.NDArray[np.bool_],
              border: npt.NDArray[np.bool_], st: DudeSettings) -> list[_CutSet]:
    """Cut sets of every notch with their weights (§8.2)."""
    tau = st.tau_px
    sets: list[_CutSet] = []
    bd = _Boundary(rings)
    for vi, v in enumerate(notches):
        notch_ends, tips = _far_ends(v, vi, notches, rings, bd, st)
        ends = notch_ends + tips
        if not ends:
            continue
        P1 = np.array([e.pt for e in ends])
        P0 = np.repeat(v.pt[None, :], len(ends), axis=0)
        clear = _segments_clear(vis, border, P0, P1, 1.5)
        vis_ends = [e for e, c in zip(ends, clear) if c]
        if not vis_ends:
            continue

        def weight_of(cut_ends: list[_End], res_v: bool) -> tuple[set[int], float]:
            resolved = {vi} if res_v else set()
            total = v.conc if res_v else 0.5 * v.conc
            length = 0.0
            for e in cut_ends:
                length += max(e.length, 1.0)
                if e.notch >= 0:
                    u = notches[e.notch]
                    if _resolves(u, [v.pt], tau):
                        resolved.add(e.notch)
                        total += u.conc
                    else:
                        total += 0.5 * u.conc
            return resolved, total / length

        singles_res = [(_resolves(v, [e.pt], tau), e) for e in vis_ends]
        best_tip = None
        any_res = False
        for res, e in singles_res:
            if e.notch >= 0:
                resolved, w = weight_of([e], res)
                sets.append(_CutSet(vi, [(v.pt, e.pt)], resolved, w, {e.notch}))
                any_res |= res
            elif res and (best_tip is None or e.length < best_tip.length):
                best_tip = e
        if best_tip is not None:
            resolved, w = weight_of([best_tip], True)
            sets.append(_CutSet(vi, [(v.pt, best_tip.pt)], resolved, w))
            any_res = True
        if any_res:
            continue
        # pairs of cuts: the shortest pair that resolves v jointly
        short = sorted(vis_ends, key=lambda e: e.length)[:8]
        best_pair = None
        for i in range(len(short)):
            for j in range(i + 1, len(short)):
                e1, e2 = short[i], short[j]
                tot = e1.length + e2.length
                if best_pair is not None and tot >= best_pair[0]:
                    continue
                if _resolves(v, [e1.pt, e2.pt], tau):
                    best_pair = (tot, e1, e2)
        if best_pair is not None:
            resolved, w = weight_of([best_pair[1], best_pair[2]], True)
            far = {e.notch for e in best_pair[1:] if e.notch >= 0}
            sets.append(_CutSet(vi, [(v.pt, best_pair[1].pt), (v.pt, best_pair[2].pt)],
                                resolved, w, far))
            continue
        # nothing resolves v: keep the single cut with the best weight anyway (a cut to a
        # notch is in ``sets`` already, with this weight: every single resolved nothing)
        best, best_end = None, None
        for res, e in singles_res:
            resolved, w = weight_of([e], False)
            if best is None or w > best.weight:
                best = _CutSet(vi, [(v.pt, e.pt)], resolved, w,
                               {e.notch} if e.notch >= 0 else set())
                best_end = e
        if best is not None and best_end is not None and best_end.notch < 0:
            sets.append(best)
    return sets


def _choose(sets: list[_CutSet]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Greedy choice of cut sets (§8.3, the recommended simplification of the knapsack).

    Highest weight first, a set is accepted when it resolves a still unresolved notch,
    is not a second set of an accepted owner and crosses no accepted cut; then every
    notch still unresolved gets its best non-crossing set; finally sets whose notches
    are all resolved by others are removed, lowest weight first.
    """
    order = sorted(range(len(sets)), key=lambda i: -sets[i].weight)
    accepted: list[int] = []
    resolved: set[int] = set()

    acc_cuts: list[tuple[np.ndarray, np.ndarray]] = []

    def conflicts(i: int) -> bool:
        # same owner; a cut ending at the notch of an accepted set (that cut is one of
        # that notch's own sets too); crossing cuts
        si = sets[i]
        for j in accepted:
            sj = sets[j]
            if si.owner == sj.owner or sj.owner in si.far or si.owner in sj.far:
                return True
        if not acc_cuts:
            return False
        b0 = np.array([c[0] for c in acc_cuts])
        b1 = np.array([c[1] for c in acc_cuts])
        return any(_crosses_any(a0, a1, b0, b1) for a0, a1 in si.cuts)

    def accept(i: int) -> None:
        accepted.append(i)
        acc_cuts.extend(sets[i].cuts)

    for i in order:
        s = sets[i]
        if not (s.resolves - resolved) or conflicts(i):
            continue
        accept(i)
        resolved |= s.resolves
    for i in order:
        s = sets[i]
        if s.owner in resolved or conflicts(i):
            continue
        accept(i)
        resolved |= s.resolves | {s.owner}
    for i in sorted(accepted, key=lambda k: sets[k].weight):
        others = set()
        for j in accepted:
            if j != i:
                others |= sets[j].resolves
        if sets[i].resolves and sets[i].resolves <= others:
            accepted.remove(i)
    cuts: list[tuple[np.ndarray, np.ndarray]] = []
    seen: set[tuple] = set()
    for i in accepted:
        for a, b in sets[i].cuts:
            key = tuple(sorted([(round(a[0], 3), round(a[1], 3)),
                                (round(b[0], 3), round(b[1], 3))]))
            if key in seen:
                continue
            seen.add(key)
            cuts.append((a, b))
    return cuts


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
    outer, holes = _trace_rings(mask, st)
    if outer is None:
        return []
    rings = [outer]
    feats_per_ring: list[list[int]] = []
    raw_notches: list[tuple[int, int, float]] = []
    onotch, ofeat = _outer_features(outer, tau, st.max_pocket_depth)
    feats_per_ring.append(ofeat)
    raw_notches += [(0, i, c) for i, c in onotch]
    noise: list[_Ring] = []
    for hole in holes:
        structural, hn, hf = _hole_features(hole, tau)
        if not structural:
            noise.append(hole)
            continue
        ri = len(rings)
        rings.append(hole)
        feats_per_ring.append(hf)
        raw_notches += [(ri, i, c) for i, c in hn]
    notches: list[_Notch] = []
    for ri, i, c in raw_notches:
        nt = _Notch(ri, i, rings[ri].pts[i].copy(), c)
        if _wedge(nt, rings[ri], feats_per_ring[ri]):
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
    sets = _cut_sets(notches, rings, vis, border, st)
    if not sets:
        return []
    return _choose(sets)


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
