"""PoseFusion: SLAM corrections composed with drifting odometry (ROS-free)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.angles import wrap_angle
from explore_seg.core.pose_fusion import (POSE_SOURCES, PoseFusion, PoseFusionParams,
                                          StampedPoses, compose, inverse)

NS = 1_000_000_000
ODOM_HZ, SLAM_HZ = 50, 5
#: Tolerances the fused pose keeps to ground truth in the drift scenario (m, rad).
TOL_M, TOL_RAD = 0.05, 0.02


def truth(t: float) -> tuple[float, float, float]:
    """A figure-eight-ish drive with a stand-still between 20 s and 35 s."""
    s = min(t, 20.0) + max(0.0, t - 35.0)          # arc parameter: frozen while standing
    return (2.0 * math.sin(0.2 * s), 1.5 * math.sin(0.4 * s),
            wrap_angle(math.atan2(0.6 * math.cos(0.4 * s), 0.4 * math.cos(0.2 * s))))


def drifting_odometry(times: np.ndarray, scale: float = 1.04, yaw_bias_radps: float = 0.03,
                      start=(0.3, -0.2, 0.4)) -> list[tuple[float, float, float]]:
    """Odometry integrating the true body-frame increments with a scale error and a gyro
    bias (only while moving), starting at an offset odom frame."""
    odom = [start]
    prev = truth(times[0])
    for t0, t1 in zip(times[:-1], times[1:]):
        cur = truth(t1)
        d = compose(inverse(prev), cur)
        moving = math.hypot(d[0], d[1]) > 1e-9
        d = (d[0] * scale, d[1] * scale,
             d[2] + (yaw_bias_radps * (t1 - t0) if moving else 0.0))
        odom.append(compose(odom[-1], d))
        prev = cur
    return odom


def pose_err(a, b) -> tuple[float, float]:
    return math.hypot(a[0] - b[0], a[1] - b[1]), abs(wrap_angle(a[2] - b[2]))


def run_scenario(source: str, slam_delay_s: float = 0.15, slam_silent=(20.0, 35.0)):
    """Feed odometry (50 Hz) and delayed SLAM poses (5 Hz, none while standing still) in
    arrival order; return the per-odometry-message error of the newest pose and the
    fusion."""
    rng = np.random.default_rng(3)
    times = np.arange(0.0, 50.0, 1.0 / ODOM_HZ)
    odom = drifting_odometry(times)
    slam_t = [t for t in np.arange(0.0, 50.0, 1.0 / SLAM_HZ)
              if not slam_silent[0] < t < slam_silent[1]]
    events = [(t, "odom", t, o) for t, o in zip(times, odom)]
    for t in slam_t:
        x, y, a = truth(t)
        noisy = (x + rng.normal(0, 0.005), y + rng.normal(0, 0.005), a + rng.normal(0, 0.002))
        events.append((t + slam_delay_s, "slam", t, noisy))
    events.sort(key=lambda e: (e[0], e[1] == "slam"))
    fusion = PoseFusion(source, PoseFusionParams())
    errors = []
    for _, kind, t, pose in events:
        if kind == "odom":
            fusion.add_odom(int(t * NS), pose)
            got = fusion.latest()
            if got is not None and t > 1.0:
                errors.append((t, *pose_err(got[1], truth(got[0] / NS)), got[0] / NS))
        else:
            fusion.add_map_pose(int(t * NS), pose)
    return errors, fusion


def test_fused_pose_tracks_truth_at_odometry_rate_through_drift_and_stand_still():
    errors, fusion = run_scenario("fused")
    lag = max(t - stamp for t, _, _, stamp in errors)
    assert lag < 1e-6                       # every odometry message gives a pose at its stamp
    assert len(errors) == pytest.approx(49 * ODOM_HZ, abs=2)
    worst_m = max(e[1] for e in errors)
    worst_rad = max(e[2] for e in errors)
    assert worst_m < TOL_M and worst_rad < TOL_RAD, (worst_m, worst_rad)
    # the odometry alone (treated as map-frame) is far off: the test has teeth
    odom_only, _ = run_scenario("odom")
    assert max(e[1] for e in odom_only) > 0.5


def test_fused_pose_interpolates_at_image_stamps():
    _, fusion = run_scenario("fused")
    for t in np.arange(41.013, 49.9, 0.137):           # stamps between odometry messages
        got = fusion.pose_at(int(t * NS), int(0.1 * NS))
        assert got is not None
        d_m, d_rad = pose_err(got, truth(t))
        assert d_m < TOL_M and d_rad < TOL_RAD, (t, d_m, d_rad)


def test_slam_pose_alone_stalls_while_standing_still():
    _, fusion = run_scenario("pose")
    tol = int(0.2 * NS)
    assert fusion.pose_at(int(30.0 * NS), tol) is None          # SLAM silent 20..35 s
    fused_errors, fused = run_scenario("fused")
    assert fused.pose_at(int(30.0 * NS), tol) is None            # older than history_s
    mid = [e for e in fused_errors if 21.0 < e[0] < 34.0]
    assert len(mid) > 12 * ODOM_HZ and max(e[1] for e in mid) < TOL_M


def test_slam_pose_ahead_of_odometry_waits_for_it():
    ms = NS // 1000
    f = PoseFusion("fused", PoseFusionParams())
    f.add_odom(0, (0.0, 0.0, 0.0))
    f.add_odom(450 * ms, (0.45, 0.0, 0.0))
    assert f.add_map_pose(500 * ms, (10.0, 0.0, 0.0)) is None    # no odometry at 0.5 s yet
    assert f.pose_at(500 * ms, 100 * ms) == (10.0, 0.0, 0.0)     # SLAM alone meanwhile
    f.add_odom(550 * ms, (0.55, 0.0, 0.0))                         # odometry passes 0.5 s
    assert f.pose_at(550 * ms, 100 * ms) == pytest.approx((10.05, 0.0, 0.0))
    assert f.latest() == (550 * ms, pytest.approx((10.05, 0.0, 0.0)))


def test_slam_pose_without_odometry_near_it_makes_no_correction():
    f = PoseFusion("fused", PoseFusionParams(match_tolerance_s=0.1))
    f.add_odom(0, (0.0, 0.0, 0.0))
    f.add_odom(2 * NS, (2.0, 0.0, 0.0))
    ev = f.add_map_pose(NS, (5.0, 5.0, 0.0))
    assert ev is not None and ev.kind == "dropped" and "on both sides within 0.1 s" in ev.message
    assert f.latest() == (NS, (5.0, 5.0, 0.0))                   # falls back to SLAM alone
    # odometry on one side only (50 ms before): no correction either (a lever arm: a
    # heading error of the odometry tilts the whole correction)
    f.add_odom(NS - NS // 20, (0.95, 0.0, 0.0))
    f.add_odom(3 * NS, (3.0, 0.0, 0.0))
    ev = f.add_map_pose(2 * NS + NS // 2, (9.0, 9.0, 0.0))
    assert ev is not None and ev.kind == "dropped"


def test_time_going_back_clears_and_reports():
    f = PoseFusion("fused", PoseFusionParams(backwards_s=0.5))
    for k in range(20):
        f.add_odom(100 * NS + k * NS // 10, (0.1 * k, 0.0, 0.0))
    f.add_map_pose(101 * NS, (3.0, 0.0, 0.0))
    assert f.pose_at(101 * NS, NS // 10) is not None
    assert f.add_odom(101 * NS + 85 * NS // 100, (1.85, 0.0, 0.0)) is None   # reordered: kept
    ev = f.add_odom(5 * NS, (0.0, 0.0, 0.0))                          # simulator reset
    assert ev is not None and ev.kind == "reset" and "went back" in ev.message
    assert f.resets == 1
    assert f.pose_at(101 * NS, NS) is None                         # the old time line is gone
    # a new time line starts like a start-up: odometry stands for the map pose until SLAM
    assert f.pose_at(5 * NS, NS // 10) == (0.0, 0.0, 0.0)
    f.add_map_pose(5 * NS, (1.0, 1.0, 0.0))
    assert f.pose_at(5 * NS, NS // 10) == pytest.approx((1.0, 1.0, 0.0))


def test_loop_closure_jump_is_accepted_and_rekeys():
    f = PoseFusion("fused", PoseFusionParams(jump_m=0.3))
    for k in range(31):
        f.add_odom(k * NS // 10, (0.1 * k, 0.0, 0.0))
    f.add_map_pose(NS, (1.0, 0.0, 0.0))
    f.add_map_pose(2 * NS, (2.02, 0.0, 0.0))                  # small correction change
    assert f.rekeys == 0
    # between two corrections the correction is interpolated
    assert f.pose_at(3 * NS // 2, 0)[0] == pytest.approx(1.51)
    ev = f.add_map_pose(3 * NS, (3.0, 1.0, 0.0))               # loop closure: 1 m sideways
    assert ev is not None and ev.kind == "jump" and f.rekeys == 1
    # every stamp now uses the new correction (no blend of the two)
    assert f.pose_at(3 * NS // 2, 0) == pytest.approx((1.5, 1.0, 0.0))
    assert f.latest() == (3 * NS, pytest.approx((3.0, 1.0, 0.0)))


def test_heading_drift_far_from_the_odom_origin_is_no_loop_closure():
    """50 m from the odometry's origin a 0.05 rad/s gyro bias swings the correction by
    ~2.5 m per second; the robot's pose moves by millimetres: no re-key."""
    times = np.arange(0.0, 20.0, 0.02)
    odom = drifting_odometry(times, scale=1.0, yaw_bias_radps=0.05, start=(50.0, 0.0, 0.0))
    f = PoseFusion("fused", PoseFusionParams())
    corrections = []
    for k, (t, o) in enumerate(zip(times, odom)):
        f.add_odom(int(t * NS), o)
        if k % 50 == 25:                                      # SLAM at 1 Hz, 0.5 s late
            ts = times[k - 25]
            assert f.add_map_pose(int(ts * NS), truth(ts)) is None
            corrections.append(f._corr.newest()[1])
    swings = [math.hypot(a[0] - b[0], a[1] - b[1]) for a, b in zip(corrections, corrections[1:])]
    assert max(swings) > 1.0 and f.rekeys == 0
    d_m, d_rad = pose_err(f.latest()[1], truth(f.latest()[0] / NS))
    assert d_m < TOL_M and d_rad < 0.06         # at most 1 s of gyro bias since the last


def test_sources_and_validation():
    assert POSE_SOURCES == ("odom", "pose", "fused")
    with pytest.raises(ValueError, match="source must be one of"):
        PoseFusion("tf", PoseFusionParams())
    f = PoseFusion("odom", PoseFusionParams())
    with pytest.raises(ValueError, match="odometry pose must be finite"):
        f.add_odom(0, (math.nan, 0.0, 0.0))
    with pytest.raises(ValueError, match="SLAM pose must be finite"):
        f.add_map_pose(0, (0.0, math.inf, 0.0))
    assert f.latest() is None
    f.add_map_pose(0, (1.0, 0.0, 0.0))                        # odom source ignores SLAM
    assert f.latest() is None
    with pytest.raises(ValueError, match="odom_frame must not be empty"):
        PoseFusionParams(odom_frame=" ")
    for name in ("history_s", "match_tolerance_s", "backwards_s", "jump_m", "jump_rad"):
        with pytest.raises(ValueError, match=f"{name} must be finite and > 0"):
            PoseFusionParams(**{name: 0.0})


def test_history_is_bounded():
    f = PoseFusion("odom", PoseFusionParams(history_s=1.0))
    for k in range(1000):
        f.add_odom(k * NS // 50, (0.0, 0.0, 0.0))
    lo, hi = f._odom.span_ns()
    assert hi - lo <= NS and len(f._odom) <= 51


def test_pose_at_an_image_stamp_is_interpolated_between_the_bracketing_poses():
    s = 1_000_000_000
    poses = StampedPoses(10 * s)
    poses.add(s, (1.0, 2.0, -3.0))                             # any order
    poses.add(0, (0.0, 0.0, 3.0))                              # yaw crosses +-pi
    x, y, yaw = poses.at(s // 4, s)
    assert (x, y) == pytest.approx((0.25, 0.5))
    assert math.cos(yaw) == pytest.approx(math.cos(3.0 + 0.25 * (2 * math.pi - 6.0)))
    # only one side within the tolerance: the nearest pose; none: None
    assert poses.at(s // 10, s // 5) == (0.0, 0.0, 3.0)
    assert poses.at(3 * s, s // 5) is None
    assert StampedPoses(s).at(0, s) is None


def test_odometry_stands_for_the_map_pose_until_the_first_slam_pose():
    # slam_toolbox publishes a pose per processed scan only: a robot that stands still after
    # start-up (or whose first pose was published before we subscribed) has none yet.
    f = PoseFusion("fused", PoseFusionParams())
    f.add_odom(0, (0.0, 0.0, 0.0))
    f.add_odom(10**9, (0.5, 0.0, 0.0))
    assert f.pose_at(10**9, 10**8) == (0.5, 0.0, 0.0) and f.newest_ns() == 10**9
    f.add_odom(2 * 10**9, (1.0, 0.0, 0.0))
    f.add_map_pose(2 * 10**9, (3.0, 1.0, 0.0))     # now SLAM knows better: its frame wins
    assert f.pose_at(2 * 10**9, 10**8) == pytest.approx((3.0, 1.0, 0.0))
    off = PoseFusion("fused", PoseFusionParams(odom_until_first_slam=False))
    off.add_odom(0, (0.0, 0.0, 0.0))
    assert off.pose_at(0, 10**8) is None and off.latest() is None
