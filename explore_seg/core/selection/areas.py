"""Events counted per area, and the turn-in-place look (ROS-free).

:class:`AreaCounts` counts events by place: an event within a radius of an area's first
point counts for that area, else it opens a new one. The goal manager counts goals whose
frontier vanished before arrival, reached goals whose frontier remained revealed,
navigator aborts without a path, and turn-in-place looks with it.

A **turn look** (:func:`turn_goal`) is a goal at the robot's own position, heading half a
turn from its current heading. When no frontier is selectable, the map may still hold
noise that a new scan would clear: speckle or ragged, doubled wall ends that close a
doorway next to the robot. A SLAM map (slam_toolbox) adds a scan only at a keyframe,
after ``minimum_travel_distance`` (0.5 m) or ``minimum_travel_heading`` (0.5 rad) of
motion; a robot that stands still adds nothing, however long it looks. Half a turn
passes that heading threshold even when the navigator stops short of the goal heading by
its yaw tolerance, so each look adds at least one keyframe from where the robot stands.

Examples
--------
>>> a = AreaCounts()
>>> a.note((0.0, 0.0), 1.0)[0], a.note((0.5, 0.0), 1.0)[0], a.note((3.0, 0.0), 1.0)[0]
(1, 2, 1)
>>> a.count_near((0.2, 0.2), 1.0), a.count_near((9.0, 9.0), 1.0)
(2, 0)
>>> g = turn_goal((1.0, 2.0), 0.5, (40, 20))
>>> g.is_turn, round(g.yaw_rad, 4)
(True, -2.6416)
"""

from __future__ import annotations

import math

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


def turn_goal(xy_m: tuple[float, float], yaw_rad: float, rc: tuple[int, int]) -> Goal:
    """A turn look at ``xy_m``: heading ``yaw_rad`` + half a turn (module docstring)."""
    yaw = math.atan2(math.sin(yaw_rad + TURN_LOOK_RAD), math.cos(yaw_rad + TURN_LOOK_RAD))
    return Goal((float(xy_m[0]), float(xy_m[1])), yaw, rc, 0, 0.0, is_turn=True)


def turned(goal: Goal, yaw_rad: float | None, tolerance_rad: float) -> bool:
    """True when a heading ``yaw_rad`` lies within ``tolerance_rad`` of the goal's."""
    if yaw_rad is None:
        return False
    err = math.atan2(math.sin(yaw_rad - goal.yaw_rad), math.cos(yaw_rad - goal.yaw_rad))
    return abs(err) <= tolerance_rad


__all__ = ["AREAS_KEPT", "AREA_POINTS", "AreaCounts", "TURN_DONE_RAD", "TURN_LOOK_RAD",
           "turn_goal", "turned"]
