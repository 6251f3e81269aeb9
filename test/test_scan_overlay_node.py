"""target_selector's ``scan`` subscription: scans since the map fill its unknown cells."""

from __future__ import annotations

import math

from test_frontier_nodes import feed, start_selector

# An unknown band (columns 6-8) the robot's lidar sees through, and the map's open end
# (column 13, its border) that no scan can fill.
BAND = """
##############
#.....???....?
#.....???....?
#..R..???....?
#.....???....?
#.....???....?
##############
"""


def _scan_msg(stamp_ns: int, range_max: float = 2.0):
    from sensor_msgs.msg import LaserScan

    from explore_seg import convert

    msg = LaserScan()
    msg.header.frame_id = "base_scan"
    msg.header.stamp = convert.ns_to_stamp(stamp_ns)
    msg.angle_min, msg.angle_increment = -math.pi, 2 * math.pi / 360
    msg.angle_max = msg.angle_min + 359 * msg.angle_increment
    msg.range_min, msg.range_max = 0.1, range_max
    msg.ranges = [math.inf] * 360
    return msg


def _columns(node) -> set[int]:
    return {int(c) for f in node.frontiers for c in f.cells[:, 1]}


def test_selector_decides_on_the_scans_since_the_map(ros):
    from sensor_msgs.msg import LaserScan

    from explore_seg.qos import SENSOR_QOS

    node = start_selector(ros)
    _grid, _marks, _keep = feed(ros, BAND)
    ros.spin_until(lambda: node.frontiers, timeout_s=15, what="frontiers")
    assert min(_columns(node)) <= 9                    # the band's frontiers
    pub = ros.node("scanner").create_publisher(LaserScan, "scan", SENSOR_QOS)
    # stamped like the odometry the feeder publishes (stamp 0): a pose at the scan's time
    timer = ros.node("scanner").create_timer(0.1, lambda: pub.publish(_scan_msg(0)))
    ros.spin_until(lambda: node._scans.used and min(_columns(node), default=0) >= 12,
                   timeout_s=15, what="a decision on the scanned band")
    timer.cancel()


def test_selector_drops_scans_without_a_pose_of_their_time(ros):
    from sensor_msgs.msg import LaserScan

    from explore_seg.qos import SENSOR_QOS

    node = start_selector(ros)
    _grid, _marks, _keep = feed(ros, BAND)
    ros.spin_until(lambda: node.frontiers, timeout_s=15, what="frontiers")
    pub = ros.node("scanner").create_publisher(LaserScan, "scan", SENSOR_QOS)
    bad = _scan_msg(0)
    bad.ranges = []
    timer = ros.node("scanner").create_timer(
        0.1, lambda: (pub.publish(_scan_msg(5_000_000_000)), pub.publish(bad)))
    ros.spin_until(lambda: node._scans.dropped >= 4, timeout_s=15, what="dropped scans")
    timer.cancel()
    assert node._scans.used == 0
    assert min(_columns(node)) <= 9                    # the band is still unknown


def test_selector_overlay_forgets_its_scans_at_a_map_moved_by_0_3_m(ros):
    """A re-render that moved the map's walls by 0.3 m is a SLAM correction: the overlay
    forgets the scans taken before it; a map that only grew is none."""
    import dataclasses

    import numpy as np
    from nav_msgs.msg import OccupancyGrid, Odometry
    from sensor_msgs.msg import LaserScan
    from test_object_costmap_corrections import _room

    from explore_seg import convert
    from explore_seg.qos import MAP_QOS, RELIABLE_QOS, SENSOR_QOS

    # the room is all known: the selector keeps deciding (and listening to poses) instead
    # of finishing
    node = start_selector(ros, done_confirmations=1_000_000)
    pub = ros.node("slam")
    maps = pub.create_publisher(OccupancyGrid, "map", MAP_QOS)
    odom = pub.create_publisher(Odometry, "odom", RELIABLE_QOS)
    scans = pub.create_publisher(LaserScan, "scan", SENSOR_QOS)
    clock = pub.get_clock()

    def send_odom():
        msg = Odometry()
        msg.header = convert.make_header("map", clock.now().to_msg())
        msg.pose.pose = convert.pose_from_2d(0.0, 0.0, 0.0)
        odom.publish(msg)

    def send_map(grid) -> None:
        maps.publish(convert.grid_to_msg(
            dataclasses.replace(grid, stamp_ns=clock.now().nanoseconds)))

    pub.create_timer(0.05, send_odom)
    scan_timer = pub.create_timer(0.1, lambda: scans.publish(
        _scan_msg(clock.now().nanoseconds)))
    unknown = _room().with_data(np.full((120, 200), -1, np.int8))

    def filled() -> bool:
        return node._explorer._overlay.apply(unknown) is not unknown

    send_map(_room())
    ros.spin_until(lambda: node._scans.used >= 3 and filled(), what="scans on the overlay")
    send_map(_room(grown=True))                     # the map grew: no correction
    ros.spin_until(lambda: np.array_equal(node._grid.data, _room(grown=True).data),
                   what="the grown map")
    scan_timer.cancel()
    ros.spin_for(0.3)
    assert node._corrections.count == 0 and filled()
    send_map(_room(0.3, grown=True))                # a re-render moved the map by 0.3 m
    ros.spin_until(lambda: node._corrections.count == 1, what="the correction")
    assert not filled()                             # the scans before it are forgotten
