"""Camera geometry (explore_seg.core.camera): back-projection, intrinsics, extrinsics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.camera import (CameraIntrinsics, apply_transform, base_from_optical,
                                     depth_to_points, invert_transform, map_from_base)

K = CameraIntrinsics(fx=525.0, fy=525.0, cx=319.5, cy=239.5, width=640, height=480)


def test_depth_to_points_back_projects_known_pixels():
    k = CameraIntrinsics(fx=320.0, fy=320.0, cx=319.5, cy=239.5, width=640, height=480)
    depth = np.full((480, 640), 2.0, np.float32)
    depth[0, 0] = np.nan
    depth[1, 0] = -1.0
    pts = depth_to_points(depth, k)
    assert pts.shape == (480 * 640 - 2, 3)
    # pixel (row 239, col 319) is 0.5 px from the principal point
    one = depth_to_points(depth, k, mask=np.pad(np.ones((1, 1), bool), ((239, 240), (319, 320))))
    np.testing.assert_allclose(one, [[-0.5 * 2.0 / 320.0, -0.5 * 2.0 / 320.0, 2.0]], atol=1e-6)
    corner = depth_to_points(depth, k, mask=np.pad(np.ones((1, 1), bool), ((479, 0), (639, 0))))
    np.testing.assert_allclose(corner, [[319.5 * 2 / 320, 239.5 * 2 / 320, 2.0]], atol=1e-5)


def test_depth_to_points_drops_far_pixels():
    depth = np.full((480, 640), 5.0, np.float32)
    depth[:, :10] = 1.0
    assert len(depth_to_points(depth, K, max_depth_m=4.0)) == 480 * 10


@pytest.mark.parametrize("depth, mask, match", [
    (np.zeros((480,), np.float32), None, "2D"),
    (np.zeros((240, 320), np.float32), None, "does not match intrinsics"),
    (np.zeros((480, 640), np.float32), np.zeros((2, 2), bool), "mask shape"),
])
def test_depth_to_points_rejects_bad_shapes(depth, mask, match):
    with pytest.raises(ValueError, match=match):
        depth_to_points(depth, K, mask)


@pytest.mark.parametrize("kwargs, match", [
    (dict(fx=0.0), "focal lengths"),
    (dict(fy=-1.0), "focal lengths"),
    (dict(cx=float("nan")), "cx must be finite"),
    (dict(width=0), "image size"),
    (dict(height=2.5), "integers"),
])
def test_intrinsics_validation(kwargs, match):
    base = dict(fx=500.0, fy=500.0, cx=320.0, cy=240.0, width=640, height=480)
    with pytest.raises(ValueError, match=match):
        CameraIntrinsics(**{**base, **kwargs})


def test_extrinsics_optical_axis_and_pitch():
    level = base_from_optical(0.1, 0.0, 0.5, 0.0, 0.0, 0.0)
    np.testing.assert_allclose(apply_transform(level, np.array([[0.0, 0.0, 2.0]])),
                               [[2.1, 0.0, 0.5]], atol=1e-12)
    # image right (+x optical) is the robot's right (-y); image down is -z
    np.testing.assert_allclose(apply_transform(level, np.array([[1.0, 1.0, 0.0]])),
                               [[0.1, -1.0, -0.5]], atol=1e-12)
    down = base_from_optical(0.0, 0.0, 1.0, 0.0, math.pi / 4, 0.0)   # positive pitch looks down
    p = apply_transform(down, np.array([[0.0, 0.0, math.sqrt(2.0)]]))
    np.testing.assert_allclose(p, [[1.0, 0.0, 0.0]], atol=1e-12)


def test_transform_round_trip_on_random_points():
    rng = np.random.default_rng(3)
    t = map_from_base(1.0, -2.0, 0.7) @ base_from_optical(0.2, 0.1, 0.4, 0.1, 0.3, -0.2)
    pts = rng.uniform(-5, 5, (50, 3))
    back = apply_transform(invert_transform(t), apply_transform(t, pts))
    np.testing.assert_allclose(back, pts, atol=1e-9)
