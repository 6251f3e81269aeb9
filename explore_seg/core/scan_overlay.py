"""What the lidar saw since the map: recent scans laid over the SLAM map's unknown cells.

slam_toolbox publishes its map every ``map_update_interval`` (5 s by default) and builds it
from keyframe scans only (after 0.5 m of travel or 0.5 rad of turn), so the map the
explorer decides on can be seconds behind what the robot has already seen: a room it has
looked into still shows frontiers, and a reached goal waits for the next map before it
counts as explored. Nav2's costmaps avoid this by marking and clearing from every scan;
:class:`ScanOverlay` gives the explorer the same view of the recent past.

* :meth:`ScanOverlay.add_scan` rasterises one scan, taken at a robot pose in the map frame,
  onto a square window of cells aligned with the map's cells: the cells its beams cross
  are stamped "seen free", the cells of its returns "seen occupied" (a beam without a
  return carves free space up to ``range_max``, as the SLAM map does).
* :meth:`ScanOverlay.apply` returns the map with its **unknown** cells that a scan saw in
  the last ``keep_s`` seconds filled in (occupied where a return fell, else free), stamped
  with the newest scan. Known cells of the map are never changed: the SLAM map stays the
  authority on everything it has; the overlay only bridges the time until the next map.
  The map's outermost ring of cells is left alone, so that space seen beyond the map's
  current extent still shows as a frontier at its border.

Cells seen only by scans older than ``keep_s`` fall back to what the map says: a view that
never became a keyframe reappears as a frontier, so the explorer goes back until the SLAM
map has it. The window (``window_m`` on a side) follows the newest scan; memory is fixed.
The overlay forgets everything when the map's resolution or cell lattice changes (a new
map) or time goes back. At a SLAM correction (a loop closure that re-rendered the map from
corrected poses) :meth:`ScanOverlay.forget_before` drops the cells last seen before it: the
scans behind them were laid at the uncorrected poses, so they would fill unknown cells where
the corrected map has no room (free cells beyond a wall that moved). A cell seen again since
the correction keeps that newer, corrected view.

Examples
--------
>>> import numpy as np
>>> from explore_seg.core.grid import GridMap
>>> grid = GridMap(np.full((40, 40), -1, dtype=np.int8), 0.1, (0.0, 0.0))
>>> ov = ScanOverlay(ScanOverlayParams())
>>> ov.add_scan(1.0, (2.0, 2.0, 0.0), np.array([0.0]), np.array([1.0]), 3.5)
>>> seen = ov.apply(grid)
>>> int(seen.data[20, 25]), int(seen.data[20, 30]), int(seen.data[20, 31])
(0, 100, -1)
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.corrections import CorrectionParams
from explore_seg.core.fields import param_meta
from explore_seg.core.grid import OCCUPIED, UNKNOWN, GridMap, beam_samples, range_returns

#: Beams per scan accepted (a 0.1 deg scanner has 3600).
MAX_BEAMS = 100_000
#: Scans kept while no map has given the cell lattice yet.
_PENDING_SCANS = 64
#: Sub-cell misalignment of a map's origin that still counts as the same lattice.
_LATTICE_TOL = 0.01
#: Time going back by more than this resets the overlay.
_BACK_TOL_S = 0.5
#: Free samples per cell along a beam.
_SAMPLES_PER_CELL = 2.0


@dataclass(frozen=True)
class ScanOverlayParams(CorrectionParams):
    """Parameters of :class:`ScanOverlay` (ROS parameters ``scan_overlay.*`` of
    ``target_selector``); the ``correction_*`` thresholds find the SLAM corrections at
    which the overlay forgets the scans taken before them."""

    enabled: bool = field(default=True, metadata=param_meta(
        "decide on the map with its unknown cells filled in by the scans of the last keep_s "
        "(subscribes 'scan'); the SLAM map alone decides that exploration is done"))
    keep_s: float = field(default=10.0, metadata=param_meta(
        "a scan fills unknown cells for this long (two of slam_toolbox's 5 s "
        "map_update_interval: by then the map holds what its keyframes saw)", "s",
        range=(0.0, math.inf)))
    window_m: float = field(default=24.0, metadata=param_meta(
        "side of the square window, following the robot, that scans are kept on; beams "
        "reach at most half of it", "m", range=(0.0, math.inf)))
    lidar_x_m: float = field(default=0.0, metadata=param_meta(
        "the scanner's x in the robot's base frame (TurtleBot3 waffle: -0.064)", "m"))
    lidar_y_m: float = field(default=0.0, metadata=param_meta(
        "the scanner's y in the robot's base frame", "m"))
    lidar_yaw_rad: float = field(default=0.0, metadata=param_meta(
        "the scanner's yaw in the robot's base frame", "rad"))
    max_pose_age_s: float = field(default=0.2, metadata=param_meta(
        "a scan is used only with a robot pose stamped within this of it", "s",
        range=(0.0, math.inf)))
    def __post_init__(self) -> None:
        for name in ("keep_s", "window_m", "max_pose_age_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        for name in ("lidar_x_m", "lidar_y_m", "lidar_yaw_rad"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v}")
        self.check_corrections()


@dataclass(frozen=True)
class _Scan:
    """One scan in the map frame: sensor position, beam directions, lengths, returns."""

    stamp_s: float
    x: float
    y: float
    angles: npt.NDArray[np.float64]     # map-frame beam directions
    length: npt.NDArray[np.float64]     # metres to the return, or range_max
    hit: npt.NDArray[np.bool_]          # the beam ends at a return


class ScanOverlay:
    """Recent scans on a window of cells aligned with the map: see the module docstring.

    Parameters
    ----------
    params : ScanOverlayParams
    """

    def __init__(self, params: ScanOverlayParams) -> None:
        self.params = params
        self._pending: deque[_Scan] = deque(maxlen=_PENDING_SCANS)
        self._newest_s = -math.inf
        self._forgot_s = -math.inf        # scans taken before this are refused
        self._clear_lattice()

    def _clear_lattice(self) -> None:
        self._res = 0.0
        self._anchor = (0.0, 0.0)          # a map-frame corner of the lattice
        self._corner = (0, 0)              # lattice (col, row) of window cell [0, 0]
        self._free_t: npt.NDArray[np.float32] | None = None
        self._hit_t: npt.NDArray[np.float32] | None = None
        self._t0 = 0.0

    def reset(self) -> None:
        """Forget every scan (time jumped, a new map session)."""
        self._pending.clear()
        self._newest_s = -math.inf
        self._forgot_s = -math.inf
        self._clear_lattice()

    def forget_before(self, stamp_s: float | None = None) -> None:
        """Forget what the scans taken before ``stamp_s`` saw (None: every scan), keeping
        the cells a later scan saw (a SLAM correction at ``stamp_s``: module docstring).
        A scan taken before ``stamp_s`` that arrives later is refused too."""
        if stamp_s is None or not math.isfinite(stamp_s):
            self.reset()
            return
        self._forgot_s = max(self._forgot_s, float(stamp_s))
        kept = [s for s in self._pending if s.stamp_s >= stamp_s]
        self._pending.clear()
        self._pending.extend(kept)
        if self._free_t is not None and self._hit_t is not None:
            cut = np.float32(stamp_s - self._t0)
            self._free_t[self._free_t < cut] = -np.inf
            self._hit_t[self._hit_t < cut] = -np.inf

    def add_scan(self, stamp_s: float, robot_pose: tuple[float, float, float],
                 angles: npt.ArrayLike, ranges: npt.ArrayLike, range_max_m: float,
                 range_min_m: float = 0.0) -> None:
        """Lay one scan over the window.

        Parameters
        ----------
        stamp_s : float
            The scan's time (the clock of :meth:`apply`'s maps).
        robot_pose : (x_m, y_m, yaw_rad)
            The robot's map-frame pose when the scan was taken; the scanner sits at
            ``lidar_x_m`` / ``lidar_y_m`` / ``lidar_yaw_rad`` on it.
        angles, ranges : array_like, shape (N,)
            Beam angles in the scanner frame and ranges in metres (inf or >= range_max:
            no return, free up to range_max; NaN or below range_min: ignored).
        range_max_m, range_min_m : float

        Raises
        ------
        ValueError
            On a non-finite stamp or pose, mismatched or non-1D arrays, more than
            :data:`MAX_BEAMS` beams, non-finite angles, or a range_max that is not
            finite and > 0. Nothing is changed then.
        """
        scan = self._checked(stamp_s, robot_pose, angles, ranges, range_max_m, range_min_m)
        if scan is None:
            return
        if stamp_s < self._newest_s - _BACK_TOL_S:
            self.reset()
        if stamp_s < self._forgot_s:
            return                        # laid at a pose from before a correction
        self._newest_s = max(self._newest_s, float(stamp_s))
        if self._free_t is None:
            self._pending.append(scan)
        else:
            self._rasterise(scan)

    def _checked(self, stamp_s: float, robot_pose: tuple[float, float, float],
                 angles: npt.ArrayLike, ranges: npt.ArrayLike, range_max_m: float,
                 range_min_m: float) -> _Scan | None:
        """The scan in the map frame (None: no beam to use), or ValueError."""
        if not math.isfinite(stamp_s):
            raise ValueError(f"scan stamp must be finite, got {stamp_s}")
        x, y, yaw = (float(v) for v in robot_pose)
        if not all(math.isfinite(v) for v in (x, y, yaw)):
            raise ValueError(f"robot pose must be finite, got {robot_pose}")
        a = np.asarray(angles, dtype=np.float64)
        r = np.asarray(ranges, dtype=np.float64)
        if a.ndim != 1 or r.shape != a.shape:
            raise ValueError(f"angles and ranges must be 1D of one length, got shapes "
                             f"{a.shape} and {r.shape}")
        if a.size > MAX_BEAMS:
            raise ValueError(f"scan has {a.size} beams, at most {MAX_BEAMS} accepted")
        if not np.isfinite(a).all():
            raise ValueError("scan angles must be finite")
        if not (math.isfinite(range_max_m) and range_max_m > 0):
            raise ValueError(f"range_max must be finite and > 0, got {range_max_m}")
        p = self.params
        c, s = math.cos(yaw), math.sin(yaw)
        sx = x + c * p.lidar_x_m - s * p.lidar_y_m
        sy = y + s * p.lidar_x_m + c * p.lidar_y_m
        hit, miss = range_returns(r, range_min_m, range_max_m)
        keep = hit | miss
        if not keep.any():
            return None
        reach = min(float(range_max_m), 0.5 * p.window_m)
        length = np.minimum(np.where(hit, r, range_max_m), reach)[keep]
        hit = (hit & (r <= reach))[keep]
        return _Scan(float(stamp_s), sx, sy, yaw + p.lidar_yaw_rad + a[keep], length, hit)

    # ---------------------------------------------------------------- lattice
    def _align(self, grid: GridMap) -> tuple[int, int] | None:
        """Lattice (col, row) of ``grid``'s cell [0, 0], starting a lattice on it when
        there is none or its cells are not ``grid``'s (None: a rotated map)."""
        if grid.origin_yaw_rad != 0.0:
            return None
        ox, oy = grid.origin_xy_m
        if self._free_t is not None and abs(grid.resolution_m - self._res) <= 1e-9:
            fx = (ox - self._anchor[0]) / self._res
            fy = (oy - self._anchor[1]) / self._res
            cx, cy = round(fx), round(fy)
            if abs(fx - cx) <= _LATTICE_TOL and abs(fy - cy) <= _LATTICE_TOL:
                return int(cx), int(cy)
        self._clear_lattice()
        self._res, self._anchor = grid.resolution_m, (ox, oy)
        n = max(1, int(math.ceil(self.params.window_m / self._res)))
        self._free_t = np.full((n, n), -np.inf, dtype=np.float32)
        self._hit_t = np.full((n, n), -np.inf, dtype=np.float32)
        self._t0 = self._newest_s if math.isfinite(self._newest_s) else 0.0
        self._centre_on(0.0, 0.0)
        for scan in self._pending:
            self._rasterise(scan)
        self._pending.clear()
        return 0, 0

    def _centre_on(self, x: float, y: float) -> None:
        """Move the window so that map point (x, y) lies at its centre, keeping the cells
        both windows hold."""
        assert self._free_t is not None and self._hit_t is not None
        n = self._free_t.shape[0]
        col = int(math.floor((x - self._anchor[0]) / self._res)) - n // 2
        row = int(math.floor((y - self._anchor[1]) / self._res)) - n // 2
        dc, dr = col - self._corner[0], row - self._corner[1]
        if (dc, dr) == (0, 0):
            return
        for name in ("_free_t", "_hit_t"):
            old = getattr(self, name)
            new = np.full_like(old, -np.inf)
            r0, r1 = max(0, dr), min(n, n + dr)
            c0, c1 = max(0, dc), min(n, n + dc)
            if r0 < r1 and c0 < c1:
                new[r0 - dr:r1 - dr, c0 - dc:c1 - dc] = old[r0:r1, c0:c1]
            setattr(self, name, new)
        self._corner = (col, row)

    def _rasterise(self, scan: _Scan) -> None:
        """Stamp the cells ``scan``'s beams cross (free) and end in (returns)."""
        assert self._free_t is not None and self._hit_t is not None
        n = self._free_t.shape[0]
        res = self._res
        reach = float(scan.length.max()) / res + 2
        sc = (scan.x - self._anchor[0]) / res - self._corner[0]
        sr = (scan.y - self._anchor[1]) / res - self._corner[1]
        if min(sc, sr) < reach or max(sc, sr) > n - reach:
            self._centre_on(scan.x, scan.y)
            sc = (scan.x - self._anchor[0]) / res - self._corner[0]
            sr = (scan.y - self._anchor[1]) / res - self._corner[1]
        t = np.float32(scan.stamp_s - self._t0)
        ca, sa = np.cos(scan.angles), np.sin(scan.angles)
        len_cells = scan.length / res
        rows_f, cols_f = beam_samples(sc, sr, len_cells, ca, sa, 1.0 / _SAMPLES_PER_CELL)
        self._stamp(self._free_t, rows_f.astype(np.int64), cols_f.astype(np.int64), t)
        ends = scan.hit
        if ends.any():
            cols = np.floor(sc + len_cells[ends] * ca[ends]).astype(np.int64)
            rows = np.floor(sr + len_cells[ends] * sa[ends]).astype(np.int64)
            self._stamp(self._hit_t, rows, cols, t)

    @staticmethod
    def _stamp(arr: npt.NDArray[np.float32], rows: npt.NDArray[np.int64],
               cols: npt.NDArray[np.int64], t: np.float32) -> None:
        n = arr.shape[0]
        ok = (rows >= 0) & (rows < n) & (cols >= 0) & (cols < n)
        arr[rows[ok], cols[ok]] = t

    # ------------------------------------------------------------------ apply
    def apply(self, grid: GridMap) -> GridMap:
        """``grid`` with its unknown cells seen by the scans of the last ``keep_s`` filled
        in (see the module docstring); ``grid`` itself when nothing changes."""
        if not self.params.enabled or not math.isfinite(self._newest_s):
            return grid
        corner = self._align(grid)
        if corner is None:
            return grid
        assert self._free_t is not None and self._hit_t is not None
        n = self._free_t.shape[0]
        h, w = grid.shape
        # grid cell (r, c) is window cell (r + dr, c + dc)
        dc, dr = corner[0] - self._corner[0], corner[1] - self._corner[1]
        r0, r1 = max(1, -dr), min(h - 1, n - dr)
        c0, c1 = max(1, -dc), min(w - 1, n - dc)
        if r0 >= r1 or c0 >= c1:
            return grid
        cutoff = np.float32(self._newest_s - self.params.keep_s - self._t0)
        win = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
        sub = grid.data[r0:r1, c0:c1]
        unknown = sub == UNKNOWN
        hit = unknown & (self._hit_t[win] >= cutoff)
        free = unknown & (self._free_t[win] >= cutoff) & ~hit
        if not (hit.any() or free.any()):
            return grid
        data = grid.data.copy()
        out = data[r0:r1, c0:c1]
        out[hit] = OCCUPIED
        out[free] = 0
        stamp_ns = max(int(grid.stamp_ns), int(round(self._newest_s * 1e9)))
        return GridMap(data, grid.resolution_m, grid.origin_xy_m, grid.origin_yaw_rad,
                       grid.frame_id, stamp_ns)
