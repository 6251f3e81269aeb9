"""Maps, clouds and images survive real rclpy transport, in one process and across two."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import Image, PointCloud2

from explore_seg import convert
from explore_seg.core.grid import GridMap
from explore_seg.qos import MAP_QOS, RELIABLE_QOS

RNG = np.random.default_rng(3)


def _payloads():
    grid = GridMap(RNG.integers(-1, 101, (120, 90)).astype(np.int8), 0.05, (-2.0, 3.5), 0.3,
                   "map", 42_000_000_123)
    cloud = convert.xyz_cloud(RNG.random((500, 3)), {"group_id": RNG.integers(0, 9, 500)})
    depth = (RNG.random((48, 64)) * 4).astype(np.float32)
    return grid, cloud, depth


def _check(received, grid, cloud, depth):
    g = convert.grid_from_msg(received["map"])
    np.testing.assert_array_equal(g.data, grid.data)
    assert g.same_geometry(grid) and g.stamp_ns == grid.stamp_ns
    c = convert.cloud_from_msg(received["cloud"])
    for name in cloud.dtype.names:
        np.testing.assert_array_equal(c[name], cloud[name])
    np.testing.assert_array_equal(convert.image_from_msg(received["image"]), depth)


def _publish_all(pubs, grid, cloud, depth):
    pubs["map"].publish(convert.grid_to_msg(grid))
    pubs["cloud"].publish(convert.cloud_to_msg(cloud, convert.make_header("map", 7)))
    pubs["image"].publish(convert.image_to_msg(depth, "32FC1", convert.make_header("camera", 7)))


def _endpoints(node, suffix):
    received = {}
    subs = []
    pubs = {}
    for topic, typ, qos in (("map", OccupancyGrid, MAP_QOS), ("cloud", PointCloud2, RELIABLE_QOS),
                            ("image", Image, RELIABLE_QOS)):
        pubs[topic] = node.create_publisher(typ, topic, qos)
        subs.append(node.create_subscription(
            typ, topic + suffix, lambda m, t=topic: received.__setitem__(t, m), qos))
    return pubs, received


def test_same_process_publisher_to_subscriber_node(ros):
    grid, cloud, depth = _payloads()
    pub_node = ros.node("pub_node")
    sub_node = ros.node("sub_node")
    pubs, _ = _endpoints(pub_node, "_unused")
    received = {}
    for topic, typ, qos in (("map", OccupancyGrid, MAP_QOS), ("cloud", PointCloud2, RELIABLE_QOS),
                            ("image", Image, RELIABLE_QOS)):
        sub_node.create_subscription(typ, topic, lambda m, t=topic: received.__setitem__(t, m), qos)
    ros.spin_until(lambda: all(p.get_subscription_count() > 0 for p in pubs.values()),
                   what="subscriptions to match")
    _publish_all(pubs, grid, cloud, depth)
    ros.spin_until(lambda: len(received) == 3, what=f"map+cloud+image (got {sorted(received)})")
    _check(received, grid, cloud, depth)


def test_latched_map_reaches_late_subscriber(ros):
    grid, _, _ = _payloads()
    pub = ros.node("latch_pub").create_publisher(OccupancyGrid, "map", MAP_QOS)
    pub.publish(convert.grid_to_msg(grid))
    got = []
    ros.node("late_sub").create_subscription(OccupancyGrid, "map", got.append, MAP_QOS)
    ros.spin_until(lambda: bool(got), what="the latched map")
    np.testing.assert_array_equal(convert.grid_from_msg(got[0]).data, grid.data)


def test_across_two_processes(ros):
    grid, cloud, depth = _payloads()
    script = Path(__file__).parent / "procs" / "echo_node.py"
    env = dict(os.environ)
    proc = subprocess.Popen([sys.executable, str(script), "--timeout", "60"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        node = ros.node("two_proc_test")
        pubs, received = _endpoints(node, "_echo")
        ros.spin_until(lambda: all(p.get_subscription_count() > 0 for p in pubs.values()),
                       timeout_s=30, what="the echo process's subscriptions")
        ros.spin_until(lambda: node.count_publishers("map_echo") > 0, timeout_s=30,
                       what="the echo process's publishers")
        _publish_all(pubs, grid, cloud, depth)
        ros.spin_until(lambda: len(received) == 3, timeout_s=30,
                       what=f"echoes from the other process (got {sorted(received)})")
        _check(received, grid, cloud, depth)
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            pytest.fail("echo process did not exit on SIGTERM")
    assert proc.returncode == 0, proc.stdout.read() if proc.stdout else ""
