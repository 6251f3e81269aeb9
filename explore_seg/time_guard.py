"""Time model of a node: clock jumps, disagreeing clock sources, stalls (ROS-free).

A node feeds :class:`TimeGuard` the stamp of every timed input (per stream: ``camera``,
``pose``, the node's own ``clock``) and gets a :class:`Jump` back when a stream goes back
(simulator restart, ``/clock`` reset, the message after a future-stamped one) or ahead by
more than ``jump_s``; it then resets what it keeps keyed by time and logs the jump once.
Given the node's clock, a stream's step ahead is measured against the time that passed on
that clock since the stream's previous newest stamp: a map published every 6 s with true
stamps (slam_toolbox's ``map_update_interval``) is a slow stream, not a clock jump, while
stamps that run ahead of the node's clock still are.
:meth:`TimeGuard.disagreement` names two streams whose newest stamps lie further apart
than ``jump_s`` (e.g. odometry an hour behind the camera). :class:`StallWatchdog` counts
periods in which inputs arrived but nothing was produced and says when to log why.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

_NS = 1_000_000_000


@dataclass(frozen=True)
class Jump:
    """A stream's stamp moved by more than the jump threshold."""

    stream: str
    from_ns: int
    to_ns: int

    @property
    def backwards(self) -> bool:
        """True for a jump back in time."""
        return self.to_ns < self.from_ns

    def describe(self) -> str:
        """One log line naming the stream, direction, size and both stamps."""
        d = abs(self.to_ns - self.from_ns) / _NS
        how = ("back (simulator restart or clock reset?)" if self.backwards
               else "ahead (future-stamped input or a paused source?)")
        return (f"{self.stream} stamps jumped {how} by {d:.1f} s: "
                f"{self.from_ns / _NS:.3f} -> {self.to_ns / _NS:.3f} s")


class TimeGuard:
    """Newest stamp per stream; detects jumps and streams that disagree.

    Examples
    --------
    >>> g = TimeGuard(jump_s=5.0)
    >>> g.observe("camera", 100 * _NS) is None
    True
    >>> g.observe("camera", 10 * _NS).backwards     # a sim restart
    True
    >>> g.newest("camera") == 10 * _NS              # the new time line is followed
    True
    """

    #: The stream of the node's own clock: the reference the other streams are measured
    #: against, so its own steps are checked against ``expected_gap_ns`` only.
    CLOCK = "clock"

    def __init__(self, jump_s: float, clock: Callable[[], int] | None = None) -> None:
        self.jump_s = float(jump_s)
        self._clock = clock
        self._newest: dict[str, int] = {}
        #: Node clock (ns) when each stream's newest stamp was recorded.
        self._seen_at: dict[str, int] = {}
        #: Jumps seen by :meth:`track`.
        self.jumps = 0

    def observe(self, stream: str, t_ns: int, expected_gap_ns: int = 0) -> Jump | None:
        """Record ``t_ns`` of ``stream``; a :class:`Jump` when it went back by more than
        ``jump_s`` or ahead by more than ``jump_s + expected_gap_ns`` plus, with a node
        clock, the time that clock advanced since the stream's newest stamp was recorded
        (a long gap between true stamps is no jump). After a jump the stream follows the
        new time line.

        >>> now = [100 * _NS]
        >>> g = TimeGuard(jump_s=5.0, clock=lambda: now[0])
        >>> g.observe("map", 99 * _NS) is None
        True
        >>> now[0] += 6 * _NS                            # the next map, 6 s later
        >>> g.observe("map", 105 * _NS) is None
        True
        >>> g.observe("map", 160 * _NS).describe()       # stamps ran ahead of the clock
        'map stamps jumped ahead (future-stamped input or a paused source?) by 55.0 s: 105.000 -> 160.000 s'
        """
        last = self._newest.get(stream)
        jump_ns = int(self.jump_s * _NS)
        now = self._clock() if (self._clock is not None and stream != self.CLOCK) else None
        if last is None:
            self._record(stream, t_ns, now)
            return None
        allowed_ns = jump_ns + max(0, expected_gap_ns)
        if now is not None:
            allowed_ns += max(0, now - self._seen_at.get(stream, now))
        if t_ns < last - jump_ns or t_ns > last + allowed_ns:
            self._record(stream, t_ns, now)
            return Jump(stream, last, t_ns)
        if t_ns >= last:
            self._record(stream, t_ns, now)
        return None

    def _record(self, stream: str, t_ns: int, now: int | None) -> None:
        self._newest[stream] = t_ns
        if now is not None:
            self._seen_at[stream] = now

    def track(self, stream: str, t_ns: int, warn: Callable[[str, str], None],
              on_back: Callable[[], str] | None = None, expected_gap_ns: int = 0) -> bool:
        """:meth:`observe`, then on a jump: count it (:attr:`jumps`), call ``on_back`` if
        it went back (it returns what it reset, for the log line) and ``warn(key, line)``
        (a throttled warning). True when it jumped."""
        jump = self.observe(stream, t_ns, expected_gap_ns)
        if jump is None:
            return False
        self.jumps += 1
        what = on_back() if (jump.backwards and on_back is not None) else ""
        warn(*jump_warning(jump, what))
        return True

    def newest(self, stream: str) -> int | None:
        """Newest stamp of ``stream`` (ns), None before the first."""
        return self._newest.get(stream)

    def disagreement(self, a: str, b: str) -> str | None:
        """A sentence when the newest stamps of ``a`` and ``b`` differ by more than
        ``jump_s`` (clock sources on different time bases), else None."""
        ta, tb = self._newest.get(a), self._newest.get(b)
        if ta is None or tb is None or abs(ta - tb) <= self.jump_s * _NS:
            return None
        d = (ta - tb) / _NS
        return (f"clock sources disagree: {a} stamps are {abs(d):.1f} s "
                f"{'ahead of' if d > 0 else 'behind'} {b} stamps ({ta / _NS:.3f} vs "
                f"{tb / _NS:.3f} s); is one source on another clock (use_sim_time)?")

    def forget(self, *streams: str) -> None:
        """Forget the named streams (every stream when none is named)."""
        if not streams:
            self._newest.clear()
            self._seen_at.clear()
        for name in streams:
            self._newest.pop(name, None)
            self._seen_at.pop(name, None)


def jump_warning(jump: Jump, after_back: str) -> tuple[str, str]:
    """(throttle key, log line) for a jump; ``after_back`` says what a jump back reset."""
    return (f"jump_{jump.stream}",
            jump.describe() + (f"; {after_back}" if jump.backwards and after_back else ""))


class StallWatchdog:
    """Says when a node that receives inputs has produced nothing for ``periods`` ticks.

    Examples
    --------
    >>> w = StallWatchdog(periods=2)
    >>> [w.tick(waiting=True, produced=False, reason=lambda: "why") for _ in range(4)]
    [None, 'why', None, 'why']
    >>> w.tick(waiting=True, produced=True, reason=lambda: "why") is None
    True
    """

    def __init__(self, periods: int) -> None:
        self.periods = max(1, int(periods))
        self._idle = 0
        #: The last reason reported (empty before the first stall).
        self.last_reason = ""

    def reset(self) -> None:
        """Start counting afresh (e.g. after the node was paused on purpose)."""
        self._idle = 0

    def tick(self, waiting: bool, produced: bool, reason: Callable[[], str]) -> str | None:
        """Count one period; the reason (computed only then) every ``periods`` stalled
        ticks, else None. ``waiting``: inputs are there but could not be used."""
        if produced or not waiting:
            self._idle = 0
            return None
        self._idle += 1
        if self._idle % self.periods:
            return None
        self.last_reason = reason()
        return self.last_reason
