"""SLAM corrections seen from a node's inputs (ROS-free): a pose jump, a map that moved.

A real robot's map and map-frame pose come from a SLAM (slam_toolbox): when it closes a
loop it optimises its pose graph, the map-frame pose jumps and the next map is re-rendered
from the corrected poses, so walls move under the robot. What a node placed at the
uncorrected poses then lies off the corrected map: the object layer's boxes and voxels
(:meth:`~explore_seg.core.objects.ObjectMap.forget_since`), the scan overlay's recent scans
(:meth:`~explore_seg.core.scan_overlay.ScanOverlay.forget_before`).
:class:`CorrectionDetector` finds such a correction from the two inputs the
``object_costmap`` and ``target_selector`` nodes have:

* **a pose jump**: two consecutive map-frame robot poses (at most
  ``correction_pose_max_gap_s`` apart) further apart than the robot can drive in the time
  between them (``correction_max_speed_mps``, ``correction_max_turn_rps``) by at least
  ``correction_pose_jump_m`` or ``correction_pose_jump_rad``;
* **a map that moved**: at least ``correction_map_moved_fraction`` (and
  ``correction_map_min_cells``) of the previous map's occupied cells have no occupied cell
  within ``correction_map_tolerance_m`` in the new map. A map that only grew keeps its
  occupied cells where they were, so growth is no correction; a re-render that moved
  the walls by more than the tolerance is, whether the whole map moved or only the part
  mapped since the previous loop closure.

One loop closure shows in both (the pose at once, the map at the next map update): a
detection within ``correction_merge_s`` of the previous one is the same correction.
Every method may be called from different threads (a lock guards the state).
"""

from __future__ import annotations

import dataclasses
import math
import threading
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.angles import wrap_angle
from explore_seg.core.fields import check_non_negative, param_meta
from explore_seg.core.grid import GridMap

#: An OccupancyGrid cell at or above this value is occupied (slam_toolbox writes 100; the
#: object layer's walls use the same threshold).
OCCUPIED_THRESHOLD = 65

Pose2D = tuple[float, float, float]


@dataclass(frozen=True)
class CorrectionParams:
    """The thresholds :class:`CorrectionDetector` reads: the ``correction_*`` parameters of
    the ``object_costmap`` node (:class:`~explore_seg.core.objects.ObjectCostmapNodeParams`)
    and of ``target_selector``'s scan overlay
    (:class:`~explore_seg.core.scan_overlay.ScanOverlayParams`), declared once here."""

    correction_pose_jump_m: float = field(default=0.1, metadata=param_meta(
        "a SLAM correction (a loop closure) is found when two consecutive map-frame robot "
        "poses lie further apart than the robot drives in the time between them "
        "(correction_max_speed_mps) by at least this (0 = not from the position)", "m",
        range=(0.0, math.inf)))
    correction_pose_jump_rad: float = field(default=0.15, metadata=param_meta(
        "... or turned more than correction_max_turn_rps allows by at least this (0 = not "
        "from the heading)", "rad", range=(0.0, math.inf)))
    correction_max_speed_mps: float = field(default=0.5, metadata=param_meta(
        "fastest the robot drives (the pose jump test's allowance; a TurtleBot3: 0.26)",
        "m/s", range=(0.0, math.inf)))
    correction_max_turn_rps: float = field(default=3.0, metadata=param_meta(
        "fastest the robot turns (a TurtleBot3: 2.84)", "rad/s", range=(0.0, math.inf)))
    correction_pose_max_gap_s: float = field(default=1.0, metadata=param_meta(
        "poses further apart in time are not compared (after a gap any jump is explained)",
        "s", range=(0.0, math.inf)))
    correction_map_moved_fraction: float = field(default=0.02, metadata=param_meta(
        "... or when at least this share of the previous map's occupied cells has no "
        "occupied cell within correction_map_tolerance_m in the new map (a re-render moved "
        "the walls; a map that only grew keeps them; 0 = not from the map)",
        range=(0.0, 1.0)))
    correction_map_min_cells: int = field(default=100, metadata=param_meta(
        "... and at least this many of them (drift between map updates moves a few walls "
        "by a cell or two)", range=(1, 2**31 - 1)))
    correction_map_tolerance_m: float = field(default=0.1, metadata=param_meta(
        "an occupied cell of the previous map with an occupied cell of the new map within "
        "this has not moved", "m", range=(0.0, math.inf)))
    correction_merge_s: float = field(default=6.0, metadata=param_meta(
        "a correction found within this of the previous one is the same (a loop closure "
        "shows in the pose at once and in the map at the next map update)", "s",
        range=(0.0, math.inf)))

    def __post_init__(self) -> None:
        self.check_corrections()

    def check_corrections(self) -> None:
        """Raise ValueError on a threshold out of its range (subclasses call it from their
        own ``__post_init__``)."""
        check_non_negative(self, ("correction_pose_jump_m", "correction_pose_jump_rad",
                                  "correction_max_speed_mps", "correction_max_turn_rps",
                                  "correction_pose_max_gap_s", "correction_map_tolerance_m",
                                  "correction_merge_s"))
        if not 0.0 <= self.correction_map_moved_fraction <= 1.0:
            raise ValueError(f"correction_map_moved_fraction must be in [0, 1], got "
                             f"{self.correction_map_moved_fraction}")
        if self.correction_map_min_cells < 1:
            raise ValueError(f"correction_map_min_cells must be >= 1, got "
                             f"{self.correction_map_min_cells}")


@dataclass(frozen=True)
class Correction:
    """One detected correction: when (the pose's or the map's stamp), which input showed
    it (``pose`` or ``map``), what it saw (for a log line) and, when a pose jump showed it,
    the jump: the rigid map-frame transform from the pose before to the pose after
    (``after o before^-1``; the driving between the two poses is in it too, at most
    ``correction_max_speed_mps`` times their gap)."""

    stamp_ns: int
    source: str
    detail: str
    jump: Pose2D | None = None


def pose_jump(prev: tuple[int, Pose2D], cur: tuple[int, Pose2D],
              s: CorrectionParams) -> str | None:
    """What makes ``cur`` a jump from ``prev`` (both ``(stamp ns, map-frame pose)``), or
    None when driving explains it, the two are too far apart in time, or out of order.

    >>> from explore_seg.core.objects import ObjectCostmapNodeParams
    >>> p = ObjectCostmapNodeParams()
    >>> pose_jump((0, (0.0, 0.0, 0.0)), (50_000_000, (0.02, 0.0, 0.0)), p) is None
    True
    >>> pose_jump((0, (0.0, 0.0, 0.0)), (50_000_000, (0.32, 0.0, 0.0)), p)[:20]
    'moved 0.320 m in 0.0'
    """
    dt = (cur[0] - prev[0]) * 1e-9
    if not 0 <= dt <= s.correction_pose_max_gap_s:
        return None
    (x0, y0, a0), (x1, y1, a1) = prev[1], cur[1]
    moved = math.hypot(x1 - x0, y1 - y0)
    turned = abs(wrap_angle(a1 - a0))
    excess_m = moved - s.correction_max_speed_mps * dt
    excess_rad = turned - s.correction_max_turn_rps * dt
    if s.correction_pose_jump_m > 0 and excess_m >= s.correction_pose_jump_m:
        return (f"moved {moved:.3f} m in {dt:.3f} s (at most "
                f"{s.correction_max_speed_mps:g} m/s)")
    if s.correction_pose_jump_rad > 0 and excess_rad >= s.correction_pose_jump_rad:
        return (f"turned {turned:.3f} rad in {dt:.3f} s (at most "
                f"{s.correction_max_turn_rps:g} rad/s)")
    return None


def _relative(before: Pose2D, after: Pose2D) -> Pose2D:
    """The rigid map-frame transform ``after o before^-1``: it takes ``before`` to
    ``after`` (and every point near the robot along with it)."""
    x0, y0, a0 = before
    x1, y1, a1 = after
    th = wrap_angle(a1 - a0)
    c, s = math.cos(th), math.sin(th)
    return (x1 - (c * x0 - s * y0), y1 - (s * x0 + c * y0), th)


def occupied_xy(grid: GridMap, threshold: int = OCCUPIED_THRESHOLD) -> npt.NDArray[np.float64]:
    """World (x, y) of the occupied cells' centres, shape (N, 2)."""
    rows, cols = np.nonzero(grid.data >= threshold)
    x, y = grid.cells_to_world(rows, cols)
    return np.column_stack([x, y]).astype(np.float64)


def moved_cells(prev_xy: npt.NDArray[np.float64], grid: GridMap, tolerance_m: float,
                threshold: int = OCCUPIED_THRESHOLD) -> int:
    """How many of the points ``prev_xy`` (the previous map's occupied cells) have no
    occupied cell of ``grid`` within ``tolerance_m`` (points off ``grid`` count too)."""
    if len(prev_xy) == 0:
        return 0
    occ = grid.data >= threshold
    if not occ.any():
        return len(prev_xy)
    # Distance (cells) from every cell to the nearest occupied one.
    dist = cv2.distanceTransform((~occ).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    res = grid.resolution_m
    rows, cols = grid.world_to_cells(prev_xy[:, 0], prev_xy[:, 1])
    h, w = occ.shape
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    near = np.zeros(len(prev_xy), dtype=bool)
    near[inside] = dist[rows[inside], cols[inside]] * res <= tolerance_m + 1e-9
    return int((~near).sum())


class CorrectionDetector:
    """Finds SLAM corrections in a stream of map-frame poses and maps (module docstring).

    ``settings`` may be replaced (:attr:`settings`) when the node's parameters change.
    """

    def __init__(self, settings: CorrectionParams) -> None:
        self.settings = settings
        self._lock = threading.Lock()
        self._last_pose: tuple[int, Pose2D] | None = None
        self._last_map_xy: npt.NDArray[np.float64] | None = None
        self._last_found_ns: int | None = None
        self._pending: list[Correction] = []
        #: Corrections found (merged ones not counted).
        self.count = 0

    def observe_pose(self, t_ns: int, pose: Pose2D) -> Correction | None:
        """Feed the newest map-frame robot pose; the correction it shows, if any (also
        queued for :meth:`take`). A pose older than the last one is ignored."""
        with self._lock:
            last, cur = self._last_pose, (int(t_ns), tuple(float(v) for v in pose))
            if last is not None and cur[0] < last[0]:
                return None
            self._last_pose = cur  # type: ignore[assignment]
            if last is None:
                return None
            why = pose_jump(last, cur, self.settings)  # type: ignore[arg-type]
            if why is None:
                return None
            jump = _relative(last[1], cur[1])  # type: ignore[arg-type]
            return self._found(cur[0], "pose", why, jump)

    def observe_map(self, grid: GridMap) -> Correction | None:
        """Feed a new map; the correction it shows against the previous one, if any (also
        queued for :meth:`take`)."""
        s = self.settings
        xy = occupied_xy(grid)
        with self._lock:
            prev, self._last_map_xy = self._last_map_xy, xy
        if prev is None or s.correction_map_moved_fraction <= 0 or len(prev) == 0:
            return None
        moved = moved_cells(prev, grid, s.correction_map_tolerance_m)
        if (moved < s.correction_map_min_cells
                or moved < s.correction_map_moved_fraction * len(prev)):
            return None
        why = (f"{moved} of the previous map's {len(prev)} occupied cells moved by more "
               f"than {s.correction_map_tolerance_m:g} m")
        with self._lock:
            return self._found(grid.stamp_ns, "map", why)

    def take(self) -> list[Correction]:
        """The corrections found since the last call (oldest first)."""
        with self._lock:
            out, self._pending = self._pending, []
        return out

    def reset(self) -> None:
        """Forget the last pose and map (time went back: they belong to the old time
        line); the pending corrections stay."""
        with self._lock:
            self._last_pose = None
            self._last_map_xy = None
            self._last_found_ns = None

    def _found(self, t_ns: int, source: str, why: str, jump: Pose2D | None = None
               ) -> Correction | None:
        """Record a correction at ``t_ns`` unless it is the previous one seen again
        (within ``correction_merge_s``; a pose jump seen after the map showed the same
        correction lends it its jump while it waits for :meth:`take`). Called with the
        lock held."""
        last = self._last_found_ns
        if last is not None and abs(t_ns - last) <= self.settings.correction_merge_s * 1e9:
            if jump is not None and self._pending and self._pending[-1].jump is None:
                self._pending[-1] = dataclasses.replace(self._pending[-1], jump=jump)
            return None
        self._last_found_ns = t_ns
        c = Correction(int(t_ns), source, why, jump)
        self._pending.append(c)
        self.count += 1
        return c
