"""Idle after ``exploration_done``: pause a node's periodic work while the flag is true.

``target_selector`` publishes ``exploration_done`` (std_msgs/Bool, MAP_QOS: latched); once
it is true nothing consumes new object boxes or regions, yet the simulator or robot keeps
sending camera frames and maps. :class:`DoneGate` subscribes to the flag and, while it is
true (and the node's ``idle_when_done`` is set), cancels the node's timers and destroys
the input subscriptions made through :meth:`DoneGate.subscribe` (sensor streams: odometry,
camera, scan), which it makes again when the flag turns false (``~/start`` or ``~/resume``
of the selector); the node keeps its state, and inputs that are not paused (the latched
map) keep being stored, so the first tick after the pause works on fresh data. Each
transition is logged at info level (at most once per :data:`LOG_PERIOD_S`).

Why subscriptions too: with the timers cancelled, rclpy's executor still wakes for every
message (about 1 ms each for the ``explorer`` process's three nodes), and odometry at the
simulator's tick rate plus camera frames kept a quarter of a core busy after done.
"""

from __future__ import annotations

from typing import Any, Callable

from rclpy.node import Node
from rclpy.subscription import Subscription
from rclpy.timer import Timer
from std_msgs.msg import Bool

from explore_seg.node_util import WarnThrottle
from explore_seg.qos import MAP_QOS

#: Seconds between two logged pauses (or resumes) of one node: a flapping flag is one line.
LOG_PERIOD_S = 5.0


class DoneGate:
    """Pauses ``timers()`` while ``exploration_done`` is true and ``enabled()`` holds.

    ``timers`` is called at each transition (a node may have replaced its timer after a
    rate change); ``on_resume`` runs after the timers are reset, e.g. to forget
    watchdog counts and clock stamps that went stale during the pause.
    """

    def __init__(self, node: Node, what: str, timers: Callable[[], list[Timer]],
                 enabled: Callable[[], bool],
                 on_resume: Callable[[], None] | None = None) -> None:
        self._node = node
        self._what = what
        self._timers = timers
        self._enabled = enabled
        self._on_resume = on_resume
        self._done = False
        #: True while the timers are cancelled.
        self.paused = False
        #: Number of pauses so far.
        self.pauses = 0
        self._specs: list[tuple[tuple[Any, ...], dict[str, Any]]] = []
        self._subs: list[Subscription] = []
        self._log = WarnThrottle(node, LOG_PERIOD_S)
        node.create_subscription(Bool, "exploration_done", self._on_done, MAP_QOS)

    def subscribe(self, *args: Any, **kwargs: Any) -> None:
        """``node.create_subscription(*args, **kwargs)``, destroyed while paused."""
        self._specs.append((args, kwargs))
        if not self.paused:
            self._subs.append(self._node.create_subscription(*args, **kwargs))

    @property
    def subscriptions(self) -> list[Subscription]:
        """The live pausable subscriptions (none while paused)."""
        return list(self._subs)

    def _on_done(self, msg: Bool) -> None:
        self._done = bool(msg.data)
        self.update()

    def adopt(self, timer: Timer) -> Timer:
        """A timer the node just created (rate change): cancelled while paused."""
        if self.paused:
            timer.cancel()
        return timer

    def update(self) -> None:
        """Pause or resume after the flag or ``enabled()`` changed."""
        want = self._done and self._enabled()
        if want == self.paused:
            return
        self.paused = want
        if want:
            self.pauses += 1
            for t in self._timers():
                t.cancel()
            for sub in self._subs:
                self._node.destroy_subscription(sub)
            self._subs = []
            self._log.info("pause", f"exploration done: {self._what} paused until "
                                    "exploration_done turns false (idle_when_done)")
            return
        self._subs = [self._node.create_subscription(*a, **kw) for a, kw in self._specs]
        for t in self._timers():
            t.reset()
        if self._on_resume is not None:
            self._on_resume()
        self._log.info("resume", f"{self._what} resumed" + (
            "" if self._done else " (exploration_done is false)"))
