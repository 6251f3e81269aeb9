"""Plane geometry of the DuDe polygon stage, in pixel units: areas, distances,
Douglas-Peucker, convex hull membership and segment crossings."""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

#: Points closer than this to a convex hull edge are on the hull (px).
HULL_TOL_PX = 0.5


def signed_area(pts: npt.NDArray[np.float64]) -> float:
    x, y = pts[:, 0], pts[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


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


def seg_dist(p: npt.NDArray[np.float64], a: npt.NDArray[np.float64],
              b: npt.NDArray[np.float64]) -> float:
    return float(point_segment_dist(p, a, b)[0])


def dp_keep(pts: npt.NDArray[np.float64], eps: float) -> npt.NDArray[np.intp]:
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
        d = point_segment_dist(pts[i + 1:j], pts[i], pts[j])
        k = int(np.argmax(d))
        if d[k] > eps:
            m = i + 1 + k
            keep[m] = True
            stack.append((i, m))
            stack.append((m, j))
    return np.flatnonzero(keep)


def hull_indices(pts: npt.NDArray[np.float64], tol: float = HULL_TOL_PX
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

