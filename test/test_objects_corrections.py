"""SLAM corrections from a node's inputs (ROS-free): a map-frame pose that jumps more than
the robot can drive, a map whose walls moved; growth and ordinary motion are none."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.objects import CorrectionDetector, ObjectCostmapNodeParams
from explore_seg.core.objects.corrections import moved_cells, occupied_xy, pose_jump

NS = 1_000_000_000
P = ObjectCostmapNodeParams()
RES = 0.05


def _house(shift_m: tuple[float, float] = (0.0, 0.0), extra_room: bool = False,
           size: int = 200, origin: tuple[float, float] = (-5.0, -5.0)) -> GridMap:
    """Walls of a 2-room house (10 x 10 m grid) drawn shifted by ``shift_m``; with
    ``extra_room`` also the walls of a room further east (the map grew)."""
    data = np.full((size, size), -1, np.int8)
    grid = GridMap(data, RES, origin)
    walls = [((-4, -4), (4, -4)), ((4, -4), (4, 4)), ((4, 4), (-4, 4)), ((-4, 4), (-4, -4)),
             ((0, -4), (0, -1)), ((0, 1), (0, 4)), ((-4, 0), (-2, 0))]
    if extra_room:
        walls += [((4, -2), (7, -2)), ((7, -2), (7, 2)), ((7, 2), (4, 2))]
    free = np.zeros(data.shape, bool)
    r, c = grid.world_to_cells(np.array([-3.9, 3.9]), np.array([-3.9, 3.9]))
    free[r[0]:r[1], c[0]:c[1]] = True
    data[free] = 0
    for (x0, y0), (x1, y1) in walls:
        n = int(math.hypot(x1 - x0, y1 - y0) / (0.5 * RES)) + 1
        xs = np.linspace(x0, x1, n) + shift_m[0]
        ys = np.linspace(y0, y1, n) + shift_m[1]
        rows, cols = grid.world_to_cells(xs, ys)
        ok = (rows >= 0) & (rows < size) & (cols >= 0) & (cols < size)
        data[rows[ok], cols[ok]] = 100
    return GridMap(data, RES, origin)


def test_a_re_render_that_moves_the_map_by_0_3_m_is_a_correction():
    det = CorrectionDetector(P)
    assert det.observe_map(_house()) is None                    # first map: nothing to compare
    c = det.observe_map(dataclasses.replace(_house((0.3, 0.0)), stamp_ns=7 * NS))
    assert c is not None and c.source == "map" and c.stamp_ns == 7 * NS
    assert det.take() == [c] and det.take() == []


def test_a_map_that_only_grew_is_no_correction():
    det = CorrectionDetector(P)
    det.observe_map(_house())
    # more walls, and a larger grid with another origin (the map grew to the east)
    grown = _house(extra_room=True, size=260, origin=(-5.0, -6.5))
    assert det.observe_map(grown) is None
    assert moved_cells(occupied_xy(_house()), grown, P.correction_map_tolerance_m) == 0
    assert det.count == 0


def test_walls_a_cell_thicker_or_thinner_are_no_correction():
    """Drift between two visits thickens walls by a cell or two (within the tolerance)."""
    det = CorrectionDetector(P)
    det.observe_map(_house())
    assert det.observe_map(_house((RES, -RES))) is None
    assert det.observe_map(_house((2 * RES, 0.0))) is None


def test_a_re_render_of_only_the_part_since_the_last_closure_is_a_correction():
    """A loop closure moves the keyframes since the previous one: here the inner walls
    (about a quarter of the occupied cells) move by 0.3 m, the outer walls stay."""
    base = _house()
    moved = _house((0.3, 0.0))
    outer = _house()
    inner_only = outer.data.copy()
    # keep the outer walls of `base`, take the inner ones from `moved`
    r, c = base.world_to_cells(np.array([-3.8, 3.8]), np.array([-3.8, 3.8]))
    inner_only[r[0]:r[1], c[0]:c[1]] = moved.data[r[0]:r[1], c[0]:c[1]]
    det = CorrectionDetector(P)
    det.observe_map(base)
    share = moved_cells(occupied_xy(base), base.with_data(inner_only),
                        P.correction_map_tolerance_m) / len(occupied_xy(base))
    assert 0.1 <= share < 0.5
    assert det.observe_map(base.with_data(inner_only)) is not None


def test_ordinary_motion_is_no_jump_and_a_0_3_m_jump_is():
    det = CorrectionDetector(P)
    t, x, yaw = 0, 0.0, 0.0
    for k in range(400):                       # 20 s at 20 Hz: drive, turn on the spot
        t += NS // 20
        if k < 200:
            x += 0.26 / 20
        else:
            yaw += 2.84 / 20
        assert det.observe_pose(t, (x, 0.0, yaw)) is None
    c = det.observe_pose(t + NS // 20, (x + 0.3, 0.0, yaw))
    assert c is not None and c.source == "pose" and "0.300 m" in c.detail
    assert det.count == 1


def test_no_jump_across_a_gap_in_the_poses_or_back_in_time():
    assert pose_jump((0, (0.0, 0.0, 0.0)), (2 * NS, (0.3, 0.0, 0.0)), P) is None
    assert pose_jump((NS, (0.0, 0.0, 0.0)), (0, (0.3, 0.0, 0.0)), P) is None
    assert pose_jump((0, (0.0, 0.0, 0.0)), (NS // 20, (0.0, 0.0, 0.4)), P) is not None
    off = dataclasses.replace(P, correction_pose_jump_m=0.0, correction_pose_jump_rad=0.0)
    assert pose_jump((0, (0.0, 0.0, 0.0)), (NS // 20, (1.0, 0.0, 1.0)), off) is None


def test_one_closure_seen_in_the_pose_and_then_the_map_counts_once():
    det = CorrectionDetector(P)
    det.observe_map(dataclasses.replace(_house(), stamp_ns=0))
    det.observe_pose(10 * NS, (0.0, 0.0, 0.0))
    assert det.observe_pose(10 * NS + NS // 20, (0.3, 0.0, 0.0)) is not None
    # the next map update (5 s later) shows the same closure
    assert det.observe_map(dataclasses.replace(_house((0.3, 0.0)), stamp_ns=15 * NS)) is None
    # a later one is another correction
    assert det.observe_map(dataclasses.replace(_house(), stamp_ns=40 * NS)) is not None
    assert [c.source for c in det.take()] == ["pose", "map"]


def test_the_simulators_re_render_is_detected():
    """The mapping error model's own re-render (sim_bridge.slam_error.shift), as the node
    sees it in the published map."""
    from sim_bridge.engine import SimEngine, SimParams
    from sim_bridge.worlds import default_world

    eng = SimEngine(default_world("small_house"), SimParams(
        seed=3, compute_coverage=False, mapping_error="harsh"))
    eng.step(0.5)
    det = CorrectionDetector(P)
    det.observe_map(eng.live_map)
    eng.step(0.5)
    assert det.observe_map(eng.live_map) is None               # standing still: same map
    # 0.3 m across most of the first scan's walls (a shift along a wall slides it onto
    # itself: only its ends move)
    eng.slam_error.shift((0.0, 0.3, 0.0))
    assert det.observe_map(eng.live_map) is not None


@pytest.mark.parametrize("field,value", [("correction_map_moved_fraction", 1.5),
                                         ("correction_pose_jump_m", -0.1),
                                         ("correction_map_min_cells", 0)])
def test_bad_thresholds_are_rejected(field, value):
    with pytest.raises(ValueError, match=field):
        dataclasses.replace(P, **{field: value})


def test_a_pose_jump_carries_the_transform_a_map_moved_first_gets_it_later():
    """The pose source's correction carries after o before^-1; a correction the map
    showed first takes the jump of the pose jump merged into it while it waits."""
    import math

    from explore_seg.core.pose_fusion import compose
    d = CorrectionDetector(ObjectCostmapNodeParams())
    before, after = (1.0, 2.0, 0.3), (1.1, 2.4, 0.5)
    d.observe_pose(0, before)
    c = d.observe_pose(50_000_000, after)
    assert c is not None and c.source == "pose"
    moved = compose(c.jump, before)
    assert all(math.isclose(a, b, abs_tol=1e-12) for a, b in zip(moved, after))
    assert d.take()[0].jump == c.jump
    d2 = CorrectionDetector(ObjectCostmapNodeParams())
    d2._found(10**9, "map", "walls moved")           # the map first
    d2.observe_pose(10**9, before)
    d2.observe_pose(10**9 + 50_000_000, after)       # the same correction, merged
    (only,) = d2.take()
    assert only.source == "map" and only.jump is not None
