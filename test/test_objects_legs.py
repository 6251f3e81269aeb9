"""Unclassified objects from laser legs and posts (explore_seg.core.objects.legs)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.objects import (UNKNOWN_CLASS, DepthFrame, Object3D, ObjectParams,
                                      group_legs, scan_legs, scan_posts, unknown_objects,
                                      wall_mask)
from objects_scene import K, PRIORS, box_parts, camera_pose, leg_scan, render_depth, table_parts


def test_scan_legs_finds_legs_and_ignores_walls():
    params = ObjectParams()
    legs = [(2.0, 0.0), (2.0, 1.0), (3.0, 0.0)]
    wall = np.stack([np.full(200, 4.0), np.linspace(-2, 2, 200)], axis=1)
    got = scan_legs(np.vstack([leg_scan(legs), wall]), params, robot_xy=(0.0, 0.0))
    assert len(got) == 3
    np.testing.assert_allclose(sorted(map(tuple, got.round(1))), sorted(legs), atol=0.05)
    assert len(group_legs(got, 1.6, 2)) == 1
    assert group_legs(got, 0.5, 2) == []


def test_unknown_object_from_four_legs_and_a_table_top():
    pose = camera_pose()
    table = table_parts((2.5, 0.1), 1.2, 0.8, 0.75)
    frame = DepthFrame(render_depth(table, pose), K, pose)
    leg_xy = [p[0][:2] for p in table[1:]]
    objs = unknown_objects(frame, leg_scan(leg_xy), ObjectParams(), (), PRIORS[UNKNOWN_CLASS])
    assert len(objs) == 1
    obj = objs[0]
    assert obj.cls == UNKNOWN_CLASS
    np.testing.assert_allclose(obj.center_xyz[:2], (2.5, 0.1), atol=0.06)
    np.testing.assert_allclose(sorted(obj.size_xyz[:2]), [0.8, 1.2], atol=0.08)
    assert obj.size_xyz[2] == pytest.approx(0.75, abs=0.05)


def test_unknown_objects_need_depth_above_the_legs_and_skip_known_objects():
    pose = camera_pose()
    table = table_parts((2.5, 0.1), 1.2, 0.8, 0.75)
    legs_only = DepthFrame(render_depth(table[1:], pose), K, pose)
    scan = leg_scan([p[0][:2] for p in table[1:]])
    # legs alone (no top): the depth points on the legs are no evidence of an object
    assert unknown_objects(legs_only, scan, ObjectParams()) == []
    full = DepthFrame(render_depth(table, pose), K, pose)
    known = [Object3D("dining table", 0.9, (2.5, 0.1, 0.375), (1.2, 0.8, 0.75), 0.0, 100)]
    assert unknown_objects(full, scan, ObjectParams(), known) == []


def face_scan(x_m, y0_m, y1_m, n=12):
    """Scan points on the near face (x = x_m) of a box, as a lidar at the origin sees it."""
    return np.stack([np.full(n, x_m), np.linspace(y0_m, y1_m, n)], axis=1)


def bin_parts(center_xy, body_m=0.4, rim_m=0.6, rim_z=(0.5, 0.74)):
    """A bin whose rim overhangs its body (the body is all a lidar at 0.17 m sees)."""
    return [box_parts(center_xy, (body_m, body_m, rim_z[0])),
            box_parts(center_xy, (rim_m, rim_m, rim_z[1] - rim_z[0]), z0=rim_z[0])]


POSTS_ON = ObjectParams(post_max_width_m=0.7)    # the default


def test_scan_posts_are_isolated_clusters_wider_than_a_leg():
    params = POSTS_ON
    post = face_scan(1.8, -0.2, 0.2)
    wall = np.stack([np.full(100, 3.5), np.linspace(-1, 1, 100)], axis=1)
    touching = face_scan(3.4, 0.5, 0.9)                 # 0.1 m from the wall: not isolated
    posts, others = scan_posts(np.vstack([post, wall, touching, leg_scan([(2.0, -1.0)])]),
                               params, robot_xy=(0.0, 0.0))
    assert len(posts) == 1
    np.testing.assert_allclose(posts[0], post)
    assert len(others) == len(wall) + len(touching) + 5
    assert scan_posts(post, replace(params, post_max_width_m=0.0))[0] == []
    assert scan_posts(post, replace(params, post_max_width_m=0.3))[0] == []   # too wide


def test_rim_overhanging_a_post_makes_an_unknown_object():
    """A bin: the lidar sees its 0.4 m body, the camera its 0.6 m rim: the box must
    cover the rim (the robot would hit it), and a post with nothing overhanging it (the
    lidar already sees all of it) or nothing above it gives no object."""
    pose = camera_pose()
    scan = face_scan(1.8, -0.2, 0.2)
    frame = DepthFrame(render_depth(bin_parts((2.0, 0.0)), pose), K, pose)
    off = replace(POSTS_ON, post_max_width_m=0.0)
    assert unknown_objects(frame, scan, off, (), PRIORS[UNKNOWN_CLASS]) == []
    objs = unknown_objects(frame, scan, POSTS_ON, (), PRIORS[UNKNOWN_CLASS])
    assert len(objs) == 1
    obj = objs[0]
    assert obj.cls == UNKNOWN_CLASS
    lo, hi = obj.footprint().min(axis=0), obj.footprint().max(axis=0)
    assert lo[0] == pytest.approx(1.7, abs=0.04)            # the rim's near edge
    assert lo[1] == pytest.approx(-0.3, abs=0.04) and hi[1] == pytest.approx(0.3, abs=0.04)
    assert hi[0] >= 2.0
    assert obj.size_xyz[2] == pytest.approx(0.74, abs=0.05)
    # a thin panel: the lidar sees all of it, nothing overhangs
    panel = DepthFrame(render_depth([box_parts((2.0, 0.0), (0.02, 0.4, 1.0))], pose), K, pose)
    assert unknown_objects(panel, face_scan(1.99, -0.2, 0.2), POSTS_ON) == []
    low = DepthFrame(render_depth([box_parts((2.0, 0.0), (0.4, 0.4, 0.15))], pose), K, pose)
    assert unknown_objects(low, scan, POSTS_ON) == []
    known = [Object3D("chair", 0.9, (2.0, 0.0, 0.37), (0.6, 0.6, 0.74), 0.0, 100)]
    assert unknown_objects(frame, scan, POSTS_ON, known) == []


def test_post_overhang_must_lie_over_free_map_cells():
    """With the 2D map, only depth points over cells the lidar saw through count as
    overhang: the bin's rim over free cells makes an object, the same points over cells
    the map does not know (unknown) do not."""
    pose = camera_pose()
    scan = face_scan(1.8, -0.2, 0.2)
    frame = DepthFrame(render_depth(bin_parts((2.0, 0.0)), pose), K, pose)
    data = np.zeros((40, 60), dtype=np.int8)            # 3 x 2 m from (0, -1), all free
    grid = GridMap(data, 0.05, (0.0, -1.0))
    body = grid.world_to_cells(np.array([1.8, 2.2]), np.array([-0.2, 0.2]))
    data[body[0][0]:body[0][1], body[1][0]:body[1][1]] = 100
    params = POSTS_ON
    free_around = wall_mask(grid.with_data(data), params)
    objs = unknown_objects(frame, scan, params, (), PRIORS[UNKNOWN_CLASS], free_around)
    assert len(objs) == 1
    assert objs[0].footprint()[:, 1].max() == pytest.approx(0.3, abs=0.04)
    unknown_around = data.copy()
    unknown_around[:, body[1][0] - 3:] = np.where(unknown_around[:, body[1][0] - 3:] == 100,
                                                  100, -1)
    assert unknown_objects(frame, scan, params, (), PRIORS[UNKNOWN_CLASS],
                           wall_mask(grid.with_data(unknown_around), params)) == []


def test_post_overhang_must_be_at_one_height_and_attached_to_the_post():
    """A pillar's side faces that the scan missed spread over all heights: no overhang
    (with a camera looking down steeply, pitch 0.5 rad, they do not spread enough and the
    pillar gets a box of its own, on the pillar). A table top 0.25 m beside a bin is not
    the bin's rim: the bin's box stays on the bin."""
    pose = camera_pose(y=1.0, pitch=0.2)
    pillar = [box_parts((2.0, 0.0), (0.4, 0.4, 2.5))]
    frame = DepthFrame(render_depth(pillar, pose), K, pose)
    front = face_scan(1.8, -0.2, 0.2)
    assert unknown_objects(frame, front, POSTS_ON, (), PRIORS[UNKNOWN_CLASS]) == []
    assert len(unknown_objects(frame, front, replace(POSTS_ON, unknown_top_fraction=0.0), (),
                               PRIORS[UNKNOWN_CLASS])) == 1
    pose = camera_pose()
    table = [box_parts((2.0, 0.77), (0.8, 0.6, 0.04), z0=0.66)]   # top 0.17 m beside the rim
    frame = DepthFrame(render_depth(bin_parts((2.0, 0.0)) + table, pose), K, pose)
    objs = unknown_objects(frame, face_scan(1.8, -0.2, 0.2), POSTS_ON, (),
                           PRIORS[UNKNOWN_CLASS])
    assert len(objs) == 1
    assert objs[0].footprint()[:, 1].max() == pytest.approx(0.3, abs=0.04)
    linked = unknown_objects(frame, face_scan(1.8, -0.2, 0.2),
                             replace(POSTS_ON, post_link_m=1.0), (), PRIORS[UNKNOWN_CLASS])
    assert linked[0].footprint()[:, 1].max() > 0.45        # the table's edge taken in


def _scan_legs_by_cluster(scan_xy, params, robot_xy):
    """The rule of scan_legs, one cluster at a time (the reference of its vectorised form)."""
    from scipy.spatial import cKDTree

    from explore_seg.core.objects.legs import _scan_clusters

    pts, labels, counts, widths = _scan_clusters(scan_xy, params, robot_xy)
    out = []
    for lab in np.flatnonzero((counts >= params.leg_min_points)
                              & (widths >= params.leg_min_width_m)
                              & (widths <= params.leg_max_width_m)):
        sel = pts[labels == lab]
        centre = sel.mean(axis=0)
        radius = params.leg_isolation_m + 0.5 * float(widths[lab])
        if len(cKDTree(pts).query_ball_point(centre, radius)) <= len(sel):
            out.append(centre)
    return np.array(out, dtype=np.float64).reshape(-1, 2)


@pytest.mark.parametrize("seed", range(3))
def test_scan_legs_equals_the_per_cluster_rule_on_random_scans(seed):
    rng = np.random.default_rng(seed)
    p = ObjectParams()
    # Legs (tight blobs), wall lines and scattered points around a robot at the origin.
    parts = [c + rng.normal(0.0, 0.01, (int(rng.integers(3, 8)), 2))
             for c in rng.uniform(-3.0, 3.0, (12, 2))]
    parts += [np.column_stack([np.linspace(-3, 3, 150), np.full(150, y)]) for y in (-3.5, 3.2)]
    parts.append(rng.uniform(-4.0, 4.0, (40, 2)))
    scan = np.vstack(parts)
    got = scan_legs(scan, p, (0.0, 0.0))
    ref = _scan_legs_by_cluster(scan, p, (0.0, 0.0))
    assert len(ref) > 0
    assert got.shape == ref.shape and np.array_equal(got, ref)


def test_segment_means_equal_numpy_mean_bit_for_bit():
    """scan_legs' cluster centres (all clusters at once) equal ``.mean(axis=0)`` of each
    cluster's points, to the bit, on random clusters of random sizes and scales."""
    from explore_seg.core.objects.legs import _segment_means
    rng = np.random.default_rng(49)
    for _ in range(300):
        n = int(rng.integers(1, 300))
        pts = rng.normal(0.0, 5.0, (n, 2)) * 10.0 ** rng.uniform(-2, 2)
        labels = rng.integers(0, max(1, n // int(rng.integers(1, 30))), n)
        counts = np.bincount(labels)
        order = np.argsort(labels, kind="stable")
        first = np.cumsum(counts) - counts
        cand = np.flatnonzero(counts >= 1)
        cand = cand[rng.random(cand.size) < 0.7]
        want = np.array([pts[order[first[k]:first[k] + counts[k]]].mean(axis=0)
                         for k in cand], dtype=np.float64).reshape(-1, 2)
        got = _segment_means(pts[order], first[cand], counts[cand])
        assert got.shape == want.shape
        assert np.array_equal(got.view(np.uint64), want.view(np.uint64))
