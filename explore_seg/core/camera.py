"""Pinhole camera model, depth back-projection and camera extrinsics.

Frames (REP 103 / REP 105):

* **body** frames (``base_link``, ``camera_link``): x forward, y left, z up.
* **optical** frame (``camera_color_optical_frame``): x right, y down, z forward
  (the frame image pixels and depth live in).

A point ``p_opt`` in the optical frame maps to the body-style camera frame by
``p_cam = R_BODY_FROM_OPTICAL @ p_opt``. The camera mount on the robot is given as
``(x, y, z, roll, pitch, yaw)`` of the body-style camera frame in ``base_link``
(the usual URDF / ``static_transform_publisher`` convention, rotation
``Rz(yaw) @ Ry(pitch) @ Rx(roll)``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

#: Rotation taking optical-frame coordinates (x right, y down, z forward) to
#: body-style camera coordinates (x forward, y left, z up).
R_BODY_FROM_OPTICAL: npt.NDArray[np.float64] = np.array(
    [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]], dtype=np.float64
)
#: Inverse of :data:`R_BODY_FROM_OPTICAL`.
R_OPTICAL_FROM_BODY: npt.NDArray[np.float64] = R_BODY_FROM_OPTICAL.T.copy()


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics of an undistorted image.

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels, > 0.
    cx, cy : float
        Principal point in pixels.
    width, height : int
        Image size in pixels, > 0.

    Raises
    ------
    ValueError
        On non-finite values, non-positive focal lengths or image size.

    Examples
    --------
    >>> k = CameraIntrinsics(500.0, 500.0, 320.0, 240.0, 640, 480)
    >>> float(k.matrix()[0, 2])
    320.0
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int

    def __post_init__(self) -> None:
        for name in ("fx", "fy", "cx", "cy"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite, got {value}")
        if not (self.fx > 0 and self.fy > 0):
            raise ValueError(f"focal lengths must be > 0, got fx={self.fx}, fy={self.fy}")
        if int(self.width) != self.width or int(self.height) != self.height:
            raise ValueError(
                f"width/height must be integers, got {self.width}x{self.height}")
        if not (self.width > 0 and self.height > 0):
            raise ValueError(
                f"image size must be > 0, got width={self.width}, height={self.height}")

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(height, width)``."""
        return (int(self.height), int(self.width))

    def matrix(self) -> npt.NDArray[np.float64]:
        """Return the 3x3 camera matrix ``K``."""
        return np.array(
            [[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]],
            dtype=np.float64,
        )

    def scaled(self, width: int, height: int) -> CameraIntrinsics:
        """Intrinsics of the same camera resized to ``width`` x ``height`` pixels."""
        sx = width / self.width
        sy = height / self.height
        return CameraIntrinsics(self.fx * sx, self.fy * sy, self.cx * sx, self.cy * sy,
                                int(width), int(height))


def depth_to_points(
    depth_m: npt.NDArray[np.floating],
    intrinsics: CameraIntrinsics,
    mask: npt.NDArray[np.bool_] | None = None,
    max_depth_m: float = math.inf,
) -> npt.NDArray[np.float32]:
    """Back-project a depth image to points in the optical frame.

    Parameters
    ----------
    depth_m : ndarray of float, shape (H, W)
        Depth along the optical axis in metres; NaN, inf and ``<= 0`` are invalid.
    intrinsics : CameraIntrinsics
        Must match the image size (``width == W``, ``height == H``).
    mask : ndarray of bool, shape (H, W), optional
        Only pixels where ``mask`` is true are returned.
    max_depth_m : float
        Pixels farther than this are dropped.

    Returns
    -------
    ndarray of float32, shape (N, 3)
        ``(x right, y down, z forward)`` in metres, in row-major pixel order.

    Raises
    ------
    ValueError
        If ``depth_m`` is not 2D, its size differs from the intrinsics or the mask
        shape differs from the image.

    Examples
    --------
    >>> k = CameraIntrinsics(2.0, 2.0, 1.0, 1.0, 2, 2)
    >>> depth_to_points(np.full((2, 2), 1.0, np.float32), k)[0]
    array([-0.5, -0.5,  1. ], dtype=float32)
    """
    depth = np.asarray(depth_m)
    if depth.ndim != 2:
        raise ValueError(f"depth must be 2D (H, W), got shape {depth.shape}")
    if depth.shape != intrinsics.shape:
        raise ValueError(
            f"depth shape {depth.shape} does not match intrinsics (height, width)="
            f"{intrinsics.shape}")
    valid = np.isfinite(depth) & (depth > 0) & (depth <= max_depth_m)
    if mask is not None:
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != depth.shape:
            raise ValueError(f"mask shape {mask.shape} does not match depth {depth.shape}")
        valid &= mask
    rows, cols = np.nonzero(valid)
    z = depth[rows, cols].astype(np.float32)
    # ROS convention: pixel (col, row) is centred at integer (u, v) = (col, row).
    x = (cols.astype(np.float32) - np.float32(intrinsics.cx)) * z / np.float32(intrinsics.fx)
    y = (rows.astype(np.float32) - np.float32(intrinsics.cy)) * z / np.float32(intrinsics.fy)
    return np.stack([x, y, z], axis=1).astype(np.float32, copy=False)


def project_points(
    points_opt: npt.NDArray[np.floating], intrinsics: CameraIntrinsics
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]]:
    """Project optical-frame points to pixel coordinates.

    Parameters
    ----------
    points_opt : ndarray of float, shape (N, 3)
        Points in the optical frame (metres).
    intrinsics : CameraIntrinsics
        Camera model.

    Returns
    -------
    u, v : ndarray of float64, shape (N,)
        Column and row pixel coordinates (NaN behind the camera).
    in_front : ndarray of bool, shape (N,)
        True where ``z > 0``.

    Raises
    ------
    ValueError
        If ``points_opt`` is not (N, 3).
    """
    pts = np.asarray(points_opt, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {pts.shape}")
    z = pts[:, 2]
    in_front = z > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        u = np.where(in_front, intrinsics.fx * pts[:, 0] / z + intrinsics.cx, np.nan)
        v = np.where(in_front, intrinsics.fy * pts[:, 1] / z + intrinsics.cy, np.nan)
    return u, v, in_front


def rotation_rpy(roll_rad: float, pitch_rad: float, yaw_rad: float) -> npt.NDArray[np.float64]:
    """Rotation matrix ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (fixed-axis roll, pitch, yaw).

    Parameters
    ----------
    roll_rad, pitch_rad, yaw_rad : float
        Angles in radians.

    Returns
    -------
    ndarray of float64, shape (3, 3)
    """
    cr, sr = math.cos(roll_rad), math.sin(roll_rad)
    cp, sp = math.cos(pitch_rad), math.sin(pitch_rad)
    cy, sy = math.cos(yaw_rad), math.sin(yaw_rad)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def make_transform(rotation: npt.ArrayLike, translation: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Build a 4x4 homogeneous transform from a 3x3 rotation and a 3-vector.

    Raises
    ------
    ValueError
        On wrong shapes.
    """
    rot = np.asarray(rotation, dtype=np.float64)
    trans = np.asarray(translation, dtype=np.float64).reshape(-1)
    if rot.shape != (3, 3):
        raise ValueError(f"rotation must be 3x3, got {rot.shape}")
    if trans.shape != (3,):
        raise ValueError(f"translation must have 3 elements, got {trans.shape}")
    out = np.eye(4)
    out[:3, :3] = rot
    out[:3, 3] = trans
    return out


def base_from_optical(
    x_m: float, y_m: float, z_m: float, roll_rad: float, pitch_rad: float, yaw_rad: float
) -> npt.NDArray[np.float64]:
    """Transform taking optical-frame points to ``base_link``.

    Parameters
    ----------
    x_m, y_m, z_m : float
        Position of the camera in ``base_link`` (metres).
    roll_rad, pitch_rad, yaw_rad : float
        Orientation of the body-style camera frame (x forward, z up) in ``base_link``;
        all zero for a level camera looking along the robot's x axis.

    Returns
    -------
    ndarray of float64, shape (4, 4)
        ``T`` with ``p_base = T[:3, :3] @ p_opt + T[:3, 3]``.

    Examples
    --------
    >>> t = base_from_optical(0.1, 0.0, 0.5, 0.0, 0.0, 0.0)
    >>> apply_transform(t, np.array([[0.0, 0.0, 2.0]]))  # 2 m ahead of the lens
    array([[2.1, 0. , 0.5]])
    """
    rot = rotation_rpy(roll_rad, pitch_rad, yaw_rad) @ R_BODY_FROM_OPTICAL
    return make_transform(rot, (x_m, y_m, z_m))


def map_from_base(x_m: float, y_m: float, yaw_rad: float) -> npt.NDArray[np.float64]:
    """Transform of a planar robot pose ``(x, y, yaw)``: ``base_link`` -> ``map``."""
    return make_transform(rotation_rpy(0.0, 0.0, yaw_rad), (x_m, y_m, 0.0))


def invert_transform(transform: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Inverse of a rigid 4x4 transform.

    Raises
    ------
    ValueError
        If ``transform`` is not 4x4.
    """
    t = np.asarray(transform, dtype=np.float64)
    if t.shape != (4, 4):
        raise ValueError(f"transform must be 4x4, got {t.shape}")
    rot = t[:3, :3].T
    return make_transform(rot, -rot @ t[:3, 3])


def apply_transform(
    transform: npt.ArrayLike, points: npt.NDArray[np.floating]
) -> npt.NDArray[np.float64]:
    """Apply a 4x4 transform to points.

    Parameters
    ----------
    transform : array_like, shape (4, 4)
    points : ndarray, shape (N, 3)

    Returns
    -------
    ndarray of float64, shape (N, 3)

    Raises
    ------
    ValueError
        On wrong shapes.
    """
    t = np.asarray(transform, dtype=np.float64)
    pts = np.asarray(points, dtype=np.float64)
    if t.shape != (4, 4):
        raise ValueError(f"transform must be 4x4, got {t.shape}")
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {pts.shape}")
    return pts @ t[:3, :3].T + t[:3, 3]
