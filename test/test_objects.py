"""Object costmap core: camera geometry, detection -> 3D box, unclassified objects, fusion.

Depth images are rendered here by ray casting boxes and the floor (``render_depth``), so
every expected size and position is known exactly.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from explore_seg.core.camera import (CameraIntrinsics, apply_transform, base_from_optical,
                                     depth_to_points, invert_transform, map_from_base,
                                     project_points)
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.objects import (MAX_SURFACE_POINTS, UNKNOWN_CLASS, DepthFrame, Object3D,
                                      ObjectMap, ObjectParams, SizePrior, box_mask,
                                      clamp_to_prior, euclidean_clusters, fit_box,
                                      footprint_iou, fuse_boxes,
                                      footprint_orientation, group_legs, load_priors,
                                      object_from_detection, points_in_rect, process_frame,
                                      scan_legs, scan_posts,
                                      segment_detection, statistical_outlier_mask,
                                      unknown_objects, voxel_downsample, wall_mask)

K = CameraIntrinsics(fx=525.0, fy=525.0, cx=319.5, cy=239.5, width=640, height=480)
PRIORS = load_priors()
CAM_Z_M = 1.0
CAM_PITCH_RAD = 0.5


# ------------------------------------------------------------------ test scene helpers


def box_parts(center_xy, size_xyz, yaw=0.0, z0=0.0):
    """(center_xyz, size_xyz, yaw) of one solid box standing at height z0."""
    return ((center_xy[0], center_xy[1], z0 + 0.5 * size_xyz[2]), tuple(size_xyz), yaw)


def table_parts(center_xy, length_m, width_m, height_m=0.75, yaw=0.0, top_m=0.04,
                leg_m=0.05):
    """A table: top slab + 4 legs at the corners (list of box_parts)."""
    parts = [box_parts(center_xy, (length_m, width_m, top_m), yaw, height_m - top_m)]
    c, s = math.cos(yaw), math.sin(yaw)
    for sx in (-1, 1):
        for sy in (-1, 1):
            lx, ly = sx * (0.5 * length_m - leg_m), sy * (0.5 * width_m - leg_m)
            xy = (center_xy[0] + c * lx - s * ly, center_xy[1] + s * lx + c * ly)
            parts.append(box_parts(xy, (leg_m, leg_m, height_m - top_m), yaw))
    return parts


def camera_pose(x=0.0, y=0.0, yaw=0.0, z=CAM_Z_M, pitch=CAM_PITCH_RAD):
    """map <- optical transform of a camera on a robot at (x, y, yaw)."""
    return map_from_base(x, y, yaw) @ base_from_optical(0.0, 0.0, z, 0.0, pitch, 0.0)


def render_depth(parts, map_from_optical, intr=K, floor=True, max_range_m=20.0):
    """Depth image (optical z, NaN for no hit) of boxes + the floor plane z = 0."""
    v, u = np.mgrid[0:intr.height, 0:intr.width]
    d_opt = np.stack([(u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy,
                      np.ones(u.shape)], axis=-1).reshape(-1, 3)
    rot, org = map_from_optical[:3, :3], map_from_optical[:3, 3]
    d = d_opt @ rot.T          # ray direction in map; ray parameter t == optical z
    best = np.full(len(d), np.inf)
    if floor:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -org[2] / d[:, 2]
        best = np.where((t > 0) & np.isfinite(t), t, best)
    for center, size, yaw in parts:
        c, s = math.cos(yaw), math.sin(yaw)
        r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])   # map -> box
        o = r @ (org - np.asarray(center))
        dl = d @ r.T
        half = 0.5 * np.asarray(size)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (-half - o) / dl, (half - o) / dl
        tmin = np.nanmax(np.minimum(t1, t2), axis=1)
        tmax = np.nanmin(np.maximum(t1, t2), axis=1)
        hit = (tmax >= np.maximum(tmin, 0.0)) & (tmin > 0)
        best = np.where(hit & (tmin < best), tmin, best)
    best[best > max_range_m] = np.inf
    out = best.reshape(intr.height, intr.width).astype(np.float32)
    out[~np.isfinite(out)] = np.nan
    return out


def project_box(parts, map_from_optical, intr=K):
    """Tight 2D box (x0, y0, x1, y1) of the corners of the given parts."""
    pts = []
    for center, size, yaw in parts:
        obj = Object3D("x", 1.0, center, size, yaw, 0)
        for z in (center[2] - 0.5 * size[2], center[2] + 0.5 * size[2]):
            pts += [(x, y, z) for x, y in obj.footprint()]
    opt = apply_transform(invert_transform(map_from_optical), np.array(pts))
    u, v, _ = project_points(opt, intr)
    return (max(u.min(), 0), max(v.min(), 0), min(u.max(), intr.width - 1),
            min(v.max(), intr.height - 1))


class Det:
    """Minimal detection (duck-typed like core.detector.Detection)."""

    def __init__(self, cls_name, box_xyxy, score=0.9):
        self.cls_name, self.box_xyxy, self.score = cls_name, tuple(box_xyxy), score


def leg_scan(centres, radius_m=0.025, n=5):
    """Scan points on the near half-circle of round legs (map frame)."""
    out = []
    for cx, cy in centres:
        a = np.linspace(math.pi * 0.6, math.pi * 1.4, n)
        out.append(np.stack([cx + radius_m * np.cos(a), cy + radius_m * np.sin(a)], axis=1))
    return np.vstack(out)


# --------------------------------------------------------------------------- camera


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


# ----------------------------------------------------------------- geometry steps


def test_statistical_outlier_removal_drops_injected_outliers():
    rng = np.random.default_rng(0)
    cloud = rng.uniform(0, 0.5, (800, 3))
    outliers = rng.uniform(3, 4, (10, 3)) * rng.choice([-1, 1], (10, 3))
    keep = statistical_outlier_mask(np.vstack([cloud, outliers]), k=8, std_ratio=1.5)
    assert not keep[800:].any()
    assert keep[:800].mean() > 0.95


def test_euclidean_clusters_separates_two_objects():
    rng = np.random.default_rng(1)
    a = rng.uniform(0, 0.3, (300, 3))
    b = rng.uniform(0, 0.3, (200, 3)) + [0.6, 0, 0]
    lone = np.array([[5.0, 5.0, 5.0]])
    labels = euclidean_clusters(np.vstack([a, b, lone]), 0.08, 10)
    assert set(labels[:300]) == {0}
    assert set(labels[300:500]) == {1}
    assert labels[500] == -1


def test_voxel_downsample_keeps_one_point_per_voxel():
    pts = np.array([[0.01, 0.01, 0.01], [0.02, 0.02, 0.02], [0.5, 0.0, 0.0]])
    np.testing.assert_array_equal(voxel_downsample(pts, 0.1), [0, 2])
    np.testing.assert_array_equal(voxel_downsample(pts, 0.0), [0, 1, 2])


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


def test_default_priors_hold_the_paper_values():
    assert PRIORS["chair"] == SizePrior(0.5, 1.5, 0.5, 2.0)
    assert PRIORS["dining table"] == SizePrior(0.75, 5.0, 0.5, 4.5)
    assert UNKNOWN_CLASS in PRIORS


@pytest.mark.parametrize("text, match", [
    ("- 1\n- 2\n", "'priors' mapping"),
    ("priors: {}\n", "empty"),
    ("priors:\n  chair: {min_xy_m: 0.5}\n", "must have keys"),
    ("priors:\n  chair: {min_xy_m: 2, max_xy_m: 1, min_z_m: 0, max_z_m: 1}\n", "min <= max"),
])
def test_load_priors_rejects_bad_files(tmp_path, text, match):
    path = tmp_path / "p.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        load_priors(path)


@pytest.mark.parametrize("kwargs, match", [
    (dict(rate_hz=0.0), "rate_hz"),
    (dict(sor_k=0), "sor_k"),
    (dict(merge_iou=1.5), "merge_iou"),
    (dict(floor_height_m=3.0), "below ceiling_height_m"),
    (dict(unknown_min_height_m=2.0), "below unknown_max_height_m"),
    (dict(leg_min_width_m=0.5), "must not exceed leg_max_width_m"),
    (dict(orientation_method="ransac"), "orientation_method"),
    (dict(pose_topic_type="tf"), "pose_topic_type"),
    (dict(object_value=101), "object_value"),
    (dict(background_value=-2), "background_value"),
    (dict(camera_z_m=float("inf")), "camera_z_m"),
    (dict(map_frame=""), "map_frame"),
    (dict(wall_min_length_m=-0.1), "wall_min_length_m"),
])
def test_object_params_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ObjectParams(**kwargs)


@pytest.mark.parametrize("box, match", [
    ((700, 10, 800, 20), "outside"),
    ((10, 20, 5, 30), "x0 <= x1"),
    ((0, 0, float("nan"), 3), "finite"),
    ((0, 0, 3), "4 finite"),
])
def test_box_mask_rejects_bad_boxes(box, match):
    with pytest.raises(ValueError, match=match):
        box_mask(box, (480, 640))


def test_box_mask_clips_to_image():
    m = box_mask((-10, 470, 5, 900), (480, 640))
    assert m.sum() == 6 * 10 and m[479, 0] and m[470, 5]


# ---------------------------------------------------------- detection -> 3D box


@pytest.mark.parametrize("method", ["min_area_rect", "pca"])
@pytest.mark.parametrize("yaw", [0.0, 0.4, -0.3])
def test_table_box_from_synthetic_depth(yaw, method):
    pose = camera_pose(z=1.3, pitch=0.6)
    table = table_parts((2.4, 0.2), 1.4, 0.9, 0.75, yaw)
    frame = DepthFrame(render_depth(table, pose), K, pose)
    obj = object_from_detection(frame, project_box(table, pose), "dining table", 0.9,
                                PRIORS["dining table"], ObjectParams(orientation_method=method))
    assert obj is not None and obj.cls == "dining table"
    # PCA (the paper's choice) is biased by the uneven sampling of the top: looser bounds
    tol_m, tol_deg = (0.03, 1.0) if method == "min_area_rect" else (0.15, 10.0)
    np.testing.assert_allclose(obj.center_xyz, (2.4, 0.2, 0.375), atol=tol_m)
    err = ((obj.yaw - yaw) + math.pi / 4) % (math.pi / 2) - math.pi / 4
    assert abs(err) < math.radians(tol_deg)
    np.testing.assert_allclose(sorted(obj.size_xyz[:2]), [0.9, 1.4], atol=tol_m)
    assert obj.size_xyz[2] == pytest.approx(0.75, abs=0.01)


def test_table_top_at_a_grazing_angle_is_still_one_box():
    """Camera 0.25 m above the top: the top is sampled in strips 0.1-0.3 m apart; the
    neighbouring-pixel links keep it one cluster, only its far edge is not seen."""
    pose = camera_pose(z=1.0, pitch=0.5)
    table = table_parts((2.4, 0.2), 1.4, 0.9, 0.75, 0.0)
    frame = DepthFrame(render_depth(table, pose), K, pose)
    obj = object_from_detection(frame, project_box(table, pose), "dining table", 0.9,
                                PRIORS["dining table"], ObjectParams())
    near_x = obj.center_xyz[0] - 0.5 * obj.size_xyz[0]
    assert abs(obj.yaw) < math.radians(1.0)
    assert near_x == pytest.approx(1.7, abs=0.03)
    assert 1.2 <= obj.size_xyz[0] <= 1.43
    assert obj.size_xyz[1] == pytest.approx(0.9, abs=0.03)


def test_chair_box_is_grown_to_the_prior_away_from_the_camera():
    pose = camera_pose()
    seat = [box_parts((2.0, -0.5), (0.3, 0.3, 0.45))]   # smaller than the 0.5 m prior
    frame = DepthFrame(render_depth(seat, pose), K, pose)
    obj = object_from_detection(frame, project_box(seat, pose), "chair", 0.9,
                                PRIORS["chair"], ObjectParams())
    np.testing.assert_allclose(obj.size_xyz[:2], (0.5, 0.5), atol=1e-6)
    # the near face (x = 1.85) stays, the box grows to larger x
    near_x = obj.center_xyz[0] - 0.5 * obj.size_xyz[0]
    assert abs(near_x - 1.85) < 0.05
    assert obj.size_xyz[2] == pytest.approx(0.5, abs=1e-6)   # min_z grows from the floor


def test_cluster_choice_ignores_background_in_the_box():
    pose = camera_pose()
    chair = [box_parts((2.0, 0.0), (0.5, 0.5, 0.9))]
    wall = [box_parts((3.5, 0.0), (0.1, 4.0, 2.0))]
    frame = DepthFrame(render_depth(chair + wall, pose), K, pose)
    box = project_box(chair, pose)
    obj, pts, depth = segment_detection(frame, box, "chair", 0.9, PRIORS["chair"],
                                        ObjectParams())
    assert pts[:, 0].max() < 2.3          # no wall point
    np.testing.assert_allclose(obj.center_xyz[:2], (2.0, 0.0), atol=0.05)


def desk_at_wall_map(desk, wall_x_m, wall_half_m=0.05):
    """2D map (0.05 m cells, x 0..4, y -2..2) of a wall (|x - wall_x_m| <= wall_half_m)
    and the legs of ``desk`` (table_parts), as the lidar maps them."""
    grid = GridMap(np.zeros((80, 80), np.int8), 0.05, (0.0, -2.0))
    x, y = grid.cells_to_world(*np.indices(grid.shape))
    occ = np.abs(x - wall_x_m) <= wall_half_m
    for (cx, cy, _), _, _ in desk[1:]:
        occ |= (np.abs(x - cx) <= 0.03) & (np.abs(y - cy) <= 0.03)
    return grid.with_data(np.where(occ, 100, 0).astype(np.int8))


def test_wall_mask_holds_walls_grown_but_not_furniture_legs():
    desk = table_parts((2.3, 0.0), 1.2, 0.6, 0.75, yaw=math.pi / 2)
    grid = desk_at_wall_map(desk, 2.7)
    walls = wall_mask(grid, ObjectParams())
    legs = np.array([c[:2] for c, _, _ in desk[1:]])
    assert grid.data[grid.world_to_cells(legs[:, 0], legs[:, 1])].min() == 100
    assert not walls.on(legs).any()                    # legs are short: kept
    # the wall and one margin cell (0.05 m) on either side; beyond that free
    on = walls.on(np.array([[2.7, 0.0], [2.62, 1.5], [2.78, -1.5], [2.55, 0.0], [4.5, 0.0]]))
    assert on.tolist() == [True, True, True, False, False]
    every = wall_mask(grid, ObjectParams(wall_min_length_m=0.0, wall_margin_m=0.0))
    assert every.on(legs).all()
    assert every.mask.sum() == (grid.data == 100).sum()


def test_desk_against_a_wall_gets_its_own_box_with_the_map_walls():
    """The wall behind a desk shows between its legs and beside it: with the 2D map's
    walls its points are dropped before clustering, so the box is the desk's."""
    pose = camera_pose(y=0.3)
    desk = table_parts((2.3, 0.0), 1.2, 0.6, 0.75, yaw=math.pi / 2)   # x 2.0..2.6
    wall = [box_parts((2.7, 0.0), (0.1, 6.0, 2.0))]                    # face at x = 2.65
    frame = DepthFrame(render_depth(desk + wall, pose), K, pose)
    walls = wall_mask(desk_at_wall_map(desk, 2.7), ObjectParams())
    res = process_frame(frame, [Det("dining table", project_box(desk, pose))], PRIORS,
                        ObjectParams(), walls=walls)
    assert len(res.objects) == 1
    corners = res.objects[0].footprint()
    # the desk's front (x = 2.0) and ends (y = +-0.6) are kept; the 0.6 m depth grows to
    # the prior's 0.75 m away from the camera, i.e. into the wall
    np.testing.assert_allclose(corners.min(axis=0), (2.0, -0.6), atol=0.04)
    np.testing.assert_allclose(corners.max(axis=0), (2.75, 0.6), atol=0.04)
    # the scene does exercise the wall: without the drop the box is pushed off the front
    off = process_frame(frame, [Det("dining table", project_box(desk, pose))], PRIORS,
                        ObjectParams(drop_wall_points=False), walls=walls)
    assert not off.objects or off.objects[0].footprint()[:, 0].min() > 2.1


def test_process_frame_skips_unknown_classes_and_reports_bad_boxes():
    pose = camera_pose()
    table = table_parts((2.4, 0.0), 1.2, 0.8)
    frame = DepthFrame(render_depth(table, pose), K, pose)
    box = project_box(table, pose)
    dets = [Det("dining table", box), Det("person", box), Det("chair", box, score=0.1),
            Det("chair", (900, 0, 950, 40))]
    res = process_frame(frame, dets, PRIORS, ObjectParams())
    assert [o.cls for o in res.objects] == ["dining table"]
    assert len(res.dropped) == 1 and "outside" in res.dropped[0]


def test_depth_frame_rejects_mismatched_inputs():
    with pytest.raises(ValueError, match="does not match camera info"):
        DepthFrame(np.zeros((10, 10), np.float32), K, np.eye(4))
    with pytest.raises(ValueError, match="4x4"):
        DepthFrame(np.zeros((480, 640), np.float32), K, np.eye(3))


# ------------------------------------------------------------------- real frames

_CLASS = {"chair": "chair", "desk": "dining table", "table": "dining table", "sofa": "couch"}


def _floor_transform(depth_m, intr, rng):
    """map <- optical for a frame with unknown pose: the floor is the large plane with
    (almost) nothing below it; the camera sits at its height above it (test helper)."""
    mask = np.zeros(depth_m.shape, bool)
    mask[::4, ::4] = True
    pts = depth_to_points(depth_m, intr, mask).astype(np.float64)
    best = None
    for _ in range(600):
        s = pts[rng.choice(len(pts), 3, replace=False)]
        n = np.cross(s[1] - s[0], s[2] - s[0])
        if np.linalg.norm(n) < 1e-9:
            continue
        n /= np.linalg.norm(n)
        n = -n if n[1] > 0 else n          # up = -y in the optical frame
        if n[1] > -0.7:
            continue
        d = -n @ s[0]
        signed = pts @ n + d
        if np.mean(signed < -0.05) > 0.01:
            continue
        support = int(np.count_nonzero(np.abs(signed) < 0.03))
        if best is None or support > best[0]:
            best = (support, n, d)
    assert best is not None, "no floor plane found"
    _, z, d = best
    x = np.array([0.0, 0.0, 1.0]) - z * z[2]
    x /= np.linalg.norm(x)
    t = np.eye(4)
    t[:3, :3] = np.stack([x, np.cross(z, x), z])
    t[2, 3] = d
    return t


def _real_frames(shared: Path):
    import cv2
    import yaml

    root = shared / "data" / "rgbd"
    if not (root / "frames.yaml").is_file():
        pytest.skip("no RGB-D frames in ../shared/data/rgbd")
    rng = np.random.default_rng(0)
    for f in yaml.safe_load((root / "frames.yaml").read_text())["frames"]:
        intr = CameraIntrinsics(**{k: f["intrinsics"][k]
                                   for k in ("fx", "fy", "cx", "cy", "width", "height")})
        raw = cv2.imread(str(root / f["depth_file"]), cv2.IMREAD_UNCHANGED)
        depth = raw.astype(np.float32) / float(f["depth_units_per_m"])
        depth[raw == 0] = np.nan
        yield f, DepthFrame(depth, intr, _floor_transform(depth, intr, rng))


def test_real_frames_annotated_boxes_give_the_annotated_objects(shared):
    """Annotated 2D boxes (not the detector) -> clusters on the annotated objects.

    The labels are rough (README): we require the probe point (annotated pixel at
    ``distance_m``) inside the fitted footprint (+0.1 m) for >= 90 % of the objects in
    depth range, the chosen cluster's median depth within 0.3 m of ``distance_m`` for
    >= 80 % of the chairs (compact objects; a long table's median lies far behind its
    near corner), and raw (unclamped) sizes within the class priors for all.
    """
    params = ObjectParams()
    probe_ok, median_ok, report = [], [], []
    for f, frame in _real_frames(shared):
        for o in f["objects"]:
            if o.get("distance_m") is None or o["distance_m"] > params.max_depth_m - 0.3:
                continue
            cls = _CLASS[o["class"]]
            seg = segment_detection(frame, o["bbox_px"], cls, 1.0, PRIORS[cls], params)
            assert seg is not None, f"{f['name']} {o['class']}: no cluster"
            obj, pts, depth = seg
            u, v = o["probe_px"]
            z = o["distance_m"]
            k = frame.intrinsics
            probe = apply_transform(frame.map_from_optical,
                                    np.array([[(u - k.cx) * z / k.fx, (v - k.cy) * z / k.fy, z]]))
            inside = bool(points_in_rect(probe[:, :2], obj.center_xyz[:2], obj.size_xyz[:2],
                                         obj.yaw, 0.1)[0])
            probe_ok.append(inside)
            med = float(np.median(depth))
            if cls == "chair":
                median_ok.append(abs(med - z) <= 0.3)
            raw = fit_box(pts, cls, 1.0, None, params)
            prior = PRIORS[cls]
            assert max(raw.size_xyz[:2]) <= prior.max_xy_m, (f["name"], o, raw)
            assert prior.min_z_m <= raw.size_xyz[2] <= prior.max_z_m, (f["name"], o, raw)
            report.append((f["name"], o["class"], z, round(med, 2), inside))
    assert len(probe_ok) >= 10
    assert np.mean(probe_ok) >= 0.9, report
    assert np.mean(median_ok) >= 0.8, report


# ------------------------------------------------------------ unclassified objects


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


# ------------------------------------------------------------------------- fusion


def _obj(x, y, cls="chair", size=(0.6, 0.6, 0.9), yaw=0.0, n=100):
    return Object3D(cls, 0.9, (x, y, 0.5 * size[2]), size, yaw, n)


def test_redetections_merge_and_keep_the_larger_size():
    """Noise (whole boxes shifted by 5 cm) does not inflate a fused box; a larger
    measurement of the same object (turned by 90 deg: the same box) extends it at once,
    and more of it changes nothing."""
    omap = ObjectMap(ObjectParams(), PRIORS)
    rng = np.random.default_rng(5)
    for _ in range(10):
        jitter = rng.normal(0, 0.05, 2)
        omap.update([_obj(2.0 + jitter[0], 1.0 + jitter[1]), _obj(5.0, 1.0, "dining table",
                                                                  (1.5, 0.9, 0.75))])
    chair = next(o for o in omap.objects() if o.cls == "chair")
    assert chair.size_xyz[:2] == pytest.approx((0.6, 0.6), abs=1e-9)
    np.testing.assert_allclose(chair.center_xyz[:2], (2.0, 1.0), atol=0.05)
    bigger = _obj(2.0, 1.0, size=(0.8, 0.6, 0.9), yaw=math.pi / 2)
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


def test_view_cut_marks_the_image_border_and_occluded_points():
    from explore_seg.core.objects import view_cut

    depth = np.full((K.height, K.width), 3.0, dtype=np.float32)
    depth[:, 100:110] = 1.0                                   # an occluder in front
    frame = DepthFrame(depth, K, np.eye(4))
    uv = np.array([[1, 50], [112, 50], [200, 50], [200, K.height - 1], [94, 50]], float)
    got = view_cut(frame, uv, np.full(5, 3.0), 4, 0.08)
    np.testing.assert_array_equal(got, [True, True, False, True, False])


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


def test_classified_detection_replaces_unknown_object():
    omap = ObjectMap(ObjectParams(), PRIORS)
    omap.update([_obj(2.0, 0.0, UNKNOWN_CLASS, (1.0, 0.8, 0.75))])
    omap.update([_obj(2.1, 0.0, "dining table", (1.2, 0.8, 0.75))])
    assert [o.cls for o in omap.objects()] == ["dining table"]
    # different known classes never merge
    omap.update([_obj(2.1, 0.0, "chair")])
    assert sorted(o.cls for o in omap.objects()) == ["chair", "dining table"]


def test_object_removed_after_misses_when_the_camera_sees_through_it():
    params = ObjectParams(clear_after_misses=3)
    omap = ObjectMap(params, PRIORS)
    pose = camera_pose()
    chair = [box_parts((2.0, 0.0), (0.5, 0.5, 0.9))]
    present = DepthFrame(render_depth(chair, pose), K, pose)
    omap.update([_obj(2.0, 0.0, size=(0.5, 0.5, 0.9))], present)
    omap.update([], present)               # still there, just not detected: no miss
    assert omap.tracked[0].misses == 0
    gone = DepthFrame(render_depth([], pose), K, pose)
    for expected in (1, 2):
        omap.update([], gone)
        assert omap.tracked[0].misses == expected
    omap.update([], gone)
    assert len(omap) == 0


def _measured_table(height_m, params):
    """A 1.2 x 0.8 table at (2, 0) with its top at ``height_m``, fitted to points on its
    top face and legs (as a camera measures them)."""
    table = table_parts((2.0, 0.0), 1.2, 0.8, height_m=height_m)
    gx, gy = np.meshgrid(np.linspace(1.42, 2.58, 12), np.linspace(-0.38, 0.38, 8))
    top = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, height_m)])
    legs = np.array([(c[0], c[1], z) for c, _, _ in table[1:]
                     for z in np.linspace(0.05, height_m - 0.05, 6)])
    return table, fit_box(np.vstack([top, legs]), "dining table", 0.9,
                          PRIORS["dining table"], params)


@pytest.mark.parametrize("robot", [(0.3, 0.0, 0.0), (2.0, -1.8, 0.5 * math.pi)])
def test_table_seen_under_its_top_is_not_missed_but_a_removed_one_is(robot):
    """A top above the camera's view line: the camera sees under it, through most of the
    box. Misses are judged on the measured surface (top and legs), not the box faces
    (which would drop the table while it stands there, undetected)."""
    params = ObjectParams(clear_after_misses=2)
    table, obj = _measured_table(0.95, params)
    assert obj.surface is not None and 20 <= len(obj.surface) <= MAX_SURFACE_POINTS
    pose = camera_pose(*robot)
    present = DepthFrame(render_depth(table, pose), K, pose)
    omap = ObjectMap(params, PRIORS)
    assert omap._seen_through(replace(obj, surface=None), present)     # the box faces
    omap.update([obj], present)
    for _ in range(4):
        omap.update([], present)
    assert len(omap) == 1 and omap.tracked[0].misses == 0
    gone = DepthFrame(render_depth([], pose), K, pose)
    omap.update([], gone)
    assert omap.tracked[0].misses == 1
    omap.update([], gone)
    assert len(omap) == 0


def test_fused_surface_is_the_union_thinned_to_the_cap():
    params = ObjectParams()
    _, obj = _measured_table(0.75, params)
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


def test_object_not_missed_when_occluded_or_out_of_view():
    omap = ObjectMap(ObjectParams(clear_after_misses=1), PRIORS)
    pose = camera_pose()
    omap.update([_obj(3.0, 0.0, size=(0.5, 0.5, 0.9)), _obj(-3.0, 0.0, size=(0.5, 0.5, 0.9))])
    wall = [box_parts((1.5, 0.0), (0.1, 6.0, 3.0))]   # hides the chair in front
    omap.update([], DepthFrame(render_depth(wall, pose), K, pose))
    assert len(omap) == 2                  # occluded one and the one behind the camera stay


def test_object_map_is_bounded():
    omap = ObjectMap(ObjectParams(max_objects=5), PRIORS)
    for i in range(12):
        omap.update([_obj(2.0 * i, 0.0)])
    assert len(omap) == 5


@pytest.mark.parametrize("robot_xy, fraction, kept", [
    ((0.0, -0.52), 0.5, True),      # disk (R 0.22) touches the chair's side: kept
    ((0.456, -0.456), 0.5, True),   # touches a corner diagonally (0.22 away): kept
    ((0.385, -0.385), 0.5, True),   # 0.12 from the corner (0.10 in): kept, by distance
    ((0.0, -0.40), 0.5, False),     # 0.12 m into the disk (> 0.5 R): a wrong box
    ((0.0, -0.45), 0.5, True),      # 0.07 m into it: within the estimate's error
    ((0.0, -0.45), 1.0, True),      # 1 = only boxes over the robot's centre
    ((0.0, -0.25), 1.0, False),
    ((0.0, 0.0), 0.0, True),        # 0 = never
])
def test_boxes_on_the_robot_are_dropped_by_how_deep_they_reach(robot_xy, fraction, kept):
    """A box the robot merely touches (it bumped into the chair) must stay, else the
    planner drives into the seat again; one that reaches deep into the robot's body
    cannot be right (a chair of 0.6 m at the origin, robot radius 0.22 m)."""
    omap = ObjectMap(ObjectParams(robot_clear_fraction=fraction), PRIORS)
    omap.update([_obj(0.0, 0.0)])
    omap.update([], robot_xy=robot_xy)
    assert (len(omap) == 1) == kept
    fresh = ObjectMap(ObjectParams(robot_clear_fraction=fraction), PRIORS)
    fresh.update([_obj(0.0, 0.0)], robot_xy=robot_xy)     # observations alike
    assert (len(fresh) == 1) == kept


def test_footprint_iou():
    a = _obj(0.0, 0.0, size=(1.0, 1.0, 1.0))
    assert footprint_iou(a, a) == pytest.approx(1.0)
    assert footprint_iou(a, _obj(0.5, 0.0, size=(1.0, 1.0, 1.0))) == pytest.approx(1 / 3, abs=1e-3)
    assert footprint_iou(a, _obj(5.0, 0.0)) == 0.0


# ------------------------------------------------------------------------ outputs


def test_rasterize_fills_rotated_footprint_on_the_map_grid():
    grid, _ = grid_from_ascii("\n".join(["." * 40] * 30), resolution_m=0.1,
                              origin_xy_m=(-1.0, -1.0))
    omap = ObjectMap(ObjectParams(), PRIORS)
    omap.update([_obj(1.0, 0.5, "dining table", (1.0, 0.5, 0.75), yaw=math.pi / 4)])
    layer = omap.rasterize(grid)
    assert layer.same_geometry(grid)
    occ = layer.data == 100
    assert set(np.unique(layer.data)) == {0, 100}
    # the centre cell and cells along the long (45 deg) axis are inside, off-axis are not
    assert occ[grid.world_to_cell(1.0, 0.5)]
    assert occ[grid.world_to_cell(1.3, 0.8)] and not occ[grid.world_to_cell(1.3, 0.2)]
    # every cell whose centre is inside is set; set cells touch the rectangle
    x, y = grid.cells_to_world(*np.indices(grid.shape))
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)
    u, v = (x - 1.0) * c + (y - 0.5) * s, -(x - 1.0) * s + (y - 0.5) * c
    inside = (np.abs(u) <= 0.5) & (np.abs(v) <= 0.25)
    touching = (np.abs(u) <= 0.5 + 0.071) & (np.abs(v) <= 0.25 + 0.071)
    assert np.all(occ[inside]) and np.all(touching[occ])


def test_virtual_cloud_fills_boxes_and_is_bounded():
    omap = ObjectMap(ObjectParams(max_cloud_points=5000), PRIORS)
    omap.update([_obj(1.0, 0.0, size=(0.5, 0.5, 1.0)), _obj(4.0, 0.0, "dining table",
                                                           (2.0, 1.0, 0.75))])
    cloud = omap.virtual_cloud(0.05)
    assert 0 < len(cloud) <= 5000
    assert cloud[:, 2].min() >= 0.0 and cloud[:, 2].max() <= 1.0
    near = cloud[cloud[:, 0] < 2.5]
    assert np.abs(near[:, 0] - 1.0).max() <= 0.25 and np.abs(near[:, 1]).max() <= 0.25
    with pytest.raises(ValueError, match="spacing_m"):
        omap.virtual_cloud(0.0)


def test_layer_and_cloud_are_cleared_along_the_path_the_robot_drove():
    """A box grown over the robot's own path (the robot drove there, so nothing stands
    there) is cut out of the layer and the cloud along a robot-wide corridor; the rest of
    the box stays, and without the path (or with the radius 0) nothing is cleared."""
    grid, _ = grid_from_ascii("\n".join(["." * 60] * 30), resolution_m=0.05,
                              origin_xy_m=(0.0, 0.0))
    table = _obj(1.5, 0.75, "dining table", (1.6, 1.0, 0.75))   # x 0.7..2.3, y 0.25..1.25
    plain = ObjectMap(ObjectParams(), PRIORS)
    plain.update([table])
    omap = ObjectMap(ObjectParams(), PRIORS)
    omap.update([table])
    off = ObjectMap(ObjectParams(swept_clear_radius_m=0.0), PRIORS)
    off.update([table])
    for x in np.arange(0.2, 2.81, 0.02):            # drove along y = 0.4 through the box
        omap.note_robot_position(float(x), 0.4)
        off.note_robot_position(float(x), 0.4)
    full = plain.rasterize(grid).data == 100
    cut = omap.rasterize(grid).data == 100
    assert np.array_equal(off.rasterize(grid).data == 100, full)
    x, y = grid.cells_to_world(*np.indices(grid.shape))
    near = np.abs(y - 0.4) <= 0.22 - grid.resolution_m
    far = np.abs(y - 0.4) > 0.22 + grid.resolution_m
    assert full[near].any() and not cut[near].any()
    assert np.array_equal(cut[far], full[far]) and cut.any()
    cloud = omap.virtual_cloud(0.05)
    assert len(cloud) and np.abs(cloud[:, 1] - 0.4).min() > 0.22 - 0.05
    assert len(off.virtual_cloud(0.05)) == len(plain.virtual_cloud(0.05)) > len(cloud)
    with pytest.raises(ValueError, match="swept_clear_radius_m"):
        ObjectParams(swept_clear_radius_m=-0.1)


def test_fig13_frontier_under_desk_top_becomes_occupied():
    """Paper Fig. 13: the lidar sees only the desk's legs, so the free cells under the
    top border unknown space and look like a frontier; the object layer covers them."""
    # 0.1 m cells, origin (0, -1): desk 1.2 x 0.6 m centred at (1.75, 0.2) (x 1.15..2.35,
    # y -0.1..0.5), legs '#'; the '?' block (x 1.8..2.2) was hidden from the lidar.
    rows = [
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "..................????..................",
        "..................????..................",
        "...........#......????#.................",
        "..................????..................",
        "..................????..................",
        "..................????..................",
        "..................????..................",
        "...........#......????#.................",
        "..................????..................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
        "........................................",
    ]
    grid, _ = grid_from_ascii("\n".join(rows), resolution_m=0.1, origin_xy_m=(0.0, -1.0))
    pose = camera_pose()
    desk = table_parts((1.75, 0.2), 1.2, 0.6, 0.75)
    frame = DepthFrame(render_depth(desk, pose), K, pose)
    leg_xy = [p[0][:2] for p in desk[1:]]
    res = process_frame(frame, [], PRIORS, ObjectParams(), scan_xy_map=leg_scan(leg_xy))
    omap = ObjectMap(ObjectParams(), PRIORS)
    omap.update(res.objects + res.unknown, frame)
    layer = omap.rasterize(grid)
    # frontier cells under the top: free cells next to unknown, between the legs
    free, unknown = grid.free_mask(), grid.unknown_mask()
    padded = np.pad(unknown, 1)
    near_unknown = (padded[:-2, 1:-1] | padded[2:, 1:-1] | padded[1:-1, :-2] | padded[1:-1, 2:])
    frontier = free & near_unknown
    x, y = grid.cells_to_world(*np.nonzero(frontier))
    under_top = (np.abs(x - 1.75) < 0.55) & (np.abs(y - 0.2) < 0.25)
    assert under_top.sum() >= 8
    r, c = np.nonzero(frontier)
    assert np.all(layer.data[r[under_top], c[under_top]] == 100)
    # far from the desk the layer stays free
    assert np.all(layer.data[:, 30:] == 0) and np.all(layer.data[:4] == 0)
