"""Occupancy grid map: the one place where cells and metres are converted.

Conventions (shared by every module of the package):

* ``data[row, col]`` with ``row`` growing with world ``y`` and ``col`` with world ``x``
  (the layout of an OccupancyGrid message's ``data`` reshaped to ``(height, width)``).
  Image files (PGM/PNG, row 0 at the top) are flipped once when they are read.
* Values: ``-1`` unknown, ``0..100`` occupancy probability in percent.
* Cell ``(0, 0)``'s lower-left corner is at ``origin_xy_m``, the grid being turned by
  ``origin_yaw_rad`` about that corner; cell centres sit at ``+0.5`` cell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

UNKNOWN = -1
FREE = 0
OCCUPIED = 100

#: Default thresholds (percent) used to classify cells. A cell is free when
#: ``0 <= v < FREE_THRESHOLD`` and occupied when ``v >= OCCUPIED_THRESHOLD``.
FREE_THRESHOLD = 25
OCCUPIED_THRESHOLD = 65


def metres_to_cells(length_m: float, resolution_m: float) -> int:
    """Whole cells within ``length_m``: ``floor(length_m / resolution_m)``, tolerant of
    floating-point round-off (0.3 m at 0.05 m is 6 cells, not 5).

    Examples
    --------
    >>> metres_to_cells(0.3, 0.05)
    6
    >>> metres_to_cells(0.29, 0.05)
    5
    """
    return int(math.floor(length_m / resolution_m + 1e-9))


@dataclass(frozen=True)
class GridMap:
    """A 2D occupancy grid.

    Parameters
    ----------
    data : ndarray of int8, shape (height, width)
        ``-1`` unknown, ``0..100`` occupied probability (percent). Row = y, col = x.
    resolution_m : float
        Metres per cell, > 0.
    origin_xy_m : tuple of float
        World position of the lower-left corner of cell (0, 0).
    origin_yaw_rad : float
        Rotation of the grid about its origin.
    frame_id : str
        Frame the origin is expressed in (``map`` by default).
    stamp_ns : int
        Acquisition time in nanoseconds (0 when unknown).

    Raises
    ------
    ValueError
        On a non-2D array, values outside -1..100, a non-positive or non-finite
        resolution or a non-finite origin.

    Examples
    --------
    >>> g = GridMap(np.zeros((2, 3), np.int8), 0.5, (1.0, 2.0))
    >>> g.cell_to_world(0, 0)
    (1.25, 2.25)
    >>> g.world_to_cell(2.4, 2.9)
    (1, 2)
    """

    data: npt.NDArray[np.int8]
    resolution_m: float
    origin_xy_m: tuple[float, float] = (0.0, 0.0)
    origin_yaw_rad: float = 0.0
    frame_id: str = "map"
    stamp_ns: int = 0
    _cos: float = field(init=False, repr=False, compare=False)
    _sin: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        data = np.asarray(self.data)
        if data.ndim != 2:
            raise ValueError(f"data must be 2D (height, width), got shape {data.shape}")
        if data.dtype != np.int8:
            if data.size and (data.min() < -1 or data.max() > 100):
                raise ValueError(
                    f"data values must be in -1..100, got {data.min()}..{data.max()}")
            data = data.astype(np.int8)
        elif data.size and (data.min() < -1 or data.max() > 100):
            raise ValueError(f"data values must be in -1..100, got {data.min()}..{data.max()}")
        res = float(self.resolution_m)
        if not (math.isfinite(res) and res > 0.0):
            raise ValueError(f"resolution_m must be finite and > 0, got {self.resolution_m}")
        ox, oy = (float(v) for v in self.origin_xy_m)
        yaw = float(self.origin_yaw_rad)
        if not all(math.isfinite(v) for v in (ox, oy, yaw)):
            raise ValueError(
                f"origin must be finite, got xy=({ox}, {oy}) yaw={yaw}")
        object.__setattr__(self, "data", data)
        # tf2 frame names have no leading '/': "/map" and "map" are one frame.
        object.__setattr__(self, "frame_id", str(self.frame_id).lstrip("/"))
        object.__setattr__(self, "resolution_m", res)
        object.__setattr__(self, "origin_xy_m", (ox, oy))
        object.__setattr__(self, "origin_yaw_rad", yaw)
        object.__setattr__(self, "_cos", math.cos(yaw))
        object.__setattr__(self, "_sin", math.sin(yaw))

    # ------------------------------------------------------------------ shape
    @property
    def height(self) -> int:
        """Number of rows (cells along y)."""
        return int(self.data.shape[0])

    @property
    def width(self) -> int:
        """Number of columns (cells along x)."""
        return int(self.data.shape[1])

    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)``."""
        return (self.height, self.width)

    def same_geometry(self, other: "GridMap", tol_m: float = 1e-6) -> bool:
        """True when ``other`` has the same size, resolution, origin and frame."""
        return (self.shape == other.shape
                and abs(self.resolution_m - other.resolution_m) <= 1e-9
                and abs(self.origin_xy_m[0] - other.origin_xy_m[0]) <= tol_m
                and abs(self.origin_xy_m[1] - other.origin_xy_m[1]) <= tol_m
                and abs(self.origin_yaw_rad - other.origin_yaw_rad) <= 1e-9
                and self.frame_id == other.frame_id)

    # ------------------------------------------------------------ conversions
    def world_to_cell_float(self, x_m: npt.ArrayLike, y_m: npt.ArrayLike
                            ) -> tuple[np.ndarray, np.ndarray]:
        """Continuous (row, col) coordinates of world points (cell centre = k + 0.5)."""
        dx = np.asarray(x_m, dtype=np.float64) - self.origin_xy_m[0]
        dy = np.asarray(y_m, dtype=np.float64) - self.origin_xy_m[1]
        u = (self._cos * dx + self._sin * dy) / self.resolution_m
        v = (-self._sin * dx + self._cos * dy) / self.resolution_m
        return v, u

    def world_to_cell(self, x_m: float, y_m: float) -> tuple[int, int]:
        """(row, col) of the cell holding the world point (may lie outside the grid)."""
        r, c = self.world_to_cell_float(x_m, y_m)
        return int(math.floor(float(r))), int(math.floor(float(c)))

    def world_to_cells(self, x_m: npt.ArrayLike, y_m: npt.ArrayLike
                       ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """Vectorised :meth:`world_to_cell`: integer (rows, cols) arrays."""
        r, c = self.world_to_cell_float(x_m, y_m)
        return np.floor(r).astype(np.int64), np.floor(c).astype(np.int64)

    def cell_to_world(self, row: float, col: float) -> tuple[float, float]:
        """World (x, y) of the centre of cell (row, col)."""
        x, y = self.cells_to_world(np.asarray([row]), np.asarray([col]))
        return float(x[0]), float(y[0])

    def cells_to_world(self, rows: npt.ArrayLike, cols: npt.ArrayLike
                       ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Vectorised :meth:`cell_to_world` for cell centres."""
        u = (np.asarray(cols, dtype=np.float64) + 0.5) * self.resolution_m
        v = (np.asarray(rows, dtype=np.float64) + 0.5) * self.resolution_m
        x = self.origin_xy_m[0] + self._cos * u - self._sin * v
        y = self.origin_xy_m[1] + self._sin * u + self._cos * v
        return x, y

    def in_bounds(self, row: int, col: int) -> bool:
        """True when (row, col) is a cell of the grid."""
        return 0 <= row < self.height and 0 <= col < self.width

    # ---------------------------------------------------------------- classes
    def unknown_mask(self) -> npt.NDArray[np.bool_]:
        """Cells that are unknown (-1)."""
        return self.data < 0

    def free_mask(self, free_threshold: int = FREE_THRESHOLD) -> npt.NDArray[np.bool_]:
        """Cells known and below ``free_threshold`` percent."""
        return (self.data >= 0) & (self.data < free_threshold)

    def occupied_mask(self, occupied_threshold: int = OCCUPIED_THRESHOLD
                      ) -> npt.NDArray[np.bool_]:
        """Cells at or above ``occupied_threshold`` percent."""
        return self.data >= occupied_threshold

    def with_data(self, data: npt.NDArray[np.int8]) -> "GridMap":
        """A grid with the same geometry, frame and stamp holding ``data``."""
        if data.shape != self.data.shape:
            raise ValueError(f"data shape {data.shape} differs from grid shape {self.data.shape}")
        return GridMap(data, self.resolution_m, self.origin_xy_m, self.origin_yaw_rad,
                       self.frame_id, self.stamp_ns)

    def resample_to(self, other: "GridMap", fill: int = UNKNOWN) -> npt.NDArray[np.int8]:
        """This grid's values at the cell centres of ``other`` (nearest cell).

        Used to align layers (e.g. the object costmap) with the map when their
        origins or sizes differ. Cells outside this grid get ``fill``.
        """
        return resample_array(self.data, self, other, fill)


def range_returns(ranges: npt.NDArray[np.float64], range_min_m: float, range_max_m: float
                  ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """(hit, miss) of each range reading: a hit ends at a return (finite, in
    [range_min, range_max)); a miss has no return (inf or >= range_max: free space up to
    range_max); NaN and readings below range_min are neither."""
    with np.errstate(invalid="ignore"):
        hit = np.isfinite(ranges) & (ranges >= range_min_m) & (ranges < range_max_m)
        miss = (np.isposinf(ranges) | (ranges >= range_max_m)) & ~np.isnan(ranges)
    return hit, miss


def beam_samples(start_col: float, start_row: float, len_cells: npt.NDArray[np.float64],
                 ca: npt.NDArray[np.float64], sa: npt.NDArray[np.float64], step: float
                 ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """(rows, cols), floored, of the samples along beams from (start_col, start_row) in
    cell units, direction (ca, sa), ``len_cells`` long: beam b gets
    ``floor(len_cells[b] / step)`` samples at (k + 0.5) * step cells, all strictly before
    its end (the end cell is the caller's: a return, or nothing). Ragged, beam after beam;
    float32 arithmetic (the simulator's map is bit-identical to it)."""
    n = np.floor(len_cells / step).astype(np.int64)
    total = int(n.sum())
    if not total:
        return np.zeros(0, np.float32), np.zeros(0, np.float32)
    first = np.cumsum(n) - n
    k = np.arange(total, dtype=np.float32) - np.repeat(
        first.astype(np.float32) - np.float32(0.5), n)
    cols = np.floor(np.float32(start_col) + k * np.repeat((ca * step).astype(np.float32), n))
    rows = np.floor(np.float32(start_row) + k * np.repeat((sa * step).astype(np.float32), n))
    return rows, cols


def resample_array(values: npt.NDArray, src: GridMap, dst: GridMap, fill: int | float = 0
                   ) -> npt.NDArray:
    """Values laid out on ``src``'s cells, sampled at ``dst``'s cell centres (nearest cell).

    Parameters
    ----------
    values : ndarray, shape ``src.shape``
        Any dtype (occupancy, region labels, ...).
    src, dst : GridMap
        Geometries (size, resolution, origin) of the input and of the output.
    fill : scalar
        Value for ``dst`` cells outside ``src``.

    Returns
    -------
    ndarray, shape ``dst.shape``, dtype of ``values``

    Raises
    ------
    ValueError
        When ``values`` does not have ``src``'s shape.
    """
    if values.shape != src.shape:
        raise ValueError(f"values shape {values.shape} differs from source grid {src.shape}")
    if src.same_geometry(dst):
        return values.copy()
    rows, cols = np.indices(dst.shape)
    x, y = dst.cells_to_world(rows.ravel(), cols.ravel())
    r, c = src.world_to_cells(x, y)
    ok = (r >= 0) & (r < src.height) & (c >= 0) & (c < src.width)
    out = np.full(dst.shape[0] * dst.shape[1], fill, dtype=values.dtype)
    out[ok] = values[r[ok], c[ok]]
    return out.reshape(dst.shape)


def grid_from_ascii(text: str, resolution_m: float = 0.05,
                    origin_xy_m: tuple[float, float] = (0.0, 0.0)
                    ) -> tuple[GridMap, dict[str, list[tuple[int, int]]]]:
    """Build a grid from an ASCII drawing (tests and docs).

    ``.`` free, ``#`` wall, ``?`` unknown; any other character is a free cell whose
    (row, col) is reported under that character (``R`` robot, ``G`` goal, ...). The
    *last* text line is row 0 (y grows upwards, as in the grid).

    Returns
    -------
    grid : GridMap
    marks : dict
        character -> list of (row, col) cells.

    Examples
    --------
    >>> g, marks = grid_from_ascii('''
    ... ###
    ... #R?
    ... ''')
    >>> g.data.tolist(), marks["R"]
    ([[100, 0, -1], [100, 100, 100]], [(0, 1)])
    """
    lines = [ln.strip() for ln in text.strip("\n").splitlines() if ln.strip()]
    if not lines:
        raise ValueError("ASCII grid is empty")
    width = len(lines[0])
    if any(len(ln) != width for ln in lines):
        raise ValueError(f"ASCII grid rows differ in length: {[len(ln) for ln in lines]}")
    h = len(lines)
    data = np.zeros((h, width), dtype=np.int8)
    marks: dict[str, list[tuple[int, int]]] = {}
    for i, ln in enumerate(lines):
        row = h - 1 - i
        for col, ch in enumerate(ln):
            if ch == "#":
                data[row, col] = OCCUPIED
            elif ch == "?":
                data[row, col] = UNKNOWN
            elif ch == ".":
                data[row, col] = FREE
            else:
                data[row, col] = FREE
                marks.setdefault(ch, []).append((row, col))
    return GridMap(data, resolution_m, origin_xy_m), marks


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Yaw (rad) of a quaternion: ``atan2(2(wz + xy), 1 - 2(y^2 + z^2))``."""
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_from_yaw(yaw_rad: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``yaw_rad`` about +z."""
    return (0.0, 0.0, math.sin(yaw_rad / 2.0), math.cos(yaw_rad / 2.0))


#: map_server image interpretation modes.
MAP_IMAGE_MODES = ("trinary", "scale", "raw")


def occupancy_from_map_image(img: npt.NDArray[np.uint8], mode: str, negate: bool,
                             occupied_thresh: float, free_thresh: float
                             ) -> npt.NDArray[np.int8]:
    """OccupancyGrid values (-1 / 0..100) of a map_server image, as ROS map_server reads it.

    Rows are returned as in the image (row 0 = top); flip them (``[::-1]``) for grid layout.

    Parameters
    ----------
    img : ndarray of uint8, shape (H, W)
        Grey levels.
    mode : str
        ``trinary``, ``scale`` or ``raw``.
    negate : bool
    occupied_thresh, free_thresh : float
        Thresholds on the occupancy probability ``(255 - v) / 255`` (or ``v / 255`` negated).

    Raises
    ------
    ValueError
        On an unknown ``mode``.

    Examples
    --------
    >>> occupancy_from_map_image(np.array([[0, 254, 205]], np.uint8), "trinary", False,
    ...                          0.65, 0.196).tolist()
    [[100, 0, -1]]
    """
    if mode not in MAP_IMAGE_MODES:
        raise ValueError(f"mode must be one of {MAP_IMAGE_MODES}, got {mode!r}")
    v = img.astype(np.float64)
    if mode == "raw":
        return np.where(v > 100, -1, v).astype(np.int8)
    occ = v / 255.0 if negate else (255.0 - v) / 255.0
    out = np.full(img.shape, -1, np.int8)
    out[occ > occupied_thresh] = 100
    out[occ < free_thresh] = 0
    if mode == "scale":
        mid = (occ <= occupied_thresh) & (occ >= free_thresh)
        scaled = 99.0 * (occ - free_thresh) / max(occupied_thresh - free_thresh, 1e-9)
        out[mid] = np.clip(np.round(scaled[mid]), 0, 100).astype(np.int8)
    return out
