"""Simulated lidar: analytic ranges, limits, noise and brute-force agreement."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sensor_scenes import random_free_poses, room_4x4, table_with_legs
from sim_bridge.sensors import Lidar, LidarParams
from sim_bridge.world import Primitive, World
from sim_bridge.worlds import default_world, load_world


CENTRE = LidarParams(mount_xy_m=(0.0, 0.0))


def _beam(angle_rad, params=CENTRE):
    """Index of the beam at ``angle_rad`` from the heading."""
    k = int(round((angle_rad - params.angle_min_rad) / params.angle_increment_rad))
    return k % params.num_beams


@pytest.mark.parametrize("angle, expected", [
    (0.0, 2.0), (math.pi / 2, 2.0), (-math.pi / 2, 2.0), (-math.pi, 2.0),
    (math.pi / 4, 2.0 * math.sqrt(2.0)), (-3 * math.pi / 4, 2.0 * math.sqrt(2.0)),
    (math.radians(30.0), 2.0 / math.cos(math.radians(30.0)))])
def test_lidar_box_room_from_centre(angle, expected):
    lidar = Lidar(room_4x4(), dataclasses.replace(CENTRE, num_beams=720))
    k = _beam(angle, lidar.params)
    assert lidar.params.angle_min_rad + k * lidar.params.angle_increment_rad == pytest.approx(
        angle, abs=1e-9)
    assert lidar.scan((0.0, 0.0, 0.0))[k] == pytest.approx(expected, abs=1e-5)


def test_lidar_mount_offset_and_heading():
    # default mount 0.064 m behind the base: the lidar sits at x = 0.436
    lidar = Lidar(room_4x4())
    r = lidar.scan((0.5, 0.0, 0.0))
    assert r[_beam(0.0)] == pytest.approx(1.564, abs=1e-5)
    assert r[_beam(math.pi)] == pytest.approx(2.436, abs=1e-5)
    # robot turned to +y: beam 0 rad looks along +y, the lidar sits at y = -0.064
    r = lidar.scan((0.0, 0.0, math.pi / 2))
    assert r[_beam(0.0)] == pytest.approx(2.064, abs=1e-5)
    assert r[_beam(-math.pi / 2)] == pytest.approx(2.0, abs=1e-5)


def test_lidar_cylinder():
    leg = Primitive("o", "table", "leg", "cylinder", 1.0, 0.0, 0.0, (0.1,), 0.0, 0.7)
    lidar = Lidar(room_4x4([leg]), CENTRE)
    r = lidar.scan((0.0, 0.0, 0.0))
    inc = CENTRE.angle_increment_rad
    assert r[_beam(0.0)] == pytest.approx(0.9, abs=1e-5)
    # 5 deg: grazing the circle |p - c| = r along the ray
    a = 5 * inc
    b = math.cos(a)
    assert r[_beam(a)] == pytest.approx(b - math.sqrt(b * b - 0.99), abs=1e-5)
    # 7 deg: past the circle (asin(0.1) = 5.74 deg), the wall behind
    assert r[_beam(7 * inc)] == pytest.approx(2.0 / math.cos(7 * inc), abs=1e-5)
    ranges, hit = lidar.scan_with_hits((0.0, 0.0, 0.0))
    assert hit[_beam(0.0)] == 4 and hit[_beam(7 * inc)] != 4


@pytest.mark.parametrize("pose, beam_angle, expected", [
    ((1.95, 0.0, 0.0), 0.0, -math.inf),     # 5 cm from the wall: too close
    ((0.0, 0.0, 0.0), 0.0, math.inf),       # 2 m wall beyond a 1.5 m range
])
def test_lidar_range_limits(pose, beam_angle, expected):
    lidar = Lidar(room_4x4(), dataclasses.replace(CENTRE, range_max_m=1.5))
    assert lidar.scan(pose)[_beam(beam_angle)] == expected


def test_lidar_sees_table_legs_only():
    parts, obj = table_with_legs(1.0, 0.0, length=1.2, depth=0.8)
    lidar = Lidar(room_4x4(parts, [obj]), CENTRE)
    r = lidar.scan((0.0, 0.0, 0.0))
    # beam 0 passes between the legs (y = 0) under the top: wall at 2 m
    assert r[_beam(0.0)] == pytest.approx(2.0, abs=1e-5)
    # the leg at (0.45, 0.35): range |c| - r along its own direction
    a = math.atan2(0.35, 0.45)
    k = _beam(a)
    ak = CENTRE.angle_min_rad + k * CENTRE.angle_increment_rad
    b = 0.45 * math.cos(ak) + 0.35 * math.sin(ak)
    disc = b * b - (0.45 ** 2 + 0.35 ** 2 - 0.025 ** 2)
    assert disc > 0
    assert r[k] == pytest.approx(b - math.sqrt(disc), abs=1e-5)
    # a lidar at table-top height sees the top's edge at x = 0.4
    high = Lidar(room_4x4(parts, [obj]), dataclasses.replace(CENTRE, scan_height_m=0.73))
    assert high.scan((0.0, 0.0, 0.0))[_beam(0.0)] == pytest.approx(0.4, abs=1e-5)


def test_lidar_noise_only_with_rng():
    lidar = Lidar(room_4x4(), dataclasses.replace(CENTRE, noise_std_m=0.05))
    clean = lidar.scan((0.0, 0.0, 0.0))
    assert clean[_beam(0.0)] == pytest.approx(2.0, abs=1e-5)
    noisy = lidar.scan((0.0, 0.0, 0.0), np.random.default_rng(3))
    diff = noisy - clean
    assert 0.02 < float(np.std(diff)) < 0.08
    assert np.array_equal(noisy, lidar.scan((0.0, 0.0, 0.0), np.random.default_rng(3)))


@pytest.mark.parametrize("kwargs, match", [
    ({"num_beams": 2}, "num_beams"), ({"range_min_m": 0.0}, "range_min_m"),
    ({"range_max_m": 0.1}, "range_max_m"), ({"noise_std_m": -1.0}, "noise_std_m"),
    ({"rate_hz": 0.0}, "rate_hz"), ({"scan_height_m": -0.1}, "scan_height_m"),
    ({"mount_xy_m": (0.0,)}, "mount_xy_m")])
def test_lidar_params_validate(kwargs, match):
    with pytest.raises(ValueError, match=match):
        LidarParams(**kwargs)


def _brute_scan(world, params, pose):
    """Reference: every beam against every scan-plane primitive, no culling."""
    n = params.num_beams
    x, y, yaw = pose
    mx, my = params.mount_xy_m
    ox = x + math.cos(yaw) * mx - math.sin(yaw) * my
    oy = y + math.sin(yaw) * mx + math.cos(yaw) * my
    ang = yaw + params.angle_min_rad + np.arange(n) * params.angle_increment_rad
    dx, dy = np.cos(ang), np.sin(ang)
    best = np.full(n, np.inf)
    for p in world.primitives:
        if not p.zmin <= params.scan_height_m <= p.zmax:
            continue
        if p.shape == "cylinder":
            wx, wy = p.x - ox, p.y - oy
            b = wx * dx + wy * dy
            disc = b * b - (wx * wx + wy * wy - p.size[0] ** 2)
            t = np.where(disc >= 0, b - np.sqrt(np.maximum(disc, 0)), np.inf)
            t = np.where(t >= 0, t, np.inf)
        else:   # slab test in the box frame
            c, s = math.cos(p.yaw), math.sin(p.yaw)
            px, py = c * (ox - p.x) + s * (oy - p.y), -s * (ox - p.x) + c * (oy - p.y)
            ux, uy = c * dx + s * dy, -s * dx + c * dy
            with np.errstate(divide="ignore", invalid="ignore"):
                t1, t2 = (-p.size[0] / 2 - px) / ux, (p.size[0] / 2 - px) / ux
                t3, t4 = (-p.size[1] / 2 - py) / uy, (p.size[1] / 2 - py) / uy
            tn = np.maximum(np.minimum(t1, t2), np.minimum(t3, t4))
            tf = np.minimum(np.maximum(t1, t2), np.maximum(t3, t4))
            t = np.where((tn <= tf) & (tn >= 0), tn, np.inf)
        best = np.minimum(best, t)
    best[best > params.range_max_m] = np.inf
    best[best < params.range_min_m] = -np.inf
    return best


@pytest.mark.parametrize("name", ["small_cluttered", "house_cluttered"])
def test_lidar_matches_brute_force_and_hits_lie_on_boundaries(name):
    world = default_world(name)
    params = LidarParams()
    lidar = Lidar(world, params)
    for pose in random_free_poses(world, 12, seed=5):
        ranges, hit = lidar.scan_with_hits(pose)
        ref = _brute_scan(world, params, pose)
        assert np.allclose(ranges, ref, atol=1e-4, rtol=0, equal_nan=False), pose
        fin = np.isfinite(ranges)
        assert np.all((ranges[fin] >= params.range_min_m) & (ranges[fin] <= params.range_max_m))
        assert np.all(hit[fin] >= 0) and np.all(hit[ranges == np.inf] == -1)
        ox, oy = lidar.origin(pose)
        ang = pose[2] + params.angle_min_rad + np.flatnonzero(fin) * params.angle_increment_rad
        hx = ox + ranges[fin] * np.cos(ang)
        hy = oy + ranges[fin] * np.sin(ang)
        for k, px, py in zip(hit[fin], hx, hy):
            p = world.primitives[int(k)]
            assert p.zmin <= params.scan_height_m <= p.zmax
            if p.shape == "cylinder":
                gap = abs(math.hypot(px - p.x, py - p.y) - p.size[0])
            else:
                c, s = math.cos(p.yaw), math.sin(p.yaw)
                u, v = c * (px - p.x) + s * (py - p.y), -s * (px - p.x) + c * (py - p.y)
                gap = abs(max(abs(u) - p.size[0] / 2, abs(v) - p.size[1] / 2))
            assert gap < 2e-4, (pose, p)


@pytest.mark.parametrize("spec", ["shared/house_cluttered_plus", "eb/room_with_corridor"])
def test_lidar_matches_brute_force_on_shipped_worlds(spec):
    world = load_world(spec)
    params = LidarParams()
    lidar = Lidar(world, params)
    for pose in random_free_poses(world, 8, seed=9):
        assert np.allclose(lidar.scan(pose), _brute_scan(world, params, pose), atol=1e-4,
                           rtol=0), pose


def test_lidar_world_without_primitives():
    empty = World("empty", (-1.0, -1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    r = Lidar(empty).scan((0.0, 0.0, 0.0))
    assert r.dtype == np.float32 and r.shape == (360,) and np.all(r == np.inf)
