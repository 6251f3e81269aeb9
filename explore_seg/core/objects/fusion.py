"""Fusion of a re-detection into a tracked box (:func:`fuse_boxes`): measured footprints
add up side by side, noise and the sides grown by the prior do not."""

from __future__ import annotations

import math

import cv2
import numpy as np

from explore_seg.core.objects.boxes import Object3D, surface_points
from explore_seg.core.objects.geometry import wrap_half_pi
from explore_seg.core.objects.params import UNKNOWN_CLASS, ObjectParams
from explore_seg.core.objects.priors import SizePrior


def footprint_iou(a: Object3D, b: Object3D) -> float:
    """Intersection over union of two footprints (rotated rectangles)."""
    pa = a.footprint().astype(np.float32)
    pb = b.footprint().astype(np.float32)
    area_a = a.size_xyz[0] * a.size_xyz[1]
    area_b = b.size_xyz[0] * b.size_xyz[1]
    if area_a <= 0 or area_b <= 0:
        return 0.0
    inter, _ = cv2.intersectConvexConvex(pa, pb)
    inter = max(float(inter), 0.0)
    union = area_a + area_b - inter
    return inter / union if union > 0 else 0.0


def _fuse_side(a: float, a_open: bool, b: float, b_open: bool, w_a: float, w_b: float,
               margin: float, outward: float) -> tuple[float, bool]:
    """One side of :func:`fuse_boxes` (position along ``outward`` = +-1, open flag).

    Two open sides (lower bounds): the farther. An open and a closed side: the closed one
    unless the open one lies beyond it by more than ``margin``. Two closed sides: the
    weighted mean when within ``margin``, else the farther (a part seen only once).
    """
    d = (b - a) * outward
    if a_open and b_open:
        return (b, True) if d > 0 else (a, True)
    if a_open != b_open:
        (o, c) = (a, b) if a_open else (b, a)
        return (o, True) if (o - c) * outward > margin else (c, False)
    if abs(d) > margin:
        return (b, False) if d > 0 else (a, False)
    return (a * w_a + b * w_b) / (w_a + w_b), False


def _open_sides_along(new: Object3D, axes: tuple[np.ndarray, np.ndarray]) -> list[bool]:
    """Open flags of ``new``'s sides, per fused axis (low side, high side): each fused
    side takes the flag of the side of ``new`` whose outward normal is nearest to it."""
    cn, sn = math.cos(new.yaw), math.sin(new.yaw)
    normals = [(-cn, -sn), (cn, sn), (sn, -cn), (-sn, cn)]
    open_new = []
    for ax in axes:
        for sign in (-1.0, 1.0):
            k = int(np.argmax([sign * (nx * ax[0] + ny * ax[1]) for nx, ny in normals]))
            open_new.append(new.open_sides[k])
    return open_new


def _fused_surface(old: Object3D, new: Object3D, params: ObjectParams) -> np.ndarray | None:
    """Both boxes' surface points, thinned; the newest view first: when the union is
    thinned, the latest points stay densest."""
    surfaces = [o.surface for o in (new, old) if o.surface is not None]
    return (surface_points(np.vstack(surfaces), params.miss_sample_spacing_m)
            if surfaces else None)


def fuse_boxes(old: Object3D, new: Object3D, params: ObjectParams,
               prior: SizePrior | None = None) -> Object3D:
    """Fuse a re-detection into a tracked box.

    The yaw is the point-weighted mean (``new`` turned by a multiple of 90 degrees to
    ``old``'s axes: a box is the same under such turns). Along each axis of the fused box
    the *measured* footprints (:attr:`Object3D.measured_xy`, the extent of the points
    before the prior's clamp) are fused:

    * both boxes saw both sides (none open) and measure the same length (within
      ``merge_extend_margin_m``): the sides are averaged (a shifted re-detection, noise,
      does not inflate the box);
    * otherwise side by side: two closed sides within ``merge_extend_margin_m`` are
      averaged, else the farther wins (two partial views of a long desk add up); an open
      side (:attr:`Object3D.open_sides`, where the view was cut: a lower bound) gives way
      to a closed one unless it lies beyond it by more than the margin; of two open sides
      the farther wins.

    Growth beyond a closed side of ``old`` is limited to ``merge_growth_max`` times the
    longer of the two extents (one cluster that took in a neighbour cannot blow the box
    up). The size prior then clamps the fused extents: a side shorter than ``min_xy_m``
    grows to it around the measured part, towards the point-weighted mean of the two
    boxes' centres (each grown away from its camera); a side longer than ``max_xy_m``
    shrinks around its centre. Heights: the larger, growing at most ``merge_growth_max``
    times.

    Parameters
    ----------
    old, new : Object3D
    params : ObjectParams
    prior : SizePrior, optional
        The class's prior; None = no clamp.

    Returns
    -------
    Object3D
        With the classified class (over :data:`UNKNOWN_CLASS`), the higher score, the
        summed point count and the fused measured footprint.
    """
    cls = old.cls if old.cls != UNKNOWN_CLASS else new.cls
    w_old, w_new = float(max(old.n_points, 1)), float(max(new.n_points, 1))
    mo = old.measured_xy or (*old.center_xyz[:2], *old.size_xyz[:2])
    mn = new.measured_xy or (*new.center_xyz[:2], *new.size_xyz[:2])
    # Align the new box's axes to the old one (boxes are symmetric under 90 degrees).
    d = wrap_half_pi(new.yaw - old.yaw)
    swap = abs(d) > 0.25 * math.pi
    if swap:
        d = d - math.copysign(0.5 * math.pi, d)
    yaw = wrap_half_pi(old.yaw + d * w_new / (w_old + w_new))
    axes = (np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)]))
    # Both boxes keep their extents and turn about their centres to the fused yaw.
    m_old = [(float(np.dot(mo[:2], ax)), mo[2 + i]) for i, ax in enumerate(axes)]
    m_new = [(float(np.dot(mn[:2], ax)), mn[3 - i] if swap else mn[2 + i])
             for i, ax in enumerate(axes)]
    open_new = _open_sides_along(new, axes)
    g, margin = params.merge_growth_max, params.merge_extend_margin_m
    centre_xy = np.zeros(2)
    meas_xy = np.zeros(2)
    size_xy, meas_size = [0.0, 0.0], [0.0, 0.0]
    open_out = [False] * 4
    for i, ax in enumerate(axes):
        (ca, la), (cb, lb) = m_old[i], m_new[i]
        a0, a1, b0, b1 = ca - 0.5 * la, ca + 0.5 * la, cb - 0.5 * lb, cb + 0.5 * lb
        flags = (old.open_sides[2 * i], old.open_sides[2 * i + 1],
                 open_new[2 * i], open_new[2 * i + 1])
        if not any(flags) and abs(lb - la) <= margin:
            # The same extent measured twice, shifted by noise: average both sides.
            lo = (a0 * w_old + b0 * w_new) / (w_old + w_new)
            hi = (a1 * w_old + b1 * w_new) / (w_old + w_new)
        else:
            lo, open_out[2 * i] = _fuse_side(a0, flags[0], b0, flags[2], w_old, w_new,
                                             margin, -1.0)
            hi, open_out[2 * i + 1] = _fuse_side(a1, flags[1], b1, flags[3], w_old, w_new,
                                                 margin, 1.0)
            hi = max(hi, lo)
        # Growth beyond a closed side contradicts it (a cluster that took in a neighbour):
        # at most merge_growth_max times the longer extent. Beyond an open side (a lower
        # bound) it is what the old view could not see.
        cap = g * max(la, lb)
        ext_lo = 0.0 if flags[0] else max(a0 - lo, 0.0)
        ext_hi = 0.0 if flags[1] else max(hi - a1, 0.0)
        if hi - lo > cap and ext_lo + ext_hi > 0:
            excess = min(hi - lo - cap, ext_lo + ext_hi)
            lo += excess * ext_lo / (ext_lo + ext_hi)
            hi -= excess * ext_hi / (ext_lo + ext_hi)
        # Where the clamped boxes put the object along this axis (their grown sides).
        grown = (float(np.dot(old.center_xyz[:2], ax)) * w_old
                 + float(np.dot(new.center_xyz[:2], ax)) * w_new) / (w_old + w_new)
        length, mid = hi - lo, 0.5 * (lo + hi)
        meas_xy += mid * ax
        meas_size[i] = length
        if prior is not None and length < prior.min_xy_m:
            half = 0.5 * prior.min_xy_m
            mid = min(max(grown, hi - half), lo + half)
            length = prior.min_xy_m
        elif prior is not None and length > prior.max_xy_m:
            length = prior.max_xy_m
        centre_xy += mid * ax
        size_xy[i] = length
    sz = max(old.size_xyz[2], min(new.size_xyz[2], g * old.size_xyz[2]))
    if prior is not None:
        sz = min(sz, prior.max_z_m)
    cz = 0.5 * sz if params.boxes_on_floor else \
        (old.center_xyz[2] * w_old + new.center_xyz[2] * w_new) / (w_old + w_new)
    surface = _fused_surface(old, new, params)
    return Object3D(cls, max(old.score, new.score),
                    (float(centre_xy[0]), float(centre_xy[1]), float(cz)),
                    (float(size_xy[0]), float(size_xy[1]), float(sz)), yaw,
                    int(min(old.n_points + new.n_points, 2**31 - 1)),
                    (float(meas_xy[0]), float(meas_xy[1]), meas_size[0], meas_size[1]),
                    (open_out[0], open_out[1], open_out[2], open_out[3]), surface)
