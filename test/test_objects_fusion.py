"""Fusion of re-detections into tracked boxes (explore_seg.core.objects.fusion)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from explore_seg.core.objects import (MAX_SURFACE_POINTS, Object3D, ObjectMap, ObjectParams,
                                      footprint_iou, fuse_boxes)
from objects_scene import PRIORS, make_obj, measured_table


def test_redetections_merge_and_keep_the_larger_size():
    """Noise (whole boxes shifted by 5 cm) does not inflate a fused box; a larger
    measurement of the same object (turned by 90 deg: the same box) extends it at once,
    and more of it changes nothing."""
    omap = ObjectMap(ObjectParams(), PRIORS)
    rng = np.random.default_rng(5)
    for _ in range(10):
        jitter = rng.normal(0, 0.05, 2)
        omap.update([make_obj(2.0 + jitter[0], 1.0 + jitter[1]), make_obj(5.0, 1.0, "dining table",
                                                                  (1.5, 0.9, 0.75))])
    chair = next(o for o in omap.objects() if o.cls == "chair")
    assert chair.size_xyz[:2] == pytest.approx((0.6, 0.6), abs=1e-9)
    np.testing.assert_allclose(chair.center_xyz[:2], (2.0, 1.0), atol=0.05)
    bigger = make_obj(2.0, 1.0, size=(0.8, 0.6, 0.9), yaw=math.pi / 2)
    for _ in range(4):
        omap.update([bigger])
        assert len(omap) == 2
        chair = next(o for o in omap.objects() if o.cls == "chair")
        np.testing.assert_allclose(chair.center_xyz[:2], (2.0, 1.0), atol=0.05)
        assert sorted(chair.size_xyz[:2]) == pytest.approx([0.6, 0.8], abs=1e-9)


def test_partial_views_of_a_desk_add_up_but_hidden_sides_do_not():
    """Two views of a 1.4 x 0.6 m desk, each seeing one end (the other end cut by an
    occluder or the image border: an open side) and its depth grown to the 0.75 m prior
    away from the camera (on opposite sides): the fused box spans the whole desk, and
    its depth is the prior's, around the measured part, not the union of the grown sides."""
    prior = PRIORS["dining table"]
    p = ObjectParams()
    omap = ObjectMap(p, PRIORS)
    # Measured: x in [-0.7, 0.2] (view 1, open at +x) and [-0.2, 0.7] (view 2, open at -x);
    # y in [-0.3, 0.3] both; grown to 0.75 towards -y (view 1) and +y (view 2).
    v1 = Object3D("dining table", 0.9, (-0.25, -0.075, 0.37), (0.9, 0.75, 0.74), 0.0, 500,
                  (-0.25, 0.0, 0.9, 0.6), (False, True, False, False))
    v2 = Object3D("dining table", 0.9, (0.25, 0.075, 0.37), (0.9, 0.75, 0.74), 0.0, 500,
                  (0.25, 0.0, 0.9, 0.6), (True, False, False, False))
    omap.update([v1])
    omap.update([v2])
    assert len(omap) == 1
    desk = omap.objects()[0]
    corners = desk.footprint()
    assert corners[:, 0].min() == pytest.approx(-0.7, abs=1e-6)
    assert corners[:, 0].max() == pytest.approx(0.7, abs=1e-6)
    assert desk.size_xyz[1] == pytest.approx(prior.min_xy_m, abs=1e-6)
    assert abs(desk.center_xyz[1]) < 0.1
    # Growth per observation stays bounded: a view of a far larger extent (a cluster that
    # took in a neighbour) extends the box to at most merge_growth_max times it.
    far = Object3D("dining table", 0.9, (1.2, 0.0, 0.37), (1.6, 0.6, 0.74), 0.0, 500,
                   (1.2, 0.0, 1.6, 0.6), (False, False, False, False))
    omap.update([far])
    assert omap.objects()[0].size_xyz[0] <= p.merge_growth_max * 1.6 + 1e-6


def test_fused_surface_is_the_union_thinned_to_the_cap():
    params = ObjectParams()
    _, obj = measured_table(0.75, params)
    moved = replace(obj, surface=obj.surface + np.float32([0.05, 0.0, 0.0]))
    fused = fuse_boxes(obj, moved, params, PRIORS["dining table"])
    keys = {tuple(k) for k in np.floor(fused.surface.astype(np.float64) / 0.1).astype(int)}
    assert len(keys) == len(fused.surface)                   # one point per voxel
    assert len(fused.surface) >= len(obj.surface)
    many = replace(obj, surface=np.random.default_rng(0).uniform(
        0, 5, (3 * MAX_SURFACE_POINTS, 3)).astype(np.float32))
    assert len(fuse_boxes(obj, many, params).surface) == MAX_SURFACE_POINTS
    assert fuse_boxes(replace(obj, surface=None), replace(obj, surface=None),
                      params).surface is None


def test_footprint_iou():
    a = make_obj(0.0, 0.0, size=(1.0, 1.0, 1.0))
    assert footprint_iou(a, a) == pytest.approx(1.0)
    assert footprint_iou(a, make_obj(0.5, 0.0, size=(1.0, 1.0, 1.0))) == pytest.approx(1 / 3, abs=1e-3)
    assert footprint_iou(a, make_obj(5.0, 0.0)) == 0.0
