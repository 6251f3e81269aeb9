"""Planar geometry of footprints: rotated rectangles, their orientation from points, and
how much of one a set of points covers (map frame, metres, radians)."""

from __future__ import annotations

import math
from typing import Sequence

import cv2
import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from explore_seg.core.objects.params import ORIENTATION_METHODS


def rect_corners(center_xy: Sequence[float], size_xy: Sequence[float], yaw: float
                 ) -> npt.NDArray[np.float64]:
    """Corners of a rotated rectangle, counter-clockwise, shape (4, 2)."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = 0.5 * float(size_xy[0]), 0.5 * float(size_xy[1])
    local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.asarray(center_xy, dtype=np.float64)[:2]


def points_in_rect(points_xy: npt.NDArray[np.floating], center_xy: Sequence[float],
                   size_xy: Sequence[float], yaw: float, margin_m: float = 0.0
                   ) -> npt.NDArray[np.bool_]:
    """True for points inside a rotated rectangle grown by ``margin_m`` on every side."""
    pts = np.asarray(points_xy, dtype=np.float64)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = pts[:, 0] - center_xy[0], pts[:, 1] - center_xy[1]
    u, v = dx * c + dy * s, -dx * s + dy * c
    return (np.abs(u) <= 0.5 * size_xy[0] + margin_m) & (np.abs(v) <= 0.5 * size_xy[1] + margin_m)


def footprint_orientation(points_xy: npt.NDArray[np.floating], method: str = "min_area_rect",
                          cut: npt.NDArray[np.bool_] | None = None
                          ) -> tuple[tuple[float, float], tuple[float, float], float]:
    """Oriented rectangle around footprint points.

    Parameters
    ----------
    points_xy : ndarray, shape (N, 2), N >= 1
    method : {"min_area_rect", "pca"}
        ``"min_area_rect"``: the minimum-area enclosing rectangle (exact for rectangular
        furniture); ``"pca"``: axes from the principal components of the points (the
        paper; biased when the footprint is sampled unevenly or seen in part).
    cut : ndarray of bool, shape (N,), optional
        ``"min_area_rect"`` only: points where the view cuts the object (image border, an
        occluder in front; :func:`view_cut`). A convex-hull edge between two such points
        is the trace of the view, not a side of the object (a desk top cut by the side of
        the image ends along the ray of that side, and the smallest rectangle turns with
        it); the orientation then comes from the other hull edges, the object's own
        outline (see ``_min_area_yaw``).

    Returns
    -------
    center_xy : tuple of float
        Centre of the rectangle (mid-range along each axis, not the point mean).
    size_xy : tuple of float
        Extents along the rectangle's x axis (direction ``yaw``, the long side) and y axis;
        ``size_xy[0] >= size_xy[1]``.
    yaw : float
        In [-pi/2, pi/2).

    Raises
    ------
    ValueError
        On an empty or non-(N, 2) input or an unknown method.

    Examples
    --------
    >>> pts = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    >>> c, s, yaw = footprint_orientation(pts)
    >>> [round(v, 6) for v in (*c, *s, yaw)]
    [1.0, 0.5, 2.0, 1.0, 0.0]
    """
    pts = np.asarray(points_xy, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0:
        raise ValueError(f"points_xy must have shape (N>=1, 2), got {pts.shape}")
    if method not in ORIENTATION_METHODS:
        raise ValueError(f"method must be one of {ORIENTATION_METHODS}, got {method!r}")
    if method == "min_area_rect" and len(pts) >= 3:
        yaw = _min_area_yaw(pts, cut)
    elif len(pts) >= 2:
        mean = pts.mean(axis=0)
        cov = np.cov((pts - mean).T)
        evals, evecs = np.linalg.eigh(cov)
        major = evecs[:, int(np.argmax(evals))]
        yaw = math.atan2(major[1], major[0])
    else:
        yaw = 0.0
    yaw = wrap_half_pi(yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    u = pts[:, 0] * c + pts[:, 1] * s
    v = -pts[:, 0] * s + pts[:, 1] * c
    um, vm = 0.5 * (u.min() + u.max()), 0.5 * (v.min() + v.max())
    center = (um * c - vm * s, um * s + vm * c)
    size_u, size_v = float(np.ptp(u)), float(np.ptp(v))
    if size_u < size_v:     # canonical: x along the long side
        size_u, size_v, yaw = size_v, size_u, wrap_half_pi(yaw + 0.5 * math.pi)
    return (float(center[0]), float(center[1])), (size_u, size_v), yaw


def _min_area_yaw(pts: npt.NDArray[np.float64], cut: npt.NDArray[np.bool_] | None) -> float:
    """Direction of a side of the rectangle around ``pts`` (N >= 3), see
    :func:`footprint_orientation`.

    Without cut points: the minimum-area rectangle. With them, the footprint's outline is
    partly the view's (an image border's or occluder's trace, along a ray or across the
    view) and the smallest rectangle follows that outline; the object's own outline is the
    convex-hull edges not between two cut points, and on a rectangular object these run
    along two perpendicular directions: the direction (modulo 90 degrees, 2-degree bins,
    +-1 bin) holding the most length of them wins, refined by their length-weighted mean.
    Less than 0.2 m of own outline: the minimum-area rectangle.
    """
    if cut is None or not np.any(cut):
        return math.radians(cv2.minAreaRect(pts.astype(np.float32))[2])
    hull = cv2.convexHull(pts.astype(np.float32), returnPoints=False).reshape(-1)
    cut = np.asarray(cut, dtype=bool)
    nxt = np.roll(hull, -1)
    own = ~(cut[hull] & cut[nxt])
    edge = pts[nxt[own]] - pts[hull[own]]
    length = np.hypot(edge[:, 0], edge[:, 1])
    if len(hull) < 3 or length.sum() < 0.2:
        return math.radians(cv2.minAreaRect(pts.astype(np.float32))[2])
    ang = np.mod(np.arctan2(edge[:, 1], edge[:, 0]), 0.5 * math.pi)
    n_bins = 45
    hist = np.bincount(np.minimum((ang / (0.5 * math.pi) * n_bins).astype(np.int64), n_bins - 1),
                       weights=length, minlength=n_bins)
    smooth = hist + np.roll(hist, 1) + np.roll(hist, -1)
    peak = (int(np.argmax(smooth)) + 0.5) * 0.5 * math.pi / n_bins
    diff = np.mod(ang - peak + 0.25 * math.pi, 0.5 * math.pi) - 0.25 * math.pi
    near = np.abs(diff) <= 1.5 * 0.5 * math.pi / n_bins
    return float(peak + np.sum(diff[near] * length[near]) / np.sum(length[near]))


def wrap_half_pi(yaw: float) -> float:
    """Wrap an axis direction (defined modulo pi) to [-pi/2, pi/2)."""
    return (yaw + 0.5 * math.pi) % math.pi - 0.5 * math.pi


def top_fraction(heights_m: npt.NDArray[np.floating], band_m: float) -> float:
    """Largest share of ``heights_m`` inside any window of height ``band_m``.

    A horizontal top seen by a depth camera gives one dense band of heights; a vertical
    surface spreads its points over all heights. Returns 0 for no points.

    Examples
    --------
    >>> float(top_fraction(np.array([0.70, 0.72, 0.74, 0.3, 0.9]), 0.1))
    0.6
    """
    z = np.sort(np.asarray(heights_m, dtype=np.float64).reshape(-1))
    if z.size == 0:
        return 0.0
    upper = np.searchsorted(z, z + band_m, side="right")
    return float((upper - np.arange(z.size)).max() / z.size)


def top_cover(points_xy: npt.NDArray[np.floating], center_xy: Sequence[float],
              size_xy: Sequence[float], yaw: float, cell_m: float) -> float:
    """Share of a rotated rectangle covered by points (x, y).

    The rectangle is cut into cells of about ``cell_m``; a cell is covered when a point
    lies within ``cell_m`` of its centre. A table top covers its legs' rectangle; legs of
    two tables grouped together leave the floor between them uncovered.

    Parameters
    ----------
    points_xy : ndarray, shape (N, 2)
    center_xy, size_xy : sequence of 2 float
    yaw : float
    cell_m : float
        > 0.

    Returns
    -------
    float
        In [0, 1]; 0 without points.

    Raises
    ------
    ValueError
        If ``cell_m`` is not > 0.
    """
    if not cell_m > 0:
        raise ValueError(f"cell_m must be > 0, got {cell_m}")
    pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return 0.0
    c, s = math.cos(yaw), math.sin(yaw)
    nu = max(int(math.ceil(float(size_xy[0]) / cell_m)), 1)
    nv = max(int(math.ceil(float(size_xy[1]) / cell_m)), 1)
    gu, gv = np.meshgrid(((np.arange(nu) + 0.5) / nu - 0.5) * float(size_xy[0]),
                         ((np.arange(nv) + 0.5) / nv - 0.5) * float(size_xy[1]), indexing="ij")
    cells = np.column_stack([center_xy[0] + gu.ravel() * c - gv.ravel() * s,
                             center_xy[1] + gu.ravel() * s + gv.ravel() * c])
    d, _ = cKDTree(pts).query(cells, distance_upper_bound=cell_m)
    return float(np.mean(np.isfinite(d)))
