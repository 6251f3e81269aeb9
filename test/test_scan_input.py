"""explore_seg.scan_input: scans paired with the robot pose of their time."""

from __future__ import annotations

import math

from explore_seg import convert
from explore_seg.core.scan_overlay import ScanOverlayParams
from explore_seg.scan_input import MAX_WAITING, ScanInput


def _scan(t_ns: int, n: int = 8):
    return convert.scan_to_msg([1.0] * n, -math.pi, 2 * math.pi / n, 0.1, 3.5,
                               header=convert.make_header("base_scan",
                                                          convert.ns_to_stamp(t_ns)))


def _input(**kw):
    got, warned = [], []
    si = ScanInput(lambda: ScanOverlayParams(**kw), lambda *a: got.append(a),
                   lambda key, text: warned.append((key, text)))
    return si, got, warned


def test_a_scan_gets_the_pose_nearest_its_stamp():
    si, got, _ = _input()
    for k in range(5):
        si.note_pose(k * 50_000_000, (float(k), 0.0, 0.0))
    si.on_scan(_scan(110_000_000))
    assert len(got) == 1 and got[0][0] == 0.11 and got[0][1] == (2.0, 0.0, 0.0)
    assert got[0][4] == 3.5 and got[0][5] == 0.1


def test_a_scan_ahead_of_the_poses_waits_for_one_of_its_time():
    si, got, warned = _input()
    si.note_pose(0, (0.0, 0.0, 0.0))
    si.on_scan(_scan(200_000_000))          # the odometry of its instant is not here yet
    assert got == [] and warned == []
    si.note_pose(200_000_000, (1.0, 0.0, 0.0))
    assert len(got) == 1 and got[0][1] == (1.0, 0.0, 0.0)


def test_scans_without_a_pose_of_their_time_are_dropped_with_a_warning():
    si, got, warned = _input(max_pose_age_s=0.2)
    si.note_pose(0, (0.0, 0.0, 0.0))
    for k in range(MAX_WAITING + 3):
        si.on_scan(_scan(5_000_000_000 + k))
    assert got == [] and si.dropped == 3
    assert warned[0][0] == "scan_pose" and "within 0.2 s" in warned[0][1]
    si.note_pose(5_000_000_000 + 100, (1.0, 0.0, 0.0))   # the waiting ones get their pose
    assert len(got) == MAX_WAITING and si.dropped == 3


def test_time_going_back_forgets_poses_and_waiting_scans():
    si, got, _ = _input()
    si.note_pose(1_000_000_000, (0.0, 0.0, 0.0))
    si.on_scan(_scan(1_500_000_000))
    si.note_pose(500_000_000, (0.0, 0.0, 0.0))           # time went back
    si.note_pose(1_600_000_000, (0.0, 0.0, 0.0))
    assert got == [] and si.dropped == 0


def test_malformed_scans_and_a_disabled_overlay():
    si, got, warned = _input()
    si.note_pose(0, (0.0, 0.0, 0.0))
    bad = _scan(0)
    bad.ranges = []
    si.on_scan(bad)
    assert got == [] and warned[0][0] == "scan" and "no ranges" in warned[0][1]
    off, got_off, _ = _input(enabled=False)
    off.note_pose(0, (0.0, 0.0, 0.0))
    off.on_scan(_scan(0))
    assert got_off == [] and off.dropped == 0
