"""frontier_detector and target_selector through real publishers/subscribers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.core.frontiers import FrontierParams, find_frontiers, traversable_mask
from explore_seg.core.grid import grid_from_ascii
from explore_seg.qos import MAP_QOS, RELIABLE_QOS

# Robot R in a corridor open (unknown) at its right end only; at 0.1 m per cell.
CORRIDOR = """
##############
#............?
#............?
#..R.........?
#............?
#............?
##############
"""
EXPLORED = CORRIDOR.replace("?", "#")
RES = 0.1
ORIGIN = (-1.0, -2.0)


def selector_overrides(**extra):
    # The paper's strategy: these tiny maps' frontiers reveal less than routed's
    # min_gain_m2 (routed, the default, is tested on a bigger map below).
    values = {"strategy": "paper", "rate_hz": 20.0, "done_confirmations": 2,
              "frontier.min_group_size_cells": 3, "frontier.robot_radius_m": 0.1,
              "path_block_cells": 2}
    values.update(extra)
    return [Parameter(k, value=v) for k, v in values.items()]


def map_msg(text: str):
    grid, marks = grid_from_ascii(text, resolution_m=RES, origin_xy_m=ORIGIN)
    return grid, marks, convert.grid_to_msg(grid)


def odom_msg(x: float, y: float):
    from nav_msgs.msg import Odometry

    msg = Odometry()
    msg.header.frame_id = "map"
    msg.pose.pose = convert.pose_from_2d(x, y, 0.0)
    return msg


class Inbox:
    """Collects messages of one topic."""

    def __init__(self, ros, msg_type, topic, qos=10):
        self.msgs = []
        self.node = ros.node(f"inbox_{topic.replace('/', '_').strip('_')}")
        self.node.create_subscription(msg_type, topic, self.msgs.append, qos)


def start_selector(ros, **params):
    from explore_seg.selector_node import TargetSelectorNode

    return ros.add(TargetSelectorNode(context=ros.context,
                                      parameter_overrides=selector_overrides(**params)))


def feed(ros, text: str, robot: str = "R"):
    from nav_msgs.msg import OccupancyGrid, Odometry

    grid, marks, msg = map_msg(text)
    pub = ros.node("feeder")
    map_pub = pub.create_publisher(OccupancyGrid, "map", MAP_QOS)
    odom_pub = pub.create_publisher(Odometry, "odom", RELIABLE_QOS)
    map_pub.publish(msg)
    x, y = grid.cell_to_world(*marks[robot][0])
    timer = pub.create_timer(0.05, lambda: odom_pub.publish(odom_msg(x, y)))
    return grid, marks, (map_pub, odom_pub, timer)


def test_selector_sends_goal_at_the_frontier(ros):
    from geometry_msgs.msg import PoseStamped

    node = start_selector(ros)
    goals = Inbox(ros, PoseStamped, "goal_pose")
    grid, _, _keep = feed(ros, CORRIDOR)
    ros.spin_until(lambda: goals.msgs, timeout_s=15, what="a goal_pose")
    goal = goals.msgs[0]
    fp = FrontierParams(min_group_size_cells=3, robot_radius_m=0.1)
    (frontier,) = find_frontiers(grid, None, fp, traversable_mask(grid, None, fp))
    assert goal.header.frame_id == "map"
    assert (goal.pose.position.x, goal.pose.position.y) == pytest.approx(frontier.point_xy_m)
    assert frontier.point_rc == (3, 12)   # beside the open end, the middle row
    yaw = 2.0 * math.atan2(goal.pose.orientation.z, goal.pose.orientation.w)
    assert yaw == pytest.approx(0.0, abs=1e-6)   # facing the unknown (+x)
    assert node.state.value == "navigating"


HALL = "\n".join(["#" * 42] + ["#" + "." * 15 + "?" * 25 + "#"] * 4
                 + ["#..R" + "." * 12 + "?" * 25 + "#"] + ["#" + "." * 15 + "?" * 25 + "#"] * 11
                 + ["#" * 42])


def test_default_routed_selector_sends_a_viewpoint_goal(ros):
    from geometry_msgs.msg import PoseStamped

    from explore_seg.core.explorer import Explorer
    from explore_seg.core.selection import SelectionParams

    assert SelectionParams().strategy == "routed"
    node = start_selector(ros, strategy="routed")
    goals = Inbox(ros, PoseStamped, "goal_pose")
    grid, marks, _keep = feed(ros, HALL)
    ros.spin_until(lambda: goals.msgs, timeout_s=15, what="a goal_pose")
    goal = goals.msgs[0]
    # the core's routed goal on the same map: the viewpoint, not the frontier's cPoint
    fp = FrontierParams(min_group_size_cells=3, robot_radius_m=0.1)
    x, y = grid.cell_to_world(*marks["R"][0])
    core = {s: Explorer(fp, SelectionParams(strategy=s, path_block_cells=2)).step(
        0.0, grid, (x, y, 0.0)) for s in ("routed", "paper")}
    assert core["routed"].tour is not None and core["routed"].goal != core["paper"].goal
    gx, gy = goal.pose.position.x, goal.pose.position.y
    # within a cell (the node's pose comes through odometry: ties between equally good
    # candidates may break one cell apart); the paper's cPoint is 0.9 m away
    assert math.dist((gx, gy), core["routed"].goal.xy_m) <= 1.5 * RES
    assert math.dist((gx, gy), core["paper"].goal.xy_m) > 0.5
    assert node.state.value == "navigating"


def test_selector_reports_done_on_explored_map(ros):
    from std_msgs.msg import Bool

    start_selector(ros)
    done = Inbox(ros, Bool, "exploration_done", MAP_QOS)
    _keep = feed(ros, EXPLORED)
    ros.spin_until(lambda: any(m.data for m in done.msgs), timeout_s=15,
                   what="exploration_done True")
    assert done.msgs[0].data is False          # published False at start


def call(ros, node_name: str, service: str):
    from std_srvs.srv import Trigger

    client = ros.node(f"client_{service}").create_client(Trigger, f"/{node_name}/{service}")
    ros.spin_until(lambda: client.service_is_ready(), timeout_s=10, what=f"{service} service")
    fut = client.call_async(Trigger.Request())
    ros.spin_until(fut.done, timeout_s=10, what=f"{service} response")
    return fut.result()


def test_selector_stop_start_services(ros):
    from geometry_msgs.msg import PoseStamped

    node = start_selector(ros, autostart=False)
    goals = Inbox(ros, PoseStamped, "goal_pose")
    _keep = feed(ros, CORRIDOR)
    ros.spin_for(0.5)
    assert node.state.value == "stopped" and goals.msgs == []
    assert call(ros, "target_selector", "start").success
    ros.spin_until(lambda: goals.msgs, timeout_s=15, what="a goal after ~/start")
    res = call(ros, "target_selector", "stop")
    assert res.success and node.state.value == "stopped"
    n = len(goals.msgs)
    res = call(ros, "target_selector", "resume")
    assert res.success and "resumed" in res.message
    ros.spin_until(lambda: node.state.value == "navigating", timeout_s=10, what="navigating")
    assert len(goals.msgs) == n          # the kept goal is not re-sent


def test_selector_survives_bad_map_and_waits_for_pose(ros):
    from nav_msgs.msg import OccupancyGrid

    node = start_selector(ros)
    pub = ros.node("bad_feeder").create_publisher(OccupancyGrid, "map", MAP_QOS)
    _, _, msg = map_msg(CORRIDOR)
    msg.data = msg.data[:5]              # wrong length: dropped
    pub.publish(msg)
    ros.spin_for(0.3)
    assert node.state.value == "waiting_for_map"
    _, _, good = map_msg(CORRIDOR)
    pub.publish(good)
    ros.spin_until(lambda: node.state.value == "waiting_for_pose", timeout_s=10,
                   what="waiting_for_pose after a good map without odom")


def test_selector_publishes_timing(ros):
    from std_msgs.msg import Float64MultiArray

    start_selector(ros)
    timing = Inbox(ros, Float64MultiArray, "/target_selector/timing")
    _keep = feed(ros, CORRIDOR)
    ros.spin_until(lambda: any(m.data[0] > 0 for m in timing.msgs), timeout_s=15,
                   what="timing with a detection")
    m = timing.msgs[-1]
    assert m.layout.dim[0].label == "detect_cluster_ms,selection_ms,frontiers"
    assert len(m.data) == 3 and m.data[2] == 1.0


def test_frontier_detector_publishes_groups_and_cells(ros):
    from nav_msgs.msg import OccupancyGrid
    from sensor_msgs.msg import PointCloud2
    from visualization_msgs.msg import MarkerArray

    from explore_seg.frontier_node import FrontierDetectorNode

    params = [Parameter("frontier.min_group_size_cells", value=3),
              Parameter("frontier.robot_radius_m", value=0.1),
              Parameter("rate_hz", value=20.0)]
    node = ros.add(FrontierDetectorNode(context=ros.context, parameter_overrides=params))
    groups = Inbox(ros, PointCloud2, "frontiers/groups")
    cells = Inbox(ros, PointCloud2, "frontiers")
    markers = Inbox(ros, MarkerArray, "frontiers/markers")
    grid, _, msg = map_msg(CORRIDOR)
    ros.node("map_feeder").create_publisher(OccupancyGrid, "map", MAP_QOS).publish(msg)
    ros.spin_until(lambda: groups.msgs and cells.msgs and markers.msgs, timeout_s=15,
                   what="frontier clouds and markers")
    g = convert.cloud_from_msg(groups.msgs[0])
    c = convert.cloud_from_msg(cells.msgs[0])
    assert g.dtype.names == ("x", "y", "z", "group_id", "group_size")
    assert len(g) == 1 and g["group_size"][0] == 5.0 and len(c) == 5
    assert (float(g["x"][0]), float(g["y"][0])) == pytest.approx(grid.cell_to_world(3, 12))
    assert np.all(c["group_id"] == 0.0)
    ros.spin_for(0.3)
    assert node.runs == 1                # nothing new: no recomputation
