"""Nav2's ``navigate_to_pose`` action seen from outside: goal status and cancel, no nav2_msgs.

:class:`NavClient` subscribes to ``<action>/_action/status`` (action_msgs/GoalStatusArray)
and feeds :class:`~explore_seg.core.selection.nav_status.GoalStatusTracker`, which
attributes the newest goal accepted after our ``goal_pose`` publish to our goal; it cancels
through ``<action>/_action/cancel_goal`` (action_msgs/srv/CancelGoal: our attributed goal
id, else zero id + zero stamp = every goal) and says once when no server answers within
``cancel_timeout_s``. The action name is relative, so namespaces work.

The owner calls :meth:`goal_sent` after each publish and :meth:`poll` once per tick; it
gets :class:`~explore_seg.core.selection.nav_status.NavEvent` objects (each outcome
once) and decides what to do (the ``target_selector`` reports them to the Explorer).
"""

from __future__ import annotations

from typing import Callable

from action_msgs.msg import GoalInfo, GoalStatusArray
from action_msgs.srv import CancelGoal
from rclpy.node import Node
from rclpy.task import Future

from explore_seg.core.selection.nav_status import GoalStatusTracker, NavEvent, StatusEntry
from explore_seg.qos import ACTION_STATUS_QOS

#: CancelGoal response codes (action_msgs/srv/CancelGoal), for the log.
_CANCEL_CODES = {0: "accepted", 1: "rejected", 2: "unknown goal id", 3: "goal terminated"}


def status_entries(msg: GoalStatusArray) -> list[StatusEntry]:
    """The entries of a GoalStatusArray as plain tuples (ids as 16 bytes)."""
    out = []
    for st in msg.status_list:
        stamp = st.goal_info.stamp
        out.append(StatusEntry(bytes(bytearray(st.goal_info.goal_id.uuid)), int(st.status),
                               stamp.sec + stamp.nanosec * 1e-9))
    return out


class NavClient:
    """Status and cancel of one action (see the module docstring).

    Parameters
    ----------
    node : Node
        Owner (clock, logger, subscriptions).
    action : str
        Action name, e.g. ``navigate_to_pose``.
    accept_timeout_s, cancel_timeout_s : float
        Our goal not in any status array after ``accept_timeout_s`` is REJECTED; a cancel
        not answered after ``cancel_timeout_s`` is logged.
    warn : callable(key, message)
        Throttled warning (``node_util.WarnThrottle``).
    """

    def __init__(self, node: Node, action: str, accept_timeout_s: float,
                 cancel_timeout_s: float, warn: Callable[[str, str], None]) -> None:
        self._node = node
        self._warn = warn
        self.action = action
        self.tracker = GoalStatusTracker(accept_timeout_s)
        self.cancel_timeout_s = float(cancel_timeout_s)
        self._status_topic = f"{action}/_action/status"
        self._events: list[NavEvent] = []
        self._had_publisher = False
        self._sub = node.create_subscription(GoalStatusArray, self._status_topic,
                                             self._on_status, ACTION_STATUS_QOS)
        self._cancel = node.create_client(CancelGoal, f"{action}/_action/cancel_goal")
        self._pending: list[tuple[float, Future, str]] = []
        self.cancels_sent = 0

    def _now_s(self) -> float:
        return self._node.get_clock().now().nanoseconds * 1e-9

    def _on_status(self, msg: GoalStatusArray) -> None:
        try:
            entries = status_entries(msg)
        except (AttributeError, TypeError, ValueError) as err:
            self._warn("nav_status", f"dropped {self._status_topic}: {err}")
            return
        self._events.extend(self.tracker.update(entries, self._now_s()))

    # ------------------------------------------------------------------ api
    def publisher_present(self) -> bool:
        """True when some node publishes the action's status topic."""
        return self._node.count_publishers(self._status_topic) > 0

    def goal_sent(self, goal_xy_m: tuple[float, float]) -> None:
        """Our goal was just published on ``goal_pose``."""
        self.tracker.goal_sent(self._now_s(), goal_xy_m)

    def poll(self) -> list[NavEvent]:
        """Events since the last call (status arrays, accept timeout, cancel answers);
        ``ignored`` ones are logged here (throttled)."""
        now_s = self._now_s()
        present = self.publisher_present()
        if present != self._had_publisher:
            self._had_publisher = present
            self._node.get_logger().info(
                f"{self._status_topic}: " + ("publisher found: navigation outcomes followed"
                                            if present else "no publisher: goals end by "
                                            "progress_timeout_s only"))
        timeout = self.tracker.check_timeout(now_s, present)
        events, self._events = self._events, []
        if timeout is not None:
            events.append(timeout)
        for ev in events:
            if ev.kind == "ignored":
                self._warn("nav_status", f"{self._status_topic}: {ev.message}")
        self._check_cancels(now_s)
        return [ev for ev in events if ev.kind != "ignored"]

    def cancel(self, why: str) -> bool:
        """Ask the navigator to cancel our goal (every goal when ours is not identified);
        False (logged) when no cancel server exists."""
        tracker = self.tracker
        if not tracker.active:
            return False
        if not self._cancel.service_is_ready():
            self._warn("nav_cancel", f"{why}: no server for {self._cancel.srv_name}: the "
                                     "navigator keeps its goal")
            return False
        req = CancelGoal.Request()
        req.goal_info = GoalInfo()
        goal_id = tracker.goal_id
        if goal_id is not None:
            req.goal_info.goal_id.uuid = list(goal_id)
        tracker.cancel_requested()
        self._pending.append((self._now_s(), self._cancel.call_async(req), why))
        self.cancels_sent += 1
        self._node.get_logger().info(
            f"{why}: canceling " + (f"goal {goal_id.hex()[:8]}" if goal_id else "all goals")
            + f" via {self._cancel.srv_name}")
        return True

    def _check_cancels(self, now_s: float) -> None:
        keep = []
        for sent_s, fut, why in self._pending:
            if fut.done():
                res = fut.result()
                code = getattr(res, "return_code", -1)
                self._node.get_logger().info(
                    f"{why}: cancel {_CANCEL_CODES.get(code, f'code {code}')}, "
                    f"{len(getattr(res, 'goals_canceling', []))} goal(s) canceling")
            elif now_s - sent_s > self.cancel_timeout_s or now_s < sent_s:
                self._warn("nav_cancel", f"{why}: no answer from {self._cancel.srv_name} "
                                         f"within {self.cancel_timeout_s:g} s")
            else:
                keep.append((sent_s, fut, why))
        self._pending = keep

    def destroy(self) -> None:
        """Release the subscription and the client."""
        self._node.destroy_subscription(self._sub)
        self._node.destroy_client(self._cancel)
