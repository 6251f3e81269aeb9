"""The simulator's real-robot pose contract (ROS-free): drifting odometry and SLAM poses.

A real robot publishes wheel odometry in an ``odom`` frame that starts at the power-on pose
and drifts, and slam_toolbox publishes the map-frame ``pose`` only for the scans it
processes (after ``minimum_travel_distance`` / ``minimum_travel_heading`` of motion; none
while the robot stands still). slam_toolbox's map frame starts where the odom frame does
(map <- odom is the identity until odometry drifts), which is what lets a node that
subscribed after the first SLAM pose take odometry as the map pose until the robot moves
(``pose_fusion.odom_until_first_slam``). The simulator's map frame is the world's, so its
odom frame starts at the robot's true start pose in it, not at (0, 0, 0): with an offset
there a late subscriber's pose would be off by the start pose's distance, placing the robot
outside its own map, where it gets no goal and so never moves to earn a SLAM pose.
:class:`DriftingOdometry` integrates the true motion with a distance
scale error and a gyro bias while moving; :class:`SlamPoses` decides which scans yield a
pose. ``sim_bridge`` uses both when ``odom_frame`` is not ``map``.
"""

from __future__ import annotations

import math

from explore_seg.core.pose_fusion import Pose2D, compose, inverse
from sim_bridge.slam_error import is_keyframe

#: Below this true displacement per update (m, rad) the robot counts as standing still.
_STILL_M, _STILL_RAD = 1e-6, 1e-6


class DriftingOdometry:
    """Odometry of a robot whose true map-frame poses are fed in time order.

    ``scale``: travelled distance is multiplied by ``1 + scale``; ``yaw_bias_radps`` is
    added to the heading while the robot moves (translating or turning).

    Examples
    --------
    >>> odo = DriftingOdometry(scale=0.1, yaw_bias_radps=0.0)
    >>> odo.update(0.0, (5.0, 2.0, 0.0))          # the odom frame starts at the map frame
    (5.0, 2.0, 0.0)
    >>> odo.update(1.0, (6.0, 2.0, 0.0))          # 1 m true, 1.1 m measured
    (6.1, 2.0, 0.0)
    """

    def __init__(self, scale: float, yaw_bias_radps: float) -> None:
        self.scale = float(scale)
        self.yaw_bias_radps = float(yaw_bias_radps)
        self._last: tuple[float, Pose2D] | None = None
        self._odom: Pose2D = (0.0, 0.0, 0.0)

    def update(self, t_s: float, true_pose: Pose2D) -> Pose2D:
        """The odometry at ``t_s`` given the true pose then (the first call, or one going
        back in time, restarts the odom frame on the map frame: odometry = the true pose)."""
        if self._last is None or t_s < self._last[0]:
            self._last = (t_s, true_pose)
            self._odom = (float(true_pose[0]), float(true_pose[1]), float(true_pose[2]))
            return self._odom
        t0, prev = self._last
        d = compose(inverse(prev), true_pose)
        if math.hypot(d[0], d[1]) > _STILL_M or abs(d[2]) > _STILL_RAD:
            k = 1.0 + self.scale
            d = (d[0] * k, d[1] * k, d[2] + self.yaw_bias_radps * (t_s - t0))
            self._odom = compose(self._odom, d)
        self._last = (t_s, true_pose)
        return self._odom


class SlamPoses:
    """Which scans make a SLAM pose: the first, then one after ``min_travel_m`` of travel
    or ``min_turn_rad`` of turning since the last (0 and 0: every scan); the keyframe rule
    of :func:`sim_bridge.slam_error.is_keyframe`.

    >>> s = SlamPoses(0.5, 0.5)
    >>> [s.take((x, 0.0, 0.0)) for x in (0.0, 0.2, 0.6, 0.7)]
    [True, False, True, False]
    """

    def __init__(self, min_travel_m: float, min_turn_rad: float) -> None:
        self.min_travel_m = float(min_travel_m)
        self.min_turn_rad = float(min_turn_rad)
        self._last: Pose2D | None = None

    def take(self, pose: Pose2D) -> bool:
        """True when the scan taken at ``pose`` yields a SLAM pose."""
        if not is_keyframe(self._last, pose, self.min_travel_m, self.min_turn_rad):
            return False
        self._last = pose
        return True
