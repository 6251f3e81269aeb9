"""A map-frame robot pose at odometry rate: SLAM corrections composed with odometry.

SLAM (slam_toolbox's ``pose``) gives map <- base only per processed scan, and none while the
robot stands still; odometry (``odom``) gives odom <- base at 20-50 Hz but drifts. For each
SLAM pose at stamp ``t_k``, :class:`PoseFusion` interpolates the odometry at ``t_k`` and keeps
the correction ``map <- odom = T_map_base(t_k) o T_odom_base(t_k)^-1``; the pose at any stamp
``t`` in the kept window is ``correction(t) o T_odom_base(t)`` (corrections are interpolated
between their stamps, the newest is used after it, the oldest before it). A SLAM pose newer
than the newest odometry waits until the odometry passes its stamp.

Sources (:data:`POSE_SOURCES`, the ``pose_topic_type`` of ``object_costmap`` and
``target_selector``):

``odom``
    odometry alone, already in the map frame (``sim_bridge``'s default);
``pose``
    the SLAM pose alone (interpolated between its stamps; stalls while SLAM is silent);
``fused``
    the composition above; where no correction exists yet or the odometry does not cover
    a stamp, the SLAM pose alone.

Faults: a stamp that goes back by more than ``backwards_s`` on either stream (simulator
reset) clears everything; a SLAM pose farther than ``jump_m`` / ``jump_rad`` from the
fused pose at its stamp (loop closure) is accepted and re-keys the fusion (older
corrections are forgotten, so no pose blends the two). Both return a :class:`PoseEvent` for
the node to log. Non-finite poses raise ``ValueError``.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

from explore_seg.core.angles import wrap_angle
from explore_seg.core.fields import param_meta

#: Robot pose sources, see the module docstring.
POSE_SOURCES = ("odom", "pose", "fused")
#: The docstring of a node's ``pose_topic_type`` (one text for every node).
POSE_SOURCE_DOC = (
    "where the robot pose in the map frame comes from: 'odom' (nav_msgs/Odometry on 'odom', "
    "already in the map frame: the simulator), 'pose' (PoseWithCovarianceStamped on 'pose', "
    "e.g. slam_toolbox: stalls while SLAM processes no scan) or 'fused' (both: the latest "
    "SLAM correction map<-odom composed with odometry in pose_fusion.odom_frame, a map-frame "
    "pose at odometry rate; see pose_fusion.*)")

Pose2D = tuple[float, float, float]
_NS = 1_000_000_000
#: SLAM poses kept while they wait for odometry past their stamp.
_MAX_PENDING = 16


@dataclass(frozen=True)
class PoseFusionParams:
    """Settings of :class:`PoseFusion` (``pose_fusion.*`` in the nodes that bind it).

    Raises
    ------
    ValueError
        From ``__post_init__`` on an empty frame or a non-positive or non-finite value.
    """

    odom_frame: str = field(default="odom", metadata=param_meta(
        "frame of the odometry with pose_topic_type 'fused' (slam_toolbox's odom_frame)"))
    history_s: float = field(default=10.0, metadata=param_meta(
        "odometry, SLAM poses and corrections are kept this long (newest stamp minus this); "
        "an image older than that gets no pose", "s", range=(0.0, math.inf)))
    match_tolerance_s: float = field(default=0.1, metadata=param_meta(
        "a SLAM pose makes a correction only with odometry this close to its stamp on both "
        "sides (a one-sided match while turning would tilt the correction)", "s",
        range=(0.0, math.inf)))
    backwards_s: float = field(default=0.5, metadata=param_meta(
        "an odometry or SLAM stamp this much older than the newest one (simulator reset) "
        "clears the fusion (logged)", "s", range=(0.0, math.inf)))
    jump_m: float = field(default=0.3, metadata=param_meta(
        "a SLAM pose farther than this from the fused pose at its stamp (loop closure) "
        "re-keys the fusion: older corrections are forgotten (logged)", "m",
        range=(0.0, math.inf)))
    jump_rad: float = field(default=0.3, metadata=param_meta(
        "as jump_m, for the correction's heading", "rad", range=(0.0, math.inf)))
    odom_until_first_slam: bool = field(default=True, metadata=param_meta(
        "with 'fused', odometry stands for the map pose until the first SLAM pose arrives "
        "(slam_toolbox starts map and odom together and publishes a pose only per "
        "processed scan: a robot standing still after start-up, or whose first pose was "
        "published before this node subscribed, would otherwise never get a pose)"))

    def __post_init__(self) -> None:
        if not self.odom_frame.strip():
            raise ValueError("odom_frame must not be empty")
        for name in ("history_s", "match_tolerance_s", "backwards_s", "jump_m", "jump_rad"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")


@dataclass(frozen=True)
class PoseEvent:
    """Something the node should log once: ``kind`` is ``reset``, ``jump`` or ``dropped``."""

    kind: str
    message: str


# ------------------------------------------------------------------ SE(2) helpers
def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """``a o b``: the pose ``b`` (given in frame ``a``) in ``a``'s parent frame.

    >>> tuple(round(v, 6) for v in compose((1.0, 0.0, math.pi / 2), (1.0, 0.0, 0.0)))
    (1.0, 1.0, 1.570796)
    """
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrap_angle(a[2] + b[2]))


def inverse(a: Pose2D) -> Pose2D:
    """``a^-1`` (``compose(a, inverse(a))`` is the identity)."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], wrap_angle(-a[2]))


def blend(a: Pose2D, b: Pose2D, w: float) -> Pose2D:
    """Linear between ``a`` (w = 0) and ``b`` (w = 1), heading along the shorter arc."""
    da = wrap_angle(b[2] - a[2])
    return (a[0] + w * (b[0] - a[0]), a[1] + w * (b[1] - a[1]), wrap_angle(a[2] + w * da))


class StampedPoses:
    """Poses sorted by stamp (ns), kept ``history_ns`` back from the newest."""

    def __init__(self, history_ns: int) -> None:
        self.history_ns = int(history_ns)
        self._t: list[int] = []
        self._p: list[Pose2D] = []

    def __len__(self) -> int:
        return len(self._t)

    def add(self, t_ns: int, pose: Pose2D) -> None:
        """Insert (a pose at an existing stamp replaces it); trims the old end."""
        i = bisect.bisect_left(self._t, t_ns)
        if i < len(self._t) and self._t[i] == t_ns:
            self._p[i] = pose
        else:
            self._t.insert(i, t_ns)
            self._p.insert(i, pose)
        cut = bisect.bisect_left(self._t, self._t[-1] - self.history_ns)
        if cut:
            del self._t[:cut], self._p[:cut]

    def clear(self) -> None:
        """Forget every pose."""
        self._t.clear()
        self._p.clear()

    def drop_newer(self, horizon_ns: int) -> int:
        """Forget poses stamped after ``horizon_ns``; how many were dropped."""
        i = bisect.bisect_right(self._t, horizon_ns)
        n = len(self._t) - i
        del self._t[i:], self._p[i:]
        return n

    def newest(self) -> tuple[int, Pose2D] | None:
        """The newest (stamp, pose), None when empty."""
        return (self._t[-1], self._p[-1]) if self._t else None

    def span_ns(self) -> tuple[int, int] | None:
        """(oldest, newest) stamp, None when empty."""
        return (self._t[0], self._t[-1]) if self._t else None

    def at(self, t_ns: int, tol_ns: int | None = None, both_sides: bool = False
           ) -> Pose2D | None:
        """The pose at ``t_ns``: interpolated between its neighbours when both lie within
        ``tol_ns``, else (unless ``both_sides``) the nearest within ``tol_ns``; None when
        none does. ``tol_ns=None``: clamp to the ends (any distance)."""
        if not self._t:
            return None
        i = bisect.bisect_left(self._t, t_ns)
        if i < len(self._t) and self._t[i] == t_ns:
            return self._p[i]
        tol = math.inf if tol_ns is None else tol_ns
        ok_b = i > 0 and t_ns - self._t[i - 1] <= tol
        ok_a = i < len(self._t) and self._t[i] - t_ns <= tol
        if ok_b and ok_a:
            t0, t1 = self._t[i - 1], self._t[i]
            return blend(self._p[i - 1], self._p[i], (t_ns - t0) / (t1 - t0))
        if (ok_b or ok_a) and not both_sides:
            return self._p[i - 1] if ok_b else self._p[i]
        return None


def _check(t_ns: int, pose: Pose2D, what: str) -> Pose2D:
    if not all(math.isfinite(v) for v in pose):
        raise ValueError(f"{what} pose must be finite, got {pose} at {t_ns / _NS:.3f} s")
    return (float(pose[0]), float(pose[1]), wrap_angle(float(pose[2])))


class PoseFusion:
    """Robot pose in the map frame from odometry and/or SLAM poses (see module docstring).

    Examples
    --------
    >>> f = PoseFusion("fused", PoseFusionParams())
    >>> f.add_odom(0, (0.0, 0.0, 0.0)); f.add_odom(10**9, (1.0, 0.0, 0.0))
    >>> f.add_map_pose(0, (5.0, 2.0, 0.0))           # SLAM: the robot is at (5, 2)
    >>> f.pose_at(10**9, 10**8)                      # odometry moved it 1 m since
    (6.0, 2.0, 0.0)
    """

    def __init__(self, source: str, params: PoseFusionParams) -> None:
        if source not in POSE_SOURCES:
            raise ValueError(f"source must be one of {POSE_SOURCES}, got {source!r}")
        self.source = source
        self.params = params
        h = int(params.history_s * _NS)
        self._odom = StampedPoses(h)
        self._slam = StampedPoses(h)
        self._corr = StampedPoses(h)          # map <- odom, keyed by SLAM stamp
        self._pending: list[tuple[int, Pose2D]] = []    # SLAM poses ahead of the odometry
        #: Counts of resets (time going back) and re-keys (loop closures).
        self.resets = 0
        self.rekeys = 0

    # ------------------------------------------------------------------ inputs
    def add_odom(self, t_ns: int, pose: Pose2D) -> PoseEvent | None:
        """Odometry (``odom`` source: map frame; ``fused``: odom frame)."""
        pose = _check(t_ns, pose, "odometry")
        event = self._went_back(self._odom, t_ns, "odometry")
        self._odom.add(t_ns, pose)
        if self._pending:
            event = self._resolve_pending() or event
        return event

    def add_map_pose(self, t_ns: int, pose: Pose2D) -> PoseEvent | None:
        """A SLAM pose (map frame)."""
        pose = _check(t_ns, pose, "SLAM")
        event = self._went_back(self._slam, t_ns, "SLAM pose")
        self._slam.add(t_ns, pose)
        if self.source != "fused":
            return event
        self._pending.append((t_ns, pose))
        del self._pending[:-_MAX_PENDING]
        return self._resolve_pending() or event

    def set_params(self, params: PoseFusionParams) -> None:
        """New settings (history applies from the next input)."""
        self.params = params
        for buf in (self._odom, self._slam, self._corr):
            buf.history_ns = int(params.history_s * _NS)

    def clear(self) -> None:
        """Forget everything (the time line was abandoned)."""
        for buf in (self._odom, self._slam, self._corr):
            buf.clear()
        self._pending.clear()

    def drop_newer(self, horizon_ns: int) -> None:
        """Forget everything stamped after ``horizon_ns`` (a node saw the clock jump back)."""
        for buf in (self._odom, self._slam, self._corr):
            buf.drop_newer(horizon_ns)
        self._pending = [tp for tp in self._pending if tp[0] <= horizon_ns]

    # ----------------------------------------------------------------- queries
    def _odom_stands_for_map(self) -> bool:
        """``fused`` before any SLAM pose: odometry is the map pose (see the parameter)."""
        return (self.source == "fused" and self.params.odom_until_first_slam
                and not len(self._slam) and not len(self._corr) and not self._pending)

    def pose_at(self, t_ns: int, tol_ns: int) -> Pose2D | None:
        """The map-frame pose at ``t_ns`` from inputs within ``tol_ns`` of it; None if none."""
        if self.source == "odom" or self._odom_stands_for_map():
            return self._odom.at(t_ns, tol_ns)
        if self.source == "fused" and len(self._corr):
            odom = self._odom.at(t_ns, tol_ns)
            if odom is not None:
                return compose(self._corr.at(t_ns), odom)
        return self._slam.at(t_ns, tol_ns)

    def latest(self) -> tuple[int, Pose2D] | None:
        """The newest (stamp, map-frame pose) available, None before the first."""
        t = self.newest_ns()
        if t is None:
            return None
        pose = self.pose_at(t, 0)
        return None if pose is None else (t, pose)

    def newest_ns(self) -> int | None:
        """Newest stamp a pose can be given for (odometry rate once fused)."""
        span = self.span_ns()
        return None if span is None else span[1]

    def span_ns(self) -> tuple[int, int] | None:
        """(oldest, newest) stamp of the poses held for :meth:`pose_at` (odometry rate once
        fused); None before the first. An image older than the oldest by more than the
        tolerance has no pose (e.g. odometry stamped on another clock, ahead)."""
        if self.source == "odom" or self._odom_stands_for_map():
            buf = self._odom
        elif self.source == "fused" and len(self._corr) and len(self._odom):
            buf = self._odom
        else:
            buf = self._slam
        return buf.span_ns()

    def describe(self) -> str:
        """The stamps held, for a log line."""
        def span(buf: StampedPoses, what: str) -> str:
            s = buf.span_ns()
            return f"{what} {s[0] / _NS:.2f}..{s[1] / _NS:.2f} s" if s else f"no {what}"
        parts = {"odom": [span(self._odom, "odometry")], "pose": [span(self._slam, "SLAM pose")],
                 "fused": [span(self._odom, "odometry"), span(self._slam, "SLAM pose"),
                           f"{len(self._corr)} corrections"]}[self.source]
        return ", ".join(parts)

    # --------------------------------------------------------------- internals
    def _went_back(self, buf: StampedPoses, t_ns: int, what: str) -> PoseEvent | None:
        newest = buf.newest()
        if newest is None or t_ns >= newest[0] - int(self.params.backwards_s * _NS):
            return None
        self.clear()
        self.resets += 1
        return PoseEvent("reset", f"{what} stamp went back {(newest[0] - t_ns) / _NS:.2f} s "
                                  f"({newest[0] / _NS:.3f} -> {t_ns / _NS:.3f} s): pose "
                                  "fusion cleared (simulator reset?)")

    def _resolve_pending(self) -> PoseEvent | None:
        """Turn the SLAM poses the odometry now covers into corrections."""
        newest_odom = self._odom.newest()
        if newest_odom is None:
            return None
        tol = int(self.params.match_tolerance_s * _NS)
        event = None
        keep = []
        for t_ns, pose in self._pending:
            if t_ns > newest_odom[0]:
                keep.append((t_ns, pose))
                continue
            odom = self._odom.at(t_ns, tol, both_sides=True)
            if odom is None:
                event = PoseEvent("dropped", f"SLAM pose at {t_ns / _NS:.3f} s has no "
                                             "odometry on both sides within "
                                             f"{self.params.match_tolerance_s:g} s "
                                             f"({self.describe()}): no correction made")
                continue
            event = self._add_correction(t_ns, pose, odom) or event
        self._pending = keep
        return event

    def _add_correction(self, t_ns: int, slam: Pose2D, odom: Pose2D) -> PoseEvent | None:
        """Keep map <- odom at ``t_ns``; a jump is judged at the robot: the SLAM pose
        against the pose the corrections so far predict (not the correction itself, which
        swings by the heading drift times the odometry's distance from its origin)."""
        predicted = self._corr.at(t_ns) if len(self._corr) else None
        self._corr.add(t_ns, compose(slam, inverse(odom)))
        if predicted is None:
            return None
        was = compose(predicted, odom)
        d_m = math.hypot(slam[0] - was[0], slam[1] - was[1])
        d_rad = abs(wrap_angle(slam[2] - was[2]))
        if d_m <= self.params.jump_m and d_rad <= self.params.jump_rad:
            return None
        self._corr.clear()
        self._corr.add(t_ns, compose(slam, inverse(odom)))
        self.rekeys += 1
        return PoseEvent("jump", f"SLAM pose at {t_ns / _NS:.3f} s is {d_m:.2f} m / "
                                 f"{d_rad:.2f} rad from the fused pose (loop closure?): "
                                 "accepted, older corrections forgotten")
