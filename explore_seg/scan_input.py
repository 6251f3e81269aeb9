"""The lidar scans of ``target_selector``: each ``scan`` with the robot pose of its stamp,
for the decision core's scan overlay (:class:`~explore_seg.core.scan_overlay.ScanOverlay`).

There is no tf here: the robot's map-frame poses come from the node's pose input, and the
scan's stamp picks the nearest of the recent ones (at most ``scan_overlay.max_pose_age_s``
away); the scanner's mount on the robot is ``scan_overlay.lidar_*``. A scan that arrives
before any pose of its time or later (a driver publishing the scan before the odometry of
the same instant) waits for one, up to :data:`MAX_WAITING` scans. A scan without such a
pose, or a malformed one, is dropped with a throttled warning naming what was expected.
"""

from __future__ import annotations

from bisect import bisect_left
from collections import deque
from typing import Callable

import numpy as np
from sensor_msgs.msg import LaserScan

from explore_seg import convert
from explore_seg.core.scan_overlay import ScanOverlayParams

#: Robot poses kept for matching scan stamps (at 50 Hz odometry: 4 s).
POSE_HISTORY = 200
#: Scans kept waiting for a pose of their time (at 10 Hz: 1 s).
MAX_WAITING = 10

#: (stamp_s, robot pose, angles, ranges, range_max_m, range_min_m) -> None
ScanSink = Callable[[float, tuple[float, float, float], np.ndarray, np.ndarray, float, float],
                    None]


class ScanInput:
    """Pair ``scan`` messages with recent robot poses and hand them to ``sink``.

    Parameters
    ----------
    params : callable
        The node's current :class:`ScanOverlayParams`.
    sink : ScanSink
        Usually :meth:`Explorer.add_scan`; a ValueError it raises drops the scan.
    warn : callable
        The node's throttled warning, ``warn(key, text)``.
    """

    def __init__(self, params: Callable[[], ScanOverlayParams], sink: ScanSink,
                 warn: Callable[[str, str], None]) -> None:
        self._params = params
        self._sink = sink
        self._warn = warn
        self._stamps: deque[int] = deque(maxlen=POSE_HISTORY)
        self._poses: deque[tuple[float, float, float]] = deque(maxlen=POSE_HISTORY)
        self._waiting: deque[tuple[int, np.ndarray, np.ndarray, float, float]] = deque()
        self.used = 0
        self.dropped = 0

    def clear(self) -> None:
        """Forget the poses and the waiting scans (time went back)."""
        self._stamps.clear()
        self._poses.clear()
        self._waiting.clear()

    def note_pose(self, t_ns: int, pose: tuple[float, float, float]) -> None:
        """A new newest map-frame robot pose; an older stamp than the last restarts the
        history (time went back). Scans waiting for a pose of this time are handed on."""
        if self._stamps and t_ns < self._stamps[-1]:
            self.clear()
        self._stamps.append(int(t_ns))
        self._poses.append(pose)
        while self._waiting and self._waiting[0][0] <= t_ns:
            self._hand_on(*self._waiting.popleft())

    def pose_at(self, t_ns: int) -> tuple[tuple[float, float, float] | None, float]:
        """The kept pose nearest to ``t_ns`` and its distance in seconds (None, inf:
        no pose kept)."""
        if not self._stamps:
            return None, float("inf")
        stamps = list(self._stamps)
        i = bisect_left(stamps, t_ns)
        best = min((j for j in (i - 1, i) if 0 <= j < len(stamps)),
                   key=lambda j: abs(stamps[j] - t_ns))
        return self._poses[best], abs(stamps[best] - t_ns) * 1e-9

    def on_scan(self, msg: LaserScan) -> None:
        """Subscription callback: validate, find the pose, hand on; drop on a fault."""
        p = self._params()
        if not p.enabled:
            return
        try:
            t_ns = convert.checked_stamp_ns(msg.header.stamp, "scan")
            angles, ranges = convert.scan_ranges(msg)
        except ValueError as err:
            self._drop("scan", f"dropped scan: {err}")
            return
        item = (t_ns, angles, ranges, float(msg.range_max), float(msg.range_min))
        if self._stamps and self._stamps[-1] >= t_ns:
            self._hand_on(*item)
            return
        self._waiting.append(item)
        while len(self._waiting) > MAX_WAITING:
            self._hand_on(*self._waiting.popleft())

    def _hand_on(self, t_ns: int, angles: np.ndarray, ranges: np.ndarray, range_max: float,
                 range_min: float) -> None:
        """Give the scan to the sink with the pose nearest its stamp, or drop it."""
        p = self._params()
        pose, age_s = self.pose_at(t_ns)
        if pose is None or age_s > p.max_pose_age_s:
            self._drop("scan_pose", f"dropped scan stamped {t_ns * 1e-9:.3f} s: expected a "
                                    f"robot pose within {p.max_pose_age_s:g} s of it, got "
                                    + ("none" if pose is None else f"one {age_s:.3f} s away"))
            return
        try:
            self._sink(t_ns * 1e-9, pose, angles, ranges, range_max, range_min)
        except ValueError as err:
            self._drop("scan", f"dropped scan: {err}")
            return
        self.used += 1

    def _drop(self, key: str, text: str) -> None:
        self.dropped += 1
        self._warn(key, text)
