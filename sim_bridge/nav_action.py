"""The navigation stand-in as Nav2's ``navigate_to_pose`` action looks from outside.

:class:`SimNavAction` publishes ``<action>/_action/status`` (action_msgs/GoalStatusArray:
every ``goal_pose`` the engine accepted gets an id; ACCEPTED -> EXECUTING -> SUCCEEDED /
ABORTED / CANCELED) and serves ``<action>/_action/cancel_goal`` (action_msgs/srv/CancelGoal:
zero id and zero stamp cancel every goal, a zero id with a stamp those accepted up to it,
an id that goal), so the explorer's real-robot path (goal outcomes, cancel) is what the
simulator exercises. The bookkeeping is :class:`~sim_bridge.navigation.GoalBook`'s.
"""

from __future__ import annotations

from action_msgs.msg import GoalInfo, GoalStatus, GoalStatusArray
from action_msgs.srv import CancelGoal
from rclpy.node import Node

from explore_seg import convert
from explore_seg.qos import ACTION_STATUS_QOS
from sim_bridge.engine import SimEngine
from sim_bridge.navigation import GoalBook

_NS_PER_S = 1_000_000_000


def _goal_info(goal_id: bytes, stamp_s: float) -> GoalInfo:
    info = GoalInfo()
    info.goal_id.uuid = list(goal_id)
    info.stamp = convert.ns_to_stamp(int(round(stamp_s * _NS_PER_S)))
    return info


class SimNavAction:
    """Status topic and cancel service of the engine's navigation stand-in."""

    def __init__(self, node: Node, engine: SimEngine, action: str) -> None:
        self._node = node
        self._engine = engine
        self.book = GoalBook()
        self._published = -1
        self._pub = node.create_publisher(GoalStatusArray, f"{action}/_action/status",
                                          ACTION_STATUS_QOS)
        self._srv = node.create_service(CancelGoal, f"{action}/_action/cancel_goal",
                                        self._on_cancel)
        self.cancels = 0

    def accepted(self) -> None:
        """The engine just accepted a goal (at its current time)."""
        self.book.accept(self._engine.time_s)
        self.publish()

    def publish(self) -> None:
        """Follow the engine's navigation state; publish the array when it changed."""
        self.book.follow(self._engine.nav_status.state)
        if self.book.version == self._published:
            return
        self._published = self.book.version
        msg = GoalStatusArray()
        for e in self.book.entries():
            st = GoalStatus()
            st.goal_info = _goal_info(e.goal_id, e.stamp_s)
            st.status = e.status
            msg.status_list.append(st)
        self._pub.publish(msg)

    def _on_cancel(self, request: CancelGoal.Request, response: CancelGoal.Response
                   ) -> CancelGoal.Response:
        info = request.goal_info
        goal_id = bytes(bytearray(info.goal_id.uuid))
        stamp_s = info.stamp.sec + info.stamp.nanosec * 1e-9
        targets = self.book.cancel_targets(goal_id, stamp_s)
        if not targets:
            response.return_code = (CancelGoal.Response.ERROR_GOAL_TERMINATED
                                    if self.book.known(goal_id)
                                    else CancelGoal.Response.ERROR_UNKNOWN_GOAL_ID
                                    if any(goal_id) else CancelGoal.Response.ERROR_NONE)
            return response
        # Only the current goal is ever active in the stand-in.
        self._engine.cancel_goal()
        self.cancels += 1
        response.return_code = CancelGoal.Response.ERROR_NONE
        response.goals_canceling = [_goal_info(g, self.book.stamp_of(g)) for g in targets]
        self._node.get_logger().info(f"navigation goal canceled by request "
                                     f"({len(targets)} goal(s))")
        self.publish()
        return response
