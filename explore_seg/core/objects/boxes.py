"""Oriented 3D boxes (:class:`Object3D`) and fitting one to a cluster's points: footprint,
heights, open sides, the class's size prior (clamp, plausibility) and the measured
surface kept to judge misses."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.objects.cloud import voxel_downsample
from explore_seg.core.objects.geometry import footprint_orientation, rect_corners, wrap_half_pi
from explore_seg.core.objects.params import ObjectParams
from explore_seg.core.objects.priors import SizePrior


@dataclass(frozen=True)
class Object3D:
    """An oriented 3D box in the map frame.

    Parameters
    ----------
    cls : str
        Class name (COCO name or :data:`UNKNOWN_CLASS`).
    score : float
        Detection confidence (1.0 for unclassified objects).
    center_xyz : tuple of float
        Box centre (metres, map frame).
    size_xyz : tuple of float
        Extent along the box's own x (yaw direction), y and z axes (metres, >= 0).
    yaw : float
        Rotation of the box about z (radians), normalised to [-pi/2, pi/2).
    n_points : int
        Points the box was fitted to.
    measured_xy : tuple of 4 float, optional
        The footprint the points themselves span, before the size prior grew or shrank it:
        centre (x, y) and extents along the box's x and y axes (same ``yaw``). None when
        unknown (the box is then taken as measured). :class:`ObjectMap` fuses these, so
        that parts of an object seen from different sides add up while the sides grown by
        the prior (hidden, not seen) do not.
    open_sides : tuple of 4 bool
        Sides of ``measured_xy`` (-x, +x, -y, +y in the box frame) where the view, not the
        object, ended (image border, an occluder in front): the object reaches at least
        that far. Closed sides are the object's own.
    surface : ndarray of float32, shape (M, 3), optional
        Where the object's points were measured (map frame, one per voxel of
        ``miss_sample_spacing_m``, at most :data:`MAX_SURFACE_POINTS`): what the camera
        must see past before :class:`ObjectMap` counts a miss. A table or chair is mostly
        empty space under its top, which the camera sees through from any side; only its
        own surfaces tell it is gone. None: the box's faces are used instead.
    """

    cls: str
    score: float
    center_xyz: tuple[float, float, float]
    size_xyz: tuple[float, float, float]
    yaw: float
    n_points: int
    measured_xy: tuple[float, float, float, float] | None = None
    open_sides: tuple[bool, bool, bool, bool] = (False, False, False, False)
    surface: npt.NDArray[np.float32] | None = field(default=None, compare=False, repr=False)

    def footprint(self) -> npt.NDArray[np.float64]:
        """The 4 corners (x, y) of the footprint, counter-clockwise, shape (4, 2)."""
        return rect_corners(self.center_xyz[:2], self.size_xyz[:2], self.yaw)

    def moved(self, transform: tuple[float, float, float]) -> Object3D:
        """The box moved by the rigid map-frame transform ``(x, y, yaw)`` (a point p goes
        to ``R(yaw) p + (x, y)``): centre, heading, measured footprint and surface; the
        sizes and heights stay. When the heading wraps by pi (it is kept in
        [-pi/2, pi/2)), the box's own axes turn round and the open sides swap.

        >>> b = Object3D("chair", 0.9, (1.0, 0.0, 0.4), (0.5, 0.4, 0.8), 0.0, 10)
        >>> m = b.moved((0.5, 0.0, math.pi / 2))
        >>> [round(v, 6) for v in m.center_xyz], round(m.yaw, 6)
        ([0.5, 1.0, 0.4], -1.570796)
        """
        tx, ty, th = (float(v) for v in transform)
        c, s = math.cos(th), math.sin(th)
        x, y, z = self.center_xyz
        yaw = wrap_half_pi(self.yaw + th)
        # the wrap took off an odd multiple of pi: the box's axes point the other way
        flipped = abs(math.remainder(yaw - self.yaw - th, 2.0 * math.pi)) > 0.5 * math.pi
        measured = self.measured_xy
        if measured is not None:
            mx, my, ex, ey = measured
            measured = (c * mx - s * my + tx, s * mx + c * my + ty, ex, ey)
        sides = self.open_sides
        if flipped:
            sides = (sides[1], sides[0], sides[3], sides[2])
        surface = self.surface
        if surface is not None:
            pts = np.asarray(surface, dtype=np.float64)
            surface = np.column_stack([c * pts[:, 0] - s * pts[:, 1] + tx,
                                       s * pts[:, 0] + c * pts[:, 1] + ty,
                                       pts[:, 2]]).astype(np.float32)
        return Object3D(self.cls, self.score, (c * x - s * y + tx, s * x + c * y + ty, z),
                        self.size_xyz, yaw, self.n_points, measured, sides, surface)


#: Most points an object keeps of its measured surface (:attr:`Object3D.surface`).
MAX_SURFACE_POINTS = 400


def surface_points(points: npt.NDArray[np.floating], voxel_m: float
                   ) -> npt.NDArray[np.float32]:
    """One point per voxel of ``voxel_m`` (the first in input order), thinned evenly to at
    most :data:`MAX_SURFACE_POINTS`: an object's measured surface, shape (M, 3)."""
    pts = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    pts = pts[voxel_downsample(pts, voxel_m)]
    if len(pts) > MAX_SURFACE_POINTS:
        pts = pts[np.linspace(0, len(pts) - 1, MAX_SURFACE_POINTS).round().astype(np.int64)]
    return pts


def clamp_to_prior(center_xyz: Sequence[float], size_xyz: Sequence[float], yaw: float,
                   prior: SizePrior, camera_xy: Sequence[float] | None = None,
                   floor_z_m: float | None = 0.0
                   ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Clamp a box's extents to a size prior.

    Footprint sides shorter than ``prior.min_xy_m`` grow to it: away from the camera when
    ``camera_xy`` is given (the near face was measured, the far side was hidden), around
    the centre otherwise. Sides longer than ``prior.max_xy_m`` shrink around the centre.
    A height below ``prior.min_z_m`` grows upwards from the bottom when ``floor_z_m`` is
    given (the box stands on the floor), around the centre otherwise; above
    ``prior.max_z_m`` it shrinks around the centre (or keeps the bottom on the floor).

    Parameters
    ----------
    center_xyz, size_xyz : sequence of 3 float
    yaw : float
    prior : SizePrior
    camera_xy : sequence of 2 float, optional
    floor_z_m : float, optional

    Returns
    -------
    center_xyz, size_xyz : tuple of float
    """
    cx, cy, cz = (float(v) for v in center_xyz)
    sx, sy, sz = (float(v) for v in size_xyz)
    axes = (np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)]))
    centre = np.array([cx, cy])
    sizes = [sx, sy]
    for i in range(2):
        if sizes[i] < prior.min_xy_m:
            grow = prior.min_xy_m - sizes[i]
            if camera_xy is not None:
                away = float(np.dot(centre - np.asarray(camera_xy, dtype=np.float64), axes[i]))
                sign = 1.0 if away >= 0 else -1.0
                centre = centre + axes[i] * sign * 0.5 * grow
            sizes[i] = prior.min_xy_m
        elif sizes[i] > prior.max_xy_m:
            sizes[i] = prior.max_xy_m
    bottom = cz - 0.5 * sz
    on_floor = floor_z_m is not None and abs(bottom - floor_z_m) < 1e-6
    if sz < prior.min_z_m:
        sz = prior.min_z_m
        cz = bottom + 0.5 * sz if on_floor else cz
    elif sz > prior.max_z_m:
        sz = prior.max_z_m
        cz = bottom + 0.5 * sz if on_floor else cz
    return (float(centre[0]), float(centre[1]), cz), (sizes[0], sizes[1], sz)


def fit_box(points_map: npt.NDArray[np.floating], cls: str, score: float,
            prior: SizePrior | None, params: ObjectParams,
            camera_xy: Sequence[float] | None = None,
            cut: npt.NDArray[np.bool_] | None = None) -> Object3D:
    """3D box of a cluster in the map frame, clamped by the class's prior.

    Parameters
    ----------
    points_map : ndarray, shape (N, 3), N >= 1
    cls : str
    score : float
    prior : SizePrior or None
        None skips the clamp.
    params : ObjectParams
        ``orientation_method`` and ``boxes_on_floor`` are used.
    camera_xy : sequence of 2 float, optional
        Camera position (map frame): footprints grow away from it.
    cut : ndarray of bool, shape (N,), optional
        Points seen at the image border (see :func:`footprint_orientation`).

    Returns
    -------
    Object3D

    Raises
    ------
    ValueError
        If ``points_map`` is empty or not (N, 3).
    """
    pts = np.asarray(points_map, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise ValueError(f"points_map must have shape (N>=1, 3), got {pts.shape}")
    cxy, sxy, yaw = footprint_orientation(pts[:, :2], params.orientation_method, cut)
    zmin = 0.0 if params.boxes_on_floor else float(pts[:, 2].min())
    zmax = max(float(pts[:, 2].max()), zmin)
    center = (cxy[0], cxy[1], 0.5 * (zmin + zmax))
    size = (sxy[0], sxy[1], zmax - zmin)
    if prior is not None:
        center, size = clamp_to_prior(center, size, yaw, prior, camera_xy,
                                      0.0 if params.boxes_on_floor else None)
    open_sides = (False, False, False, False)
    if cut is not None and np.any(cut):
        open_sides = _open_sides(pts[:, :2], np.asarray(cut, dtype=bool), cxy, sxy, yaw,
                                 0.5 * params.cluster_tolerance_m)
    return Object3D(cls, float(score), tuple(center), tuple(size), yaw, int(len(pts)),
                    (float(cxy[0]), float(cxy[1]), float(sxy[0]), float(sxy[1])), open_sides,
                    surface_points(pts, params.miss_sample_spacing_m))


def _open_sides(points_xy: npt.NDArray[np.float64], cut: npt.NDArray[np.bool_],
                center_xy: Sequence[float], size_xy: Sequence[float], yaw: float,
                band_m: float) -> tuple[bool, bool, bool, bool]:
    """Sides (-x, +x, -y, +y) of a fitted rectangle formed mostly (>= half) by cut points
    (those within ``band_m`` of the side)."""
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = points_xy[:, 0] - center_xy[0], points_xy[:, 1] - center_xy[1]
    coords = (dx * c + dy * s, -dx * s + dy * c)
    out = []
    for i in range(2):
        for sign in (-1.0, 1.0):
            near = sign * coords[i] >= 0.5 * float(size_xy[i]) - band_m
            out.append(bool(np.any(near) and np.mean(cut[near]) >= 0.5))
    return (out[0], out[1], out[2], out[3])


def plausible_extent(points_map: npt.NDArray[np.floating], prior: SizePrior,
                     params: ObjectParams) -> bool:
    """False when a cluster is far larger or far smaller than its class can be.

    The footprint (minimum-area rectangle) or height exceeding ``prior_reject_factor``
    times the prior's maximum means the cluster took in a wall or a neighbouring object;
    clamping such a cluster to the prior would still place the box wrongly, so the
    observation is dropped. ``prior_reject_factor`` 0 disables the test.

    A footprint whose longer side is below ``min_extent_fraction`` times the prior's
    ``min_xy_m`` is a fragment (a table leg, a chair leg in front of the chair, the corner
    of a top cut by the image border): its minimum-area rectangle has an arbitrary
    orientation, and growing it to the prior's minimum puts the box anywhere around it.
    ``min_extent_fraction`` 0 disables this test.
    """
    if len(points_map) == 0:
        return True
    f, g = params.prior_reject_factor, params.min_extent_fraction
    if f <= 0 and g <= 0:
        return True
    pts = np.asarray(points_map, dtype=np.float64)
    _, sxy, _ = footprint_orientation(pts[:, :2], params.orientation_method)
    if g > 0 and max(sxy) < g * prior.min_xy_m:
        return False
    if f <= 0:
        return True
    height = float(pts[:, 2].max() - (0.0 if params.boxes_on_floor else pts[:, 2].min()))
    return max(sxy) <= f * prior.max_xy_m and height <= f * prior.max_z_m
