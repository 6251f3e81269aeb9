"""Tests of sim_bridge.sensors: analytic lidar and ray-cast RGB-D camera."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sim_bridge.sensors import (CLASS_IDS, CLASS_NAMES, CameraParams, DepthCamera, Lidar,
                                LidarParams, camera_pose_in_world)
from sim_bridge.world import Primitive, World, WorldObject
from sim_bridge.worlds import default_world, ground_truth

CENTRE = LidarParams(mount_xy_m=(0.0, 0.0))


def _wall(x, y, sx, sy, z=(0.0, 2.5)):
    return Primitive("", "wall", "wall", "box", x, y, 0.0, (sx, sy), z[0], z[1])


def _room(extra=(), objects=()):
    """4 x 4 m room: inner wall faces at x, y = +-2 (walls 0.15 m thick)."""
    walls = [_wall(0.0, 2.075, 4.3, 0.15), _wall(0.0, -2.075, 4.3, 0.15),
             _wall(2.075, 0.0, 0.15, 4.3), _wall(-2.075, 0.0, 0.15, 4.3)]
    return World("room", (-2.5, -2.5, 2.5, 2.5), (0.0, 0.0, 0.0), walls + list(extra),
                 list(objects))


def _beam(angle_rad, params=CENTRE):
    """Index of the beam at ``angle_rad`` from the heading."""
    k = int(round((angle_rad - params.angle_min_rad) / params.angle_increment_rad))
    return k % params.num_beams


def _table(x, y, length=1.2, depth=0.8, top=(0.72, 0.75), leg_r=0.025):
    parts = [Primitive("table", "table", "leg", "cylinder", x + sx * (length / 2 - 0.05),
                       y + sy * (depth / 2 - 0.05), 0.0, (leg_r,), 0.0, top[0])
             for sx in (-1, 1) for sy in (-1, 1)]
    parts.append(Primitive("table", "table", "top", "box", x, y, 0.0, (length, depth),
                           top[0], top[1]))
    obj = WorldObject("table", "table", (x, y, 0.0),
                      (x - length / 2, y - depth / 2, 0.0, x + length / 2, y + depth / 2, top[1]))
    return parts, obj


# ------------------------------------------------------------------ lidar, analytic
@pytest.mark.parametrize("angle, expected", [
    (0.0, 2.0), (math.pi / 2, 2.0), (-math.pi / 2, 2.0), (-math.pi, 2.0),
    (math.pi / 4, 2.0 * math.sqrt(2.0)), (-3 * math.pi / 4, 2.0 * math.sqrt(2.0)),
    (math.radians(30.0), 2.0 / math.cos(math.radians(30.0)))])
def test_lidar_box_room_from_centre(angle, expected):
    lidar = Lidar(_room(), dataclasses.replace(CENTRE, num_beams=720))
    k = _beam(angle, lidar.params)
    assert lidar.params.angle_min_rad + k * lidar.params.angle_increment_rad == pytest.approx(
        angle, abs=1e-9)
    assert lidar.scan((0.0, 0.0, 0.0))[k] == pytest.approx(expected, abs=1e-5)


def test_lidar_mount_offset_and_heading():
    # default mount 0.064 m behind the base: the lidar sits at x = 0.436
    lidar = Lidar(_room())
    r = lidar.scan((0.5, 0.0, 0.0))
    assert r[_beam(0.0)] == pytest.approx(1.564, abs=1e-5)
    assert r[_beam(math.pi)] == pytest.approx(2.436, abs=1e-5)
    # robot turned to +y: beam 0 rad looks along +y, the lidar sits at y = -0.064
    r = lidar.scan((0.0, 0.0, math.pi / 2))
    assert r[_beam(0.0)] == pytest.approx(2.064, abs=1e-5)
    assert r[_beam(-math.pi / 2)] == pytest.approx(2.0, abs=1e-5)


def test_lidar_cylinder():
    leg = Primitive("o", "table", "leg", "cylinder", 1.0, 0.0, 0.0, (0.1,), 0.0, 0.7)
    lidar = Lidar(_room([leg]), CENTRE)
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
    lidar = Lidar(_room(), dataclasses.replace(CENTRE, range_max_m=1.5))
    assert lidar.scan(pose)[_beam(beam_angle)] == expected


def test_lidar_sees_table_legs_only():
    parts, obj = _table(1.0, 0.0, length=1.2, depth=0.8)
    lidar = Lidar(_room(parts, [obj]), CENTRE)
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
    high = Lidar(_room(parts, [obj]), dataclasses.replace(CENTRE, scan_height_m=0.73))
    assert high.scan((0.0, 0.0, 0.0))[_beam(0.0)] == pytest.approx(0.4, abs=1e-5)


def test_lidar_noise_only_with_rng():
    lidar = Lidar(_room(), dataclasses.replace(CENTRE, noise_std_m=0.05))
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


# ------------------------------------------------------------------ lidar, invariants
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


def _random_free_poses(world, n, seed, clearance_m=0.25):
    from scipy import ndimage
    gt = ground_truth(world)
    dist = ndimage.distance_transform_edt(gt.footprint.data < 65) * gt.resolution_m
    rr, cc = np.nonzero(gt.inside & (dist >= clearance_m))
    rng = np.random.default_rng(seed)
    pick = rng.choice(rr.size, n, replace=False)
    xs, ys = gt.lidar.cells_to_world(rr[pick], cc[pick])
    return [(float(x), float(y), float(a)) for x, y, a in zip(xs, ys, rng.uniform(-4, 4, n))]


@pytest.mark.parametrize("name", ["small_cluttered", "house_cluttered"])
def test_lidar_matches_brute_force_and_hits_lie_on_boundaries(name):
    world = default_world(name)
    params = LidarParams()
    lidar = Lidar(world, params)
    for pose in _random_free_poses(world, 12, seed=5):
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


@pytest.mark.parametrize("rel", ["house_cluttered_plus.world.yaml",
                                 "explore_bench/room_with_corridor.yaml"])
def test_lidar_matches_brute_force_on_shared_worlds(shared, rel):
    from sim_bridge.worlds import load_world
    world = load_world(shared / "worlds" / rel)
    params = LidarParams()
    lidar = Lidar(world, params)
    for pose in _random_free_poses(world, 8, seed=9):
        assert np.allclose(lidar.scan(pose), _brute_scan(world, params, pose), atol=1e-4,
                           rtol=0), pose


def test_lidar_world_without_primitives():
    empty = World("empty", (-1.0, -1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    r = Lidar(empty).scan((0.0, 0.0, 0.0))
    assert r.dtype == np.float32 and r.shape == (360,) and np.all(r == np.inf)


# ------------------------------------------------------------------ camera
LEVEL = CameraParams(mount_x_m=0.0, mount_z_m=0.2)


def test_camera_pose_in_world():
    rot, t = camera_pose_in_world((1.0, 2.0, math.pi / 2), CameraParams())
    assert t == pytest.approx([1.0, 2.0 + 0.064, 0.2])
    assert rot @ np.array([0.0, 0.0, 1.0]) == pytest.approx([0.0, 1.0, 0.0], abs=1e-12)  # z fwd
    assert rot @ np.array([1.0, 0.0, 0.0]) == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)  # x right
    assert rot @ np.array([0.0, 1.0, 0.0]) == pytest.approx([0.0, 0.0, -1.0], abs=1e-12)  # y down
    rot, _ = camera_pose_in_world((0.0, 0.0, 0.0), CameraParams(pitch_rad=0.1))
    fwd = rot @ np.array([0.0, 0.0, 1.0])
    assert fwd == pytest.approx([math.cos(0.1), 0.0, -math.sin(0.1)])   # looks down


def test_camera_intrinsics():
    k = CameraParams().intrinsics()
    assert (k.fx, k.fy, k.cx, k.cy, k.width, k.height) == (525.0, 525.0, 319.5, 239.5, 640, 480)


def _row_of_height(z_m, dist_m, params=LEVEL):
    return int(round(params.cy - params.fy * (z_m - params.mount_z_m) / dist_m))


def test_camera_wall_and_floor_depth():
    cam = DepthCamera(_room(), LEVEL)
    f = cam.render((0.0, 0.0, 0.0))
    c = int(LEVEL.cx + 0.5)
    # centre column looks at the wall 2 m ahead: depth 2 at any row that sees the wall
    row = _row_of_height(1.0, 2.0)
    assert f.depth_m[row, c] == pytest.approx(2.0, abs=1e-5)
    assert f.semantic[row, c] == CLASS_IDS["wall"] and f.instance[row, c] == -1
    # off-centre pixel: optical z (not Euclidean distance) is still 2 m
    assert f.depth_m[row, 20] == pytest.approx(2.0, abs=1e-5)
    # the floor: a pixel looking down hits z = 0 at depth 0.2 * fy / (v - cy)
    v = 400
    assert f.depth_m[v, c] == pytest.approx(0.2 * LEVEL.fy / (v - LEVEL.cy), rel=1e-5)
    assert f.semantic[v, c] == 0 and f.instance[v, c] == -1
    # above the 2.5 m walls seen from 2 m: nothing (NaN) only higher than the image: all hit
    assert np.isfinite(f.depth_m).all()
    assert f.rgb.shape == (480, 640, 3) and f.rgb.dtype == np.uint8
    assert f.depth_m.dtype == np.float32 and f.instance.dtype == np.int32
    assert f.semantic.dtype == np.uint8


def test_camera_range_max_and_no_ceiling():
    cam = DepthCamera(_room(), dataclasses.replace(LEVEL, range_max_m=1.5))
    f = cam.render((0.0, 0.0, 0.0))
    c = int(LEVEL.cx + 0.5)
    assert np.isnan(f.depth_m[_row_of_height(1.0, 2.0), c])
    assert f.semantic[_row_of_height(1.0, 2.0), c] == 0
    low = World("low", (-2.5, -2.5, 2.5, 2.5), (0.0, 0.0, 0.0), [_wall(2.075, 0.0, 0.15, 4.3,
                                                                       z=(0.0, 0.5))])
    f = DepthCamera(low, LEVEL).render((0.0, 0.0, 0.0))
    assert np.isnan(f.depth_m[_row_of_height(1.0, 2.0), c])     # over the wall: sky
    assert f.depth_m[_row_of_height(0.3, 2.0), c] == pytest.approx(2.0, abs=1e-5)


def test_camera_sees_table_top_and_legs():
    parts, obj = _table(2.0, 0.0, length=0.8, depth=1.2)
    world = _room(parts, [obj])
    world.primitives[0:4] = []   # no walls: only the table and the floor
    cam = DepthCamera(world, LEVEL)
    f = cam.render((0.0, 0.0, 0.0))
    c = int(LEVEL.cx + 0.5)
    # front face of the top at x = 1.6 between 0.72 and 0.75 m
    row = _row_of_height(0.735, 1.6)
    assert f.semantic[row, c] == CLASS_IDS["table"] and f.instance[row, c] == 0
    assert f.depth_m[row, c] == pytest.approx(1.6, abs=1e-5)
    # a ray rising to the underside of the top: z = 0.72 at depth 0.52 * fy / (cy - v)
    row = _row_of_height(0.72, 2.0)
    assert f.semantic[row, c] == CLASS_IDS["table"]
    assert f.depth_m[row, c] == pytest.approx(0.52 * LEVEL.fy / (LEVEL.cy - row), rel=1e-5)
    # between the legs at 0.4 m height: nothing behind the table
    assert np.isnan(f.depth_m[_row_of_height(0.4, 2.0), c])
    # a front leg at (1.65, -0.55) is seen in its own column
    col = int(round(LEVEL.cx + LEVEL.fx * 0.55 / 1.65))
    r = _row_of_height(0.3, 1.65)
    assert f.semantic[r, col] == CLASS_IDS["table"]
    assert f.depth_m[r, col] == pytest.approx(1.625, abs=0.01)


def _brute_render(world, params, pose):
    """Reference depth: every pixel against every primitive and the floor."""
    rot, t = camera_pose_in_world(pose, params)
    u, v = np.meshgrid(np.arange(params.width), np.arange(params.height))
    d = np.stack([(u - params.cx) / params.fx, (v - params.cy) / params.fy,
                  np.ones(u.shape)], -1) @ rot.T
    best = np.where(d[..., 2] < 0, -t[2] / np.where(d[..., 2] < 0, d[..., 2], -1), np.inf)
    cls = np.zeros(u.shape, np.uint8)
    for p in world.primitives:
        with np.errstate(divide="ignore", invalid="ignore"):
            tz = np.stack([(p.zmin - t[2]) / d[..., 2], (p.zmax - t[2]) / d[..., 2]])
            tn, tf = tz.min(0), tz.max(0)
            ox, oy = t[0] - p.x, t[1] - p.y
            if p.shape == "box":
                c, s = math.cos(p.yaw), math.sin(p.yaw)
                lx, ly = c * ox + s * oy, -s * ox + c * oy
                dx = c * d[..., 0] + s * d[..., 1]
                dy = -s * d[..., 0] + c * d[..., 1]
                tx = np.stack([(-p.size[0] / 2 - lx) / dx, (p.size[0] / 2 - lx) / dx])
                ty = np.stack([(-p.size[1] / 2 - ly) / dy, (p.size[1] / 2 - ly) / dy])
                tn = np.maximum(tn, np.maximum(tx.min(0), ty.min(0)))
                tf = np.minimum(tf, np.minimum(tx.max(0), ty.max(0)))
            else:
                a = d[..., 0] ** 2 + d[..., 1] ** 2
                b = ox * d[..., 0] + oy * d[..., 1]
                disc = b * b - a * (ox * ox + oy * oy - p.size[0] ** 2)
                tn = np.maximum(tn, (-b - np.sqrt(disc)) / a)
                tf = np.minimum(tf, (-b + np.sqrt(disc)) / a)
            hit = (tn <= tf) & (tn > params.range_min_m) & (tn < best)
        best = np.where(hit, tn, best)
        cls = np.where(hit, CLASS_IDS[p.cls], cls)
    valid = best <= params.range_max_m
    return np.where(valid, best, np.nan), np.where(valid, cls, 0)


@pytest.mark.parametrize("name, pitch", [("small_cluttered", 0.0), ("house_cluttered", 0.25)])
def test_camera_matches_brute_force(name, pitch):
    world = default_world(name)
    params = CameraParams(width=96, height=72, fx=78.75, fy=78.75, cx=47.5, cy=35.5,
                          pitch_rad=pitch, mount_z_m=0.5 if pitch else 0.2)
    cam = DepthCamera(world, params)
    for pose in _random_free_poses(world, 6, seed=11):
        f = cam.render(pose)
        ref_d, ref_c = _brute_render(world, params, pose)
        both = np.isfinite(ref_d) & np.isfinite(f.depth_m)
        assert np.array_equal(np.isfinite(ref_d), np.isfinite(f.depth_m)), pose
        assert np.allclose(f.depth_m[both], ref_d[both], atol=2e-4 * 6), pose
        agree = (f.semantic == ref_c).mean()
        assert agree > 0.995, pose      # ties at shared faces may pick either class


def _surface_gap(p, px, py, pz):
    """Distance of a point outside or on a primitive to its surface (inf when inside)."""
    if p.shape == "box":
        c, s = math.cos(p.yaw), math.sin(p.yaw)
        u, v = c * (px - p.x) + s * (py - p.y), -s * (px - p.x) + c * (py - p.y)
        g = max(abs(u) - p.size[0] / 2, abs(v) - p.size[1] / 2)
    else:
        g = math.hypot(px - p.x, py - p.y) - p.size[0]
    g = max(g, p.zmin - pz, pz - p.zmax)
    return abs(g) if g >= -1e-3 else math.inf


def test_camera_points_lie_on_surfaces():
    world = default_world("small_cluttered")
    cam = DepthCamera(world, CameraParams())
    prims = world.primitives
    rng = np.random.default_rng(2)
    for pose in _random_free_poses(world, 3, seed=2):
        f = cam.render(pose)
        valid = np.isfinite(f.depth_m)
        assert np.all((f.depth_m[valid] > 0.05) & (f.depth_m[valid] <= 6.0))
        assert np.all(f.semantic[~valid] == 0) and np.all(f.instance[~valid] == -1)
        rows, cols = np.nonzero(valid)
        pick = rng.choice(rows.size, 300, replace=False)
        rows, cols = rows[pick], cols[pick]
        z = f.depth_m[rows, cols].astype(np.float64)
        opt = np.stack([(cols - 319.5) / 525.0 * z, (rows - 239.5) / 525.0 * z, z], 1)
        pts = opt @ f.rotation.T + f.translation
        for (px, py, pz), sem, inst in zip(pts, f.semantic[rows, cols], f.instance[rows, cols]):
            if sem == 0:
                assert abs(pz) < 1e-3
                continue
            gaps = np.array([_surface_gap(q, px, py, pz) for q in prims])
            same_class = np.array([CLASS_IDS[q.cls] == sem for q in prims])
            assert gaps[same_class].min() < 2e-3, (pose, px, py, pz, CLASS_NAMES[int(sem)])
            if inst >= 0:
                obj = world.objects[inst]
                assert obj.cls == CLASS_NAMES[int(sem)]
                mine = np.array([q.object == obj.name for q in prims])
                assert gaps[mine].min() < 2e-3
            else:
                assert sem == CLASS_IDS["wall"]


def test_camera_depth_noise_only_with_rng():
    cam = DepthCamera(_room(), dataclasses.replace(LEVEL, depth_noise_std_m=0.01))
    clean = cam.render((0.0, 0.0, 0.0)).depth_m
    noisy = cam.render((0.0, 0.0, 0.0), np.random.default_rng(0)).depth_m
    assert 0.005 < float(np.nanstd(noisy - clean)) < 0.02
    assert np.array_equal(np.isnan(noisy), np.isnan(clean))


def test_class_ids_are_invertible():
    assert CLASS_IDS["none"] == 0 and {"wall", "chair", "table", "desk"} <= set(CLASS_IDS)
    assert all(CLASS_NAMES[v] == k for k, v in CLASS_IDS.items())


@pytest.mark.parametrize("kwargs, match", [
    ({"width": 0}, "width"), ({"fx": -1.0}, "fx"), ({"range_max_m": 0.01}, "range_max_m"),
    ({"pitch_rad": 2.0}, "pitch_rad"), ({"depth_noise_std_m": -0.1}, "depth_noise_std_m"),
    ({"cx": float("nan")}, "cx"), ({"rate_hz": 0.0}, "rate_hz")])
def test_camera_params_validate(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CameraParams(**kwargs)
