"""Regression tests of issue 24's findings: time faults and hostile input.

Each test drives a node's callbacks directly (no spinning: deterministic and fast) and
failed on the code before the fix (see the commit message).
"""

from __future__ import annotations

import time
import tracemalloc

import numpy as np
import pytest
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.core.camera import CameraIntrinsics
from explore_seg.core.explorer import detect_frontiers
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import GridMap
from explore_seg.core.limits import InputLimits
from explore_seg.core.paths import inflate

S = 1_000_000_000
K = CameraIntrinsics(fx=2.0, fy=2.0, cx=1.0, cy=1.0, width=2, height=2)


class Log:
    """Stands in for a node's WarnThrottle: records (key, text)."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, str]] = []

    def __call__(self, key: str, msg: str) -> None:
        self.lines.append((key, msg))

    def text(self, key: str) -> str:
        return "\n".join(m for k, m in self.lines if k == key)


def _costmap(ros, **extra):
    from explore_seg.object_costmap_node import ObjectCostmapNode

    params = {"detector.backend": "oracle", "rate_hz": 2.0, **extra}
    node = ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=[
        Parameter(k, value=v) for k, v in params.items()]))
    node._warn = Log()
    return node


def _frame(node, t_ns: int) -> None:
    """A colour/depth/semantic triple stamped t_ns through the node's callbacks."""
    header = convert.make_header("camera", 0)
    header.stamp = convert.Time(sec=t_ns // S, nanosec=t_ns % S)
    img = convert.image_to_msg(np.zeros((2, 2), np.uint8), "mono8", header)
    node._on_depth(img)
    node._on_color(img)
    node._on_semantic(img)


def _odom(t_ns: int, x: float = 0.0, frame: str = "map", sec: int | None = None) -> Odometry:
    msg = convert.odometry_msg((x, 0.0, 0.0), (0.0, 0.0), frame, "base_link", 0)
    msg.header.stamp.sec = t_ns // S if sec is None else sec
    msg.header.stamp.nanosec = t_ns % S
    return msg


def _paired_stamp(node) -> int | None:
    pair = node._newest_pair()
    return None if pair is None else convert.stamp_to_ns(pair[0].header.stamp)


# ------------------------------------------------------------------ finding 1
def test_a_future_stamped_frame_does_not_stop_the_object_costmap(ros):
    node = _costmap(ros)
    future = 5000 * S
    _frame(node, future)
    node._last_depth_ns = future            # ... it was processed
    for k in range(5):
        node._pose_in._on_odom(_odom(100 * S + k * S // 10))
    _frame(node, 100 * S + 2 * S // 10)
    assert _paired_stamp(node) == 100 * S + 2 * S // 10
    assert "jumped back" in node._warn.text("jump_camera")


def test_a_sim_clock_reset_resets_stamps_poses_and_pending_frames(ros):
    node = _costmap(ros)
    for k in range(5):
        node._pose_in._on_odom(_odom(300 * S + k * S // 10))
    _frame(node, 300 * S + 3 * S // 10)
    node._last_depth_ns = 300 * S + 3 * S // 10
    # the simulator restarts: its clock begins again at 1 s
    for k in range(3):
        node._pose_in._on_odom(_odom(1 * S + k * S // 10, x=2.0))
    _frame(node, 1 * S + S // 10)
    assert _paired_stamp(node) == 1 * S + S // 10
    assert node._pose_in.newest_ns() < 2 * S               # the old time line is gone
    assert node._pose_at(300 * S) is None
    assert node._pose_at(1 * S + S // 10)[0] == pytest.approx(2.0)


def test_a_clock_jump_back_restamps_the_objects_and_depth_voxels(ros):
    """Boxes and voxels of the old time line are kept and restamped to the new time, so
    that decay and corrections judge them on it (before, voxels stamped 300 s stayed
    until the new clock reached 300 s + depth_decay_s)."""
    from objects_scene import make_obj

    node = _costmap(ros)
    objects = node._objects
    objects.update([make_obj(2.0, 0.0, "chair")], None, 300 * S)
    depth = objects.depth
    assert depth is not None
    depth._keys, depth._score, depth._stamp = (np.array([7], np.int64),
                                               np.array([1], np.int16), np.array([300.0]))
    for k in range(5):
        node._pose_in._on_odom(_odom(300 * S + k * S // 10))
    for k in range(3):                                   # the simulator restarts at 1 s
        node._pose_in._on_odom(_odom(1 * S + k * S // 10, x=2.0))
    assert [t.last_seen_ns for t in objects.tracked] == [1 * S]
    assert depth._stamp.tolist() == [1.0] and len(depth) == 1
    assert any("restamped" in m for k, m in node._warn.lines if k.startswith("jump_"))


# ------------------------------------------------------------------ finding 2
def test_odometry_on_another_time_base_is_reported_by_the_stall_watchdog(ros):
    node = _costmap(ros, **{"input.stall_periods": 2})
    node._info = K
    for k in range(5):
        node._pose_in._on_odom(_odom(100 * S + k * S // 10))         # an hour behind the camera
    for k in range(8):
        _frame(node, 3700 * S + k * S // 2)
        node._tick()
    text = node._warn.text("stall")
    assert "no pose newer than image stamp 3703.500 s (newest pose 100.400 s" in text
    assert "clock sources disagree: camera stamps are 3603.1 s ahead of pose" in text
    assert node.frames_processed == 0


def test_a_buffer_of_processed_frames_is_no_stall(ros):
    # After the last frame was processed, the buffer still holds it (and older ones): no
    # frame is due, so the watchdog stays quiet until a frame a period later waits.
    node = _costmap(ros, **{"input.stall_periods": 2})
    node._info = K
    for k in range(5):
        node._pose_in._on_odom(_odom(5 * S + k * S // 10))          # poses end at 5.4 s
    for k in range(3):
        _frame(node, 10 * S + k * S // 2)
    node._last_depth_ns = 11 * S                          # the newest one was processed
    for _ in range(8):                                    # stall_periods x 4 ticks
        node._tick()
    assert node._warn.text("stall") == ""
    _frame(node, 11 * S + S // 2)                         # due, but no pose reaches it
    for _ in range(8):                                    # stall_periods x 4 ticks
        node._tick()
    assert "no pose newer than image stamp 11.500 s" in node._warn.text("stall")


# ------------------------------------------------------------------ finding 3
def _selector(ros, **extra):
    from explore_seg.selector_node import TargetSelectorNode

    node = ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=[
        Parameter(k, value=v) for k, v in extra.items()]))
    node._warn = Log()
    return node


def test_regions_info_is_validated_before_anything_of_its_size_is_allocated(ros):
    node = _selector(ros)
    grid = GridMap(np.zeros((10, 10), np.int8), 0.05)
    img, info = convert.labels_to_msgs(np.ones((10, 10), np.int32), grid)
    info.width = info.height = 4000                          # claims 16e6 cells
    node._on_map(convert.grid_to_msg(grid))
    node._on_regions(img)
    node._on_regions_info(info)
    tracemalloc.start()
    try:
        node._update_labels(node._grid)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1_000_000, f"{peak} bytes allocated for a 10x10 label image"
    assert node._labels is None
    assert "labels image is 10x10, map info says 4000x4000" in node._warn.text("regions")


def test_max_map_cells_rejects_a_map_before_it_is_built():
    grid = GridMap(np.zeros((50, 40), np.int8), 0.05)
    with pytest.raises(ValueError, match=r"40x50 = 2000 cells, more than input.max_map_cells"):
        convert.grid_from_msg(convert.grid_to_msg(grid), InputLimits(max_map_cells=1999))


# ------------------------------------------------------------------ finding 4
def test_a_tiny_resolution_map_is_rejected_by_the_selector(ros):
    node = _selector(ros)
    grid = GridMap(np.zeros((80, 140), np.int8), 1e-4)
    t0 = time.perf_counter()
    node._on_map(convert.grid_to_msg(grid))
    assert time.perf_counter() - t0 < 1.0
    assert node._grid is None
    assert "below input.min_resolution_m" in node._warn.text("map")


def test_inflation_with_a_huge_kernel_is_bounded_and_exact():
    blocked = np.zeros((80, 140), bool)
    blocked[40, 70] = True
    tracemalloc.start()
    try:
        t0 = time.perf_counter()
        out = inflate(blocked, 0.22, 1e-4)                  # 2200 cells
        dt = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert out.all() and dt < 1.0 and peak < 5_000_000
    rng = np.random.default_rng(3)
    blocked = rng.random((120, 90)) < 0.003
    ref = inflate(blocked, 32 * 0.05, 0.05)                  # kernel path (32 cells)
    grown = inflate(blocked, 40 * 0.05, 0.05)                # distance-transform path
    yy, xx = np.nonzero(blocked)
    rr, cc = np.mgrid[:120, :90]
    d2 = ((rr[..., None] - yy) ** 2 + (cc[..., None] - xx) ** 2).min(axis=-1)
    np.testing.assert_array_equal(grown, d2 <= 40 * 40)
    np.testing.assert_array_equal(ref, d2 <= 32 * 32)


def test_a_map_spanning_more_than_the_coordinate_limit_is_rejected():
    # found by the fuzz suite: resolution 1e300 passed, and cell centres became inf/NaN
    grid = GridMap(np.zeros((4, 3), np.int8), 0.05)
    msg = convert.grid_to_msg(grid)
    msg.info.resolution = 1e300
    with pytest.raises(ValueError, match=r"map spans 4e\+300 m \(3x4 cells at 1e\+300 m\)"):
        convert.grid_from_msg(msg)
    msg.info.resolution = 0.05
    assert convert.grid_from_msg(msg).same_geometry(grid)


# ------------------------------------------------------------------ finding 5
def test_a_negative_stamp_is_rejected_at_the_boundary(ros):
    grid = GridMap(np.zeros((5, 5), np.int8), 0.05)
    msg = convert.grid_to_msg(grid)
    msg.header.stamp.sec = -3
    with pytest.raises(ValueError, match=r"header.stamp must be >= 0.*sec=-3"):
        convert.grid_from_msg(msg)
    node = _costmap(ros)
    node._pose_in._on_odom(_odom(0, sec=-1))
    header = convert.make_header("camera", 0)
    header.stamp.sec = -7
    node._on_depth(convert.image_to_msg(np.zeros((2, 2), np.uint8), "mono8", header))
    assert not node._depths and node._pose_in.latest() is None
    assert "sec=-7" in node.last_drop["camera"] and "sec=-1" in node.last_drop["pose"]


# ------------------------------------------------------------------ finding 6
@pytest.mark.parametrize("x", [1e300, 1e308, -2e5])
def test_absurd_poses_are_dropped_by_the_selector_and_the_object_costmap(ros, x):
    sel = _selector(ros)
    sel._pose_in._on_odom(_odom(S, x=x))
    assert sel._pose is None and "input.max_coordinate_m" in sel._warn.text("pose")
    cm = _costmap(ros)
    cm._pose_in._on_odom(_odom(S, x=x))
    assert cm._pose_in.latest() is None and "input.max_coordinate_m" in cm.last_drop["pose"]


def test_poses_far_outside_the_map_are_dropped_by_the_selector_and_the_object_costmap(ros):
    grid = GridMap(np.zeros((40, 60), np.int8), 0.05, (1.0, -1.0))    # x 1..4, y -1..1 m
    sel = _selector(ros, **{"input.pose_map_margin_m": 2.0})
    cm = _costmap(ros, **{"input.pose_map_margin_m": 2.0})
    for node in (sel, cm):
        node._on_map(convert.grid_to_msg(grid))
        node._pose_in._on_odom(_odom(S, x=5.5))                       # 1.5 m beyond x = 4: kept
        node._pose_in._on_odom(_odom(S + S // 10, x=168.4))           # 164 m beyond: dropped
    assert sel._pose[0] == pytest.approx(5.5)
    assert "pose (168.400, 0.000) lies 164.40 m outside the map (x 1.00..4.00, y " \
           "-1.00..1.00 m), more than input.pose_map_margin_m = 2 m" in sel._warn.text("pose")
    assert cm._pose_in.latest()[1][0] == pytest.approx(5.5)     # the far one was not taken
    assert "164.40 m outside the map" in cm.last_drop["pose"]


# ------------------------------------------------------------------ finding 7
def test_the_simulator_logs_a_repeated_goal_once(ros, tmp_path):
    from sim_bridge.node import SimBridgeNode

    node = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"),
        Parameter("output_dir", value=str(tmp_path))]))
    infos: list[str] = []
    logger = node.get_logger()
    logger.info = lambda msg, **kw: infos.append(msg)
    x, y = node.engine.pose[:2]
    for _ in range(40):                      # a planner re-sending its goal at 40 Hz
        node._on_goal(convert.pose_stamped(x + 0.3, y, 0.0, "map"))
    assert sum(m.startswith("goal (") for m in infos) == 1


def test_the_selector_drops_odometry_in_another_frame(ros):
    node = _selector(ros)
    node._on_map(convert.grid_to_msg(GridMap(np.zeros((10, 10), np.int8), 0.05)))
    node._pose_in._on_odom(_odom(S, frame="odom"))
    assert node._pose is None
    assert "pose frame must be 'map' (the map's), got 'odom'" in node._warn.text("pose")
    node._pose_in._on_odom(_odom(S, frame="/map"))
    assert node._pose is not None


def test_a_layer_in_frame_slash_map_is_used_with_a_map_in_frame_map():
    data = np.zeros((20, 20), np.int8)
    grid = GridMap(data, 0.1, frame_id="map")
    layer = GridMap(data, 0.1, frame_id="/map")
    det = detect_frontiers(grid, layer, FrontierParams())
    assert det.layer_warning == ""
    msg = convert.grid_to_msg(grid)
    msg.header.frame_id = "/map"
    assert convert.grid_from_msg(msg).same_geometry(grid)

