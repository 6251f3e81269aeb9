"""Generic obstacles from depth (explore_seg.core.objects.depth_obstacles) in the object layer,
and a partly seen desk top that still becomes a full box."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.objects import (DepthFrame, DepthObstacles, ObjectMap, ObjectParams,
                                      object_from_detection, process_frame, wall_mask)
from objects_scene import (K, PRIORS, Det, box_parts, camera_pose, desk_at_wall_map,
                           make_obj, project_box, render_depth, table_parts)

# the paper's robot: camera 0.894 m up, pitched 0.1 rad down
PAPER_CAM = dict(z=0.894, pitch=0.1)
#: A box lower than the lidar's scan plane (0.17 m): the 2D map cannot have it.
LOW_BOX = box_parts((1.5, 0.1), (0.3, 0.3, 0.12))


def _grid():
    return GridMap(np.zeros((80, 80), np.int8), 0.05, (0.0, -2.0))


def _cells(layer, x0, x1, y0, y1):
    x, y = layer.cells_to_world(*np.indices(layer.shape))
    return (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1)


def test_a_low_box_of_an_undetected_class_is_in_the_layer_after_one_frame():
    pose = camera_pose(**PAPER_CAM)
    bin_ = [LOW_BOX]
    frame = DepthFrame(render_depth(bin_, pose), K, pose)
    params = ObjectParams()
    res = process_frame(frame, [], PRIORS, params)      # no detection at all
    om = ObjectMap(params, PRIORS)
    om.update(res.objects + res.unknown, frame, 10**9)
    assert len(om) == 0                                  # no box ...
    layer = om.rasterize(_grid())
    occ = layer.data >= 65
    # ... but the box's near edge is an obstacle, and nothing else (the floor is not)
    assert occ[_cells(layer, 1.36, 1.41, -0.02, 0.22)].all()
    assert not occ[~_cells(layer, 1.30, 1.70, -0.1, 0.3)].any()
    # off: the layer stays empty (the boxes' behaviour alone)
    om0 = ObjectMap(dataclasses.replace(params, depth_obstacles=False), PRIORS)
    om0.update([], frame, 10**9)
    assert not (om0.rasterize(_grid()).data >= 65).any()


def test_seen_through_clears_out_of_view_keeps_and_decay_forgets():
    params = ObjectParams(depth_decay_s=100.0)
    d = DepthObstacles(params)
    pose = camera_pose(**PAPER_CAM)
    bin_ = [LOW_BOX]
    assert d.update(DepthFrame(render_depth(bin_, pose), K, pose), 0.0)
    assert d.version == 1 and len(d) > 0
    # turned away: the bin is out of view and stays
    away = camera_pose(yaw=np.pi, **PAPER_CAM)
    assert not d.update(DepthFrame(render_depth(bin_, away), K, away), 1.0) and len(d) > 0
    # the bin is gone and the camera, 0.5 m further back, sees the floor behind where
    # it stood (from the first pose its lowest voxels lie below the view): cleared
    back = camera_pose(x=-0.5, **PAPER_CAM)
    assert d.update(DepthFrame(render_depth([], back), K, back), 2.0)
    assert len(d) == 0 and not d.mask(_grid()).any()
    # decay: marked at t = 0, not seen again for longer than depth_decay_s
    d.update(DepthFrame(render_depth(bin_, pose), K, pose), 0.0)
    assert len(d) > 0
    d.update(DepthFrame(render_depth(bin_, away), K, away), 101.0)
    assert len(d) == 0


def test_height_band_and_walls_do_not_mark():
    pose = camera_pose(**PAPER_CAM)
    # a shelf above the robot and a 3 cm floor mat: neither marks
    parts = [box_parts((1.5, 0.0), (0.4, 0.4, 0.2), z0=1.3),
             box_parts((1.2, -0.6), (0.5, 0.5, 0.03))]
    d = DepthObstacles(ObjectParams())
    d.update(DepthFrame(render_depth(parts, pose), K, pose), 0.0)
    assert len(d) == 0
    # a wall the 2D map has: its points do not mark (drop_wall_points; the lidar band,
    # which drops them too, off)
    wall = [box_parts((2.55, 0.0), (0.1, 4.0, 2.0))]
    frame = DepthFrame(render_depth(wall, pose), K, pose)
    grid = desk_at_wall_map([None], 2.55)
    d = DepthObstacles(ObjectParams(depth_lidar_band_m=0.0))
    d.update(frame, 0.0, wall_mask(grid, ObjectParams()))
    assert len(d) == 0
    d.update(frame, 0.0)
    assert len(d) > 0


def test_what_the_lidar_sees_does_not_mark_wherever_the_map_draws_it():
    """A column holding points at the scan plane's height is the 2D map's (a bin's face,
    a wall): it does not mark, whatever the map's walls say; the bin's top behind its face
    and a top overhanging a narrow pedestal still mark. Under SLAM drift the map's walls
    lie 0.3 m from where the frame puts the wall: the wall mask misses its points, the
    lidar band drops them."""
    pose = camera_pose(**PAPER_CAM)
    d = DepthObstacles(ObjectParams())
    d.update(DepthFrame(render_depth([box_parts((1.5, 0.1), (0.3, 0.3, 0.6))], pose), K,
                        pose), 0.0)
    assert len(d) > 0 and np.all(d.centres()[:, 2] > 0.5)             # the top only
    off = DepthObstacles(ObjectParams(depth_lidar_band_m=0.0))
    off.update(DepthFrame(render_depth([box_parts((1.5, 0.1), (0.3, 0.3, 0.6))], pose), K,
                          pose), 0.0)
    assert np.any(off.centres()[:, 2] < 0.3)                           # the face too
    table = [box_parts((1.5, 0.1), (0.1, 0.1, 0.55)),
             box_parts((1.5, 0.1), (0.5, 0.5, 0.05), z0=0.55)]
    d = DepthObstacles(ObjectParams())
    d.update(DepthFrame(render_depth(table, pose), K, pose), 0.0)
    occ = d.mask(_grid())
    grid = _grid()
    assert occ[_cells(grid, 1.26, 1.40, -0.1, 0.3)].mean() > 0.5      # the top's near part
    assert not occ[_cells(grid, 1.46, 1.49, 0.06, 0.14)].any()        # the pedestal face
    # a wall 2.55 m ahead; the drifted map draws it at 2.85 m
    wall = [box_parts((2.55, 0.0), (0.1, 4.0, 2.0))]
    frame = DepthFrame(render_depth(wall, pose), K, pose)
    walls = wall_mask(desk_at_wall_map([None], 2.85), ObjectParams())
    d = DepthObstacles(ObjectParams())
    d.update(frame, 0.0, walls)
    assert len(d) == 0
    off = DepthObstacles(ObjectParams(depth_lidar_band_m=0.0))     # the map's walls only
    off.update(frame, 0.0, walls)
    assert len(off) > 0


def test_a_desk_top_seen_only_partly_still_becomes_a_full_box():
    """The camera sees the near 40 % of a desk (the rest beyond the image's lower-right
    corner); the box keeps the measured near edge and grows to the prior's extent."""
    desk = table_parts((1.6, -0.95), 1.4, 0.7, 0.75, 0.0)
    pose = camera_pose(z=1.0, pitch=0.5)
    frame = DepthFrame(render_depth(desk, pose), K, pose)
    box = project_box(desk, pose)
    assert box[3] == K.height - 1 or box[0] == 0 or box[2] == K.width - 1   # cut by the view
    obj = object_from_detection(frame, box, "dining table", 0.9, PRIORS["dining table"],
                                ObjectParams())
    assert obj is not None
    prior = PRIORS["dining table"]
    lo, hi = sorted(obj.size_xyz[:2])
    assert lo >= prior.min_xy_m - 1e-6
    layer = ObjectMap(ObjectParams(depth_obstacles=False), PRIORS)
    layer.update([obj])
    occ = layer.rasterize(_grid()).data >= 65
    # the whole desk top's footprint (not only what was seen) is in the layer
    full = _cells(layer.rasterize(_grid()), 0.95, 2.25, -1.25, -0.65)
    assert occ[full].mean() >= 0.9


def test_the_virtual_cloud_carries_the_depth_obstacles():
    pose = camera_pose(**PAPER_CAM)
    frame = DepthFrame(render_depth([LOW_BOX], pose), K, pose)
    om = ObjectMap(ObjectParams(), PRIORS)
    om.update([], frame, 10**9)
    cloud = om.virtual_cloud()
    assert len(cloud) == len(om.depth) > 0
    assert np.all((cloud[:, 0] > 1.3) & (cloud[:, 0] < 1.7) & (cloud[:, 2] < 0.3))


def test_forget_since_drops_the_voxels_marked_after_a_correction():
    """After a SLAM correction the voxels marked since the previous one go (they lie where
    the uncorrected poses put them); older ones stay."""
    d = DepthObstacles(ObjectParams())
    pose = camera_pose(**PAPER_CAM)
    d.update(DepthFrame(render_depth([LOW_BOX], pose), K, pose), 0.0)
    old = len(d)
    moved = camera_pose(yaw=np.pi, **PAPER_CAM)                  # the first box behind
    other = [box_parts((-1.5, 0.1), (0.3, 0.3, 0.12))]
    d.update(DepthFrame(render_depth(other, moved), K, moved), 10.0)
    assert len(d) > old
    version = d.version
    assert d.forget_since(5.0)
    assert len(d) == old and d.version == version + 1
    assert d.mask(_grid())[_cells(_grid(), 1.3, 1.7, -0.1, 0.3)].any()
    assert not d.forget_since(5.0)


#: A low box 2.8 m ahead: with every 12th pixel, each of its voxels holds one point a frame.
FAR_BOX = box_parts((2.8, 0.1), (0.3, 0.3, 0.12))


def _far_frame(boxes, **pose_kw):
    pose = camera_pose(**PAPER_CAM, **pose_kw)
    return DepthFrame(render_depth(boxes, pose), K, pose)


def test_points_too_few_for_one_frame_add_up_over_the_window():
    """A voxel with one point a frame is marked by the second frame within
    depth_evidence_window_s, never with the window off, not when the window ended
    first."""
    frame = _far_frame([FAR_BOX])
    params = ObjectParams(depth_pixel_stride=12, depth_evidence_window_s=3.0)
    d = DepthObstacles(params)
    assert not d.update(frame, 0.0) and len(d) == 0       # one point each: pending
    assert d.update(frame, 1.0) and len(d) > 0            # two: marked
    assert d.mask(_grid())[_cells(_grid(), 2.6, 3.0, -0.1, 0.3)].any()
    off = DepthObstacles(dataclasses.replace(params, depth_evidence_window_s=0.0))
    for t in (0.0, 1.0, 2.0):
        off.update(frame, t)
    assert len(off) == 0
    late = DepthObstacles(params)
    late.update(frame, 0.0)
    late.update(frame, 3.5)                               # the first point has expired
    assert len(late) == 0
    assert late.update(frame, 4.0) and len(late) > 0      # 3.5 s and 4.0 s add up


def test_a_pending_voxel_seen_through_starts_again():
    """The box's single points are forgotten when a frame sees the floor behind where it
    stood; its next single points do not complete them."""
    params = ObjectParams(depth_pixel_stride=12, depth_evidence_window_s=10.0)
    d = DepthObstacles(params)
    d.update(_far_frame([FAR_BOX]), 0.0)
    d.update(_far_frame([]), 1.0)                         # gone: seen through
    assert not d.update(_far_frame([FAR_BOX]), 2.0) and len(d) == 0
    assert d.update(_far_frame([FAR_BOX]), 3.0) and len(d) > 0


def test_forget_since_drops_pending_points_after_a_correction():
    params = ObjectParams(depth_pixel_stride=12, depth_evidence_window_s=10.0)
    d = DepthObstacles(params)
    d.update(_far_frame([FAR_BOX]), 10.0)
    d.forget_since(5.0)                                   # the points of 10 s go
    assert not d.update(_far_frame([FAR_BOX]), 11.0) and len(d) == 0


def test_depth_noise_of_a_stereo_camera_on_an_empty_floor_marks_nothing_over_frames():
    """An empty floor seen with a RealSense-like depth error (std 0.005 z^2 m) for 12
    frames at 2 Hz: the points added up over the window mark no voxel."""
    pose = camera_pose(**PAPER_CAM)
    clean = render_depth([], pose)
    rng = np.random.default_rng(0)
    d = DepthObstacles(ObjectParams(depth_evidence_window_s=3.0))
    for k in range(12):
        noisy = clean + rng.normal(0.0, 1.0, clean.shape) * 0.005 * clean ** 2
        d.update(DepthFrame(noisy, K, pose), 0.5 * k)
        assert len(d) == 0


def test_pending_points_of_an_old_time_line_do_not_add_up_after_a_clock_jump_back():
    params = ObjectParams(depth_pixel_stride=12, depth_evidence_window_s=3.0)
    d = DepthObstacles(params)
    d.update(_far_frame([FAR_BOX]), 100.0)
    assert not d.update(_far_frame([FAR_BOX]), 1.0) and len(d) == 0   # clock reset
    assert d.update(_far_frame([FAR_BOX]), 2.0) and len(d) > 0        # the new line's own


def test_what_the_lidar_saw_within_the_window_does_not_mark_from_close_by():
    """A wall seen from 1.5 m shows its scan-plane row, so it does not mark; from 0.9 m
    that row lies below the camera's view. Within depth_evidence_window_s of the far
    frame its columns still do not mark (the lidar saw what stands there); with the
    window off, or once it has passed, the near frame marks the wall's face. The far
    frame may also come after the near one (frames out of order)."""
    wall = [box_parts((1.55, 0.0), (0.1, 1.0, 1.0))]
    far, near = _far_frame(wall), _far_frame(wall, x=0.6)
    lowest_m = PAPER_CAM["z"] - 0.9 * np.tan(PAPER_CAM["pitch"] + np.arctan(K.cy / K.fy))
    assert lowest_m > ObjectParams().depth_lidar_height_m + 0.1    # the row is out of view
    params = ObjectParams(depth_evidence_window_s=3.0)
    d = DepthObstacles(params)
    d.update(far, 0.0)
    assert len(d) == 0
    d.update(near, 2.0)
    assert len(d) == 0
    late = DepthObstacles(params)
    late.update(far, 0.0)
    assert late.update(near, 3.5) and len(late) > 0       # the far frame is past the window
    off = DepthObstacles(dataclasses.replace(params, depth_evidence_window_s=0.0))
    off.update(far, 0.0)
    assert off.update(near, 2.0) and len(off) > 0
    swapped = DepthObstacles(params)
    swapped.update(far, 2.0)
    swapped.update(near, 1.0)
    assert len(swapped) == 0
    jumped = DepthObstacles(params)                       # the clock jumped back 100 s
    jumped.update(far, 100.0)
    assert jumped.update(near, 1.0) and len(jumped) > 0


def test_after_a_clock_jump_back_the_voxels_decay_from_the_new_time():
    """Voxels marked at 1000 s, then the clock restarts at 10 s: they stay (lose no
    state) and are forgotten depth_decay_s after the jump, not when the new clock
    reaches 1000 s; so are a box's last-seen stamps."""
    params = ObjectParams(depth_decay_s=30.0)
    om = ObjectMap(params, PRIORS)
    om.update([], _far_frame([LOW_BOX]), 1000 * 10**9)
    d = om.depth
    assert d is not None and len(d) > 0
    away = _far_frame([], yaw=np.pi)                      # out of view: no clearing
    stale = DepthObstacles(params)
    stale.update(_far_frame([LOW_BOX]), 1000.0)
    om.time_went_back(10 * 10**9)
    d.update(away, 20.0)
    stale.update(away, 20.0)
    assert len(d) > 0 and len(stale) > 0                  # kept
    d.update(away, 41.0)
    stale.update(away, 41.0)
    assert len(d) == 0                                    # 31 s after the jump
    assert len(stale) > 0                                 # without it: until 970 s
    om.update([make_obj(2.0, 0.0, "chair")], None, 1000 * 10**9)
    om.time_went_back(10 * 10**9)
    assert [t.last_seen_ns for t in om.tracked] == [10 * 10**9]


def test_forget_since_moves_the_voxels_of_the_last_moments_with_the_jump():
    """With the correction's jump, voxels marked at or after ``recent_s`` move by it
    (binned again; one landing on a kept voxel keeps the higher score and the later
    stamp); those marked since the previous correction but before ``recent_s`` go; older
    ones stay where they are."""
    d = DepthObstacles(ObjectParams())
    pose = camera_pose(**PAPER_CAM)
    d.update(DepthFrame(render_depth([LOW_BOX], pose), K, pose), 0.0)      # before: kept
    kept = d.centres()
    behind = camera_pose(yaw=np.pi, **PAPER_CAM)
    d.update(DepthFrame(render_depth([box_parts((-1.5, 0.1), (0.3, 0.3, 0.12))], behind),
                        K, behind), 6.0)                                   # since: goes
    d.update(DepthFrame(render_depth([box_parts((0.1, 1.5), (0.3, 0.3, 0.12))],
                                     camera_pose(yaw=np.pi / 2, **PAPER_CAM)), K,
                        camera_pose(yaw=np.pi / 2, **PAPER_CAM)), 9.0)     # recent: moves
    recent = d.centres()[d.centres()[:, 1] > 1.0]
    assert len(recent) > 0
    v = ObjectParams().depth_voxel_m
    jump = (0.0, -0.3, np.pi / 2)            # turns the recent box's voxels onto x < 0
    assert d.forget_since(5.0, jump, recent_s=8.0)
    got = {tuple(np.round(c, 6)) for c in d.centres()}
    x = -recent[:, 1] + jump[0]
    y = recent[:, 0] - 0.3
    moved = {(round((np.floor(a / v) + 0.5) * v, 6), round((np.floor(b / v) + 0.5) * v, 6),
              round(z, 6)) for a, b, z in zip(x, y, recent[:, 2])}
    assert got == {tuple(np.round(c, 6)) for c in kept} | moved
    # without the jump the recent voxels go too, as before
    e = DepthObstacles(ObjectParams())
    e.update(DepthFrame(render_depth([LOW_BOX], pose), K, pose), 9.0)
    assert e.forget_since(5.0, None, recent_s=8.0) and len(e) == 0


def test_moved_voxels_that_land_on_kept_ones_keep_the_higher_score():
    from explore_seg.core.objects.depth_obstacles import _merge
    keys, score, stamp = _merge(np.array([3, 7], np.int64), np.array([1, 5], np.int16),
                                np.array([1.0, 2.0]), np.array([7, 7, 9], np.int64),
                                np.array([2, 6, 1], np.int16), np.array([9.0, 3.0, 4.0]))
    assert keys.tolist() == [3, 7, 9] and score.tolist() == [1, 6, 1]
    assert stamp.tolist() == [1.0, 9.0, 4.0]
