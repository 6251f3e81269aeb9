"""3D boxes: the prior's clamp and plausibility (explore_seg.core.objects.boxes)."""

from __future__ import annotations

import numpy as np

from explore_seg.core.objects import (DepthFrame, ObjectParams, SizePrior, clamp_to_prior,
                                      object_from_detection, plausible_extent)
from objects_scene import (K, PRIORS, box_parts, camera_pose, project_box, render_depth,
                           table_parts)


def test_clamp_grows_away_from_camera_and_shrinks_around_centre():
    prior = SizePrior(0.5, 1.5, 0.5, 2.0)
    # a 0.2 m deep chair front seen from the camera at the origin: grows to +x
    c, s = clamp_to_prior((2.0, 0.0, 0.2), (0.2, 2.0, 0.4), 0.0, prior, camera_xy=(0.0, 0.0))
    np.testing.assert_allclose(c, (2.15, 0.0, 0.25))
    np.testing.assert_allclose(s, (0.5, 1.5, 0.5))
    c, s = clamp_to_prior((2.0, 0.0, 1.5), (0.2, 1.0, 3.0), 0.0, prior, camera_xy=None,
                          floor_z_m=None)
    np.testing.assert_allclose(c, (2.0, 0.0, 1.5))
    np.testing.assert_allclose(s, (0.5, 1.0, 2.0))


def test_fragments_are_not_taken_for_the_object():
    """A table leg (5 cm) or a chair leg is a cluster of a table detection, but far below
    the class's size: it gives no orientation, and growing it to the prior places the box
    anywhere around the leg."""
    from explore_seg.core.objects import plausible_extent

    rng = np.random.default_rng(1)
    leg = np.column_stack([rng.uniform(0, 0.05, 100), rng.uniform(0, 0.05, 100),
                           rng.uniform(0.05, 0.7, 100)])
    p = ObjectParams()
    assert not plausible_extent(leg, PRIORS["dining table"], p)
    assert not plausible_extent(leg, PRIORS["chair"], p)
    assert plausible_extent(leg, PRIORS["chair"], ObjectParams(min_extent_fraction=0.0))
    seat = np.column_stack([rng.uniform(0, 0.3, 200), rng.uniform(0, 0.3, 200),
                            rng.uniform(0.4, 0.45, 200)])
    assert plausible_extent(seat, PRIORS["chair"], p)    # grows to the prior as before
    # A scene: the detection box holds a leg in front of a table top; the top is chosen.
    pose = camera_pose(z=1.3, pitch=0.6)
    table = table_parts((2.4, 0.2), 1.4, 0.9, 0.75, 0.0)
    front_leg = [box_parts((1.3, 0.2), (0.05, 0.05, 0.7))]
    frame = DepthFrame(render_depth(table + front_leg, pose), K, pose)
    obj = object_from_detection(frame, project_box(table + front_leg, pose), "dining table",
                                0.9, PRIORS["dining table"], p)
    assert obj is not None
    np.testing.assert_allclose(obj.center_xyz[:2], (2.4, 0.2), atol=0.05)


def test_cluster_far_beyond_the_prior_is_dropped_not_clamped():
    from explore_seg.core.objects import plausible_extent

    prior = PRIORS["chair"]
    p = ObjectParams()
    rng = np.random.default_rng(0)
    chair_pts = np.column_stack([rng.uniform(0, 0.5, 200), rng.uniform(0, 0.5, 200),
                                 rng.uniform(0.05, 0.9, 200)])
    wall_pts = np.column_stack([rng.uniform(0, 3.0, 300), np.full(300, 0.6),
                                rng.uniform(0.05, 0.9, 300)])
    assert plausible_extent(chair_pts, prior, p)
    assert not plausible_extent(np.vstack([chair_pts, wall_pts]), prior, p)
    assert plausible_extent(np.vstack([chair_pts, wall_pts]), prior,
                            ObjectParams(prior_reject_factor=0.0))


def test_a_moved_box_keeps_its_shape_and_turns_its_sides_with_its_axes():
    """Object3D.moved: the footprint's corners go where the transform takes them (sizes
    and heights kept); when the heading wraps by pi the open sides swap with the axes;
    the measured footprint and surface move too."""
    from explore_seg.core.objects import Object3D
    surface = np.array([[1.2, 0.1, 0.7], [0.8, -0.1, 0.7]], np.float32)
    b = Object3D("dining table", 0.9, (1.0, 0.0, 0.37), (0.9, 0.6, 0.74), 0.2, 50,
                 (1.0, 0.0, 0.8, 0.5), (True, False, False, True), surface)
    for jump in [(0.3, -0.2, 0.1), (0.0, 0.0, 1.5), (-1.0, 2.0, -2.9)]:
        m = b.moved(jump)
        c, s = np.cos(jump[2]), np.sin(jump[2])
        rot = np.array([[c, -s], [s, c]])
        want = b.footprint() @ rot.T + np.array(jump[:2])
        got = m.footprint()
        # the same four corners (their order may start elsewhere)
        assert all(np.min(np.hypot(*(got - w).T)) < 1e-9 for w in want)
        assert m.size_xyz == b.size_xyz and m.center_xyz[2] == b.center_xyz[2]
        assert -np.pi / 2 <= m.yaw < np.pi / 2
        flipped = abs(np.cos(m.yaw - (b.yaw + jump[2])) + 1.0) < 1e-9
        assert m.open_sides == ((False, True, True, False) if flipped
                                else (True, False, False, True))
        np.testing.assert_allclose(m.measured_xy[:2], rot @ [1.0, 0.0] + jump[:2])
        np.testing.assert_allclose(m.surface[:, :2], surface[:, :2] @ rot.T + jump[:2],
                                   atol=1e-6)
    assert b.moved((0.0, 0.0, 1.5)).open_sides == (False, True, True, False)   # 1.7 wraps
