"""Simulator metrics: coverage, collisions, JSON and bounded history."""

from __future__ import annotations

import json

import pytest

from explore_seg.core.grid import GridMap, grid_from_ascii
from sim_bridge.metrics import CollisionEvent, CoverageReference, SimMetrics


def test_coverage_counts_inside_cells_known_free_in_a_shifted_map():
    truth, _ = grid_from_ascii("""
    ######
    #....#
    #....#
    ######
    """, resolution_m=0.1)
    inside = truth.free_mask()
    ref = CoverageReference(inside, truth)
    mdata, _ = grid_from_ascii("""
    ???????
    ??..#.?
    ???????
    ??????.
    """, resolution_m=0.1)
    # origin (-0.1, -0.1): map cell (r, c) lies on truth cell (r - 1, c - 1), so map row 2
    # covers inside row 1: 3 of the 8 inside cells known free, 4 known.
    shifted = GridMap(mdata.data, 0.1, (-0.1, -0.1))
    assert ref.coverage(shifted) == pytest.approx((37.5, 50.0))
    off_lattice = GridMap(mdata.data, 0.1, (-0.1 + 0.01, -0.1 + 0.01))   # general path
    assert ref.coverage(off_lattice) == pytest.approx((37.5, 50.0))


def test_metrics_json_and_diagnostics(tmp_path):
    m = SimMetrics(None, history_max=4)
    m.add_distance(1.5)
    m.add_collision(CollisionEvent(2.0, 1.0, 2.0, "chair_1", "chair", "seat"))
    m.goal_received()
    m.goal_aborted("collision with chair_1 (seat)")
    out = m.to_json(tmp_path / "a" / "m.json")
    d = json.loads(out.read_text())
    assert d["collisions"] == 1 and d["path_length_m"] == 1.5 and d["coverage_pct"] is None
    assert d["collision_events"][0]["object"] == "chair_1"
    assert d["abort_reasons"] == {"collision with": 1}
    diag = dict(m.to_diagnostics())
    assert diag["collisions"] == "1" and diag["goals_aborted"] == "1"
    assert "chair_1/seat" in diag["last_collision"]


def test_coverage_history_stays_bounded():
    truth, _ = grid_from_ascii("....\n....")
    gt = type("GT", (), {"inside": truth.free_mask(), "lidar": truth})()
    m = SimMetrics(gt, history_max=8)
    for k in range(100):
        m.update_coverage(truth, float(k))
    hist = m.coverage_history
    assert len(hist) < 8 and hist[0][0] == 0.0 and hist[-1][0] > 80.0
    assert all(c == 100.0 for _, c in hist)
