"""Simulated RGB-D camera with semantic and instance images.

:class:`DepthCamera` ray-casts every pixel against the upright boxes and cylinders in 3D
(slab test) and the floor ``z = 0``. Primitives are culled by range and view frustum,
projected to a screen rectangle (exactly, with near-plane clipping) and drawn front to
back; only the pixels of that rectangle are tested, and a primitive wholly behind what
is already drawn in its rectangle is skipped.

The mount is given relative to ``base_footprint``. The camera optical frame is REP-103
optical (x right, y down, z forward); depth is the optical z, NaN where nothing is hit
within ``range_max_m``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.camera import CameraIntrinsics, base_from_optical, map_from_base
from explore_seg.core.fields import param_meta
from sim_bridge.sensors.common import CLASS_IDS, CLASS_RGB, FLOOR_RGB, require_positive
from sim_bridge.world import Primitive, World


@dataclass(frozen=True)
class CameraParams:
    """Pinhole RGB-D camera (RealSense-like) on the robot.

    The default mount is a TurtleBot3-waffle-like camera raised to 0.2 m: at that height
    chair seats and table tops (0.42-0.75 m) are in view from about 1 m on. The paper's
    robot carried it 0.894 m up, pitched 0.1 rad down (set ``mount_z_m``/``pitch_rad``).
    """

    width: int = field(default=640, metadata=param_meta(
        "image width", "px", range=(1, 2**31 - 1)))
    height: int = field(default=480, metadata=param_meta(
        "image height", "px", range=(1, 2**31 - 1)))
    fx: float = field(default=525.0, metadata=param_meta(
        "focal length x", "px", range=(0.0, math.inf)))
    fy: float = field(default=525.0, metadata=param_meta(
        "focal length y", "px", range=(0.0, math.inf)))
    cx: float = field(default=319.5, metadata=param_meta("principal point x", "px"))
    cy: float = field(default=239.5, metadata=param_meta("principal point y", "px"))
    mount_x_m: float = field(default=0.064, metadata=param_meta(
        "camera x in base_footprint (forward)", "m"))
    mount_y_m: float = field(default=0.0, metadata=param_meta(
        "camera y in base_footprint (left)", "m"))
    mount_z_m: float = field(default=0.2, metadata=param_meta(
        "camera height above the floor", "m"))
    pitch_rad: float = field(default=0.0, metadata=param_meta(
        "camera pitch, positive looks down (REP 103)", "rad", range=(-math.pi / 2, math.pi / 2)))
    range_min_m: float = field(default=0.05, metadata=param_meta(
        "near plane: closer surfaces are not drawn", "m", range=(0.0, math.inf)))
    range_max_m: float = field(default=6.0, metadata=param_meta(
        "depth (optical z) beyond which pixels read NaN", "m", range=(0.0, math.inf)))
    rate_hz: float = field(default=15.0, metadata=param_meta(
        "frame rate", "Hz", range=(0.0, math.inf)))
    depth_noise_std_m: float = field(default=0.0, metadata=param_meta(
        "std of Gaussian depth noise (applied when an rng is given)", "m", range=(0.0, math.inf)))
    floor_tile_m: float = field(default=0.5, metadata=param_meta(
        "checker tile size of the floor colour", "m", range=(0.0, math.inf)))

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v}")
        for name in ("fx", "fy", "range_min_m", "rate_hz", "floor_tile_m"):
            require_positive(name, getattr(self, name))
        for name in ("cx", "cy", "mount_x_m", "mount_y_m", "mount_z_m", "pitch_rad"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)}")
        if not (math.isfinite(self.range_max_m) and self.range_max_m > self.range_min_m):
            raise ValueError(f"range_max_m must be finite and > range_min_m {self.range_min_m}, "
                             f"got {self.range_max_m}")
        if not abs(self.pitch_rad) < math.pi / 2:
            raise ValueError(f"pitch_rad must be within (-pi/2, pi/2), got {self.pitch_rad}")
        if not (math.isfinite(self.depth_noise_std_m) and self.depth_noise_std_m >= 0):
            raise ValueError(f"depth_noise_std_m must be >= 0, got {self.depth_noise_std_m}")

    def intrinsics(self) -> CameraIntrinsics:
        """Intrinsics for CameraInfo and back-projection."""
        return CameraIntrinsics(self.fx, self.fy, self.cx, self.cy, int(self.width),
                                int(self.height))


def camera_pose_in_world(robot_pose: tuple[float, float, float], params: CameraParams
                         ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Rotation and position of the camera optical frame in the world.

    Returns
    -------
    R : ndarray of float64, shape (3, 3)
        ``p_world = R @ p_optical + t``.
    t : ndarray of float64, shape (3,)
    """
    tf = map_from_base(*robot_pose) @ base_from_optical(
        params.mount_x_m, params.mount_y_m, params.mount_z_m, 0.0, params.pitch_rad, 0.0)
    return tf[:3, :3].copy(), tf[:3, 3].copy()


@dataclass(frozen=True)
class CameraFrame:
    """One rendered RGB-D frame.

    The colour image is shaded on first access of :attr:`rgb` (then kept): a consumer
    that reads only depth, semantic and instance images (the oracle detector) does not
    pay for it.

    Attributes
    ----------
    depth_m : ndarray of float32, shape (H, W)
        Optical z of the first surface (m); NaN where none within range.
    semantic : ndarray of uint8, shape (H, W)
        :data:`CLASS_IDS` id per pixel (0 = floor / nothing).
    instance : ndarray of int32, shape (H, W)
        Index into ``world.objects`` of the object seen, -1 for walls, floor, nothing.
    rotation, translation : ndarray of float64
        Camera optical frame in the world (``p_world = rotation @ p_opt + translation``).
    shade : callable
        Returns the colour image (:attr:`rgb`); called at most once.
    """

    depth_m: npt.NDArray[np.float32]
    semantic: npt.NDArray[np.uint8]
    instance: npt.NDArray[np.int32]
    rotation: npt.NDArray[np.float64]
    translation: npt.NDArray[np.float64]
    shade: Callable[[], npt.NDArray[np.uint8]] = field(repr=False, compare=False)

    @functools.cached_property
    def rgb(self) -> npt.NDArray[np.uint8]:
        """ndarray of uint8, shape (H, W, 3): colour per class, shaded by face orientation
        and distance; floor checkered."""
        return self.shade()


# 12 edges of a prism given as 8 corners: bottom 0..3, top 4..7
_EDGES = np.array([(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                   (0, 4), (1, 5), (2, 6), (3, 7)])
#: Brightness of faces facing local x, local y, up/down (boxes; cylinder sides use x),
#: and of the floor.
_FACE_SHADE = np.array([0.85, 0.65, 1.0, 1.0], np.float32)
#: Distance fade levels of the colour look-up table.
_SHADE_LEVELS = 64
#: Colour-table rows of the two floor tiles and of "nothing hit".
_FLOOR_INDEX = len(CLASS_IDS)
_NONE_INDEX = _FLOOR_INDEX + 2


class DepthCamera:
    """Ray-casting RGB-D camera of a world's boxes, cylinders and floor.

    Parameters
    ----------
    world : World
    params : CameraParams
    """

    def __init__(self, world: World, params: CameraParams | None = None) -> None:
        self.params = params or CameraParams()
        p = self.params
        obj_index = {o.name: k for k, o in enumerate(world.objects)}
        prims: list[Primitive] = list(world.primitives)
        n = len(prims)
        self._n = n
        self._is_box = np.array([q.shape == "box" for q in prims], bool)
        self._xy = np.array([(q.x, q.y) for q in prims], np.float64).reshape(-1, 2)
        yaw = np.array([q.yaw for q in prims], np.float64)
        self._cos, self._sin = np.cos(yaw), np.sin(yaw)
        self._half = np.array([(q.size[0] / 2, q.size[1] / 2) if q.shape == "box"
                               else (q.size[0], q.size[0]) for q in prims],
                              np.float64).reshape(-1, 2)
        self._z = np.array([(q.zmin, q.zmax) for q in prims], np.float64).reshape(-1, 2)
        self._cls = np.array([CLASS_IDS.get(q.cls, CLASS_IDS["other"]) for q in prims], np.uint8)
        self._inst = np.array([obj_index.get(q.object, -1) if q.cls != "wall" else -1
                               for q in prims], np.int32)
        # axis-aligned boxes (yaw a multiple of pi/2): half sizes in world axes
        quarter = np.round(yaw / (math.pi / 2))
        self._aligned = self._is_box & (np.abs(yaw - quarter * math.pi / 2) < 1e-9)
        swap = (np.mod(quarter, 2) == 1)
        self._half_world = np.where(swap[:, None], self._half[:, ::-1], self._half)
        # 8 corners of each prism (cylinders: the circumscribed square prism)
        sx = np.array([1, -1, -1, 1], np.float64)
        sy = np.array([1, 1, -1, -1], np.float64)
        cos_c = np.where(self._is_box, self._cos, 1.0)
        sin_c = np.where(self._is_box, self._sin, 0.0)
        u = self._half[:, :1] * sx
        v = self._half[:, 1:] * sy
        cx = self._xy[:, :1] + cos_c[:, None] * u - sin_c[:, None] * v
        cy = self._xy[:, 1:] + sin_c[:, None] * u + cos_c[:, None] * v
        corners = np.zeros((n, 8, 3))
        corners[:, :4, 0] = cx
        corners[:, 4:, 0] = cx
        corners[:, :4, 1] = cy
        corners[:, 4:, 1] = cy
        corners[:, :4, 2] = self._z[:, :1]
        corners[:, 4:, 2] = self._z[:, 1:]
        self._corners = corners
        # pixel ray directions in the camera optical frame (z = 1)
        self._a = ((np.arange(p.width) - p.cx) / p.fx).astype(np.float32)
        self._b = ((np.arange(p.height) - p.cy) / p.fy).astype(np.float32)
        base = np.array([CLASS_RGB.get(k, CLASS_RGB[CLASS_IDS["other"]])
                         for k in range(_FLOOR_INDEX)] + list(FLOOR_RGB) + [CLASS_RGB[0]],
                        np.float32)                                   # (classes + 3, 3)
        fade = 0.5 + 0.5 * np.arange(_SHADE_LEVELS, dtype=np.float32) / (_SHADE_LEVELS - 1)
        lut = base[:, None, None, :] * _FACE_SHADE[None, :, None, None] \
            * fade[None, None, :, None]
        lut[_NONE_INDEX] = base[_NONE_INDEX]
        # (colour index, face, fade level) -> RGB
        self._lut = np.clip(np.round(lut), 0, 255).astype(np.uint8)

    # ------------------------------------------------------------------ helpers
    def _screen_boxes(self, rot: npt.NDArray[np.float64], t: npt.NDArray[np.float64]
                      ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
        """Candidate primitives and their pixel rectangles + nearest depth.

        Returns ``(ids, rects)`` with rects rows ``(u0, v0, u1, v1, dmin)``, u/v exclusive
        ends, sorted front to back.
        """
        p = self.params
        near, far = p.range_min_m, p.range_max_m
        opt = (self._corners - t) @ rot                  # (n, 8, 3) optical coordinates
        z = opt[..., 2]
        keep = (z.max(axis=1) > near) & (z.min(axis=1) < far)
        # 2D check that some corner lies within the horizontal frustum side planes is
        # left to the rectangle clipping below (exact enough, cheap).
        ids = np.flatnonzero(keep)
        if ids.size == 0:
            return ids, np.zeros((0, 5))
        opt = opt[ids]
        z = opt[..., 2]
        a = opt[:, _EDGES[:, 0], :]
        b = opt[:, _EDGES[:, 1], :]
        za, zb = a[..., 2], b[..., 2]
        cross = (za - near) * (zb - near) < 0
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(cross, (near - za) / (zb - za), 0.0)
        inter = a + f[..., None] * (b - a)               # on the near plane where cross
        pts = np.concatenate([opt, inter], axis=1)       # (m, 20, 3)
        valid = np.concatenate([z >= near, cross], axis=1)
        zz = np.where(valid, np.maximum(pts[..., 2], near), 1.0)
        u = np.where(valid, p.fx * pts[..., 0] / zz + p.cx, np.nan)
        v = np.where(valid, p.fy * pts[..., 1] / zz + p.cy, np.nan)
        u0 = np.floor(np.nanmin(u, axis=1)) - 1
        u1 = np.ceil(np.nanmax(u, axis=1)) + 2
        v0 = np.floor(np.nanmin(v, axis=1)) - 1
        v1 = np.ceil(np.nanmax(v, axis=1)) + 2
        u0 = np.clip(u0, 0, p.width)
        u1 = np.clip(u1, 0, p.width)
        v0 = np.clip(v0, 0, p.height)
        v1 = np.clip(v1, 0, p.height)
        dmin = np.where(valid, pts[..., 2], np.inf).min(axis=1)
        ok = (u1 > u0) & (v1 > v0)
        ids, rects = ids[ok], np.stack([u0, v0, u1, v1, dmin], axis=1)[ok]
        order = np.argsort(rects[:, 4], kind="stable")
        return ids[order], rects[order]

    def render(self, pose: tuple[float, float, float],
               rng: np.random.Generator | None = None) -> CameraFrame:
        """Render the frame seen from a robot pose.

        Parameters
        ----------
        pose : tuple of float
            Robot (x, y, yaw) in the world.
        rng : numpy.random.Generator, optional
            Source of depth noise (``depth_noise_std_m``); none without it.

        Returns
        -------
        CameraFrame
        """
        p = self.params
        h, w = int(p.height), int(p.width)
        rot, t = camera_pose_in_world(pose, p)
        rays = self._rays(rot.astype(np.float32))
        dx, dy, dz, inv_z = rays.dx, rays.dy, rays.dz, rays.inv_z
        tz = np.float32(t[2])
        near = np.float32(p.range_min_m)
        if tz > 0:
            with np.errstate(invalid="ignore"):
                tfl = -tz * inv_z
            floor_col = np.where((dz < 0) & (tfl > near), tfl, np.float32(np.inf))
        else:
            floor_col = np.full((h, 1), np.inf, np.float32)
        zbuf = np.ascontiguousarray(np.broadcast_to(floor_col, (h, w)), dtype=np.float32)
        sem = np.zeros((h, w), np.uint8)
        inst = np.full((h, w), -1, np.int32)
        face = np.full((h, w), 3, np.uint8)     # 3 = floor / nothing
        ids, rects = self._screen_boxes(rot, t)
        ox, oy = float(t[0]), float(t[1])
        for k, (u0, v0, u1, v1, dmin) in zip(ids.tolist(), rects.tolist()):
            rs, cs = slice(int(v0), int(v1)), slice(int(u0), int(u1))
            zb = zbuf[rs, cs]
            if dmin >= zb.max():
                continue
            izr = inv_z[rs]
            z0 = np.float32(self._z[k, 0] - tz) * izr
            z1 = np.float32(self._z[k, 1] - tz) * izr
            tn = np.minimum(z0, z1)
            tfar = np.maximum(z0, z1)
            px, py = ox - self._xy[k, 0], oy - self._xy[k, 1]
            with np.errstate(invalid="ignore", divide="ignore"):
                side, side_far, side_face = self._side_hits(k, (px, py), rays, rs, cs)
                tnear = np.maximum(tn, side)
                hit = tnear <= np.minimum(tfar, side_far)
                hit &= tnear > near
                hit &= tnear < zb
            if not hit.any():
                continue
            np.copyto(zb, tnear, where=hit)
            np.copyto(sem[rs, cs], self._cls[k], where=hit)
            np.copyto(inst[rs, cs], self._inst[k], where=hit)
            np.copyto(face[rs, cs], np.where(tn >= side, np.uint8(2), side_face), where=hit)
        valid = zbuf <= np.float32(p.range_max_m)
        np.copyto(sem, 0, where=~valid)
        np.copyto(inst, -1, where=~valid)
        depth = np.where(valid, zbuf, np.float32(np.nan))
        if p.depth_noise_std_m > 0 and rng is not None:
            depth[valid] += rng.normal(0.0, p.depth_noise_std_m, int(valid.sum())).astype(
                np.float32)
        # Shaded on demand from arrays the frame owns (sem, inst are the frame's own; the
        # copies keep the colours independent of what a consumer does with them).
        sem_c, t_c = sem.copy(), t.copy()
        return CameraFrame(depth, sem, inst, rot, t,
                           lambda: self._colour(zbuf, valid, sem_c, face, dx, dy, t_c))

    def _rays(self, rf: npt.NDArray[np.float32]) -> _Rays:
        """World ray directions (optical z component 1, so a ray's t is the depth) of a
        camera turned by ``rf``. The camera has no roll, so the optical x axis is
        horizontal: dz depends on the row only, and with zero pitch dx, dy depend on the
        column only. Arrays keep the smallest broadcastable shape and every per-pixel
        expression broadcasts."""
        a = self._a[None, :]
        b = self._b[:, None]
        dz = rf[2, 1] * b + rf[2, 2]                                    # (h, 1)
        if abs(rf[0, 1]) > 0 or abs(rf[1, 1]) > 0:
            dx = rf[0, 0] * a + rf[0, 1] * b + rf[0, 2]                 # (h, w)
            dy = rf[1, 0] * a + rf[1, 1] * b + rf[1, 2]
        else:
            dx = rf[0, 0] * a + rf[0, 2]                                # (1, w)
            dy = rf[1, 0] * a + rf[1, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv_x = np.float32(1.0) / dx
            inv_y = np.float32(1.0) / dy
            inv_z = np.float32(1.0) / dz
        return _Rays(dx, dy, dz, inv_x, inv_y, inv_z)

    def _side_hits(self, k: int, rel_xy: tuple[float, float], rays: _Rays, rs: slice,
                   cs: slice) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32],
                                       npt.NDArray[np.uint8] | np.uint8]:
        """Where the rays of the pixels (rs, cs) enter and leave the side walls of solid
        ``k`` (a box's slabs, a cylinder's mantle), and the entered face (0: a box's x
        side or a cylinder, 1: a box's y side). ``rel_xy`` is the camera relative to the
        solid's centre."""
        px, py = rel_xy
        dx, dy = rays.dx, rays.dy
        if self._is_box[k]:
            if self._aligned[k]:
                hx, hy = self._half_world[k]
                ix, iy = _cut(rays.inv_x, rs, cs), _cut(rays.inv_y, rs, cs)
            else:
                c, s = self._cos[k], self._sin[k]
                px, py = c * px + s * py, -s * px + c * py
                hx, hy = self._half[k]
                ddx, ddy = _cut(dx, rs, cs), _cut(dy, rs, cs)
                ix = np.float32(1.0) / (np.float32(c) * ddx + np.float32(s) * ddy)
                iy = np.float32(1.0) / (np.float32(-s) * ddx + np.float32(c) * ddy)
            x0 = np.float32(-hx - px) * ix
            x1 = np.float32(hx - px) * ix
            y0 = np.float32(-hy - py) * iy
            y1 = np.float32(hy - py) * iy
            txn = np.minimum(x0, x1)
            tyn = np.minimum(y0, y1)
            side_far = np.minimum(np.maximum(x0, x1), np.maximum(y0, y1))
            side = np.maximum(txn, tyn)
            return side, side_far, np.where(txn >= tyn, np.uint8(0), np.uint8(1))
        r = self._half[k, 0]
        ddx, ddy = _cut(dx, rs, cs), _cut(dy, rs, cs)
        qa = ddx * ddx + ddy * ddy
        qb = np.float32(px) * ddx + np.float32(py) * ddy
        qc = np.float32(px * px + py * py - r * r)
        root = np.sqrt(qb * qb - qa * qc)
        return (-qb - root) / qa, (-qb + root) / qa, np.uint8(0)

    def _colour(self, zbuf: npt.NDArray[np.float32], valid: npt.NDArray[np.bool_],
                sem: npt.NDArray[np.uint8], face: npt.NDArray[np.uint8],
                dx: npt.NDArray[np.float32], dy: npt.NDArray[np.float32],
                t: npt.NDArray[np.float64]) -> npt.NDArray[np.uint8]:
        """Class colour x face shade x distance fade via one uint8 look-up table."""
        p = self.params
        levels = _SHADE_LEVELS
        # colour index: class id for objects, floor tiles after the classes, no-hit last
        ci = sem.copy()
        floor = valid & (face == 3)
        rows = np.flatnonzero(floor.any(axis=1))
        if rows.size:
            rs = slice(int(rows[0]), int(rows[-1]) + 1)
            d = zbuf[rs]
            inv_tile = np.float32(1.0 / p.floor_tile_m)
            fx = (np.float32(t[0]) + _cut(dx, rs, slice(None)) * d) * inv_tile
            fy = (np.float32(t[1]) + _cut(dy, rs, slice(None)) * d) * inv_tile
            tile = ((np.floor(fx) + np.floor(fy)).astype(np.int32) & 1).astype(np.uint8)
            np.copyto(ci[rs], _FLOOR_INDEX + tile, where=floor[rs])
        np.copyto(ci, _NONE_INDEX, where=~valid)
        fade = np.minimum(zbuf, np.float32(p.range_max_m)) * np.float32(
            (levels - 1) * 0.5 / p.range_max_m)
        q = (np.float32(levels - 1) - fade).astype(np.uint8)      # 0..levels-1
        return self._lut[ci, face, q]


@dataclass(frozen=True, eq=False)
class _Rays:
    """A frame's world ray directions (float32, optical z component 1) and their
    inverses, each in its smallest broadcastable shape ((h, 1), (1, w) or (h, w))."""

    dx: npt.NDArray[np.float32]
    dy: npt.NDArray[np.float32]
    dz: npt.NDArray[np.float32]
    inv_x: npt.NDArray[np.float32]
    inv_y: npt.NDArray[np.float32]
    inv_z: npt.NDArray[np.float32]


def _cut(arr: npt.NDArray[np.float32], rs: slice, cs: slice) -> npt.NDArray[np.float32]:
    """``arr[rs, cs]`` for an array that may be broadcast along rows or columns."""
    return arr[rs if arr.shape[0] > 1 else slice(None), cs if arr.shape[1] > 1 else slice(None)]
