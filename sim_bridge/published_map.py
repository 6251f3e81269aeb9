"""The map the explorer gets, as slam_toolbox makes and publishes it (ROS-free).

slam_toolbox puts a scan in its map only as a keyframe (:func:`~sim_bridge.slam_error.is_keyframe`:
after ``minimum_travel_distance`` or ``minimum_travel_heading`` of motion) and publishes the
map every ``map_update_interval``, republishing it unchanged when no keyframe came.
:class:`KeyframeMapper` is the first, :class:`MapPublication` the second; the engine
(:mod:`sim_bridge.engine`) drives both.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.pose_fusion import Pose2D
from sim_bridge.mapping import MappingParams, ScanMapper
from sim_bridge.slam_error import LidarGeometry, is_keyframe


class KeyframeMapper:
    """A :class:`ScanMapper` fed only the keyframe scans.

    Parameters
    ----------
    center_xy_m : (float, float)
        Where the map starts (as for :class:`ScanMapper`).
    mapping : MappingParams
    lidar : LidarGeometry
    min_travel_m, min_turn_rad : float
        The keyframe rule's thresholds (true base pose to true base pose).
    """

    def __init__(self, center_xy_m: tuple[float, float], mapping: MappingParams,
                 lidar: LidarGeometry, min_travel_m: float, min_turn_rad: float) -> None:
        self._mapper = ScanMapper(center_xy_m, mapping)
        self._lidar = lidar
        self._rule = (float(min_travel_m), float(min_turn_rad))
        self._last: Pose2D | None = None

    @property
    def version(self) -> int:
        """Changes whenever a keyframe changed the map."""
        return self._mapper.version

    def grid(self, stamp_ns: int = 0) -> GridMap:
        """The keyframe map."""
        return self._mapper.grid(stamp_ns)

    def add_scan(self, true_pose: Pose2D, map_pose: Pose2D,
                 ranges: npt.NDArray[np.float32]) -> bool:
        """Map the scan at ``map_pose`` when ``true_pose`` makes it a keyframe (True)."""
        if not is_keyframe(self._last, true_pose, *self._rule):
            return False
        self._last = true_pose
        g = self._lidar
        self._mapper.integrate_scan(map_pose, ranges, g.angle_min_rad, g.angle_increment_rad,
                                    g.range_max_m, g.range_min_m)
        return True


class MapPublication:
    """The published copy of a map, renewed every ``interval_s``.

    ``grid`` is the last publication (None before the first), ``version`` the content
    version it was made from, ``count`` the publications so far (a publisher sends one
    message per increment).
    """

    def __init__(self) -> None:
        self.grid: GridMap | None = None
        self.version = -1
        self.count = 0
        self._next_s = 0.0

    def due(self, t_s: float, interval_s: float) -> bool:
        """True when a publication is due at ``t_s`` (never with ``interval_s`` 0)."""
        return interval_s > 0 and t_s >= self._next_s - 1e-9

    def publish(self, t_s: float, interval_s: float, version: int,
                current: Callable[[int], GridMap], stamp_ns: int) -> None:
        """Publish at ``t_s``, stamped ``stamp_ns``: ``current(stamp_ns)`` when the content
        ``version`` changed, else the last grid restamped (as slam_toolbox republishes an
        unchanged map); the next is due ``interval_s`` later."""
        self._next_s += interval_s
        if self._next_s <= t_s:                 # after a change of interval: no burst
            self._next_s = t_s + interval_s
        if self.grid is None or version != self.version:
            self.grid, self.version = current(stamp_ns), version
        else:
            self.grid = replace(self.grid, stamp_ns=stamp_ns)
        self.count += 1
