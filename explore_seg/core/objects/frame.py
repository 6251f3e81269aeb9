"""A camera frame of the object costmap: the depth image with its camera model and pose,
the detections it comes with, and the pixel-level steps on it (back-projection of a
mask, where the view cuts an object)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.camera import CameraIntrinsics, apply_transform


class BoxDetection(Protocol):
    """What the pipeline needs from a 2D detection (``core.detector.Detection`` fits)."""

    cls_name: str
    score: float
    box_xyxy: Sequence[float]


@dataclass(frozen=True)
class DepthFrame:
    """A depth image with its camera model and pose in the map frame.

    Parameters
    ----------
    depth_m : ndarray of float32, shape (H, W)
        Depth along the optical axis (metres), NaN / <= 0 invalid.
    intrinsics : CameraIntrinsics
        Matching ``depth_m``'s size.
    map_from_optical : ndarray of float64, shape (4, 4)
        Transform taking optical-frame points to the map frame.

    Raises
    ------
    ValueError
        On a size mismatch or a malformed transform.
    """

    depth_m: npt.NDArray[np.float32]
    intrinsics: CameraIntrinsics
    map_from_optical: npt.NDArray[np.float64]

    def __post_init__(self) -> None:
        depth = np.asarray(self.depth_m)
        if depth.ndim != 2:
            raise ValueError(f"depth must be 2D (H, W), got shape {depth.shape}")
        if depth.shape != self.intrinsics.shape:
            raise ValueError(f"depth shape {depth.shape} does not match camera info "
                             f"(height, width)={self.intrinsics.shape}")
        t = np.asarray(self.map_from_optical, dtype=np.float64)
        if t.shape != (4, 4) or not np.all(np.isfinite(t)):
            raise ValueError(f"map_from_optical must be a finite 4x4 matrix, got shape {t.shape}")
        object.__setattr__(self, "depth_m", depth.astype(np.float32, copy=False))
        object.__setattr__(self, "map_from_optical", t)

    @property
    def camera_xyz(self) -> npt.NDArray[np.float64]:
        """Camera position in the map frame, shape (3,)."""
        return self.map_from_optical[:3, 3].copy()


def frame_points(frame: DepthFrame, mask: npt.NDArray[np.bool_], max_depth_m: float
                 ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64],
                            npt.NDArray[np.float32]]:
    """Map-frame points, pixel (u, v) and depth of the valid pixels under ``mask``.

    Returns
    -------
    points_map : ndarray of float64, shape (N, 3)
    pixels_uv : ndarray of float64, shape (N, 2)
    depth : ndarray of float32, shape (N,)
    """
    # Work on the mask's bounding window only (a detection box is a small part of the
    # image); np.nonzero's row-major order is the same as on the whole image.
    any_row = np.flatnonzero(mask.any(axis=1))
    if len(any_row) == 0:
        empty = np.zeros((0, 2), dtype=np.float64)
        return np.zeros((0, 3), dtype=np.float64), empty, np.zeros(0, dtype=np.float32)
    any_col = np.flatnonzero(mask[any_row[0]:any_row[-1] + 1].any(axis=0))
    r0, c0 = int(any_row[0]), int(any_col[0])
    win = (slice(r0, int(any_row[-1]) + 1), slice(c0, int(any_col[-1]) + 1))
    d = frame.depth_m[win]
    with np.errstate(invalid="ignore"):
        valid = mask[win] & np.isfinite(d) & (d > 0) & (d <= max_depth_m)
    rows, cols = np.nonzero(valid)
    z = d[rows, cols]
    rows, cols = rows + r0, cols + c0
    k = frame.intrinsics
    x = (cols - k.cx) * z / k.fx
    y = (rows - k.cy) * z / k.fy
    pts_opt = np.stack([x, y, z], axis=1)
    pts_map = apply_transform(frame.map_from_optical, pts_opt)
    return pts_map, np.stack([cols, rows], axis=1).astype(np.float64), z


def view_cut(frame: DepthFrame, pixels_uv: npt.NDArray[np.floating],
             depth_m: npt.NDArray[np.floating], step_px: int, margin_m: float
             ) -> npt.NDArray[np.bool_]:
    """Points where the view, not the object, ends: at the image border or beside a
    nearer surface (an occluder).

    Parameters
    ----------
    frame : DepthFrame
    pixels_uv : ndarray, shape (N, 2)
        Pixel (column, row) of each point.
    depth_m : ndarray, shape (N,)
        Optical depth of each point.
    step_px : int
        The sampling step: a point within ``step_px`` of the border, or whose pixel
        ``step_px`` away (left, right, up, down) is nearer by more than ``margin_m``, is cut.
    margin_m : float

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    k = frame.intrinsics
    uv = np.asarray(pixels_uv, dtype=np.int64).reshape(-1, 2)
    z = np.asarray(depth_m, dtype=np.float64).reshape(-1)
    step = max(int(step_px), 1)
    u, v = uv[:, 0], uv[:, 1]
    cut = (u <= step) | (u >= k.width - 1 - step) | (v <= step) | (v >= k.height - 1 - step)
    d = frame.depth_m
    for du, dv in ((step, 0), (-step, 0), (0, step), (0, -step)):
        nd = d[np.clip(v + dv, 0, k.height - 1), np.clip(u + du, 0, k.width - 1)]
        with np.errstate(invalid="ignore"):
            cut |= np.isfinite(nd) & (nd > 0) & (nd < z - margin_m)
    return cut
