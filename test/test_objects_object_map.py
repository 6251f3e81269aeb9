"""The object map: matching, misses, bounds, the robot's disk and path, and its outputs
(explore_seg.core.objects.object_map)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.objects import (MAX_SURFACE_POINTS, UNKNOWN_CLASS, DepthFrame, ObjectMap,
                                      ObjectParams)
from objects_scene import (K, PRIORS, box_parts, camera_pose, make_obj, measured_table,
                           render_depth)


def test_classified_detection_replaces_unknown_object():
    omap = ObjectMap(ObjectParams(), PRIORS)
    omap.update([make_obj(2.0, 0.0, UNKNOWN_CLASS, (1.0, 0.8, 0.75))])
    omap.update([make_obj(2.1, 0.0, "dining table", (1.2, 0.8, 0.75))])
    assert [o.cls for o in omap.objects()] == ["dining table"]
    # different known classes never merge
    omap.update([make_obj(2.1, 0.0, "chair")])
    assert sorted(o.cls for o in omap.objects()) == ["chair", "dining table"]


def test_object_removed_after_misses_when_the_camera_sees_through_it():
    params = ObjectParams(clear_after_misses=3, confirm_hits=1)   # misses alone
    omap = ObjectMap(params, PRIORS)
    pose = camera_pose()
    chair = [box_parts((2.0, 0.0), (0.5, 0.5, 0.9))]
    present = DepthFrame(render_depth(chair, pose), K, pose)
    omap.update([make_obj(2.0, 0.0, size=(0.5, 0.5, 0.9))], present)
    omap.update([], present)               # still there, just not detected: no miss
    assert omap.tracked[0].misses == 0
    gone = DepthFrame(render_depth([], pose), K, pose)
    for expected in (1, 2):
        omap.update([], gone)
        assert omap.tracked[0].misses == expected
    omap.update([], gone)
    assert len(omap) == 0


@pytest.mark.parametrize("robot", [(0.3, 0.0, 0.0), (2.0, -1.8, 0.5 * math.pi)])
def test_table_seen_under_its_top_is_not_missed_but_a_removed_one_is(robot):
    """A top above the camera's view line: the camera sees under it, through most of the
    box. Misses are judged on the measured surface (top and legs), not the box faces
    (which would drop the table while it stands there, undetected)."""
    params = ObjectParams(clear_after_misses=2, confirm_hits=1)   # misses alone
    table, obj = measured_table(0.95, params)
    assert obj.surface is not None and 20 <= len(obj.surface) <= MAX_SURFACE_POINTS
    pose = camera_pose(*robot)
    present = DepthFrame(render_depth(table, pose), K, pose)
    faces = ObjectMap(params, PRIORS)             # judged on the box faces: missed
    faces.update([replace(obj, surface=None)], present)
    faces.update([], present)
    assert faces.tracked[0].misses == 1
    omap = ObjectMap(params, PRIORS)
    omap.update([obj], present)
    for _ in range(4):
        omap.update([], present)
    assert len(omap) == 1 and omap.tracked[0].misses == 0
    gone = DepthFrame(render_depth([], pose), K, pose)
    omap.update([], gone)
    assert omap.tracked[0].misses == 1
    omap.update([], gone)
    assert len(omap) == 0


def test_tentative_object_removed_when_its_place_is_seen_without_it():
    """A box detected in one frame (a false detection, or a box fitted to a neighbour's
    points) goes after tentative_max_unmatched frames that see its place unoccluded
    without detecting it, even where its measured surface is really there; a box
    detected twice stays, and so does a tentative one behind an occluder."""
    params = ObjectParams(confirm_hits=2, tentative_max_unmatched=3)
    pose = camera_pose()
    chair = [box_parts((2.0, 0.0), (0.5, 0.5, 0.9))]
    present = DepthFrame(render_depth(chair, pose), K, pose)
    omap = ObjectMap(params, PRIORS)
    omap.update([make_obj(2.0, 0.0, size=(0.5, 0.5, 0.9))], present)
    for expected in (1, 2):
        omap.update([], present)
        assert len(omap) == 1 and omap.tracked[0].unmatched == expected
        assert omap.tracked[0].misses == 0          # the chair is there: never seen through
    omap.update([], present)
    assert len(omap) == 0
    confirmed = ObjectMap(params, PRIORS)
    for _ in range(2):
        confirmed.update([make_obj(2.0, 0.0, size=(0.5, 0.5, 0.9))], present)
    for _ in range(5):
        confirmed.update([], present)
    assert len(confirmed) == 1 and confirmed.tracked[0].hits == 2
    hidden = ObjectMap(params, PRIORS)
    hidden.update([make_obj(3.0, 0.0, size=(0.5, 0.5, 0.9))])
    wall = DepthFrame(render_depth([box_parts((1.5, 0.0), (0.1, 6.0, 3.0))], pose), K, pose)
    for _ in range(5):
        hidden.update([], wall)
    assert len(hidden) == 1 and hidden.tracked[0].unmatched == 0


def _with_surface(obj, x0, x1, y0, y1):
    """``obj`` with measured points on a grid over [x0, x1] x [y0, y1] at mid height."""
    gx, gy = np.meshgrid(np.linspace(x0, x1, 6), np.linspace(y0, y1, 6))
    pts = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, 0.4)]).astype(np.float32)
    return replace(obj, surface=pts)


def test_detection_of_another_class_fitted_to_a_confirmed_object_is_not_a_new_one():
    """house_cluttered seeds 13 and 19: a desk's detection whose depth crop held the chair
    in front of it gave a desk box on the chair's points, grown to the desk's minimum size,
    closing the way past both. Its points lie inside the confirmed chair: no new object.
    A desk measured beside the chair, and any detection next to a chair seen only once,
    are new objects."""
    params = ObjectParams(explained_fraction=0.6, confirm_hits=2)
    chair = _with_surface(make_obj(2.0, 0.0, size=(0.5, 0.5, 0.9)), 1.8, 2.2, -0.2, 0.2)
    misfit = _with_surface(make_obj(2.2, 0.1, "dining table", (0.8, 0.75, 0.75)),
                           1.8, 2.2, -0.2, 0.2)
    beside = _with_surface(make_obj(3.0, 0.0, "dining table", (0.8, 0.75, 0.75)),
                           2.65, 3.35, -0.3, 0.3)
    omap = ObjectMap(params, PRIORS)
    omap.update([chair])
    omap.update([chair])
    omap.update([misfit])
    assert [o.cls for o in omap.objects()] == ["chair"]
    omap.update([beside])
    assert sorted(o.cls for o in omap.objects()) == ["chair", "dining table"]
    once = ObjectMap(params, PRIORS)
    once.update([chair])
    once.update([misfit])
    assert sorted(o.cls for o in once.objects()) == ["chair", "dining table"]
    off = ObjectMap(replace(params, explained_fraction=0.0), PRIORS)
    for obs in (chair, chair, misfit):
        off.update([obs])
    assert sorted(o.cls for o in off.objects()) == ["chair", "dining table"]


def test_object_not_missed_when_occluded_or_out_of_view():
    omap = ObjectMap(ObjectParams(clear_after_misses=1), PRIORS)
    pose = camera_pose()
    omap.update([make_obj(3.0, 0.0, size=(0.5, 0.5, 0.9)), make_obj(-3.0, 0.0, size=(0.5, 0.5, 0.9))])
    wall = [box_parts((1.5, 0.0), (0.1, 6.0, 3.0))]   # hides the chair in front
    omap.update([], DepthFrame(render_depth(wall, pose), K, pose))
    assert len(omap) == 2                  # occluded one and the one behind the camera stay


def test_object_map_is_bounded():
    omap = ObjectMap(ObjectParams(max_objects=5), PRIORS)
    for i in range(12):
        omap.update([make_obj(2.0 * i, 0.0)])
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
    omap.update([make_obj(0.0, 0.0)])
    omap.update([], robot_xy=robot_xy)
    assert (len(omap) == 1) == kept
    fresh = ObjectMap(ObjectParams(robot_clear_fraction=fraction), PRIORS)
    fresh.update([make_obj(0.0, 0.0)], robot_xy=robot_xy)     # observations alike
    assert (len(fresh) == 1) == kept


def test_rasterize_fills_rotated_footprint_on_the_map_grid():
    grid, _ = grid_from_ascii("\n".join(["." * 40] * 30), resolution_m=0.1,
                              origin_xy_m=(-1.0, -1.0))
    omap = ObjectMap(ObjectParams(), PRIORS)
    omap.update([make_obj(1.0, 0.5, "dining table", (1.0, 0.5, 0.75), yaw=math.pi / 4)])
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
    omap.update([make_obj(1.0, 0.0, size=(0.5, 0.5, 1.0)), make_obj(4.0, 0.0, "dining table",
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
    table = make_obj(1.5, 0.75, "dining table", (1.6, 1.0, 0.75))   # x 0.7..2.3, y 0.25..1.25
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
