"""sim_bridge.odometry: drifting odometry and slam_toolbox-like pose selection (ROS-free), and
their SimParams."""

from __future__ import annotations

import math

import pytest

from explore_seg.core.pose_fusion import compose, inverse
from sim_bridge.engine import SimParams
from sim_bridge.odometry import DriftingOdometry, SlamPoses


def test_odometry_starts_on_the_map_frame_and_scales_distance():
    # slam_toolbox's map frame starts where odom does: the odom frame starts at the
    # robot's map pose (a node that missed the first SLAM pose takes odometry as the map
    # pose until the robot moves: pose_fusion.odom_until_first_slam)
    odo = DriftingOdometry(scale=0.1, yaw_bias_radps=0.0)
    assert odo.update(0.0, (5.0, 2.0, math.pi / 2)) == (5.0, 2.0, math.pi / 2)
    # 1 m forward along the robot's heading (map +y): 1.1 m measured
    assert odo.update(1.0, (5.0, 3.0, math.pi / 2)) == pytest.approx((5.0, 3.1, math.pi / 2))


def test_gyro_bias_only_while_moving():
    odo = DriftingOdometry(scale=0.0, yaw_bias_radps=0.1)
    odo.update(0.0, (0.0, 0.0, 0.0))
    assert odo.update(5.0, (0.0, 0.0, 0.0))[2] == 0.0             # standing: no drift
    assert odo.update(6.0, (0.0, 0.0, 0.5))[2] == pytest.approx(0.6)   # turning: + 0.1


def test_without_drift_odometry_is_the_true_motion():
    odo = DriftingOdometry(0.0, 0.0)
    start = (1.0, -2.0, 0.7)
    odo.update(0.0, start)
    for k in range(1, 50):
        true = (1.0 + 0.05 * k, -2.0 + 0.02 * k * k / 50, 0.7 + 0.03 * k)
        got = odo.update(0.1 * k, true)
        assert got == pytest.approx(true, abs=1e-9)
    assert compose(inverse(start), start) == pytest.approx((0.0, 0.0, 0.0))


def test_time_going_back_restarts_the_odom_frame():
    odo = DriftingOdometry(0.0, 0.0)
    odo.update(10.0, (0.0, 0.0, 0.0))
    odo.update(11.0, (1.0, 0.0, 0.0))
    assert odo.update(1.0, (4.0, 4.0, 1.0)) == (4.0, 4.0, 1.0)


def test_slam_poses_after_travel_or_turn():
    s = SlamPoses(0.5, 0.3)
    assert [s.take(p) for p in [(0.0, 0.0, 0.0), (0.3, 0.0, 0.0), (0.3, 0.0, 0.35),
                                (0.4, 0.0, 0.4), (0.9, 0.0, 0.4)]] == [
        True, False, True, False, True]
    every = SlamPoses(0.0, 0.0)
    assert all(every.take((0.0, 0.0, 0.0)) for _ in range(3))     # every scan


def test_sim_params_of_the_pose_contract():
    assert SimParams().odom_frame == "map" and not SimParams().slam_pose   # today's default
    SimParams(odom_frame="odom", odom_drift_scale=0.05, odom_drift_yaw_radps=-0.02)
    with pytest.raises(ValueError, match="need an odom_frame other than 'map'"):
        SimParams(odom_drift_scale=0.05)
    with pytest.raises(ValueError, match="odom_frame must be a frame name"):
        SimParams(odom_frame="od om")
    with pytest.raises(ValueError, match="slam_min_travel_m and slam_min_turn_rad must be >= 0"):
        SimParams(slam_min_travel_m=-1.0)
    with pytest.raises(ValueError, match="odom_drift_scale must be finite"):
        SimParams(odom_frame="odom", odom_drift_scale=math.nan)
