"""One frame -> boxes (explore_seg.core.objects.pipeline), and the layer closing the
frontier under a desk top (paper Fig. 13)."""

from __future__ import annotations

import math

import numpy as np

from explore_seg.core.frontiers import FrontierParams, find_frontiers
from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.objects import DepthFrame, ObjectMap, ObjectParams, process_frame, wall_mask
from objects_scene import (K, PRIORS, Det, box_parts, camera_pose, desk_at_wall_map, leg_scan,
                           project_box, render_depth, table_parts)


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


def test_fig13_frontier_under_desk_top_becomes_occupied():
    """Paper Fig. 13: the lidar sees only the desk's legs, so the unknown cells under the
    top border free space and are a frontier (core frontier detection); the object layer
    covers them, and with it as an obstacle layer the frontier under the top is gone."""
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
    def frontier_cells(extra_obstacles=None):     # every frontier cell, however few
        out = np.zeros(grid.shape, dtype=bool)
        for f in find_frontiers(grid, extra_obstacles, FrontierParams(min_group_size_cells=1)):
            out[f.cells[:, 0], f.cells[:, 1]] = True
        return out

    def under_top(mask):
        x, y = grid.cells_to_world(*np.nonzero(mask))
        return (np.abs(x - 1.75) < 0.55) & (np.abs(y - 0.2) < 0.25)

    frontier = frontier_cells()
    assert under_top(frontier).sum() >= 8
    r, c = np.nonzero(frontier)
    assert np.all(layer.data[r[under_top(frontier)], c[under_top(frontier)]] == 100)
    assert not under_top(frontier_cells(layer.data == 100)).any()
    # far from the desk the layer stays free
    assert np.all(layer.data[:, 30:] == 0) and np.all(layer.data[:4] == 0)
