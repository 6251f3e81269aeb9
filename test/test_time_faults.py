"""Time faults in the map consumers (issue 24): simulator restart (map stamps and clock
going back), a future-stamped map, an object layer on another time base; and the
selector's clock reset. Callbacks and ticks are driven directly (deterministic)."""

from __future__ import annotations

import numpy as np
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.core.grid import grid_from_ascii
from test_robustness import Log, _odom, _selector
from test_segmentation import two_rooms

S = 1_000_000_000

# A corridor open to unknown space at its right end; the object layer below walls it off.
CORRIDOR = "\n".join(["############"] + ["#..........?"] * 12 + ["############"])


def _segmentation(ros):
    from explore_seg.segmentation_node import SegmentationNode

    node = ros.add(SegmentationNode(context=ros.context,
                                    parameter_overrides=[Parameter("tau_m", value=2.5)]))
    node._warn = Log()
    return node


def _segment(node, grid, t_ns: int) -> str:
    node._on_map(convert.grid_to_msg(grid, stamp=t_ns))
    node._tick()
    return node.segmenter.last_update_info.mode


def test_segmentation_restarts_from_scratch_when_the_map_stamps_go_back(ros):
    node = _segmentation(ros)
    grid = two_rooms(door_at_end=True)
    assert _segment(node, grid, 100 * S) == "full"
    assert _segment(node, grid, 101 * S) == "unchanged"
    assert _segment(node, grid, 2 * S) == "full"            # the simulator restarted
    assert "map stamps jumped back (simulator restart or clock reset?) by 99.0 s" in \
        node._warn.text("jump_map")
    assert "segmented from scratch" in node._warn.text("jump_map")
    labels = node.last_labels
    assert len(np.unique(labels[labels > 0])) == 2 and node.time_jumps == 1


def test_segmentation_after_a_future_stamped_map_follows_the_normal_stamps(ros):
    node = _segmentation(ros)
    grid = two_rooms(door_at_end=True)
    _segment(node, grid, 100 * S)
    _segment(node, grid, 90_000 * S)                         # one far-future stamp
    assert "jumped ahead" in node._warn.text("jump_map")
    assert _segment(node, grid, 101 * S) == "full"           # back on the normal time line
    assert _segment(node, grid, 102 * S) == "unchanged"     # ... and incremental again
    assert node.time_jumps == 2


def _frontier_node(ros):
    from explore_seg.frontier_node import FrontierDetectorNode

    node = ros.add(FrontierDetectorNode(context=ros.context))
    node._warn = Log()
    return node


def _corridor():
    grid = grid_from_ascii(CORRIDOR, resolution_m=0.1)[0]
    wall = np.zeros_like(grid.data)
    wall[:, -3] = 100                                        # blocks the open end
    return grid, grid.with_data(wall)


def test_frontier_detector_drops_the_layer_of_the_old_time_line(ros):
    node = _frontier_node(ros)
    grid, layer = _corridor()
    node._on_map(convert.grid_to_msg(grid, stamp=500 * S))
    node._on_layer(convert.grid_to_msg(layer, stamp=500 * S))
    node._tick()
    assert [f.point_passable for f in node.frontiers] == [False]   # walled off by it
    node._on_map(convert.grid_to_msg(grid, stamp=3 * S))     # simulator restart
    node._tick()
    assert [f.point_passable for f in node.frontiers] == [True]    # old layer not used
    assert "object layer of the old time line dropped" in node._warn.text("jump_map")


def test_frontier_detector_reports_a_layer_on_another_time_base(ros):
    node = _frontier_node(ros)
    grid, layer = _corridor()
    node._on_map(convert.grid_to_msg(grid, stamp=3700 * S))
    node._on_layer(convert.grid_to_msg(layer, stamp=100 * S))
    node._tick()
    assert ("clock sources disagree: map stamps are 3600.0 s ahead of object_costmap"
            in node._warn.text("layer_time"))


def test_selector_clock_reset_forgets_the_pose_and_restarts_the_goal_timers(ros):
    node = _selector(ros)
    node._check_clock(1000 * S)
    node._on_map(convert.grid_to_msg(_corridor()[0], stamp=1000 * S))
    node._pose_in._on_odom(_odom(1000 * S, x=0.5))
    assert node._pose is not None
    node._check_clock(4 * S)                                 # /clock restarted
    assert node._pose is None
    assert "clock stamps jumped back" in node._warn.text("clock_jump")
    assert "goal timers restarted" in node._warn.text("clock_jump")
