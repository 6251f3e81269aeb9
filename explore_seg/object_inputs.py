"""Pairing bookkeeping of ``object_costmap``'s stamped inputs (ROS-free helpers).

:func:`wait_reason` says in one sentence why no camera frame can be processed now (the
stall watchdog logs it); :func:`lag_warning` why fewer frames were processed than could
be; :func:`purge_newer` drops buffered inputs of an abandoned time line
after a clock jump.
"""

from __future__ import annotations

from collections import deque
from typing import Any, Callable, Sequence

_NS = 1e9


def purge_newer(buf: deque, horizon_ns: int, stamp: Callable[[Any], int]) -> int:
    """Remove the entries of ``buf`` stamped after ``horizon_ns`` (order kept); returns
    how many were removed.

    >>> d = deque([1, 5, 2, 9]); purge_newer(d, 4, int), list(d)
    (2, [1, 2])
    """
    keep = [m for m in buf if stamp(m) <= horizon_ns]
    removed = len(buf) - len(keep)
    if removed:
        buf.clear()
        buf.extend(keep)
    return removed


def wait_reason(depth_ns: Sequence[int], color_ns: Sequence[int], pose_ns: Sequence[int],
                last_ns: int | None, sync_tol_s: float, pose_tol_s: float,
                min_gap_s: float) -> str:
    """Why the newest depth image is not processed, naming the stamps involved.

    ``pose_ns``: the stamps of the poses held (their oldest and newest suffice).

    Examples
    --------
    >>> wait_reason([100 * 10**9], [100 * 10**9], [50 * 10**9], None, 0.05, 0.2, 0.45)
    'no pose newer than image stamp 100.000 s (newest pose 50.000 s, pose_tolerance_s 0.2)'
    >>> wait_reason([100 * 10**9], [100 * 10**9], [900 * 10**9, 901 * 10**9], 100 * 10**9,
    ...             0.05, 0.2, 0.45)
    'no pose older than image stamp 100.000 s (oldest pose 900.000 s, pose_tolerance_s 0.2)'
    """
    if not depth_ns:
        return "no depth image"
    t = max(depth_ns)
    if pose_ns and t < min(pose_ns) - int(pose_tol_s * _NS):
        # Checked first: such frames are dropped as soon as they arrive, so the newest one
        # is always the last one taken.
        return (f"no pose older than image stamp {t / _NS:.3f} s (oldest pose "
                f"{min(pose_ns) / _NS:.3f} s, pose_tolerance_s {pose_tol_s:g})")
    if last_ns is not None and t < last_ns + int(min_gap_s * _NS):
        return (f"newest image stamp {t / _NS:.3f} s is not {min_gap_s:.2f} s after the last "
                f"processed one ({last_ns / _NS:.3f} s)")
    if not pose_ns:
        return "no robot pose received"
    newest_pose = max(pose_ns)
    if t > newest_pose + int(pose_tol_s * _NS):
        return (f"no pose newer than image stamp {t / _NS:.3f} s (newest pose "
                f"{newest_pose / _NS:.3f} s, pose_tolerance_s {pose_tol_s:g})")
    near = min((abs(c - t) for c in color_ns), default=None)
    if near is None or near > int(sync_tol_s * _NS):
        got = "no colour image" if near is None else f"nearest colour {near / _NS:.3f} s away"
        return f"no colour image within sync_tolerance_s {sync_tol_s:g} of the depth ({got})"
    return "a semantic image matching the depth stamp (oracle backend)"


def lag_warning(processed: int, received: int, span_s: float, rate_hz: float,
                malformed: int, without_pose: int) -> str:
    """The frame-lag warning: how many frames were processed, and why the others were not
    (malformed, no robot pose at their stamp, or not reached: too little CPU), with the
    advice for the largest share.

    >>> text = lag_warning(0, 40, 20.0, 2.0, malformed=0, without_pose=40)
    >>> text.startswith("processed 0 of 40 camera frames"), "lags behind" in text
    (True, False)
    """
    head = f"processed {processed} of {received} camera frames in the last {span_s:.0f} s " \
           f"(rate_hz {rate_hz:g}): "
    possible = min(received, span_s * rate_hz)
    unreached = max(0, round(possible - processed - malformed - without_pose))
    causes = [(without_pose, f"{without_pose} had no robot pose at their stamp",
               "check the pose source and its clock (see the 'dropped frame' warnings)"),
              (malformed, f"{malformed} malformed",
               "the camera sends frames that cannot be used (see the 'dropped frame' "
               "warnings)"),
              (unreached, f"{unreached} not reached in time",
               "the object layer lags behind the robot; lower the camera rate or the "
               "simulation's real-time factor, or run object_costmap in a process of its "
               "own")]
    advice = max(causes, key=lambda c: c[0])[2]
    return head + ", ".join(c[1] for c in causes) + "; " + advice
