"""Simulator restart over real ROS topics (issue 24, finding 1 in the full system): the
simulator is destroyed mid-run and a new one starts with its clock at 0 again; the object
costmap must process camera frames again and the selector send goals again, each having
noticed the clock jump (before the time model the layer stayed frozen for ~90 s of sim
time)."""

from __future__ import annotations

from geometry_msgs.msg import PoseStamped
from rclpy.parameter import Parameter

from explore_seg.object_costmap_node import ObjectCostmapNode
from explore_seg.qos import RELIABLE_QOS
from explore_seg.selector_node import TargetSelectorNode
from sim_bridge.node import SimBridgeNode

SIM_TIME = Parameter("use_sim_time", value=True)


def _sim(ros, tmp_path, k: int) -> SimBridgeNode:
    return ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_cluttered"),
        # 2x and a 20 Hz tick (odometry rate): all nodes share this process's executor;
        # faster, odometry queues up on a loaded machine and frames wait for poses
        Parameter("real_time_factor", value=2.0), Parameter("tick_period_s", value=0.05),
        Parameter("enable_camera", value=True),
        Parameter("camera_width_px", value=160), Parameter("camera_height_px", value=120),
        Parameter("camera_fx_px", value=131.0), Parameter("camera_fy_px", value=131.0),
        Parameter("camera_cx_px", value=79.5), Parameter("camera_cy_px", value=59.5),
        Parameter("output_dir", value=str(tmp_path / f"sim{k}"))]))


def test_explorer_nodes_recover_from_a_simulator_restart(ros, tmp_path):
    sim = _sim(ros, tmp_path, 0)
    costmap = ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=[
        SIM_TIME, Parameter("detector.backend", value="oracle")]))
    selector = ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=[
        SIM_TIME, Parameter("strategy", value="nearest")]))
    goals: list[PoseStamped] = []
    ros.node("probe").create_subscription(PoseStamped, "goal_pose", goals.append, RELIABLE_QOS)

    ros.spin_until(lambda: costmap.frames_processed >= 2 and goals and
                   sim.engine.time_s > 30.0, timeout_s=120,
                   what="frames processed and a goal before the restart")
    frames, t_before = costmap.frames_processed, sim.engine.time_s
    ros.executor.remove_node(sim)
    ros.nodes.remove(sim)
    sim.destroy_node()
    sim = _sim(ros, tmp_path, 1)                         # its clock starts at 0 again
    new_line_ns = int((t_before - 15.0) * 1e9)           # stamps below: the new time line

    def recovered() -> bool:
        return (costmap.frames_processed >= frames + 2
                and (costmap._last_depth_ns or 2**62) < new_line_ns     # noqa: SLF001
                and (selector._pose_stamp_ns or 2**62) < new_line_ns)   # noqa: SLF001

    ros.spin_until(recovered, timeout_s=120, what=(
        "camera frames and selector poses of the new simulator's time line"))
    # ... long before the new clock caught up with the old one (the old code waited)
    assert sim.engine.time_s < t_before - 15.0, (sim.engine.time_s, t_before)
    assert costmap.time_jumps >= 1
    assert selector.state.value in ("navigating", "selecting"), selector.state
