"""``object_costmap`` finds SLAM corrections in its own inputs (map-frame pose, map) over
real topics and drops the boxes placed since the previous one; growth and motion do not."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.core.grid import GridMap
from explore_seg.core.objects import Object3D
from explore_seg.object_costmap_node import ObjectCostmapNode
from explore_seg.qos import MAP_QOS, RELIABLE_QOS

NS = 1_000_000_000


def _node(ros):
    return ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=[
        Parameter("detector.backend", value="oracle"), Parameter("rate_hz", value=10.0)]))


def _table(x: float, y: float) -> list[Object3D]:
    return [Object3D("dining table", 0.9, (x, y, 0.37), (0.9, 0.75, 0.74), 0.0, 100)]


def _room(shift_x_m: float = 0.0, grown: bool = False) -> GridMap:
    """A 6 x 4 m room on a 10 x 6 m grid; ``grown``: with the walls of a second room east
    of it (the map grew)."""
    data = np.zeros((120, 200), np.int8)
    grid = GridMap(data, 0.05, (-5.0, -3.0))
    walls = [((-3.0, -2.0), (3.0, -2.0)), ((-3.0, 2.0), (3.0, 2.0)), ((-3.0, -2.0), (-3.0, 2.0)),
             ((3.0, -2.0), (3.0, 2.0))]
    if grown:
        walls += [((3.0, -2.0), (4.8, -2.0)), ((3.0, 2.0), (4.8, 2.0)), ((4.8, -2.0), (4.8, 2.0))]
    for (x0, y0), (x1, y1) in walls:
        xs, ys = np.linspace(x0, x1, 400) + shift_x_m, np.linspace(y0, y1, 400)
        rows, cols = grid.world_to_cells(xs, ys)
        ok = (cols >= 0) & (cols < 200)
        data[rows[ok], cols[ok]] = 100
    return grid.with_data(data)


def test_a_map_moved_by_0_3_m_drops_the_boxes_growth_and_driving_do_not(ros):
    node = _node(ros)
    pub = ros.node("slam")
    maps = pub.create_publisher(OccupancyGrid, "map", MAP_QOS)
    odom = pub.create_publisher(Odometry, "odom", RELIABLE_QOS)
    clock = pub.get_clock()
    state = {"x": 0.0}

    def send_odom():
        msg = Odometry()
        msg.header = convert.make_header("map", clock.now().to_msg())
        msg.pose.pose = convert.pose_from_2d(state["x"], 0.0, 0.0)
        odom.publish(msg)
        state["x"] += 0.01                          # 0.2 m/s at 20 Hz

    pub.create_timer(0.05, send_odom)

    def send_map(grid: GridMap) -> None:
        stamped = dataclasses.replace(grid, stamp_ns=clock.now().nanoseconds)
        maps.publish(convert.grid_to_msg(stamped))

    send_map(_room())
    ros.spin_until(lambda: node._grid is not None and node._pose_in.latest() is not None,
                   what="the map and poses")
    node._objects.update(_table(1.0, 1.0), stamp_ns=clock.now().nanoseconds)
    send_map(_room(grown=True))                     # the map grew
    ros.spin_until(lambda: np.array_equal(node._grid.data, _room(grown=True).data),
                   what="the grown map")
    ros.spin_for(0.5)                              # driving on
    assert node._corrections.applied == 0 and len(node.objects()) == 1
    send_map(_room(0.3, grown=True))                 # a re-render moved the map by 0.3 m
    ros.spin_until(lambda: node._corrections.applied == 1, what="the correction")
    assert node.objects() == []
    ros.spin_for(0.3)
    assert node._corrections.applied == 1


@pytest.mark.parametrize("move_recent_s", [10.0, 0.0])
def test_the_simulators_loop_closure_is_found_from_its_topics(ros, tmp_path, move_recent_s):
    """sim_bridge with the mapping error model: its re-render moves the map and the
    map-frame pose on ``odom`` by 0.3 m; the node counts one correction and moves the box
    seen a moment before it with the pose's jump; with correction_move_recent_s 0 the box
    is dropped (the first correction: everything placed so far)."""
    from sim_bridge.node import SimBridgeNode

    sim = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"),
        Parameter("mapping_error", value="harsh"),
        Parameter("real_time_factor", value=5.0),
        Parameter("map_update_interval_s", value=0.2),
        Parameter("output_dir", value=str(tmp_path)),
    ]))
    node = ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=[
        Parameter("detector.backend", value="oracle"), Parameter("rate_hz", value=10.0),
        Parameter("correction_move_recent_s", value=move_recent_s)]))
    eng = sim.engine
    ros.spin_until(lambda: node._grid is not None and node._pose_in.latest() is not None
                   and eng.slam_error.n_keyframes >= 1, what="the map and poses")
    ros.spin_for(0.5)
    assert node._corrections.applied == 0            # standing still, the map re-sent
    x, y = eng.slam_pose[:2]
    node._objects.update(_table(x + 1.5, y), stamp_ns=node.get_clock().now().nanoseconds)
    assert len(node.objects()) == 1
    eng.slam_error.shift((0.3, 0.0, 0.0))
    ros.spin_until(lambda: node._corrections.applied >= 1, what="the correction")
    if move_recent_s > 0:                           # the robot stands still: jump exact
        (box,) = node.objects()
        assert box.center_xyz[:2] == pytest.approx((x + 1.8, y), abs=1e-6)
    else:
        assert node.objects() == []
    ros.spin_for(1.0)                               # the map shows the same closure
    assert node._corrections.applied == 1


def test_a_fused_pose_jump_moves_what_was_just_seen_and_drops_the_rest(ros):
    """With ``pose_topic_type: fused`` a loop closure moves the SLAM pose 0.3 m off what
    odometry predicts: the node finds the correction in its map-frame poses and the box
    seen a moment before moves with the jump (an obstacle beside the robot stays where
    the corrected map has it; the jump holds one odometry step of driving, 1 cm), the box
    seen since the previous correction but more than correction_move_recent_s before is
    dropped."""
    from geometry_msgs.msg import PoseWithCovarianceStamped
    from explore_seg.qos import POSE_QOS

    node = ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=[
        Parameter("detector.backend", value="oracle"), Parameter("rate_hz", value=10.0),
        Parameter("pose_topic_type", value="fused"), Parameter("correction_merge_s", value=1.0),
        Parameter("correction_move_recent_s", value=1.0)]))
    pub = ros.node("slam")
    odom = pub.create_publisher(Odometry, "odom", POSE_QOS)
    slam = pub.create_publisher(PoseWithCovarianceStamped, "pose", POSE_QOS)
    clock = pub.get_clock()
    state = {"x": 0.0, "dy": 0.0}

    def send():
        stamp = clock.now().to_msg()
        o = Odometry()
        o.header = convert.make_header("odom", stamp)
        o.pose.pose = convert.pose_from_2d(state["x"], 0.0, 0.0)
        odom.publish(o)
        m = PoseWithCovarianceStamped()
        m.header = convert.make_header("map", stamp)
        m.pose.pose = convert.pose_from_2d(state["x"] + 1.0, 2.0 + state["dy"], 0.0)
        slam.publish(m)
        state["x"] += 0.01                          # 0.2 m/s at 20 Hz

    pub.create_timer(0.05, send)
    ros.spin_until(lambda: node._pose_in.latest() is not None
                   and node._pose_in.fusion.pose_at(node._pose_in.latest()[0], 10**8)
                   is not None, what="fused poses")
    ros.spin_for(0.5)
    # (the fused pose's switch from odometry alone to the first correction may count as
    # one, with nothing placed yet)
    base = node._corrections.applied
    ros.spin_for(2.5)                               # past correction_merge_s
    assert node._corrections.applied == base
    now = clock.now().nanoseconds
    node._objects.update(_table(5.0, 0.0), stamp_ns=now - 3 * NS // 2)   # since then
    node._objects.update(_table(2.0, 3.0), stamp_ns=now - NS // 5)       # just before
    assert len(node.objects()) == 2
    state["dy"] = 0.3                               # the loop closure
    ros.spin_until(lambda: node._corrections.applied > base, what="the correction")
    objs = node.objects()
    assert len(objs) == 1
    assert objs[0].center_xyz[0] == pytest.approx(2.0, abs=0.02)
    assert objs[0].center_xyz[1] == pytest.approx(3.3, abs=1e-6)
