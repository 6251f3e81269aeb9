"""Log-odds occupancy mapping from 2D lidar scans (the simulator's stand-in for SLAM).

:class:`ScanMapper` integrates scans taken at known poses into a log-odds grid and
publishes it as a trinary :class:`~explore_seg.core.grid.GridMap` (``-1`` unknown,
``0`` free, ``100`` occupied), the way slam_toolbox publishes ``map``. Like a SLAM map
it starts small around the robot and grows in whole chunks when a scan reaches past (or
into the last cell of) its border, so free space always has unknown cells beyond it (a
frontier); the origin then moves by a whole number of cells, so a wall's world position
never changes.

Ray carving is vectorised: every beam is sampled at ``ray_step_cells`` cell steps up to
its hit (or up to ``range_max`` when there is no return); each cell is updated at most
once per scan, and a cell hit by any beam of the scan is not also cleared by it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.fields import param_meta
from explore_seg.core.grid import FREE, OCCUPIED, UNKNOWN, GridMap, beam_samples, range_returns


@dataclass(frozen=True)
class MappingParams:
    """Parameters of :class:`ScanMapper` (log-odds sensor model and map growth)."""

    resolution_m: float = field(default=0.05, metadata=param_meta(
        "map cell size", "m", range=(0.0, math.inf)))
    log_odds_hit: float = field(default=2.2, metadata=param_meta(
        "log-odds added to a cell a beam ends in (ln(0.9/0.1); ~5x a miss, so a wall seen once "
        "survives grazing beams, like slam_toolbox's 0.1 hit ratio)", range=(0.0, math.inf)))
    log_odds_miss: float = field(default=-0.4, metadata=param_meta(
        "log-odds added to a cell a beam passes through (ln(0.4/0.6); < 0)",
        range=(-math.inf, 0.0)))
    log_odds_min: float = field(default=-2.0, metadata=param_meta(
        "lower clamp of a cell's log-odds"))
    log_odds_max: float = field(default=3.5, metadata=param_meta(
        "upper clamp of a cell's log-odds"))
    occupied_threshold_log_odds: float = field(default=0.0, metadata=param_meta(
        "observed cells above this log-odds are published occupied (100), the rest free (0)"))
    ray_step_cells: float = field(default=0.5, metadata=param_meta(
        "sampling step along a beam, in cells (<= 1 so no cell is skipped along the axis)",
        range=(0.0, 1.0)))
    initial_size_m: float = field(default=4.0, metadata=param_meta(
        "side of the square map around the first pose", "m", range=(0.0, math.inf)))
    grow_chunk_m: float = field(default=4.0, metadata=param_meta(
        "the map grows by multiples of this on the side a scan leaves it",
        "m", range=(0.0, math.inf)))
    max_size_m: float = field(default=200.0, metadata=param_meta(
        "largest map side; beams beyond are dropped", "m", range=(0.0, math.inf)))

    def __post_init__(self) -> None:
        if not (math.isfinite(self.resolution_m) and self.resolution_m > 0):
            raise ValueError(f"resolution_m must be finite and > 0, got {self.resolution_m}")
        if not self.log_odds_hit > 0:
            raise ValueError(f"log_odds_hit must be > 0, got {self.log_odds_hit}")
        if not self.log_odds_miss < 0:
            raise ValueError(f"log_odds_miss must be < 0, got {self.log_odds_miss}")
        if not self.log_odds_min < self.occupied_threshold_log_odds < self.log_odds_max:
            raise ValueError(
                "need log_odds_min < occupied_threshold_log_odds < log_odds_max, got "
                f"{self.log_odds_min} < {self.occupied_threshold_log_odds} < {self.log_odds_max}")
        if not 0 < self.ray_step_cells <= 1:
            raise ValueError(f"ray_step_cells must be in (0, 1], got {self.ray_step_cells}")
        for name in ("initial_size_m", "grow_chunk_m", "max_size_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= self.resolution_m):
                raise ValueError(f"{name} must be >= resolution_m ({self.resolution_m}), "
                                 f"got {value}")
        if self.max_size_m < self.initial_size_m:
            raise ValueError(f"max_size_m ({self.max_size_m}) must be >= initial_size_m "
                             f"({self.initial_size_m})")


class ScanMapper:
    """Growing log-odds occupancy grid.

    Parameters
    ----------
    center_xy_m : (float, float)
        World point the initial square map is centred on (normally the start pose).
    params : MappingParams
    frame_id : str
        Frame of the published grid.

    Examples
    --------
    >>> m = ScanMapper((0.0, 0.0), MappingParams(initial_size_m=2.0, grow_chunk_m=1.0))
    >>> m.integrate_scan((0.0, 0.0, 0.0), np.array([1.5]), 0.0, 0.1, 3.0)
    >>> g = m.grid()
    >>> int(g.data[g.world_to_cell(1.52, 0.0)]), int(g.data[g.world_to_cell(0.5, 0.0)])
    (100, 0)
    """

    def __init__(self, center_xy_m: tuple[float, float], params: MappingParams | None = None,
                 frame_id: str = "map") -> None:
        self.params = params if params is not None else MappingParams()
        p = self.params
        cx, cy = float(center_xy_m[0]), float(center_xy_m[1])
        if not (math.isfinite(cx) and math.isfinite(cy)):
            raise ValueError(f"center_xy_m must be finite, got {center_xy_m}")
        res = p.resolution_m
        n = max(1, int(round(p.initial_size_m / res)))
        # Origin on the resolution lattice, so maps of runs from different starts align.
        self._origin_cells = (int(math.floor(cx / res)) - n // 2,
                              int(math.floor(cy / res)) - n // 2)
        self._log_odds = np.zeros((n, n), dtype=np.float32)
        self._observed = np.zeros((n, n), dtype=bool)
        # The published trinary values, kept up to date cell by cell as scans touch them
        # (a copy is published; rebuilding it from the log-odds costs a pass over the map).
        self._trinary = np.full((n, n), UNKNOWN, dtype=np.int8)
        self._frame_id = frame_id
        self._chunk_cells = max(1, int(round(p.grow_chunk_m / res)))
        self._max_cells = max(n, int(round(p.max_size_m / res)))
        self._version = 0
        self._cached: GridMap | None = None
        self._cached_key: tuple[int, int] | None = None

    # ------------------------------------------------------------------ state
    @property
    def version(self) -> int:
        """Incremented by every scan that changed the map."""
        return self._version

    @property
    def origin_xy_m(self) -> tuple[float, float]:
        """World position of the lower-left corner of cell (0, 0)."""
        res = self.params.resolution_m
        return (self._origin_cells[0] * res, self._origin_cells[1] * res)

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) of the current grid."""
        return self._log_odds.shape  # type: ignore[return-value]

    @property
    def log_odds(self) -> npt.NDArray[np.float32]:
        """Read-only view of the log-odds array, shape (height, width)."""
        v = self._log_odds.view()
        v.flags.writeable = False
        return v

    def grid(self, stamp_ns: int = 0) -> GridMap:
        """The map as a trinary GridMap (``-1``/``0``/``100``); cached per version."""
        key = (self._version, int(stamp_ns))
        if self._cached is not None and self._cached_key == key:
            return self._cached
        self._cached = GridMap(self._trinary.copy(), self.params.resolution_m,
                               self.origin_xy_m, 0.0,
                               self._frame_id, int(stamp_ns))
        self._cached_key = key
        return self._cached

    # ----------------------------------------------------------------- growth
    def _ensure_contains(self, col_min: int, row_min: int, col_max: int, row_max: int) -> None:
        """Grow the arrays (by whole chunks) so the absolute cell box fits, within max size."""
        h, w = self._log_odds.shape
        ox, oy = self._origin_cells
        ch = self._chunk_cells

        def pad(need_lo: int, need_hi: int, lo: int, size: int) -> tuple[int, int]:
            before = max(0, lo - need_lo)
            after = max(0, need_hi - (lo + size - 1))
            before = -(-before // ch) * ch
            after = -(-after // ch) * ch
            room = self._max_cells - size
            if before + after > room:  # clip growth to the size limit, keep both sides fair
                before = min(before, max(0, room - min(after, room // 2)))
                after = min(after, room - before)
            return before, after

        left, right = pad(col_min, col_max, ox, w)
        down, up = pad(row_min, row_max, oy, h)
        if not (left or right or down or up):
            return
        self._log_odds = np.pad(self._log_odds, ((down, up), (left, right)))
        self._observed = np.pad(self._observed, ((down, up), (left, right)))
        self._trinary = np.pad(self._trinary, ((down, up), (left, right)),
                               constant_values=UNKNOWN)
        self._origin_cells = (ox - left, oy - down)

    # ------------------------------------------------------------ integration
    def _flat_index(self, rows: npt.NDArray[np.float32], cols: npt.NDArray[np.float32]
                    ) -> npt.NDArray[np.int64]:
        """Flat indices of integral (row, col) values; cells outside the grid are dropped."""
        h, w = self._log_odds.shape
        if rows.size == 0:
            return np.zeros(0, dtype=np.int64)
        if rows.min() < 0 or cols.min() < 0 or rows.max() >= h or cols.max() >= w:
            ok = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
            rows, cols = rows[ok], cols[ok]
        return rows.astype(np.int64) * w + cols.astype(np.int64)

    def _free_cells(self, x0: float, y0: float, length: npt.NDArray[np.float64],
                    ca: npt.NDArray[np.float64], sa: npt.NDArray[np.float64]
                    ) -> npt.NDArray[np.int64]:
        """Flat indices of the free samples along every beam (from the sensor at (x0,
        y0), direction (ca, sa), ``length`` metres), ragged and in float32 cell units
        relative to the origin: beam b gets n_b samples at (k + 0.5) * step, all strictly
        before its end (the end cell is handled as a hit, or left alone for a miss)."""
        res = self.params.resolution_m
        ox, oy = self._origin_cells
        fr, fc = beam_samples(x0 / res - ox, y0 / res - oy, length / res, ca, sa,
                              float(self.params.ray_step_cells))
        return self._flat_index(fr, fc)

    def integrate_scan(self, pose: tuple[float, float, float],
                       ranges: npt.ArrayLike, angle_min_rad: float,
                       angle_increment_rad: float, range_max_m: float,
                       range_min_m: float = 0.0) -> None:
        """Integrate one scan taken by a sensor at ``pose`` (x, y, yaw in the map frame).

        Parameters
        ----------
        pose : (float, float, float)
            Sensor pose; beam ``i`` points at ``yaw + angle_min_rad + i * angle_increment_rad``.
        ranges : array_like of float, shape (N,)
            Ranges in metres; ``inf`` (or ``>= range_max_m``) = no return: free space is
            carved up to ``range_max_m``. NaN and ranges below ``range_min_m`` are ignored.
        angle_min_rad, angle_increment_rad : float
        range_max_m : float
            Sensor range, > 0.
        range_min_m : float
            Readings below this are dropped.

        Raises
        ------
        ValueError
            On a non-finite pose, a non-1D ranges array or a non-positive range_max_m.
        """
        x0, y0, yaw = (float(v) for v in pose)
        if not all(math.isfinite(v) for v in (x0, y0, yaw)):
            raise ValueError(f"pose must be finite, got {pose}")
        r = np.asarray(ranges, dtype=np.float64)
        if r.ndim != 1:
            raise ValueError(f"ranges must be 1D, got shape {r.shape}")
        if not (math.isfinite(range_max_m) and range_max_m > 0):
            raise ValueError(f"range_max_m must be finite and > 0, got {range_max_m}")
        if r.size == 0:
            return
        p = self.params
        res = p.resolution_m
        angles = yaw + float(angle_min_rad) + float(angle_increment_rad) * np.arange(r.size)
        hit, miss = range_returns(r, range_min_m, range_max_m)
        keep = hit | miss
        if not keep.any():
            return
        length = np.where(hit, r, range_max_m)[keep]
        hit = hit[keep]
        ca, sa = np.cos(angles[keep]), np.sin(angles[keep])
        ex, ey = x0 + length * ca, y0 + length * sa

        # Absolute lattice cells (origin-independent) of the endpoints and the sensor.
        ecx = np.floor(ex / res).astype(np.int64)
        ecy = np.floor(ey / res).astype(np.int64)
        scx, scy = int(math.floor(x0 / res)), int(math.floor(y0 / res))
        # One cell beyond every end: a beam's last free sample may fall in its end cell,
        # and free space must never reach the border (no unknown cell there: no frontier).
        self._ensure_contains(min(int(ecx.min()), scx) - 1, min(int(ecy.min()), scy) - 1,
                              max(int(ecx.max()), scx) + 1, max(int(ecy.max()), scy) + 1)
        ox, oy = self._origin_cells

        free_idx = self._free_cells(x0, y0, length, ca, sa)
        hit_idx = self._flat_index((ecy[hit] - oy).astype(np.float32),
                                   (ecx[hit] - ox).astype(np.float32))

        lo = self._log_odds.reshape(-1)
        obs = self._observed.reshape(-1)
        if free_idx.size:
            # Fancy-index "+=" applies once per distinct cell: one update per scan.
            was_free = np.zeros(lo.size, dtype=bool)
            was_free[free_idx] = True
            lo[free_idx] += np.float32(p.log_odds_miss)
            obs[free_idx] = True
        else:
            was_free = None
        if hit_idx.size:
            undo = (np.float32(p.log_odds_miss) * was_free[hit_idx]
                    if was_free is not None else np.float32(0.0))
            lo[hit_idx] += np.float32(p.log_odds_hit) - undo
            obs[hit_idx] = True
        touched = np.concatenate([free_idx, hit_idx])
        if touched.size:
            lo[touched] = np.clip(lo[touched], p.log_odds_min, p.log_odds_max)
            # Every touched cell is observed: free, or occupied above the threshold.
            self._trinary.reshape(-1)[touched] = np.where(
                lo[touched] > p.occupied_threshold_log_odds, OCCUPIED, FREE)
            self._version += 1
