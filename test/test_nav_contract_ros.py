"""target_selector <-> navigator over real rclpy topics and services: the action status
(``navigate_to_pose/_action/status``) and cancel (``navigate_to_pose/_action/cancel_goal``)
of Nav2, played by a scripted fake here and by sim_bridge's navigation stand-in."""

from __future__ import annotations

import pytest
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.qos import ACTION_STATUS_QOS
from test_frontier_nodes import Inbox, call, feed, start_selector

# Open (unknown) at both ends: two frontiers, the right one nearer to R.
TWO_ENDS = """
##############
?............?
?............?
?........R...?
?............?
?............?
##############
"""
STATUS_TOPIC = "navigate_to_pose/_action/status"


class FakeNav:
    """Publishes GoalStatusArray for every goal_pose (scripted statuses, no real action)."""

    def __init__(self, ros, accept: bool = True) -> None:
        from action_msgs.msg import GoalStatusArray
        from geometry_msgs.msg import PoseStamped

        from explore_seg.qos import RELIABLE_QOS

        self.node = ros.node("fake_nav")
        self.pub = self.node.create_publisher(GoalStatusArray, STATUS_TOPIC, ACTION_STATUS_QOS)
        self.goals: list[tuple[float, float]] = []
        self.accept = accept
        self.arrays = 0
        self._status: dict[bytes, int] = {}
        self.node.create_subscription(PoseStamped, "goal_pose", self._on_goal, RELIABLE_QOS)
        self.publish()   # an (empty) array: a status publisher exists

    def _on_goal(self, msg) -> None:
        self.goals.append(convert.pose2d_from_pose_msg(msg)[:2])
        if self.accept:
            self.set(len(self.goals), 2)   # EXECUTING

    def set(self, n: int, status: int) -> None:
        self._status[n.to_bytes(16, "big")] = status
        self.publish()

    def publish(self) -> None:
        from action_msgs.msg import GoalStatus, GoalStatusArray

        msg = GoalStatusArray()
        for gid, st in self._status.items():
            s = GoalStatus()
            s.goal_info.goal_id.uuid = list(gid)
            s.goal_info.stamp = self.node.get_clock().now().to_msg()
            s.status = st
            msg.status_list.append(s)
        self.pub.publish(msg)
        self.arrays += 1


def test_aborted_goal_is_blacklisted_within_one_status_message(ros):
    from geometry_msgs.msg import PoseStamped

    node = start_selector(ros, progress_timeout_s=30.0)
    nav = FakeNav(ros)
    goals = Inbox(ros, PoseStamped, "goal_pose")
    _keep = feed(ros, TWO_ENDS)
    ros.spin_until(lambda: nav.goals and node.nav.tracker.goal_id is not None, timeout_s=15,
                   what="a goal accepted by the fake navigator")
    first = nav.goals[0]
    nav.set(1, 6)   # ABORTED: one status message
    ros.spin_until(lambda: len(goals.msgs) >= 2, timeout_s=3,
                   what="the next goal after ABORTED (not after progress_timeout_s = 30 s)")
    assert node.manager.blacklist == (pytest.approx(first),)
    second = convert.pose2d_from_pose_msg(goals.msgs[1])[:2]
    assert second[0] < first[0]          # the other (left) end


def test_goal_never_accepted_does_not_block(ros):
    from geometry_msgs.msg import PoseStamped

    node = start_selector(ros, progress_timeout_s=30.0, nav_accept_timeout_s=0.5)
    FakeNav(ros, accept=False)           # publishes status, never lists our goal
    goals = Inbox(ros, PoseStamped, "goal_pose")
    _keep = feed(ros, TWO_ENDS)
    ros.spin_until(lambda: goals.msgs, timeout_s=15, what="a first goal")
    ros.spin_until(lambda: len(goals.msgs) >= 2, timeout_s=5,
                   what="the next goal after the accept timeout")
    assert len(node.manager.blacklist) == 1


def test_without_status_publisher_goals_are_kept_until_progress_timeout(ros):
    from geometry_msgs.msg import PoseStamped

    node = start_selector(ros, progress_timeout_s=30.0, nav_accept_timeout_s=0.2)
    goals = Inbox(ros, PoseStamped, "goal_pose")
    _keep = feed(ros, TWO_ENDS)
    ros.spin_until(lambda: goals.msgs, timeout_s=15, what="a first goal")
    ros.spin_for(1.0)
    assert len(goals.msgs) == 1 and node.manager.blacklist == ()
    assert node.state.value == "navigating"


@pytest.fixture
def sim_and_selector(ros):
    from explore_seg.selector_node import TargetSelectorNode
    from sim_bridge.node import SimBridgeNode

    sim = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"), Parameter("real_time_factor", value=2.0)]))
    sel = ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=[
        Parameter("use_sim_time", value=True), Parameter("rate_hz", value=5.0)]))
    return sim, sel


def test_stop_cancels_the_goal_in_the_stand_in(ros, sim_and_selector):
    from sim_bridge.navigation import NavState

    sim, sel = sim_and_selector
    ros.spin_until(lambda: sim.engine.nav_status.state is NavState.ACTIVE
                   and sel.nav.tracker.goal_id is not None, timeout_s=60,
                   what="a goal driven by the stand-in and attributed by the selector")
    res = call(ros, "target_selector", "stop")
    assert res.success and "canceled" in res.message
    ros.spin_until(lambda: sim.engine.nav_status.state is NavState.CANCELED, timeout_s=10,
                   what="the stand-in's goal canceled")
    assert sim.nav_action.cancels == 1
    assert sel.manager.goal is None and sel.manager.blacklist == ()
    assert sel.state.value == "stopped"


def test_stand_in_abort_reaches_the_selector_as_a_blacklisting(ros, sim_and_selector):
    from sim_bridge.navigation import NavState

    sim, sel = sim_and_selector
    ros.spin_until(lambda: sim.engine.nav_status.state is NavState.ACTIVE
                   and sel.nav.tracker.goal_id is not None, timeout_s=60,
                   what="a goal driven by the stand-in")
    goal = sel.manager.goal
    sim.engine.navigator.abort("scripted abort")
    ros.spin_until(lambda: goal.xy_m in sel.manager.blacklist, timeout_s=10,
                   what="the aborted goal blacklisted")
    assert sel.goals_sent >= 1
