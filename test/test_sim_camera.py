"""Simulated RGB-D camera: pose, intrinsics, depth, semantics and brute-force agreement."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sensor_scenes import random_free_poses, room_4x4, table_with_legs, wall_box
from sim_bridge.sensors import (CLASS_IDS, CLASS_NAMES, CameraParams, DepthCamera,
                                camera_pose_in_world)
from sim_bridge.world import World
from sim_bridge.worlds import default_world


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
    cam = DepthCamera(room_4x4(), LEVEL)
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
    cam = DepthCamera(room_4x4(), dataclasses.replace(LEVEL, range_max_m=1.5))
    f = cam.render((0.0, 0.0, 0.0))
    c = int(LEVEL.cx + 0.5)
    assert np.isnan(f.depth_m[_row_of_height(1.0, 2.0), c])
    assert f.semantic[_row_of_height(1.0, 2.0), c] == 0
    low = World("low", (-2.5, -2.5, 2.5, 2.5), (0.0, 0.0, 0.0), [wall_box(2.075, 0.0, 0.15, 4.3,
                                                                       z=(0.0, 0.5))])
    f = DepthCamera(low, LEVEL).render((0.0, 0.0, 0.0))
    assert np.isnan(f.depth_m[_row_of_height(1.0, 2.0), c])     # over the wall: sky
    assert f.depth_m[_row_of_height(0.3, 2.0), c] == pytest.approx(2.0, abs=1e-5)


def test_camera_sees_table_top_and_legs():
    parts, obj = table_with_legs(2.0, 0.0, length=0.8, depth=1.2)
    world = room_4x4(parts, [obj])
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
    for pose in random_free_poses(world, 6, seed=11):
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
    for pose in random_free_poses(world, 3, seed=2):
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
    cam = DepthCamera(room_4x4(), dataclasses.replace(LEVEL, depth_noise_std_m=0.01))
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


def test_colour_image_is_shaded_on_first_access_only(monkeypatch):
    """The oracle detector reads no colours: a frame whose rgb is never read costs no
    shading; once read, it is kept, and it does not change when a consumer edits the
    frame's semantic image."""
    parts, obj = table_with_legs(1.5, 0.0)
    cam = DepthCamera(room_4x4(parts, [obj]),
                      CameraParams(width=64, height=48, fx=52.5, fy=52.5, cx=31.5, cy=23.5))
    calls = []
    colour = cam._colour
    monkeypatch.setattr(cam, "_colour", lambda *a: calls.append(1) or colour(*a))
    f = cam.render((0.0, 0.0, 0.0))
    assert calls == [] and f.semantic.any()
    rgb = f.rgb
    assert calls == [1] and f.rgb is rgb and rgb.shape == (48, 64, 3)
    g = cam.render((0.0, 0.0, 0.0))
    g.semantic[:] = 0
    assert np.array_equal(g.rgb, rgb)
