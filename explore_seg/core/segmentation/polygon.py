"""Plane geometry of the DuDe polygon stage, in pixel units: areas, distances,
Douglas-Peucker, convex hull membership and segment crossings."""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

#: Points closer than this to a convex hull edge are on the hull (px).
HULL_TOL_PX = 0.5


def signed_area(pts: npt.NDArray[np.float64]) -> float:
    x, y = pts[:, 0], pts[:, 1]
    xn = np.concatenate([x[1:], x[:1]])
    yn = np.concatenate([y[1:], y[:1]])
    return 0.5 * float(np.dot(x, yn) - np.dot(y, xn))


def point_segment_dist(p: npt.NDArray[np.float64], a: npt.NDArray[np.float64],
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


def point_segment_dists(p: npt.NDArray[np.float64], a: npt.NDArray[np.float64],
                        b: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Distances of points ``p`` (N, 2) to their own segments a-b (N, 2 each).

    Row by row the operations of :func:`point_segment_dist` (for integer coordinates
    the same values; its dot product is then exact).
    """
    abx, aby = b[:, 0] - a[:, 0], b[:, 1] - a[:, 1]
    den = abx * abx + aby * aby
    px, py = p[:, 0] - a[:, 0], p[:, 1] - a[:, 1]
    ok = den > 1e-12
    t = np.clip((px * abx + py * aby) / np.where(ok, den, 1.0), 0.0, 1.0)
    qx = a[:, 0] + t * abx
    qy = a[:, 1] + t * aby
    d = np.hypot(p[:, 0] - qx, p[:, 1] - qy)
    return np.where(ok, d, np.hypot(px, py))


def seg_dist(p: npt.NDArray[np.float64], a: npt.NDArray[np.float64],
              b: npt.NDArray[np.float64]) -> float:
    return float(point_segment_dist(p, a, b)[0])


def seg_dist_xy(px: float, py: float, ax: float, ay: float, bx: float, by: float
                ) -> float:
    """Distance of the point (px, py) to the segment a-b, in plain Python floats.

    The same arithmetic as :func:`point_segment_dist` except for the final square root
    (``math.hypot``, which may differ from ``numpy.hypot`` in the last bit): for
    threshold tests, not for picking the largest of several distances.
    """
    abx, aby = bx - ax, by - ay
    den = abx * abx + aby * aby
    if den <= 1e-12:
        return math.hypot(px - ax, py - ay)
    t = ((px - ax) * abx + (py - ay) * aby) / den
    t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
    return math.hypot(px - (ax + t * abx), py - (ay + t * aby))


#: Up to this many points (integer coordinates), :func:`dp_keep` runs in plain Python.
_SMALL_DP = 48


def dp_keep(pts: npt.NDArray[np.float64], eps: float) -> npt.NDArray[np.intp]:
    """Douglas-Peucker on an open polyline; indices of the kept vertices (ends kept)."""
    n = len(pts)
    if n <= 2:
        return np.arange(n)
    if n <= _SMALL_DP and bool(np.all(pts == np.rint(pts))):
        return np.array(_dp_keep_small(pts.tolist(), eps), dtype=np.intp)
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        d = point_segment_dist(pts[i + 1:j], pts[i], pts[j])
        k = int(np.argmax(d))
        if d[k] > eps:
            m = i + 1 + k
            keep[m] = True
            stack.append((i, m))
            stack.append((m, j))
    return np.flatnonzero(keep)


def _dp_keep_small(p: list[list[float]], eps: float) -> list[int]:
    """:func:`dp_keep` of a few integer points, with the same result.

    The offsets to the nearest segment points are computed with the operations of
    :func:`point_segment_dist` (the dot products of integers are exact), the farthest
    point is found on squared lengths, and ``numpy.hypot`` decides among the points
    within rounding of the largest (ties go to the first, as ``argmax`` does).
    """
    n = len(p)
    keep = [False] * n
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        ax, ay = p[i]
        bx, by = p[j]
        abx, aby = bx - ax, by - ay
        den = abx * abx + aby * aby
        dxs, dys, sq = [], [], []
        for k in range(i + 1, j):
            px, py = p[k]
            if den <= 1e-12:
                dx, dy = px - ax, py - ay
            else:
                t = ((px - ax) * abx + (py - ay) * aby) / den
                t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
                dx, dy = px - (ax + t * abx), py - (ay + t * aby)
            dxs.append(dx)
            dys.append(dy)
            sq.append(dx * dx + dy * dy)
        top = max(sq)
        near = [k for k, s in enumerate(sq) if s >= top * (1.0 - 1e-9)]
        e2 = eps * eps
        if len(near) == 1 and (top > e2 * (1.0 + 1e-9) or top < e2 * (1.0 - 1e-9)):
            # one farthest point, clearly on one side of eps: no rounding question
            b, far = 0, top > e2
        else:
            d = np.hypot(np.array([dxs[k] for k in near]), np.array([dys[k] for k in near]))
            b = int(np.argmax(d))
            far = float(d[b]) > eps
        if far:
            m = i + 1 + near[b]
            keep[m] = True
            stack.append((i, m))
            stack.append((m, j))
    return [k for k in range(n) if keep[k]]


def hull_indices(pts: npt.NDArray[np.float64], tol: float = HULL_TOL_PX
                  ) -> npt.NDArray[np.intp]:
    """Indices of the points on the convex hull boundary of ``pts``, sorted ascending.

    Points within ``tol`` of a hull edge count as on the hull, so collinear runs (the
    straight outer wall of a row of rooms) do not merge several pockets into one.

    Every point lies inside the hull, where the distance to the hull boundary is the
    smallest distance to the lines through the hull edges; the test ``|cross| <= tol *
    |edge|`` is done squared (exact for the integer pixel coordinates of traced rings).
    """
    n = len(pts)
    if n < 3:
        return np.arange(n)
    if n <= _SMALL_HULL:
        out = _hull_on_small(pts.tolist(), tol)
        if out is not None:
            return np.array(out, dtype=np.intp)
    h = np.asarray(cv2.convexHull(pts.astype(np.float32).reshape(-1, 1, 2),
                                  returnPoints=False)).ravel()
    if len(h) < 3:
        return np.unique(h)
    a = pts[h]
    ab = np.empty_like(a)
    ab[:-1] = a[1:] - a[:-1]
    ab[-1] = a[0] - a[-1]
    len2 = ab[:, 0] * ab[:, 0] + ab[:, 1] * ab[:, 1]
    c = ab[:, 0] * a[:, 1] - ab[:, 1] * a[:, 0]
    cross = np.multiply.outer(pts[:, 1], ab[:, 0])
    cross -= np.multiply.outer(pts[:, 0], ab[:, 1])
    cross -= c
    on = (cross * cross <= (tol * tol) * len2).any(axis=1)
    on[h] = True
    return np.flatnonzero(on)


def hull_indices_list(p: list[list[float]], tol: float = HULL_TOL_PX) -> list[int]:
    """:func:`hull_indices` of points given as a list of ``[x, y]`` (a list result)."""
    if len(p) < 3:
        return list(range(len(p)))
    if len(p) <= _SMALL_HULL:
        out = _hull_on_small(p, tol)
        if out is not None:
            return out
    return hull_indices(np.array(p, dtype=np.float64), tol).tolist()


def dp_keep_list(p: list[list[float]], eps: float) -> list[int]:
    """:func:`dp_keep` of points with integer coordinates given as a list of ``[x, y]``."""
    if len(p) <= 2:
        return list(range(len(p)))
    if len(p) <= _SMALL_DP:
        return _dp_keep_small(p, eps)
    return dp_keep(np.array(p, dtype=np.float64), eps).tolist()


#: Up to this many points, :func:`hull_indices` runs in plain Python (numpy's per-call
#: overhead dominates on the short pocket chains).
_SMALL_HULL = 24


def _hull_on_small(p: list[list[float]], tol: float) -> list[int] | None:
    """:func:`hull_indices` of a few points (monotone chain); None when the hull is flat."""
    if len(p) == 3:
        (ax, ay), (bx, by), (cx, cy) = p
        if (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) != 0:
            return [0, 1, 2]
        return None
    order = sorted(range(len(p)), key=lambda i: (p[i][0], p[i][1]))

    def half(idx):
        chain: list[int] = []
        for i in idx:
            x, y = p[i]
            while len(chain) >= 2:
                ox, oy = p[chain[-2]]
                ax, ay = p[chain[-1]]
                if (ax - ox) * (y - oy) - (ay - oy) * (x - ox) > 0:
                    break
                chain.pop()
            chain.append(i)
        return chain

    lower = half(order)
    upper = half(order[::-1])
    hull = lower[:-1] + upper[:-1]
    if len(hull) < 3:
        return None
    t2 = tol * tol
    edges = []
    for k in range(len(hull)):
        ax, ay = p[hull[k]]
        bx, by = p[hull[(k + 1) % len(hull)]]
        ex, ey = bx - ax, by - ay
        edges.append((ex, ey, ex * ay - ey * ax, t2 * (ex * ex + ey * ey)))
    on = set(hull)
    for i, (x, y) in enumerate(p):
        if i in on:
            continue
        for ex, ey, c, lim in edges:
            cr = y * ex - x * ey - c
            if cr * cr <= lim:
                on.add(i)
                break
    return sorted(on)


def crosses_any(a0: npt.NDArray[np.float64], a1: npt.NDArray[np.float64],
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

