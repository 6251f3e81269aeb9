"""target_selector with strategy rrt_exploration: its rrt.* parameters and a goal."""

from __future__ import annotations

import pytest
from rclpy.parameter import Parameter

from test_frontier_nodes import Inbox, feed, start_selector

# A 4 x 2 m room at 0.1 m per cell, its right half unknown (room for RRT frontier points
# with at least min_info_gain_m2 of unknown space around them).
HALF_KNOWN = "\n".join(["#" * 40] + ["#" + "." * 4 + ("R" if i == 9 else ".") + "." * 14
                                      + "?" * 19 + "#" for i in range(18)] + ["#" * 40])


def test_selector_runs_rrt_exploration_and_binds_rrt_params(ros):
    from geometry_msgs.msg import PoseStamped

    node = start_selector(ros, strategy="rrt_exploration", **{"rrt.iterations_per_step": 300,
                                                              "rrt.seed": 5})
    assert node.explorer.rrt_params.iterations_per_step == 300
    assert node.explorer.rrt_params.seed == 5
    goals = Inbox(ros, PoseStamped, "goal_pose")
    grid, _, _keep = feed(ros, HALF_KNOWN)
    ros.spin_until(lambda: goals.msgs, timeout_s=15, what="a goal_pose")
    g = goals.msgs[0].pose.position
    # a known free cell near the unknown half (the first unknown column is 20)
    r, c = grid.world_to_cell(g.x, g.y)
    assert grid.data[r, c] == 0 and 14 <= c < 20
    res = node.set_parameters([Parameter("rrt.global_eta_m", value=-1.0)])
    assert not res[0].successful and "global_eta_m" in res[0].reason
    assert node.explorer.rrt_params.global_eta_m == pytest.approx(15.0)
    assert node.set_parameters([Parameter("rrt.local_eta_m", value=0.5)])[0].successful
    assert node.explorer.rrt_params.local_eta_m == pytest.approx(0.5)
