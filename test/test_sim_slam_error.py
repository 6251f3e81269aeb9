"""The SLAM-like mapping error model: drift, keyframes, loop closures, the engine's hooks."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.pose_fusion import compose
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.mapping import MappingParams
from sim_bridge.navigation import NavState
from sim_bridge.sensors import Lidar
from sim_bridge.slam_error import (HARSH, PROFILES, REALISTIC, LidarGeometry, SlamErrorModel,
                                   SlamErrorParams)
from sim_scenes import FAST, room_world

GEOM = LidarGeometry(-math.pi, 2 * math.pi / 8, 2.0, 0.1)
NO_HIT = np.full(8, np.inf, dtype=np.float32)


def _model(seed: int, **kw) -> SlamErrorModel:
    return SlamErrorModel(replace(REALISTIC, **kw), (0.0, 0.0), MappingParams(), GEOM, seed)


def _error(model: SlamErrorModel, true_pose) -> tuple[float, float]:
    est = model.estimate(true_pose)
    return (math.hypot(est[0] - true_pose[0], est[1] - true_pose[1]),
            abs(math.remainder(est[2] - true_pose[2], 2 * math.pi)))


def _drive_straight(model: SlamErrorModel, dist_m: float, step_m: float = 0.026):
    pose = (0.0, 0.0, 0.0)
    for k in range(int(round(dist_m / step_m)) + 1):
        pose = (k * step_m, 0.0, 0.0)
        model.add_scan(pose, pose, NO_HIT)
    return pose


def _turn_in_place(model: SlamErrorModel, angle_rad: float, step_rad: float = 0.18):
    pose = (0.0, 0.0, 0.0)
    for k in range(int(round(angle_rad / step_rad)) + 1):
        pose = (0.0, 0.0, math.remainder(k * step_rad, 2 * math.pi))
        model.add_scan(pose, pose, NO_HIT)
    return pose


def test_profiles_and_validation():
    assert set(PROFILES) == {"realistic", "harsh"}
    assert HARSH.drift_xy_m > REALISTIC.drift_xy_m and HARSH.loop_min_travel_m > \
        REALISTIC.loop_min_travel_m
    assert SimParams().mapping_error == "none" and SimParams().slam_error_params() is None
    assert SimParams(mapping_error="harsh").slam_error_params() == HARSH
    assert SimParams(mapping_error="custom", mapping_drift_xy_m=0.1
                     ).slam_error_params().drift_xy_m == 0.1
    with pytest.raises(ValueError, match="mapping_error must be one of"):
        SimParams(mapping_error="bad")
    with pytest.raises(ValueError, match="loop_radius_m must be finite and > 0"):
        SimParams(mapping_loop_radius_m=0.0)
    with pytest.raises(ValueError, match="drift_xy_m must be finite and >= 0"):
        SlamErrorParams(drift_xy_m=-1.0)


def test_no_motion_no_drift_and_zero_numbers_no_error():
    m = _model(0)
    for _ in range(50):
        m.add_scan((1.0, 2.0, 0.3), (1.0, 2.0, 0.3), NO_HIT)
    assert m.drift == (0.0, 0.0, 0.0) and m.n_keyframes == 1
    zero = _model(0, drift_xy_m=0.0, drift_yaw_per_m_rad=0.0, drift_yaw_per_rad=0.0)
    end = _drive_straight(zero, 6.0)
    assert _error(zero, end) == pytest.approx((0.0, 0.0), abs=1e-9)


def test_drift_grows_with_distance():
    def rms(dist_m: float) -> float:
        errs = []
        for seed in range(40):
            m = _model(seed)
            errs.append(_error(m, _drive_straight(m, dist_m))[0])
        return float(np.sqrt(np.mean(np.square(errs))))

    short, long_ = rms(1.0), rms(8.0)
    assert 0.0 < short and long_ > 2.0 * short, (short, long_)


def test_drift_grows_with_turning_and_only_with_the_turn_term():
    def rms_yaw(angle_rad: float, **kw) -> float:
        errs = []
        for seed in range(40):
            m = _model(seed, **kw)
            errs.append(_error(m, _turn_in_place(m, angle_rad))[1])
        return float(np.sqrt(np.mean(np.square(errs))))

    small, big = rms_yaw(1.0), rms_yaw(12.0)
    assert 0.0 < small and big > 2.0 * small, (small, big)
    # Turning in place moves nothing: only drift_yaw_per_rad makes an error.
    assert rms_yaw(12.0, drift_yaw_per_rad=0.0) == pytest.approx(0.0, abs=1e-9)


def test_keyframes_after_travel_or_turn_only():
    m = _model(0)
    for x in (0.0, 0.2, 0.4, 0.55, 0.7, 1.1):
        m.add_scan((x, 0.0, 0.0), (x, 0.0, 0.0), NO_HIT)
    assert m.n_keyframes == 3          # 0.0, 0.55, 1.1
    m.add_scan((1.1, 0.0, 0.6), (1.1, 0.0, 0.6), NO_HIT)
    assert m.n_keyframes == 4


# ----------------------------------------------------------------- loop closures

ROOM = room_world([], size=(6.0, 4.0), start=(1.0, 1.0, 0.0))
#: Large drift, no jitter, closures after 8 m within 1 m.
LOOPY = dict(drift_xy_m=0.03, drift_yaw_per_m_rad=0.03, drift_yaw_per_rad=0.02,
             jitter_xy_m=0.0, jitter_yaw_rad=0.0, loop_radius_m=1.0, loop_min_travel_m=8.0)


def _loop_poses(laps: int = 1, step_m: float = 0.05):
    """Counter-clockwise around the rectangle (1, 1) - (5, 3), turning at the corners."""
    corners = [(1.0, 1.0), (5.0, 1.0), (5.0, 3.0), (1.0, 3.0)]
    poses = []
    for _ in range(laps):
        for i, (x0, y0) in enumerate(corners):
            x1, y1 = corners[(i + 1) % 4]
            yaw = math.atan2(y1 - y0, x1 - x0)
            n = int(round(math.hypot(x1 - x0, y1 - y0) / step_m))
            poses += [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n, yaw) for k in range(n)]
    poses.append((1.0, 1.0, 0.0))
    return poses


def _run_loop(seed: int, **kw):
    lidar = Lidar(ROOM, SimParams(**FAST).lidar_params())
    lp = SimParams(**FAST).lidar_params()
    geom = LidarGeometry(lp.angle_min_rad, lp.angle_increment_rad, lp.range_max_m,
                         lp.range_min_m)
    m = SlamErrorModel(replace(REALISTIC, **{**LOOPY, **kw}), (1.0, 1.0), MappingParams(),
                       geom, seed)
    rng = np.random.default_rng(0)
    shifts = []
    for pose in _loop_poses():
        ranges = lidar.scan(pose, rng)
        before = m.estimate(pose)
        n = len(m.closures)
        m.add_scan(pose, pose, ranges)
        if len(m.closures) > n:
            shifts.append((before, m.estimate(pose), m.grid(), pose, ranges, m.drift))
    return m, shifts, lidar


def _hit_fraction(grid: GridMap, pose, ranges, geom_from: SimParams) -> float:
    """Share of the scan's returns that land on or next to an occupied cell of ``grid``
    when projected from ``pose``."""
    lp = geom_from.lidar_params()
    r = np.asarray(ranges, dtype=np.float64)
    ang = pose[2] + lp.angle_min_rad + lp.angle_increment_rad * np.arange(r.size)
    ok = np.isfinite(r) & (r < lp.range_max_m)
    xs, ys = pose[0] + r[ok] * np.cos(ang[ok]), pose[1] + r[ok] * np.sin(ang[ok])
    occ = grid.data >= 65
    pad = np.zeros((occ.shape[0] + 2, occ.shape[1] + 2), dtype=bool)
    for dr in (0, 1, 2):
        for dc in (0, 1, 2):
            pad[dr:dr + occ.shape[0], dc:dc + occ.shape[1]] |= occ
    hits = 0
    for x, y in zip(xs, ys):
        rr, cc = grid.world_to_cell(x, y)
        if 0 <= rr < occ.shape[0] and 0 <= cc < occ.shape[1] and pad[rr + 1, cc + 1]:
            hits += 1
    return hits / max(1, len(xs))


def test_a_loop_closure_moves_map_and_slam_pose_together():
    sp = SimParams(**FAST)
    m, shifts, _ = _run_loop(seed=3)
    assert m.closures, "driving a 12 m loop back to the start closes it"
    c = m.closures[0]
    assert c.matched < c.keyframe and c.rerendered
    before, after, grid, pose, ranges, drift = shifts[0]
    jump = math.hypot(after[0] - before[0], after[1] - before[1])
    # (the estimate before add_scan lacks that scan's own drift step: < 1 cm)
    assert jump == pytest.approx(c.shift_m, abs=0.01) and c.shift_m > 0.02
    # The closure's jump is the rigid transform between the SLAM poses (what the object
    # layer moves its last marks by): after ~ jump o before, up to that scan's drift step.
    moved = compose(c.jump, before)
    assert math.hypot(moved[0] - after[0], moved[1] - after[1]) < 0.01
    assert abs(math.remainder(moved[2] - after[2], 2 * math.pi)) < 0.01
    # The current scan, projected from the corrected SLAM pose, lands on the walls of the
    # re-rendered map.
    assert _hit_fraction(grid, after, ranges, sp) > 0.9
    # The SLAM pose now carries the drift of the keyframe it matched (up to the share of
    # the error left on the closing edge: its sigma is the jitter's, here the floor).
    assert after == pytest.approx(compose(m._kf_drift[c.matched], pose), abs=1e-4)
    assert drift == pytest.approx(m._kf_drift[c.matched], abs=1e-4)


def test_a_closure_corrects_keyframes_mapped_before_the_previous_closure():
    """Two laps: the first closes at the start; on the second lap the robot closes a loop
    with a first-lap keyframe mapped before that closure. The whole graph is re-solved, so
    keyframes between the matched one and the previous closure move too (a correction
    spread only since the previous closure would leave them, and their walls, where they
    were)."""
    lidar = Lidar(ROOM, SimParams(**FAST).lidar_params())
    lp = SimParams(**FAST).lidar_params()
    geom = LidarGeometry(lp.angle_min_rad, lp.angle_increment_rad, lp.range_max_m,
                         lp.range_min_m)
    m = SlamErrorModel(replace(REALISTIC, **LOOPY), (1.0, 1.0), MappingParams(), geom, 2)
    rng = np.random.default_rng(0)
    moved_early = []
    for pose in _loop_poses(laps=2):
        n, drifts = len(m.closures), list(m._kf_drift)
        m.add_scan(pose, pose, lidar.scan(pose, rng))
        if len(m.closures) > n and n >= 1:
            c, prev = m.closures[-1], m.closures[-2]
            if c.matched < prev.keyframe:
                moved_early.append(max(
                    math.hypot(m._kf_drift[i][0] - drifts[i][0],
                               m._kf_drift[i][1] - drifts[i][1])
                    for i in range(c.matched + 1, prev.keyframe + 1)))
    assert moved_early, "the second lap closes with a first-lap keyframe"
    assert max(moved_early) > 0.005


def _occupied(grid: GridMap) -> int:
    return int((grid.data >= 65).sum())


def test_after_the_closure_walls_line_up_again():
    """Drift doubles the walls seen at the start and at the end of the loop; the
    re-render from corrected poses leaves fewer occupied cells than the same run with
    closures off, closer to the truth's."""
    lidar = Lidar(ROOM, SimParams(**FAST).lidar_params())
    truth = SimEngine(ROOM, SimParams(**FAST), lidar=lidar)
    truth.run_until(lambda e: e.latest_scan is not None, 1.0)
    better = 0
    for seed in range(4):
        closed, _, _ = _run_loop(seed)
        open_, _, _ = _run_loop(seed, loop_min_travel_m=1e6)
        assert closed.closures and not open_.closures
        if _occupied(closed.grid()) < _occupied(open_.grid()):
            better += 1
    assert better >= 3


def test_shift_moves_every_keyframe_and_the_pose():
    m, _, _ = _run_loop(seed=1)
    pose = (1.0, 1.0, 0.0)
    est0, g0 = m.estimate(pose), m.grid()
    v0 = m.version
    m.shift((0.3, 0.0, 0.0))
    est1, g1 = m.estimate(pose), m.grid()
    assert m.version > v0
    assert (est1[0] - est0[0], est1[1] - est0[1], est1[2] - est0[2]) == pytest.approx(
        (0.3, 0.0, 0.0), abs=1e-9)
    # The re-rendered map is the old one 0.3 m (6 cells) further along x.
    occ0 = np.argwhere(g0.data >= 65)
    occ1 = np.argwhere(g1.data >= 65)
    x0 = g0.cells_to_world(occ0[:, 0], occ0[:, 1])[0]
    x1 = g1.cells_to_world(occ1[:, 0], occ1[:, 1])[0]
    assert x1.mean() - x0.mean() == pytest.approx(0.3, abs=0.03)


# ------------------------------------------------------------------------- engine


def test_engine_without_the_model_is_unchanged():
    e = SimEngine(ROOM, SimParams(**FAST))
    e.set_cmd_vel(0.2, 0.3)
    e.step(3.0)
    assert e.slam_error is None and e.slam_pose == e.pose
    assert e.live_map is e.true_map
    assert e.latest_scan.map_pose == e.latest_scan.pose


def _drifting_engine(**kw) -> SimEngine:
    p = SimParams(**FAST, mapping_error="custom", mapping_drift_xy_m=0.05,
                  mapping_drift_yaw_per_m_rad=0.08, mapping_drift_yaw_per_rad=0.02,
                  mapping_loop_min_travel_m=1e6, **kw)
    return SimEngine(ROOM, p)


def test_engine_pose_and_published_map_agree_the_true_pose_does_not():
    e = _drifting_engine(seed=2)
    e.set_cmd_vel(0.2, 0.4)          # circles of 0.5 m radius in the room
    e.step(90.0)
    scan = e.latest_scan
    drift = math.hypot(scan.map_pose[0] - scan.pose[0], scan.map_pose[1] - scan.pose[1])
    assert e.metrics.n_collisions == 0
    assert drift > 0.05, "18 m of driving drifts"
    sp = e.params
    assert e.slam_pose == pytest.approx(e.slam_error.estimate(e.pose))
    assert _hit_fraction(e.map, scan.map_pose, scan.ranges, sp) > \
        _hit_fraction(e.map, scan.pose, scan.ranges, sp)
    # Coverage keeps measuring the truth: the true map is built at true poses.
    assert _hit_fraction(e.true_map, scan.pose, scan.ranges, sp) > 0.9


@pytest.mark.parametrize("profile", ["realistic", "harsh"])
def test_navigation_reaches_goals_on_the_erroneous_map(profile):
    e = SimEngine(ROOM, SimParams(**FAST, mapping_error=profile, seed=1))
    e.run_until(lambda eng: eng.latest_scan is not None, 1.0)
    for gx, gy in ((4.5, 2.5), (1.5, 3.0), (4.5, 1.0), (1.0, 1.0)):
        e.set_goal(gx, gy)
        e.run_until(lambda eng: eng.nav_status.state is not NavState.ACTIVE, 120.0)
        assert e.nav_status.state is NavState.SUCCEEDED, e.nav_status
        # The goal is reached in the map frame: the SLAM pose is there.
        x, y, _ = e.slam_pose
        assert math.hypot(x - gx, y - gy) <= e.params.nav_goal_tolerance_xy_m + 0.05
    assert e.metrics.n_collisions == 0


def test_objects_are_placed_in_the_map_frame():
    """The lock step's object pipeline projects the scan from the SLAM pose, and the
    paper strategy (object costmap on) runs with a mapping error."""
    from sim_bridge.lockstep import LockstepParams, run_exploration
    from sim_bridge.object_pipeline import _map_from_world, scan_points_map

    e = _drifting_engine(seed=2)
    e.set_cmd_vel(0.2, 0.4)
    e.step(30.0)
    scan = e.latest_scan
    pts = scan_points_map(e)
    lp = e.params.lidar_params()
    r = np.asarray(scan.ranges, dtype=np.float64)
    ok = np.isfinite(r) & (r >= lp.range_min_m) & (r < lp.range_max_m)
    a = scan.map_pose[2] + lp.angle_min_rad + lp.angle_increment_rad * np.flatnonzero(ok)
    assert pts == pytest.approx(np.column_stack([scan.map_pose[0] + r[ok] * np.cos(a),
                                                 scan.map_pose[1] + r[ok] * np.sin(a)]))
    d = (0.3, -0.2, 0.4)
    p_world = np.array([1.0, 2.0, 0.5, 1.0])
    mx, my, _ = compose(d, (1.0, 2.0, 0.0))
    assert (_map_from_world(d) @ p_world)[:3] == pytest.approx([mx, my, 0.5])
    res = run_exploration(room_world([]), "paper", 0, params=LockstepParams(max_sim_time_s=30.0),
                          sim_params=SimParams(mapping_error="harsh", compute_coverage=True))
    assert res.goals_sent >= 1 and res.collisions == 0
