"""``bench/trace_decisions.py``: the per-decision trace and the groups' dump of a window.

Short lock-step runs (a few seconds of sim time) of the small Explore-Bench world
eb/corridor_asym (shipped in ``worlds/explore_bench``).
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import trace_decisions  # noqa: E402


def _read(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_routed_groups_window_holds_every_group_of_each_decision(tmp_path):
    summ = trace_decisions.trace_run("eb/corridor_asym", "routed", 0, tmp_path, 0.05,
                                     trace_decisions.TraceOptions(groups_window=(0.0, 4.0),
                                                                  max_sim_time_s=6.0))
    assert summ["end_s"] <= 6.1 and summ["stop"] == "timeout"
    trace = _read(tmp_path / "trace_eb_corridor_asym_routed_0.csv")
    groups = _read(tmp_path / "groups_eb_corridor_asym_routed_0.csv")
    assert list(groups[0]) == list(trace_decisions.GROUP_FIELDS)
    times = sorted({float(g["t_s"]) for g in groups})
    in_window = [r for r in trace if float(r["t_s"]) <= 4.0]
    assert times == [float(r["t_s"]) for r in in_window] and len(times) >= 4
    for r in in_window:
        rows = [g for g in groups if g["t_s"] == r["t_s"]]
        assert len(rows) == int(r["n_frontiers"])
        chosen = [g for g in rows if g["chosen"] == "1"]
        assert len(chosen) == 1
        # The chosen group's point is the goal sent, its numbers those of the trace row.
        if r["action"] == "new_goal":
            assert (chosen[0]["point_x_m"], chosen[0]["point_y_m"]) == (
                r["goal_x_m"], r["goal_y_m"])
        assert float(chosen[0]["gain_m2"]) == pytest.approx(float(r["gain_m2"]))
        assert float(chosen[0]["tour_cost_m"]) == pytest.approx(float(r["chosen_cost"]),
                                                               abs=0.01)
        # Places in the tour: 0..k-1 once each, over the groups with a finite tour cost.
        toured = sorted(int(g["tour_position"]) for g in rows if g["tour_position"])
        assert toured == list(range(len(toured)))
        assert all(float(g["tour_cost_m"]) < float("inf") for g in rows
                   if g["tour_position"])


def test_without_a_tour_the_groups_have_no_tour_columns(tmp_path):
    trace_decisions.trace_run("eb/corridor_asym", "nearest", 0, tmp_path, 0.05,
                              trace_decisions.TraceOptions(groups_window=(0.0, 1.0),
                                                           max_sim_time_s=2.0))
    groups = _read(tmp_path / "groups_eb_corridor_asym_nearest_0.csv")
    assert groups and all(g["tour_position"] == g["gain_m2"] == "" for g in groups)
    assert sum(g["chosen"] == "1" for g in groups if g["t_s"] == groups[0]["t_s"]) == 1


def test_no_groups_file_without_a_window_and_bad_options_are_refused(tmp_path, capsys):
    trace_decisions.trace_run("eb/corridor_asym", "nearest", 0, tmp_path, 0.05,
                              trace_decisions.TraceOptions(max_sim_time_s=1.0))
    assert not list(tmp_path.glob("groups_*"))
    with pytest.raises(SystemExit) as exc:
        trace_decisions.main(["--worlds", "eb/corridor_asym", "--groups", "10",
                              "--out", str(tmp_path)])
    assert exc.value.code == 2
    assert "--groups expects T0:T1" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        trace_decisions.main(["--worlds", "eb/corridor_asym", "--max-sim-time", "0",
                              "--out", str(tmp_path)])
    assert exc.value.code == 2
    assert "--max-sim-time must be > 0" in capsys.readouterr().err


def test_mapping_noise_reaches_the_simulator(tmp_path):
    with pytest.raises(ValueError, match="mapping_error"):
        trace_decisions.trace_run("eb/corridor_asym", "nearest", 0, tmp_path, 0.05,
                                  trace_decisions.TraceOptions(max_sim_time_s=1.0,
                                                               mapping_error="bogus"))
    summ = trace_decisions.trace_run("eb/corridor_asym", "nearest", 0, tmp_path, 0.05,
                                     trace_decisions.TraceOptions(max_sim_time_s=1.0,
                                                                  mapping_error="harsh"))
    assert summ["end_s"] <= 1.1
