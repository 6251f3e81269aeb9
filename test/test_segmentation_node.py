"""``segmentation`` node: map in, regions + info + colour grid + timing out."""

from __future__ import annotations

import numpy as np
import pytest
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.qos import MAP_QOS
from test_segmentation import two_rooms


@pytest.fixture
def setup(ros):
    from nav_msgs.msg import MapMetaData, OccupancyGrid
    from sensor_msgs.msg import Image
    from std_msgs.msg import Float64

    from explore_seg.segmentation_node import SegmentationNode

    node = ros.add(SegmentationNode(context=ros.context, parameter_overrides=[
        Parameter("tau_m", value=2.5), Parameter("process_period_s", value=0.02)]))
    helper = ros.node("seg_test_helper")
    got: dict[str, list] = {"regions": [], "info": [], "color": [], "timing": []}
    helper.create_subscription(Image, "regions", got["regions"].append, MAP_QOS)
    helper.create_subscription(MapMetaData, "regions/info", got["info"].append, MAP_QOS)
    helper.create_subscription(OccupancyGrid, "regions/color", got["color"].append, MAP_QOS)
    helper.create_subscription(Float64, "segmentation/timing", got["timing"].append, 10)
    pub = helper.create_publisher(OccupancyGrid, "map", MAP_QOS)
    return node, pub, got


def test_map_gives_regions_with_the_map_stamp(ros, setup):
    node, pub, got = setup
    grid = two_rooms(door_at_end=True)
    msg = convert.grid_to_msg(grid, stamp=12_345_000_000)
    msg.header.frame_id = "map"
    pub.publish(msg)
    ros.spin_until(lambda: got["regions"] and got["info"] and got["color"] and got["timing"],
                   what="regions, regions/info, regions/color and timing")
    img, info = got["regions"][-1], got["info"][-1]
    assert img.header.stamp.sec == 12 and img.header.frame_id == "map"
    assert info.map_load_time == img.header.stamp
    labels, geom = convert.labels_from_msgs(img, info)
    assert labels.shape == grid.shape and geom.resolution_m == pytest.approx(0.05)
    assert len(np.unique(labels[labels > 0])) == 2
    assert (labels[grid.data != 0] == 0).all()
    color = convert.grid_from_msg(got["color"][-1])
    assert ((color.data > 0) == (labels > 0)).all()
    assert got["timing"][-1].data > 0
    assert node.processed == 1


def test_stale_maps_are_skipped_and_bad_maps_dropped(ros, setup):
    node, pub, got = setup
    grid = two_rooms(door_at_end=False)
    bad = convert.grid_to_msg(grid, stamp=1)
    bad.info.width += 1                               # data length no longer matches
    node._on_map(bad)                                 # noqa: SLF001 - direct injection
    node._on_map(convert.grid_to_msg(grid, stamp=2_000_000_000))   # newer one replaces it
    assert node.skipped == 1
    ros.spin_until(lambda: got["regions"], what="regions after a stale map")
    assert got["regions"][-1].header.stamp.sec == 2
    node._on_map(bad)
    ros.spin_until(lambda: node._latest is None, what="the bad map being consumed")  # noqa: SLF001
    assert node.processed == 1                        # dropped, last good state kept
    assert len(got["regions"]) == 1


def test_parameter_change_is_validated(ros, setup):
    node, _pub, _got = setup
    ok = node.set_parameters([Parameter("tau_m", value=3.0)])
    assert ok[0].successful and node.params.tau_m == 3.0
    assert node.segmenter.params.tau_m == 3.0
    bad = node.set_parameters([Parameter("tau_m", value=-1.0)])
    assert not bad[0].successful and "tau_m" in bad[0].reason


def test_failsafe_a_failing_update_is_logged_and_the_node_goes_on(ros, setup, monkeypatch):
    """An exception in the segmenter costs one cycle (logged, counted); the node keeps
    its last regions, restarts the segmenter from scratch and segments the next map."""
    node, pub, got = setup
    monkeypatch.delenv("EXPLORE_SEG_STRICT")
    seg = node.segmenter
    real = seg.update
    calls = []

    def broken(grid):
        calls.append(1)
        raise ValueError("boom")

    monkeypatch.setattr(seg, "update", broken)
    grid = two_rooms(door_at_end=True)
    pub.publish(convert.grid_to_msg(grid, stamp=1_000_000_000))
    ros.spin_until(lambda: node.failures == 1, what="the failed update")
    assert node.processed == 0 and not got["regions"] and seg._force_full  # noqa: SLF001
    monkeypatch.setattr(seg, "update", real)
    pub.publish(convert.grid_to_msg(grid, stamp=2_000_000_000))
    ros.spin_until(lambda: got["regions"], what="regions after the failure")
    assert node.processed == 1 and node.failures == 1 and len(calls) == 1


def test_failsafe_strict_mode_lets_the_exception_through(monkeypatch):
    from explore_seg.node_util import failsafe

    class Fake:
        def get_logger(self):
            raise AssertionError("not logged in strict mode")

        @failsafe("work")
        def tick(self):
            raise ValueError("boom")

    monkeypatch.setenv("EXPLORE_SEG_STRICT", "1")
    with pytest.raises(ValueError, match="boom"):
        Fake().tick()


def test_failsafe_guards_the_periodic_work_of_every_node():
    from explore_seg.frontier_node import FrontierDetectorNode
    from explore_seg.object_costmap_node import ObjectCostmapNode
    from explore_seg.segmentation_node import SegmentationNode
    from explore_seg.selector_node import TargetSelectorNode

    for cls in (FrontierDetectorNode, ObjectCostmapNode, SegmentationNode, TargetSelectorNode):
        assert getattr(cls._tick, "__wrapped__", None) is not None, cls.__name__
