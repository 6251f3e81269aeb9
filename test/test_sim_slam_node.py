"""sim_bridge with a mapping error model over ROS: the published map and poses are the
SLAM ones, and the explorer keeps exploring through a map re-render that moves the map."""

from __future__ import annotations

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.parameter import Parameter
from std_msgs.msg import Bool

from explore_seg import convert
from explore_seg.qos import MAP_QOS, POSE_QOS, RELIABLE_QOS

SIM_TIME = Parameter("use_sim_time", value=True)


def _grid_equal(a, b) -> bool:
    return (a.shape == b.shape and a.origin_xy_m == pytest.approx(b.origin_xy_m)
            and np.array_equal(a.data, b.data))


def test_node_publishes_the_erroneous_map_and_slam_pose(ros, tmp_path):
    from sim_bridge.node import SimBridgeNode

    sim = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"),
        Parameter("mapping_error", value="harsh"),
        Parameter("slam_pose", value=True),
        Parameter("real_time_factor", value=5.0),
        Parameter("map_update_interval_s", value=0.2),
        Parameter("output_dir", value=str(tmp_path)),
    ]))
    eng = sim.engine
    probe = ros.node("slam_probe")
    last: dict[str, object] = {}
    for topic, typ, qos in (("odom", Odometry, RELIABLE_QOS), ("map", OccupancyGrid, MAP_QOS),
                            ("pose", PoseWithCovarianceStamped, POSE_QOS)):
        probe.create_subscription(typ, topic, lambda m, t=topic: last.__setitem__(t, m), qos)
    ros.spin_until(lambda: len(last) == 3 and eng.slam_error.n_keyframes >= 1,
                   what="odom, map, pose and the first keyframe")
    true = eng.pose
    # Standing still: no drift yet, the map is the first keyframe's.
    assert convert.pose2d_from_odometry(last["odom"]) == pytest.approx(true, abs=1e-6)
    eng.slam_error.shift((0.3, 0.0, 0.0))
    shifted = eng.live_map          # the SLAM map now; published at the next interval

    def caught_up() -> bool:
        return (all(k in last for k in ("map", "odom", "pose"))
                and _grid_equal(convert.grid_from_msg(last["map"]), eng.map)
                and convert.pose2d_from_odometry(last["odom"])[0] > true[0] + 0.29
                and last["pose"].pose.pose.position.x > true[0] + 0.29)

    last.clear()
    ros.spin_until(caught_up, what="the shifted map, odom and pose")
    assert _grid_equal(eng.map, shifted), "nothing else changed the map"
    assert convert.pose2d_from_odometry(last["odom"]) == pytest.approx(
        (true[0] + 0.3, true[1], true[2]), abs=1e-6)
    assert eng.slam_pose == pytest.approx((true[0] + 0.3, true[1], true[2]), abs=1e-9)
    assert eng.pose == true, "the robot itself did not move"


def _metrics(msg: DiagnosticArray) -> dict[str, str]:
    return {kv.key: kv.value for st in msg.status for kv in st.values}


def test_explorer_keeps_exploring_through_a_map_shift_of_0_3_m(ros):
    from explore_seg.frontier_node import FrontierDetectorNode
    from explore_seg.segmentation_node import SegmentationNode
    from explore_seg.selector_node import TargetSelectorNode
    from sim_bridge.node import SimBridgeNode

    sim = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"),
        Parameter("mapping_error", value="realistic"),
        Parameter("real_time_factor", value=2.0),
        Parameter("enable_camera", value=False),
    ]))
    ros.add(SegmentationNode(context=ros.context, parameter_overrides=[SIM_TIME]))
    ros.add(FrontierDetectorNode(context=ros.context, parameter_overrides=[SIM_TIME]))
    ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=[
        SIM_TIME, Parameter("strategy", value="nearest")]))
    probe = ros.node("probe")
    done: list[bool] = []
    metrics: dict[str, str] = {}
    probe.create_subscription(Bool, "exploration_done", lambda m: done.append(m.data), MAP_QOS)
    probe.create_subscription(DiagnosticArray, "sim/metrics",
                              lambda m: metrics.update(_metrics(m)), RELIABLE_QOS)
    eng = sim.engine

    ros.spin_until(lambda: eng.metrics.goals_received >= 2 and eng.metrics.coverage_pct >= 20,
                   timeout_s=200, what=f"two goals and 20 % coverage; metrics {metrics}")
    goals0, cov0 = eng.metrics.goals_received, eng.metrics.coverage_pct
    before = eng.slam_pose
    eng.slam_error.shift((0.3, 0.0, 0.0))
    after = eng.slam_pose
    assert math.hypot(after[0] - before[0], after[1] - before[1]) == pytest.approx(0.3)
    ros.spin_until(lambda: eng.metrics.goals_received >= goals0 + 2
                   and eng.metrics.coverage_pct >= min(95.0, cov0 + 20.0),
                   timeout_s=300,
                   what=f"exploration to go on after the shift (from {cov0:.1f} %, "
                        f"{goals0} goals); metrics {metrics}")
    ros.spin_until(lambda: done and done[-1], timeout_s=300,
                   what=f"exploration_done=true after the shift; metrics {metrics}")
    assert eng.metrics.coverage_pct >= 90.0, metrics
    assert eng.metrics.n_collisions == 0, metrics
