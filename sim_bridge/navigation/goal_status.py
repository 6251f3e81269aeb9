"""The navigation stand-in's goals as Nav2's ``navigate_to_pose`` action reports them.

:class:`GoalBook` gives every accepted goal a 16-byte id and follows the
:class:`~sim_bridge.navigation.navigator.Navigator`'s state through action_msgs' GoalStatus
codes (ACCEPTED -> EXECUTING -> SUCCEEDED / ABORTED / CANCELED; a goal replaced by a
newer one is ABORTED, as Nav2's simple action server ends a preempted goal), keeping the
newest ``keep`` goals like an action server keeps finished goals for a while. The
``sim_bridge`` node publishes :meth:`GoalBook.entries` as ``<action>/_action/status`` and
answers ``<action>/_action/cancel_goal`` through :meth:`GoalBook.cancel_targets`. ROS-free:
the codes are :mod:`explore_seg.core.selection.nav_status`'s.
"""

from __future__ import annotations

from collections import OrderedDict

from explore_seg.core.selection import NavOutcome
from explore_seg.core.selection.nav_status import (STATUS_ABORTED, STATUS_ACCEPTED,
                                                   STATUS_CANCELED, STATUS_EXECUTING,
                                                   STATUS_SUCCEEDED, StatusEntry)
from sim_bridge.navigation.navigator import NavState, NavStatus

#: Navigator state -> GoalStatus code.
STATUS_OF_STATE = {NavState.ACTIVE: STATUS_EXECUTING, NavState.SUCCEEDED: STATUS_SUCCEEDED,
                   NavState.ABORTED: STATUS_ABORTED, NavState.CANCELED: STATUS_CANCELED}
#: Navigator terminal state -> the outcome the explorer's core is told (lock step).
OUTCOME_OF_STATE = {NavState.SUCCEEDED: NavOutcome.SUCCEEDED,
                    NavState.ABORTED: NavOutcome.ABORTED,
                    NavState.CANCELED: NavOutcome.CANCELED}
_ZERO_ID = bytes(16)


class GoalBook:
    """Goal ids and statuses of the stand-in (see the module docstring).

    Parameters
    ----------
    keep : int
        Goals listed (the newest; older finished ones are forgotten).
    """

    def __init__(self, keep: int = 10) -> None:
        if keep < 1:
            raise ValueError(f"keep must be >= 1, got {keep}")
        self.keep = int(keep)
        self._goals: OrderedDict[bytes, list] = OrderedDict()   # id -> [status, stamp_s]
        self._current: bytes | None = None
        self._count = 0
        self.version = 0

    @property
    def current(self) -> bytes | None:
        """Id of the newest accepted goal (None before the first)."""
        return self._current

    def accept(self, stamp_s: float) -> bytes:
        """A goal was accepted at ``stamp_s``: a replaced active goal is ABORTED."""
        if self._current is not None and self._goals[self._current][0] in (
                STATUS_ACCEPTED, STATUS_EXECUTING):
            self._goals[self._current][0] = STATUS_ABORTED
        self._count += 1
        goal_id = self._count.to_bytes(8, "big") + b"sim_goal"
        self._goals[goal_id] = [STATUS_ACCEPTED, float(stamp_s)]
        while len(self._goals) > self.keep:
            self._goals.popitem(last=False)
        self._current = goal_id
        self.version += 1
        return goal_id

    def follow(self, state: NavState) -> bool:
        """Update the current goal from the navigator's state; True when it changed."""
        if self._current is None or self._current not in self._goals:
            return False
        code = STATUS_OF_STATE.get(state)
        entry = self._goals[self._current]
        if code is None or entry[0] == code or entry[0] in (STATUS_SUCCEEDED, STATUS_ABORTED,
                                                           STATUS_CANCELED):
            return False
        entry[0] = code
        self.version += 1
        return True

    def cancel_targets(self, goal_id: bytes, stamp_s: float) -> list[bytes]:
        """Active goals a CancelGoal request names: all for a zero id and zero stamp,
        those accepted at or before ``stamp_s`` for a zero id, else that id if active."""
        active = [g for g, (st, _) in self._goals.items()
                  if st in (STATUS_ACCEPTED, STATUS_EXECUTING)]
        if goal_id != _ZERO_ID:
            return [g for g in active if g == goal_id]
        if stamp_s == 0.0:
            return active
        return [g for g in active if self._goals[g][1] <= stamp_s]

    def known(self, goal_id: bytes) -> bool:
        """True when ``goal_id`` is listed."""
        return goal_id in self._goals

    def stamp_of(self, goal_id: bytes) -> float:
        """Accept stamp of a listed goal."""
        return self._goals[goal_id][1]

    def entries(self) -> list[StatusEntry]:
        """The listed goals, oldest first."""
        return [StatusEntry(g, st, stamp) for g, (st, stamp) in self._goals.items()]


class OutcomeFollower:
    """The stand-in's outcome of the goal last sent, once (for the lock step, which has
    no status topic): :meth:`poll` returns (outcome, goal xy) when that goal ended."""

    def __init__(self) -> None:
        self._goal: tuple[float, float] | None = None

    def sent(self, goal_xy_m: tuple[float, float]) -> None:
        """A goal was given to the navigator."""
        self._goal = (float(goal_xy_m[0]), float(goal_xy_m[1]))

    def poll(self, status: NavStatus) -> tuple[NavOutcome, tuple[float, float]] | None:
        """(outcome, goal) when the goal last sent has ended since the last call."""
        goal = self._goal
        outcome = OUTCOME_OF_STATE.get(status.state)
        if goal is None or outcome is None or status.goal is None:
            return None
        if abs(status.goal[0] - goal[0]) > 1e-9 or abs(status.goal[1] - goal[1]) > 1e-9:
            return None
        self._goal = None
        return outcome, goal


__all__ = ["GoalBook", "OUTCOME_OF_STATE", "OutcomeFollower", "STATUS_OF_STATE"]
