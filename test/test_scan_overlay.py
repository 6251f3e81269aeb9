"""The scan overlay (explore_seg.core.scan_overlay) and the explorer deciding on it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.scan_overlay import ScanOverlay, ScanOverlayParams
from explore_seg.core.selection import Action, SelectionParams


def _unknown(n: int = 60, res: float = 0.1, origin=(0.0, 0.0)) -> GridMap:
    return GridMap(np.full((n, n), -1, dtype=np.int8), res, origin)


def _ring(n_beams: int = 360) -> np.ndarray:
    return np.linspace(-math.pi, math.pi, n_beams, endpoint=False)


def test_beam_marks_free_cells_and_its_return():
    ov = ScanOverlay(ScanOverlayParams())
    ov.add_scan(1.0, (3.0, 3.0, math.pi / 2), [0.0], [1.5], 3.5)
    seen = ov.apply(_unknown())
    # beam along +y from (3, 3): cells rows 30..44 free, row 45 the return
    assert (seen.data[30:45, 30] == 0).all()
    assert seen.data[45, 30] == 100
    assert seen.data[46, 30] == -1
    assert seen.data[30:45, 31].max() == -1          # nothing beside the beam


def test_known_cells_are_never_changed():
    grid = _unknown()
    data = grid.data.copy()
    data[30:34, 30] = 100                            # a wall the beam passes through
    data[20, 20] = 0
    grid = grid.with_data(data)
    ov = ScanOverlay(ScanOverlayParams())
    ov.add_scan(1.0, (3.0, 2.5, math.pi / 2), [0.0], [math.inf], 3.5)
    seen = ov.apply(grid)
    assert (seen.data[30:34, 30] == 100).all()
    assert seen.data[25, 30] == 0 and seen.data[29, 30] == 0


def test_no_return_carves_free_to_range_max_and_leaves_the_border_unknown():
    ov = ScanOverlay(ScanOverlayParams())
    ov.add_scan(1.0, (3.0, 3.0, 0.0), [0.0], [math.inf], 10.0)
    seen = ov.apply(_unknown())
    row = seen.data[30]
    assert (row[30:59] == 0).all()
    assert row[59] == -1                             # the map's border stays unknown
    assert (row == 100).sum() == 0


def test_old_scans_expire_and_time_going_back_resets():
    ov = ScanOverlay(ScanOverlayParams(keep_s=5.0))
    grid = _unknown()
    ov.add_scan(1.0, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)
    ov.add_scan(7.0, (3.0, 3.0, math.pi / 2), [0.0], [1.0], 3.5)
    seen = ov.apply(grid)
    assert seen.data[30, 35] == -1                   # the first scan is 6 s old
    assert seen.data[35, 30] == 0
    assert seen.stamp_ns == 7_000_000_000
    ov.add_scan(2.0, (3.0, 3.0, math.pi), [0.0], [1.0], 3.5)   # clock went back
    seen = ov.apply(grid)
    assert seen.data[35, 30] == -1 and seen.data[30, 25] == 0


def test_nothing_seen_returns_the_same_map():
    ov = ScanOverlay(ScanOverlayParams())
    grid = _unknown()
    assert ov.apply(grid) is grid
    full = grid.with_data(np.zeros(grid.shape, dtype=np.int8))
    ov.add_scan(1.0, (3.0, 3.0, 0.0), _ring(), np.full(360, 1.0), 3.5)
    assert ov.apply(full) is full
    assert ScanOverlay(ScanOverlayParams(enabled=False)).apply(grid) is grid


def test_a_grown_map_keeps_the_cells_and_a_new_lattice_forgets_them():
    ov = ScanOverlay(ScanOverlayParams())
    ov.add_scan(1.0, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)
    assert ov.apply(_unknown()).data[30, 35] == 0
    grown = _unknown(80, origin=(-1.0, -1.0))         # the map grew by 1 m on two sides
    assert ov.apply(grown).data[40, 45] == 0
    shifted = _unknown(80, origin=(-1.05 + 0.025, -1.0))   # half a cell off the lattice
    assert ov.apply(shifted) is shifted


def test_the_window_follows_the_robot():
    ov = ScanOverlay(ScanOverlayParams(window_m=4.0))
    grid = _unknown(200)
    ov.add_scan(1.0, (2.0, 2.0, 0.0), [0.0], [1.0], 3.5)
    ov.add_scan(2.0, (15.0, 15.0, 0.0), [0.0], [1.0], 3.5)
    seen = ov.apply(grid)
    assert seen.data[150, 155] == 0                  # the newest scan
    assert seen.data[20, 25] == -1                   # left the window


def test_lidar_mount_offsets_the_beams():
    ov = ScanOverlay(ScanOverlayParams(lidar_x_m=-0.5))
    ov.add_scan(1.0, (3.0, 3.0, math.pi / 2), [0.0], [1.0], 3.5)
    seen = ov.apply(_unknown())
    # scanner at (3.0, 2.5) (0.5 m behind a robot facing +y): the return at y = 3.5
    assert seen.data[35, 30] == 100


@pytest.mark.parametrize("args, match", [
    ((math.nan, (0, 0, 0), [0.0], [1.0], 3.5), "stamp"),
    ((1.0, (0, math.inf, 0), [0.0], [1.0], 3.5), "pose"),
    ((1.0, (0, 0, 0), [0.0, 0.1], [1.0], 3.5), "shapes"),
    ((1.0, (0, 0, 0), [[0.0]], [[1.0]], 3.5), "1D"),
    ((1.0, (0, 0, 0), [math.nan], [1.0], 3.5), "angles"),
    ((1.0, (0, 0, 0), [0.0], [1.0], 0.0), "range_max"),
])
def test_malformed_scans_are_refused_and_change_nothing(args, match):
    ov = ScanOverlay(ScanOverlayParams())
    ov.add_scan(1.0, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)
    before = ov.apply(_unknown()).data.copy()
    with pytest.raises(ValueError, match=match):
        ov.add_scan(*args)
    assert np.array_equal(ov.apply(_unknown()).data, before)


@pytest.mark.parametrize("kw", [dict(keep_s=0.0), dict(window_m=-1.0),
                                dict(max_pose_age_s=math.inf), dict(lidar_x_m=math.nan)])
def test_params_are_checked(kw):
    with pytest.raises(ValueError):
        ScanOverlayParams(**kw)


# ---------------------------------------------------------------- the explorer

_ROOMS = '''
##############
#R.....#?????#
#......#?????#
#.......?????#
#......#?????#
#??....#?????#
##############'''


def _explorer(overlay: bool) -> tuple[Explorer, GridMap, tuple[float, float, float]]:
    grid, marks = grid_from_ascii(_ROOMS, resolution_m=0.1)
    ex = Explorer(FrontierParams(min_group_size_cells=1, robot_radius_m=0.0),
                  SelectionParams(strategy="nearest", done_confirmations=1, turn_looks=0,
                                  return_to_start=False),
                  overlay=ScanOverlayParams() if overlay else None)
    x, y = grid.cell_to_world(*marks["R"][0])
    return ex, grid, (x, y, 0.0)


def _look_into_the_room(ex: Explorer, grid: GridMap, stamp_s: float) -> None:
    """A scan from inside the unknown room that sees all of it (its walls included)."""
    x, y = grid.cell_to_world(3, 10)
    angles = _ring(720)
    ranges = []
    for a in angles:                                  # march to the first wall cell
        r = 0.05
        while r < 3.0:
            rr, cc = grid.world_to_cell(x + r * math.cos(a), y + r * math.sin(a))
            if not grid.in_bounds(rr, cc) or grid.data[rr, cc] == 100 or _is_outer(rr, cc):
                break
            r += 0.01
        ranges.append(r)
    ex.add_scan(stamp_s, (x, y, 0.0), angles, np.asarray(ranges), 3.5)


def _is_outer(r: int, c: int) -> bool:
    return r in (0, 6) or c == 13


def test_explorer_decides_on_what_the_scans_saw():
    ex, grid, pose = _explorer(overlay=True)
    first = ex.step(0.0, grid, pose)
    assert first.action is Action.NEW_GOAL and len(first.frontiers) >= 1
    _look_into_the_room(ex, grid, 1.0)
    after = ex.step(1.0, grid, pose)
    # the room is seen: only the pocket in the robot's room is left
    cells = np.concatenate([f.cells for f in after.frontiers])
    assert cells[:, 1].max() <= 3
    assert after.goal is not None and after.goal.xy_m[0] < 0.5
    plain, grid2, pose2 = _explorer(overlay=False)
    plain.step(0.0, grid2, pose2)
    _look_into_the_room(plain, grid2, 1.0)
    cells = np.concatenate([f.cells for f in plain.step(1.0, grid2, pose2).frontiers])
    assert cells[:, 1].max() >= 7


def test_a_step_on_the_overlaid_map_says_it_detected():
    """Frontiers found on the map with the scans laid over it are this step's detection
    (the node publishes them, the benchmark times them); the same map again is not."""
    ex, grid, pose = _explorer(overlay=True)
    assert ex.step(0.0, grid, pose).detected
    _look_into_the_room(ex, grid, 1.0)
    after = ex.step(1.0, grid, pose)
    assert after.detected and after.detect_s > 0
    assert not ex.step(2.0, grid, pose).detected


_POCKET = '''
##########
#R.......#
#.....???#
#.....???#
##########'''


def test_the_slam_map_alone_decides_done():
    """Scans saw the last unknown pocket, the map does not have it yet: the explorer
    goes there instead of ending with a hole in the map."""
    grid, marks = grid_from_ascii(_POCKET, resolution_m=0.1)
    ex = Explorer(FrontierParams(min_group_size_cells=1, robot_radius_m=0.0),
                  SelectionParams(strategy="nearest", done_confirmations=1, turn_looks=0,
                                  return_to_start=False),
                  overlay=ScanOverlayParams())
    x, y = grid.cell_to_world(*marks["R"][0])
    angles = _ring(720)
    ranges = []
    for a in angles:                                  # to the first wall cell
        r = 0.02
        while grid.data[grid.world_to_cell(x + r * math.cos(a), y + r * math.sin(a))] != 100:
            r += 0.01
        ranges.append(r)
    ex.add_scan(1.0, (x, y, 0.0), angles, np.asarray(ranges), 3.5)
    seen = ScanOverlay(ScanOverlayParams())
    seen.add_scan(1.0, (x, y, 0.0), angles, np.asarray(ranges), 3.5)
    assert not (seen.apply(grid).data == -1).any()    # the overlay alone: nothing left
    out = ex.step(1.0, grid, (x, y, 0.0))
    assert out.action is Action.NEW_GOAL
    assert out.goal is not None and out.goal.xy_m[0] > 0.5


def test_rrt_exploration_decides_on_the_scans_too():
    grid, marks = grid_from_ascii(_ROOMS, resolution_m=0.1)
    ex = Explorer(FrontierParams(min_group_size_cells=1, robot_radius_m=0.0),
                  SelectionParams(strategy="rrt_exploration"), overlay=ScanOverlayParams())
    x, y = grid.cell_to_world(*marks["R"][0])
    ex.step(0.0, grid, (x, y, 0.0))
    _look_into_the_room(ex, grid, 1.0)
    ex.step(1.0, grid, (x, y, 0.0))
    # the map its RRT grew in is the one with the scanned room: no unknown cell is left there
    assert ex._key is not None and (ex._key[0].data[1:6, 8:13] != -1).all()


def test_a_correction_forgets_the_scans_before_it():
    ov = ScanOverlay(ScanOverlayParams(keep_s=1e6))
    grid = _unknown()
    ov.add_scan(1.0, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)           # +x, before
    ov.add_scan(5.0, (3.0, 3.0, math.pi / 2), [0.0], [1.0], 3.5)   # +y, after
    seen = ov.apply(grid)
    assert seen.data[30, 35] == 0 and seen.data[30, 40] == 100
    assert seen.data[35, 30] == 0
    ov.forget_before(4.9)
    seen = ov.apply(grid)
    assert seen.data[30, 35] == -1 and seen.data[30, 40] == -1     # laid before: gone
    assert seen.data[35, 30] == 0 and seen.data[40, 30] == 100     # laid after: kept
    assert seen.data[30, 30] == 0          # the sensor's cell, seen again at 5 s: kept
    ov.add_scan(4.8, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)           # late, from before
    assert ov.apply(grid).data[30, 35] == -1
    ov.add_scan(6.0, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)           # seen again: back
    assert ov.apply(grid).data[30, 35] == 0
    ov.forget_before(None)                                          # when unknown: all
    assert ov.apply(grid) is grid


def test_a_correction_before_the_first_map_drops_the_waiting_scans():
    ov = ScanOverlay(ScanOverlayParams())
    ov.add_scan(1.0, (3.0, 3.0, 0.0), [0.0], [1.0], 3.5)
    ov.add_scan(5.0, (3.0, 3.0, math.pi / 2), [0.0], [1.0], 3.5)
    ov.forget_before(3.0)                                           # no lattice yet
    seen = ov.apply(_unknown())
    assert seen.data[30, 35] == -1 and seen.data[35, 30] == 0


def test_explorer_map_corrected_empties_the_overlay():
    ex, grid, pose = _explorer(overlay=True)
    _look_into_the_room(ex, grid, 1.0)
    cells = np.concatenate([f.cells for f in ex.step(1.0, grid, pose).frontiers])
    assert cells[:, 1].max() <= 3                   # the scans filled the room
    ex.map_corrected(2.0)
    cells = np.concatenate([f.cells for f in ex.step(2.0, grid, pose).frontiers])
    assert cells[:, 1].max() >= 7                   # they are forgotten: the map alone
    plain, _, _ = _explorer(overlay=False)
    plain.map_corrected(2.0)                        # no overlay: nothing to forget


def test_correction_parameters_match_the_object_nodes():
    """target_selector finds corrections with the object_costmap node's thresholds."""
    import dataclasses

    from explore_seg.core.objects import ObjectCostmapNodeParams

    obj = ObjectCostmapNodeParams()
    names = [f.name for f in dataclasses.fields(ScanOverlayParams)
             if f.name.startswith("correction_")]
    assert len(names) == 9
    assert {n: getattr(ScanOverlayParams(), n) for n in names} == \
        {n: getattr(obj, n) for n in names}


@pytest.mark.parametrize("kw", [{"correction_pose_jump_m": -0.1},
                                {"correction_merge_s": math.nan},
                                {"correction_map_moved_fraction": 1.5},
                                {"correction_map_min_cells": 0}])
def test_correction_params_are_checked(kw):
    with pytest.raises(ValueError):
        ScanOverlayParams(**kw)
