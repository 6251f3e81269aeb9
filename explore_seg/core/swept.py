"""The floor the robot's body has swept: proven free of obstacles below its height.

Where the robot drove, nothing it could collide with stands (it would have collided).
The object costmap uses this to clear its layer along the robot's path: boxes grown
from partial views, or a wrong orientation, must never close the way the robot came in
(a passage it physically used), else exploration ends early with the robot "trapped"
by virtual obstacles.

:class:`SweptPath` keeps the robot's positions (decimated by distance, bounded in
number) in the map frame, so it survives map growth and origin shifts, and rasterises
the swept corridor onto any grid geometry.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap

#: Sub-pixel bits of the cv2 drawing calls.
_SHIFT = 4


class SweptPath:
    """Positions of the robot, decimated by ``spacing_m``, for :meth:`mask`.

    Parameters
    ----------
    spacing_m : float
        A position is kept when it is at least this far from the last kept one.
    max_points : int
        When reached, every second point is dropped (and the spacing doubled), so memory
        stays bounded on long runs; the corridor between kept points is still drawn.
    max_gap_m : float
        Consecutive points farther apart than this (a pose jump: relocalisation,
        teleport, a new session) are not joined by a corridor.

    Raises
    ------
    ValueError
        On a spacing or gap that is not finite and > 0, or ``max_points < 2``.
    """

    def __init__(self, spacing_m: float = 0.05, max_points: int = 20000,
                 max_gap_m: float = 1.0) -> None:
        for name, v in (("spacing_m", spacing_m), ("max_gap_m", max_gap_m)):
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if max_points < 2:
            raise ValueError(f"max_points must be >= 2, got {max_points}")
        self.spacing_m = float(spacing_m)
        self.max_points = int(max_points)
        self.max_gap_m = float(max_gap_m)
        self._pts: list[tuple[float, float]] = []
        self._latest: tuple[float, float] | None = None

    def __len__(self) -> int:
        return len(self._pts)

    def add(self, x_m: float, y_m: float) -> bool:
        """Record a robot position (map frame); False when it was not kept (too close to
        the last one, or not finite)."""
        if not (math.isfinite(x_m) and math.isfinite(y_m)):
            return False
        self._latest = (float(x_m), float(y_m))
        if self._pts:
            lx, ly = self._pts[-1]
            if math.hypot(x_m - lx, y_m - ly) < self.spacing_m:
                return False
        self._pts.append((float(x_m), float(y_m)))
        if len(self._pts) >= self.max_points:
            # Every second point, the oldest and the newest always kept.
            keep = self._pts[::2]
            if len(self._pts) % 2 == 0:
                keep.append(self._pts[-1])
            self._pts = keep
            self.spacing_m *= 2.0
        return True

    def points(self) -> npt.NDArray[np.float64]:
        """Kept positions, oldest first, and the newest position given, shape (N, 2)."""
        pts = list(self._pts)
        if self._latest is not None and (not pts or pts[-1] != self._latest):
            pts.append(self._latest)
        return np.asarray(pts, dtype=np.float64).reshape(-1, 2)

    def mask(self, grid: GridMap, radius_m: float) -> npt.NDArray[np.bool_]:
        """Cells of ``grid`` within ``radius_m`` of the path (a disk at every kept
        position, a corridor between consecutive ones; exact to within one cell),
        shape ``grid.shape``.

        Raises
        ------
        ValueError
            When ``radius_m`` is not finite and >= 0.
        """
        if not (math.isfinite(radius_m) and radius_m >= 0):
            raise ValueError(f"radius_m must be finite and >= 0, got {radius_m}")
        img = np.zeros(grid.shape, dtype=np.uint8)
        pts = self.points()
        if len(pts) == 0 or radius_m == 0:
            return img.astype(bool)
        rows, cols = grid.world_to_cell_float(pts[:, 0], pts[:, 1])
        # Cell (r, c) spans [c, c + 1) with its centre at c + 0.5 -> pixel c in cv2.
        px = np.stack([cols - 0.5, rows - 0.5], axis=1) * (1 << _SHIFT)
        lim = float(1 << 26)     # far outside the image: cv2 clips, int32 stays safe
        px = np.clip(np.round(px), -lim, lim).astype(np.int32)
        # The centre line, one polyline per run without pose jumps, then every cell
        # within radius_m of it (distance transform; the centre line is drawn through
        # cells, so the border is exact to within a cell).
        step = np.hypot(np.diff(pts[:, 0]), np.diff(pts[:, 1]))
        cuts = np.flatnonzero(step > self.max_gap_m) + 1
        runs = [r for r in np.split(px, cuts) if len(r)]
        cv2.polylines(img, [r.reshape(-1, 1, 2) for r in runs], False, 1, 1, cv2.LINE_8,
                      _SHIFT)
        for r in runs:
            if len(r) == 1:
                cv2.circle(img, (int(r[0, 0]), int(r[0, 1])), 0, 1, -1, cv2.LINE_8, _SHIFT)
        if not img.any():
            return img.astype(bool)
        dist = cv2.distanceTransform((img == 0).astype(np.uint8), cv2.DIST_L2,
                                     cv2.DIST_MASK_PRECISE)
        return dist * grid.resolution_m <= radius_m
