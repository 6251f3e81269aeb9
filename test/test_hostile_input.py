"""Regression tests of issue 54's findings (a hostile-input run over real topics with maps
like slam_toolbox's): empty maps, slow map publishers, odometry ahead of the camera, bad
laser scans, the frame-lag warning's cause. Each test failed on the code before its fix
(see the commit message)."""

from __future__ import annotations

import array

import pytest
from nav_msgs.msg import OccupancyGrid
from rclpy.parameter import Parameter
from rclpy.time import Time as RosTime

from explore_seg import convert
from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.limits import InputLimits
from explore_seg.qos import MAP_QOS
from fuzz_support import LogCapture, tick

S = 1_000_000_000

# A corridor open to unknown space at its right end: frontiers and one region.
CORRIDOR = "\n".join(["############"] + ["#..........?"] * 12 + ["############"])


def _corridor():
    return grid_from_ascii(CORRIDOR, resolution_m=0.1)[0]


def _empty_map_msg(width: int, height: int, stamp_ns: int) -> OccupancyGrid:
    msg = convert.grid_to_msg(_corridor(), stamp=stamp_ns)
    msg.info.width, msg.info.height = width, height
    msg.data = array.array("b", [])
    return msg


# ------------------------------------------------------------------ finding 1
@pytest.mark.parametrize("width, height", [(0, 0), (0, 100), (100, 0)])
def test_grid_from_msg_rejects_an_empty_map(width, height):
    with pytest.raises(ValueError, match=rf"map size must be at least 1x1 cells, got "
                                         rf"{width}x{height}"):
        convert.grid_from_msg(_empty_map_msg(width, height, S))
    with pytest.raises(ValueError, match=r"at least 1x1 cells, got 0x3"):
        InputLimits().check_map_size(0, 3, 0.05)


@pytest.mark.parametrize("width, height", [(0, 0), (0, 100)])
def test_an_empty_map_on_the_topic_keeps_the_last_good_one_in_every_node(ros, width, height):
    from sensor_msgs.msg import Image

    from explore_seg.frontier_node import FrontierDetectorNode
    from explore_seg.segmentation_node import SegmentationNode
    from explore_seg.selector_node import TargetSelectorNode

    fd = ros.add(FrontierDetectorNode(context=ros.context))
    seg = ros.add(SegmentationNode(context=ros.context,
                                   parameter_overrides=[Parameter("tau_m", value=2.5)]))
    sel = ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=[
        Parameter("strategy", value="nearest"), Parameter("nav_action", value="")]))
    logs = {n.get_name(): LogCapture(n) for n in (fd, seg, sel)}
    helper = ros.node("hostile_map_publisher")
    pub = helper.create_publisher(OccupancyGrid, "map", MAP_QOS)
    regions: list[Image] = []
    helper.create_subscription(Image, "regions", regions.append, MAP_QOS)

    good = _corridor()
    pub.publish(convert.grid_to_msg(good, stamp=1 * S))
    ros.spin_until(lambda: fd.runs >= 1 and seg.processed >= 1 and sel._grid is not None
                   and regions, 30.0, "the good map in all three nodes and a regions image")
    n_frontiers, runs, processed = len(fd.frontiers), fd.runs, seg.processed
    assert n_frontiers > 0

    pub.publish(_empty_map_msg(width, height, 2 * S))

    def dropped_by_all() -> bool:
        return all(any("dropped map" in m for _, m in log.lines) for log in logs.values())
    ros.spin_until(dropped_by_all, 30.0, "a 'dropped map' line from every node")
    ros.spin_for(0.5)
    for name, log in logs.items():
        text = "\n".join(m for _, m in log.lines if "dropped map" in m)
        assert f"map size must be at least 1x1 cells, got {width}x{height}" in text, name
    assert fd._grid.shape == good.shape and fd.runs == runs          # noqa: SLF001
    assert len(fd.frontiers) == n_frontiers
    assert seg.processed == processed and seg.last_labels.shape == good.shape
    assert sel._grid.shape == good.shape                              # noqa: SLF001
    assert all((img.height, img.width) == good.shape for img in regions)


# ------------------------------------------------------------------ finding 2
def _on_sim_time(node, t_ns: int) -> None:
    """Set the node's ROS clock to ``t_ns`` (simulated time, no /clock publisher)."""
    clock = node.get_clock()
    clock._set_ros_time_is_active(True)                               # noqa: SLF001
    clock.set_ros_time_override(RosTime(nanoseconds=t_ns))


def _slow_maps(node, on_map, period_s: float, maps: int, tick_s: float,
               start_ns: int = 1000 * S, lag_ns: int = S // 5) -> int:
    """Run ``node`` on a clock that steps ``tick_s`` per tick; every ``period_s`` a map
    stamped ``lag_ns`` before the clock arrives (a SLAM map's true stamp). Returns the
    clock at the end (ns)."""
    grid = _corridor()
    t = start_ns
    for _ in range(maps):
        _on_sim_time(node, t)
        on_map(convert.grid_to_msg(grid, stamp=t - lag_ns))
        for _ in range(int(round(period_s / tick_s))):
            tick(node)
            t += int(tick_s * S)
            _on_sim_time(node, t)
    return t


@pytest.mark.parametrize("which", ["frontier_detector", "segmentation"])
def test_maps_every_6_s_with_true_stamps_are_no_clock_jump(ros, which):
    from explore_seg.frontier_node import FrontierDetectorNode
    from explore_seg.segmentation_node import SegmentationNode

    sim = Parameter("use_sim_time", value=True)
    if which == "frontier_detector":
        node = ros.add(FrontierDetectorNode(context=ros.context, parameter_overrides=[sim]))
        tick_s = 1.0 / node.node_params.rate_hz
    else:
        node = ros.add(SegmentationNode(context=ros.context, parameter_overrides=[
            sim, Parameter("tau_m", value=2.5)]))
        tick_s = node.params.process_period_s
    log = LogCapture(node)
    t = _slow_maps(node, node._on_map, 6.0, 5, tick_s)                # noqa: SLF001
    assert node.time_jumps == 0, "\n".join(m for _, m in log.lines)
    assert not [m for _, m in log.lines if "jumped" in m]
    # A real jump is still one: stamps 60 s ahead of a clock that moved on 1 tick.
    _on_sim_time(node, t)
    node._on_map(convert.grid_to_msg(_corridor(), stamp=t + 60 * S))   # noqa: SLF001
    tick(node)
    assert node.time_jumps == 1
    assert any("map stamps jumped ahead" in m and "by 66.2 s: 1023.800 -> 1090.000 s" in m
               for _, m in log.lines)


# ------------------------------------------------------------------ finding 5
def test_a_bad_scan_is_dropped_at_once_and_the_last_good_one_kept(ros):
    from test_robustness import _costmap

    node = _costmap(ros, unknown_enabled=True)
    header = convert.make_header("base_scan", 10 * S)
    good = convert.scan_to_msg([1.0, 2.0, 1.5], -0.1, 0.1, 0.1, 10.0, header)
    node._on_scan(good)                                               # noqa: SLF001
    bad = convert.scan_to_msg([], 0.0, 0.1, 0.1, 10.0, header)
    node._on_scan(bad)                                                # noqa: SLF001
    assert node.dropped["scan"] == 1 and "scan has no ranges" in node.last_drop["scan"]
    assert "dropped scan: scan has no ranges" in node._warn.text("scan")
    # every later frame uses the good scan: nothing is re-reported
    for _ in range(3):
        pts = node._scan_points(10 * S, (0.0, 0.0, 0.0))              # noqa: SLF001
        assert pts is not None and len(pts) == 3
    assert node.dropped["scan"] == 1


def _frames_without_poses(node, pose_ns: int, frame_ns: int, n: int) -> None:
    """Odometry around ``pose_ns``; ``n`` camera frames from ``frame_ns``, 0.5 s apart,
    each taken (and dropped) by a tick."""
    from test_robustness import _frame, _odom

    for k in range(5):
        node._pose_in._on_odom(_odom(pose_ns + k * S // 10))         # noqa: SLF001
    for k in range(n):
        _frame(node, frame_ns + k * S // 2)
        node._tick()                                                  # noqa: SLF001


@pytest.mark.parametrize("cause", ["no_pose", "malformed"])
def test_the_frame_lag_warning_names_the_real_cause(ros, cause):
    from test_robustness import K, Log, _costmap

    node = _costmap(ros)
    node._info = K                                                    # noqa: SLF001
    node._warn_lag = Log()                                            # noqa: SLF001
    if cause == "no_pose":
        _frames_without_poses(node, 100_000 * S, 10 * S, 4)          # odometry far ahead
    else:
        _frames_without_poses(node, 10 * S, 10 * S, 1)               # mono8 depth: malformed
    assert node.frames_processed == 0
    # the lag window (20 s) began before these frames: judge it now
    now = node.get_clock().now().nanoseconds
    node._lag_mark = (now - 25 * S, 0, 0, 0, 0)                      # noqa: SLF001
    node._check_lag()                                                 # noqa: SLF001
    text = node._warn_lag.text("lag")                                 # noqa: SLF001
    n = node.frames_received
    assert f"processed 0 of {n} camera frames" in text
    assert "lags behind" not in text and "process of its own" not in text
    if cause == "no_pose":
        assert f"{n} had no robot pose at their stamp" in text and "pose source" in text
    else:
        assert f"{n} malformed" in text and "cannot be used" in text


def test_the_frame_lag_warning_still_blames_the_cpu_when_frames_are_not_reached(ros):
    from test_robustness import Log, _costmap

    node = _costmap(ros)
    node._warn_lag = Log()                                            # noqa: SLF001
    now = node.get_clock().now().nanoseconds
    node._lag_mark = (now - 25 * S, 50, 40, 0, 0)                    # noqa: SLF001
    node.frames_received, node.frames_processed = 100, 50             # 10 of 50 possible
    node.frames_malformed = 2
    node._check_lag()                                                 # noqa: SLF001
    text = node._warn_lag.text("lag")                                 # noqa: SLF001
    assert "processed 10 of 50 camera frames" in text and "2 malformed" in text
    assert "38 not reached in time" in text and "lags behind the robot" in text


# ------------------------------------------------------------------ finding 3
def test_odometry_ahead_of_the_camera_is_diagnosed_like_odometry_behind(ros):
    from test_robustness import K, _costmap

    node = _costmap(ros, **{"input.stall_periods": 2})
    node._info = K                                                    # noqa: SLF001
    _frames_without_poses(node, 100_000 * S, 10 * S, 8)              # odometry 1e5 s ahead
    assert node.frames_processed == 0
    skew = "clock sources disagree: camera stamps are 99986.9 s behind pose stamps"
    assert skew in node.last_drop["frame"]                            # the throttled drop line
    stall = node._warn.text("stall")
    assert "no pose older than image stamp 13.500 s (oldest pose 100000.000 s" in stall
    assert skew in stall
