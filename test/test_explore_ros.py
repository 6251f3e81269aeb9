"""End to end over real ROS topics: sim_bridge + the explorer's nodes explore a small house.

Everything runs on one private rclpy context on sim time (the simulator publishes /clock
faster than real time); the explorer nodes see only the standard topics (map, odom, scan,
goal_pose, ...), never a sim-only one.
"""

from __future__ import annotations

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from std_msgs.msg import Bool

from explore_seg.frontier_node import FrontierDetectorNode
from explore_seg.qos import MAP_QOS, RELIABLE_QOS
from explore_seg.segmentation_node import SegmentationNode
from explore_seg.selector_node import TargetSelectorNode
from sim_bridge.node import SimBridgeNode

SIM_TIME = Parameter("use_sim_time", value=True)


def _metrics(msg: DiagnosticArray) -> dict[str, str]:
    return {kv.key: kv.value for st in msg.status for kv in st.values}


@pytest.mark.parametrize("strategy", ["paper", "nearest"])
def test_sim_and_explorer_explore_small_house_to_completion(ros, strategy):
    ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"),
        # 2x: the whole system shares this one executor; at 8x the simulator takes 0.16 s+
        # steps per tick on a loaded 2-core machine and 2 of 9 runs had a contact
        # (navigation stand-in grazing); at 4x, with odometry published at every scan and
        # frame stamp and the action status, 2 of 8 runs had one.
        Parameter("real_time_factor", value=2.0),
        Parameter("enable_camera", value=False),
    ]))
    ros.add(SegmentationNode(context=ros.context, parameter_overrides=[SIM_TIME]))
    ros.add(FrontierDetectorNode(context=ros.context, parameter_overrides=[SIM_TIME]))
    selector = ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=[
        SIM_TIME, Parameter("strategy", value=strategy)]))

    probe = ros.node("probe")
    done: list[bool] = []
    metrics: dict[str, str] = {}
    probe.create_subscription(Bool, "exploration_done", lambda m: done.append(m.data), MAP_QOS)
    probe.create_subscription(DiagnosticArray, "sim/metrics",
                              lambda m: metrics.update(_metrics(m)), RELIABLE_QOS)

    ros.spin_until(lambda: done and done[-1], timeout_s=400,
                   what=f"exploration_done=true ({strategy}); last metrics {metrics}")
    ros.spin_until(lambda: float(metrics.get("sim_time_s", 0)) > 0, what="sim metrics")
    assert done[0] is False, "exploration_done must start false"
    coverage = float(metrics["coverage_pct"])
    assert coverage >= 99.0, f"{strategy}: coverage {coverage:.1f} % at done; metrics {metrics}"
    assert int(metrics["collisions"]) == 0, metrics
    assert int(metrics["goals_received"]) >= 2, metrics
    # the simulator's scans reached the decisions (scan overlay), each with a pose of its time
    assert selector._scans.used > 0 and selector._scans.dropped <= selector._scans.used // 10
