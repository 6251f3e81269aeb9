"""Footprint geometry of the object pipeline (explore_seg.core.objects.geometry)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.objects import footprint_orientation


@pytest.mark.parametrize("method", ["pca", "min_area_rect"])
@pytest.mark.parametrize("yaw_deg", [0.0, 20.0, 45.0, -35.0, 80.0])
def test_footprint_orientation_of_rotated_rectangle(method, yaw_deg):
    rng = np.random.default_rng(int(yaw_deg) + 100)
    yaw = math.radians(yaw_deg)
    local = rng.uniform([-1.0, -0.3], [1.0, 0.3], (2000, 2))
    c, s = math.cos(yaw), math.sin(yaw)
    pts = local @ np.array([[c, -s], [s, c]]).T + [3.0, -1.0]
    center, size, got = footprint_orientation(pts, method)
    err = (got - yaw + math.pi / 2) % math.pi - math.pi / 2      # x along the long side
    assert abs(err) < math.radians(3)
    assert -math.pi / 2 <= got < math.pi / 2
    np.testing.assert_allclose(size, [2.0, 0.6], atol=0.05)
    np.testing.assert_allclose(center, [3.0, -1.0], atol=0.05)


def test_footprint_orientation_rejects_empty():
    with pytest.raises(ValueError, match="shape"):
        footprint_orientation(np.zeros((0, 2)))
    with pytest.raises(ValueError, match="method"):
        footprint_orientation(np.zeros((3, 2)), "hough")


def test_orientation_ignores_the_outline_cut_by_the_view():
    """A desk top whose visible part is cut by a ray (the image's side, an occluder): the
    minimum-area rectangle follows the cut; without the cut's hull edges the desk's own
    sides give the orientation."""
    rng = np.random.default_rng(2)
    local = rng.uniform([-0.7, -0.3], [0.7, 0.3], (4000, 2))
    ray = np.array([math.cos(0.6), math.sin(0.6)])           # the cut: a line at 34 deg
    keep = local @ np.array([-ray[1], ray[0]]) > -0.1
    pts = local[keep]
    cut = np.abs(pts @ np.array([-ray[1], ray[0]]) + 0.1) < 0.02
    _, _, yaw_plain = footprint_orientation(pts, "min_area_rect")
    _, _, yaw_cut = footprint_orientation(pts, "min_area_rect", cut)
    err = lambda y: abs((y + math.pi / 4) % (math.pi / 2) - math.pi / 4)  # noqa: E731
    assert err(yaw_cut) < math.radians(2.0)
    assert err(yaw_plain) > err(yaw_cut)
