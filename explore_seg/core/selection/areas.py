"""Events counted per area, and the turn-in-place look (ROS-free).

:class:`AreaCounts` counts events by place: an event within a radius of an area's first
point counts for that area, else it opens a new one. The goal manager counts goals whose
frontier vanished before arrival, reached goals whose frontier remained revealed,
navigator aborts without a path, and turn-in-place looks with it.

A **turn look** (:func:`turn_goal`) is a goal at the robot's own position: the first
faces the nearest frontier left without a path (or blacklisted), the next ones turn half a
turn further each. When no frontier is selectable, the maps may still hold noise that new
sensing would clear: speckle or ragged, doubled wall ends that close a doorway next to the
robot, an object-layer box from depth points of a wall mapped at a drifted pose (the
depth layer clears a cell its camera sees through). A SLAM map (slam_toolbox) adds a scan
only at a keyframe, after ``minimum_travel_distance`` (0.5 m) or
``minimum_travel_heading`` (0.5 rad) of motion; a robot that stands still adds nothing,
however long it looks. Two looks half a turn apart pass that heading threshold at least
once even when the navigator stops short of a goal heading by its yaw tolerance.

Examples
--------
>>> a = AreaCounts()
>>> a.note((0.0, 0.0), 1.0)[0], a.note((0.5, 0.0), 1.0)[0], a.note((3.0, 0.0), 1.0)[0]
(1, 2, 1)
>>> a.count_near((0.2, 0.2), 1.0), a.count_near((9.0, 9.0), 1.0)
(2, 0)
>>> g = turn_goal((1.0, 2.0), 0.5, (40, 20), (1.0, 5.0), 0)   # face (1, 5)
>>> g.is_turn, round(g.yaw_rad, 4)
(True, 1.5708)
>>> round(turn_goal((1.0, 2.0), 0.5, (40, 20), (1.0, 5.0), 1).yaw_rad, 4)
-1.5708
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier
from explore_seg.core.selection.goal_types import Goal

#: Goal points kept per counted area, and areas kept per counter (oldest dropped).
AREA_POINTS = 20
AREAS_KEPT = 100

#: A turn look's heading change, radians (half a turn).
TURN_LOOK_RAD = math.pi
#: A turn look's heading counts as reached within this of its goal heading, radians
#: (above Nav2's default yaw_goal_tolerance, 0.25 rad).
TURN_DONE_RAD = 0.3


class AreaCounts:
    """Events counted per area (an area: within a radius of its first event's point)."""

    def __init__(self) -> None:
        self._areas: list[tuple[list[int], list[tuple[float, float]]]] = []

    def clear(self) -> None:
        """Forget every area."""
        self._areas.clear()

    def note(self, xy_m: tuple[float, float], radius_m: float
             ) -> tuple[int, list[tuple[float, float]]]:
        """Count an event at ``xy_m`` in the first area whose first point lies within
        ``radius_m`` (a new area when none does); returns that area's count and its
        points (the first and the newest ``AREA_POINTS`` - 1)."""
        x, y = float(xy_m[0]), float(xy_m[1])
        for count, pts in self._areas:
            if math.hypot(x - pts[0][0], y - pts[0][1]) <= radius_m:
                count[0] += 1
                pts.append((x, y))
                del pts[1:-AREA_POINTS]
                return count[0], pts
        count, pts = [1], [(x, y)]
        self._areas.append((count, pts))
        del self._areas[:-AREAS_KEPT]
        return count[0], pts

    def count_near(self, xy_m: tuple[float, float], radius_m: float) -> int:
        """The count of the first area whose first point lies within ``radius_m`` of
        ``xy_m`` (0 when none does): the count :meth:`note` would add to."""
        for count, pts in self._areas:
            if math.hypot(xy_m[0] - pts[0][0], xy_m[1] - pts[0][1]) <= radius_m:
                return count[0]
        return 0


def turn_goal(xy_m: tuple[float, float], yaw_rad: float, rc: tuple[int, int],
              toward_xy_m: tuple[float, float] | None = None, k: int = 0) -> Goal:
    """The ``k``-th turn look at ``xy_m`` (module docstring): heading toward
    ``toward_xy_m`` plus ``k`` half turns; without a point (or on it), the current
    heading ``yaw_rad`` plus half a turn."""
    if toward_xy_m is None or (toward_xy_m[0] == xy_m[0] and toward_xy_m[1] == xy_m[1]):
        heading = yaw_rad + TURN_LOOK_RAD
    else:
        heading = (math.atan2(toward_xy_m[1] - xy_m[1], toward_xy_m[0] - xy_m[0])
                   + k * TURN_LOOK_RAD)
    yaw = math.atan2(math.sin(heading), math.cos(heading))
    return Goal((float(xy_m[0]), float(xy_m[1])), yaw, rc, 0, 0.0, is_turn=True)


def nearest_left(frontiers: Sequence[Frontier], dist_m: npt.ArrayLike,
                 excluded: npt.NDArray[np.bool_], xy_m: tuple[float, float]
                 ) -> tuple[float, float] | None:
    """The goal point nearest to ``xy_m`` (straight line) of the frontiers without a path
    (``dist_m`` not finite) or blacklisted (``excluded``); None when there is none."""
    left = ~np.isfinite(np.asarray(dist_m, dtype=np.float64)) | np.asarray(excluded, bool)
    if not len(frontiers) or not left.any():
        return None
    pts = np.asarray([f.point_xy_m for f in frontiers], dtype=np.float64)[left]
    i = int(np.argmin(np.hypot(pts[:, 0] - xy_m[0], pts[:, 1] - xy_m[1])))
    return float(pts[i, 0]), float(pts[i, 1])


def turned(goal: Goal, yaw_rad: float | None, tolerance_rad: float) -> bool:
    """True when a heading ``yaw_rad`` lies within ``tolerance_rad`` of the goal's."""
    if yaw_rad is None:
        return False
    err = math.atan2(math.sin(yaw_rad - goal.yaw_rad), math.cos(yaw_rad - goal.yaw_rad))
    return abs(err) <= tolerance_rad


__all__ = ["AREAS_KEPT", "AREA_POINTS", "AreaCounts", "TURN_DONE_RAD", "TURN_LOOK_RAD",
           "nearest_left", "turn_goal", "turned"]
