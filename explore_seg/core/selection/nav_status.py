"""Which navigation goal is ours, and how it ended: Nav2's action status without nav2_msgs.

``bt_navigator`` turns every ``goal_pose`` message into a ``navigate_to_pose`` action goal
with an id we never see. Its status topic (``navigate_to_pose/_action/status``, an
``action_msgs/GoalStatusArray``) lists the goals the server knows with their status.
:class:`GoalStatusTracker` (ROS-free; the node converts the message into
:class:`StatusEntry` tuples) attributes to our goal the newest goal that appears after our
publish and was not known before it, and reports its terminal status once as a
:class:`~explore_seg.core.selection.goals.NavOutcome`. A goal that does not appear within
``accept_timeout_s`` while a status publisher exists counts as REJECTED (a rejected
action goal never shows up in the status array).

Examples
--------
>>> t = GoalStatusTracker(accept_timeout_s=2.0)
>>> t.goal_sent(0.0, (1.0, 2.0))
>>> t.update([StatusEntry(b"a" * 16, STATUS_EXECUTING, 0.1)], 0.1)
[NavEvent(kind='accepted', goal_id=b'aaaaaaaaaaaaaaaa', goal_xy_m=(1.0, 2.0), outcome=None, message='goal accepted by the navigator')]
>>> t.update([StatusEntry(b"a" * 16, STATUS_ABORTED, 0.1)], 3.0)[0].outcome.value
'aborted'
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Iterable

from explore_seg.core.selection.goals import NavOutcome

# action_msgs/msg/GoalStatus codes (mirrored here: the core does not import ROS messages).
STATUS_UNKNOWN = 0
STATUS_ACCEPTED = 1
STATUS_EXECUTING = 2
STATUS_CANCELING = 3
STATUS_SUCCEEDED = 4
STATUS_CANCELED = 5
STATUS_ABORTED = 6
_ACTIVE = (STATUS_ACCEPTED, STATUS_EXECUTING, STATUS_CANCELING)
_TERMINAL = (STATUS_SUCCEEDED, STATUS_CANCELED, STATUS_ABORTED)
#: A goal that already ended and was accepted this long before our publish is not ours (s).
_OLD_GOAL_SLACK_S = 1.0
#: Goal ids remembered as "known before our publish" (oldest forgotten first).
_KNOWN_IDS_MAX = 1024


@dataclass(frozen=True)
class StatusEntry:
    """One element of a GoalStatusArray: goal id (16 bytes), status code, accept stamp."""

    goal_id: bytes
    status: int
    stamp_s: float


@dataclass(frozen=True)
class NavEvent:
    """Something the caller logs or acts on.

    ``kind``: ``accepted`` (our goal found), ``outcome`` (terminal: ``outcome`` set),
    ``ignored`` (bad or unknown input; ``message`` says what).
    """

    kind: str
    goal_id: bytes | None
    goal_xy_m: tuple[float, float] | None
    outcome: NavOutcome | None
    message: str


class GoalStatusTracker:
    """Attribute action goals to our published goals and report how they ended.

    Parameters
    ----------
    accept_timeout_s : float
        A published goal that no status array shows within this time is REJECTED (only
        checked while a status publisher exists, see :meth:`check_timeout`).
    """

    def __init__(self, accept_timeout_s: float = 5.0) -> None:
        if not (math.isfinite(accept_timeout_s) and accept_timeout_s > 0):
            raise ValueError(f"accept_timeout_s must be finite and > 0, got {accept_timeout_s}")
        self.accept_timeout_s = float(accept_timeout_s)
        self._known: deque[bytes] = deque(maxlen=_KNOWN_IDS_MAX)
        self._known_set: set[bytes] = set()
        self._goal_xy: tuple[float, float] | None = None
        self._sent_s = 0.0
        self._id: bytes | None = None
        self._status = STATUS_UNKNOWN
        self._cancel_requested = False

    # ----------------------------------------------------------------- state
    @property
    def goal_id(self) -> bytes | None:
        """The action goal id attributed to our current goal (None until seen)."""
        return self._id

    @property
    def goal_xy_m(self) -> tuple[float, float] | None:
        """Our current goal (None when none is pending or it ended)."""
        return self._goal_xy

    @property
    def active(self) -> bool:
        """True while our goal is pending or running (not ended, not given up)."""
        return self._goal_xy is not None

    def _remember(self, goal_id: bytes) -> None:
        if goal_id in self._known_set:
            return
        if len(self._known) == self._known.maxlen:
            self._known_set.discard(self._known[0])
        self._known.append(goal_id)
        self._known_set.add(goal_id)

    # ---------------------------------------------------------------- inputs
    def goal_sent(self, now_s: float, goal_xy_m: tuple[float, float]) -> None:
        """We published ``goal_xy_m`` at ``now_s``: the next new action goal is ours (an
        earlier attributed goal, e.g. on a re-publish, is no longer ours)."""
        if self._id is not None:
            self._remember(self._id)
        self._goal_xy = (float(goal_xy_m[0]), float(goal_xy_m[1]))
        self._sent_s = float(now_s)
        self._id = None
        self._status = STATUS_UNKNOWN
        self._cancel_requested = False

    def cancel_requested(self) -> None:
        """We asked the navigator to cancel: a CANCELED outcome is then ours."""
        self._cancel_requested = True

    def clear(self) -> None:
        """Forget our goal (after our cancel, on stop or reset); known ids are kept."""
        if self._id is not None:
            self._remember(self._id)
        self._goal_xy, self._id, self._status = None, None, STATUS_UNKNOWN
        self._cancel_requested = False

    def update(self, entries: Iterable[StatusEntry], now_s: float) -> list[NavEvent]:
        """Digest one status array; events in order (at most one outcome per goal)."""
        events: list[NavEvent] = []
        entries = list(entries)
        valid: list[StatusEntry] = []
        for e in entries:
            if not isinstance(e.goal_id, bytes) or len(e.goal_id) != 16:
                events.append(NavEvent("ignored", None, None, None,
                                       f"status entry with goal id {e.goal_id!r} (expected "
                                       "16 bytes): ignored"))
            elif e.status not in _ACTIVE + _TERMINAL + (STATUS_UNKNOWN,):
                events.append(NavEvent("ignored", e.goal_id, None, None,
                                       f"status {e.status} of goal {e.goal_id.hex()[:8]} is "
                                       "not a GoalStatus code (0..6): ignored"))
            else:
                valid.append(e)
        if self._goal_xy is not None and self._id is None:
            # Unknown ids only; one that already ended and was accepted well before our
            # publish is an old goal whose array we missed, not ours.
            new = [e for e in valid if e.goal_id not in self._known_set
                   and e.status != STATUS_UNKNOWN
                   and not (e.status in _TERMINAL
                            and e.stamp_s < self._sent_s - _OLD_GOAL_SLACK_S)]
            if new:
                mine = max(new, key=lambda e: e.stamp_s)
                self._id = mine.goal_id
                events.append(NavEvent("accepted", mine.goal_id, self._goal_xy, None,
                                       "goal accepted by the navigator"))
        for e in valid:
            if e.goal_id != self._id:
                self._remember(e.goal_id)   # someone else's (or an old one of ours)
                continue
            if self._goal_xy is None or e.status == self._status:
                continue
            self._status = e.status
            if e.status in _TERMINAL:
                events.append(self._outcome(e))
        return events

    def _outcome(self, e: StatusEntry) -> NavEvent:
        outcome = {STATUS_SUCCEEDED: NavOutcome.SUCCEEDED,
                   STATUS_ABORTED: NavOutcome.ABORTED,
                   STATUS_CANCELED: (NavOutcome.CANCELED_BY_US if self._cancel_requested
                                     else NavOutcome.CANCELED)}[e.status]
        xy = self._goal_xy
        self.clear()
        return NavEvent("outcome", e.goal_id, xy, outcome,
                        f"navigation {outcome.value} for goal ({xy[0]:.2f}, {xy[1]:.2f})")

    def check_timeout(self, now_s: float, publisher_present: bool) -> NavEvent | None:
        """REJECTED when our goal did not appear within ``accept_timeout_s`` while a
        status publisher exists (without one: None, the caller's progress timeout
        applies). A clock that went backwards (sim reset) restarts the wait."""
        if self._goal_xy is None or self._id is not None:
            return None
        if now_s < self._sent_s:
            self._sent_s = float(now_s)
            return None
        if not publisher_present or now_s - self._sent_s <= self.accept_timeout_s:
            return None
        xy = self._goal_xy
        self.clear()
        return NavEvent("outcome", None, xy, NavOutcome.REJECTED,
                        f"goal ({xy[0]:.2f}, {xy[1]:.2f}) not accepted within "
                        f"{self.accept_timeout_s:g} s: rejected")


__all__ = ["GoalStatusTracker", "NavEvent", "STATUS_ABORTED", "STATUS_ACCEPTED",
           "STATUS_CANCELED", "STATUS_CANCELING", "STATUS_EXECUTING", "STATUS_SUCCEEDED",
           "STATUS_UNKNOWN", "StatusEntry"]
