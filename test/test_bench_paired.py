"""bench/paired.py: arms of parameter overrides, their parameters, the paired report, and
one tiny end-to-end comparison where the arms must differ."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import paired  # noqa: E402
from bench_support import failing_on_seed  # noqa: E402
from sim_bridge.engine import SimParams  # noqa: E402
from sim_bridge.lockstep import ExplorerParams, LockstepParams  # noqa: E402


def test_parse_arm_plain_and_with_overrides():
    assert paired.parse_arm("new") == paired.Arm("new")
    arm = paired.parse_arm("old:explorer.segmentation.clutter_max_extent_m=0; sim.x=1")
    assert arm.name == "old"
    assert arm.overrides == (("explorer.segmentation.clutter_max_extent_m", "0"),
                             ("sim.x", "1"))
    assert paired.parse_arm(arm.spec()) == arm
    for bad in (":a=1", "x:novalue", "x:=3"):
        with pytest.raises(ValueError):
            paired.parse_arm(bad)


def test_build_params_applies_each_override_by_type_and_leaves_the_rest():
    base = (ExplorerParams(), SimParams(), LockstepParams())
    arm = paired.parse_arm("a:explorer.segmentation.clutter_max_extent_m=0;"
                           "sim.nav_inflation_soft_margin_m=0.05;lockstep.nav_feedback=true;"
                           "explorer.selection.strategy=nearest")
    ex, sim, ls = paired.build_params(arm, *base)
    assert ex.segmentation.clutter_max_extent_m == 0.0
    assert ex.selection.strategy == "nearest"
    assert sim.nav_inflation_soft_margin_m == 0.05
    assert ls.nav_feedback is True
    assert ex.frontier == base[0].frontier
    assert sim.robot_radius_m == base[1].robot_radius_m
    assert paired.build_params(paired.Arm("b"), *base) == base


@pytest.mark.parametrize("spec", [
    "a:explorer.nosuch.x=1",                          # unknown section
    "a:explorer.segmentation.nosuch=1",               # unknown field
    "a:sim.nav_inflation_soft_margin_m=-1",           # rejected by the dataclass
    "a:lockstep.nav_feedback=maybe",                  # not a bool
    "a:other.x=1",                                    # unknown prefix
])
def test_build_params_rejects(spec):
    with pytest.raises(ValueError):
        paired.build_params(paired.parse_arm(spec), ExplorerParams(), SimParams(),
                            LockstepParams())


def _row(arm, world, seed, t95, completed=1, collisions=0):
    return {"arm": arm, "world": world, "strategy": "paper", "seed": seed,
            "time_to_95_s": t95, "completed": completed, "collisions": collisions}


def test_report_pairs_by_seed_and_skips_unfinished_pairs():
    rows = [_row("ref", "w", 0, 100.0), _row("ref", "w", 1, 200.0), _row("ref", "w", 2, 50.0),
            _row("b", "w", 0, 80.0), _row("b", "w", 1, 220.0, collisions=2),
            _row("b", "w", 2, None, completed=0)]
    text = paired.report(rows, ["ref", "b"])
    line = next(x for x in text.splitlines() if x.startswith("| w | paper | b |"))
    cells = [c.strip() for c in line.strip("|").split("|")]
    # complete, contacts, median T95 of the finished runs, median of the ratios 0.8 / 1.1
    assert cells[3:] == ["2/3", "2", "150.0", "0.950", "1/1"]
    assert "| (all) | paper | ref | 3/3 | 0 | 100.0 | 1 | - |" in text


def test_against_report_pairs_strategies_by_seed_and_checks_the_best_plus_5_percent():
    def row(world, strategy, seed, t95):
        return {**_row("cur", world, seed, t95), "strategy": strategy}
    rows = [row("w", "routed", 0, 90.0), row("w", "routed", 1, 122.0),
            row("w", "explore_lite", 0, 100.0), row("w", "explore_lite", 1, 100.0),
            row("w", "nearest", 0, 180.0), row("w", "nearest", 1, None),
            row("v", "routed", 0, 130.0), row("v", "explore_lite", 0, 100.0),
            row("v", "nearest", 0, 120.0), _row("other-arm", "v", 0, 1.0)]
    rows[0]["core_ms_p95"], rows[1]["core_ms_p95"] = 40.0, 100.0    # w's routed runs
    text = paired.against_report(rows, "cur", "routed")
    cells = {ln.split("|")[1].strip(): [c.strip() for c in ln.strip("|").split("|")]
             for ln in text.splitlines() if ln.startswith("| ")}
    # w: ratios 0.9 and 1.22 against explore_lite; only seed 0 pairs with nearest (0.5)
    assert cells["w"][1:] == ["106.0", "1.060 (1/1)", "0.500 (1/0)", "no (1.06x)", "70 / 100"]
    assert cells["v"][1:] == ["130.0", "1.300 (0/1)", "1.083 (0/1)", "no (1.30x)", "-"]
    assert cells["(all pairs)"][2:4] == ["1.220 (1/2)", "0.792 (1/1)"]
    assert cells["(all pairs, time to 99 %)"][2:4] == ["-", "-"]    # no run has a T99
    for r, t99 in zip(rows[:6], [100.0, 150.0, 125.0, 100.0, 200.0, None]):
        r["time_to_99_s"] = t99                           # w: 0.8, 1.5 / lite; 0.5 / nearest
    text = paired.against_report(rows, "cur", "routed")
    line = next(ln for ln in text.splitlines() if ln.startswith("| (all pairs, time to 99"))
    assert [c.strip() for c in line.strip("|").split("|")][2:4] == ["1.150 (1/1)",
                                                                     "0.500 (1/0)"]
    rows[0]["time_to_95_s"] = 80.0                        # w: median 101 <= 1.05 * 100
    assert "| w | 101.0 | 1.010 (1/1) | 0.444 (1/0) | yes | 70 / 100 |" in \
        paired.against_report(rows, "cur", "routed")
    assert "coverage tour" not in paired.against_report(rows, "cur", "routed")
    for r, path in zip(rows[:6], [55.0, 60.0, 66.0, 50.0, 80.0, None]):
        r["path_to_99_m"] = path                          # w's tour 50 m; v has none
    line = next(ln for ln in paired.against_report(rows, "cur", "routed", {"w": 50.0})
                .splitlines() if ln.startswith("| (path to 99 % / coverage tour"))
    assert [c.strip() for c in line.strip("|").split("|")][1:4] == [
        "1.150 (n=2)", "1.160 (n=2)", "1.600 (n=1)"]


def test_load_tours_reads_the_benchmarks_tours(tmp_path):
    (tmp_path / "tours.csv").write_text("world,tour_m,viewpoints\na,53.0,8\nb,nan,0\n")
    assert paired.load_tours(tmp_path / "tours.csv") == {"a": 53.0}
    assert paired.load_tours(tmp_path / "missing.csv") == {}


def test_a_second_comparison_on_the_same_folder_is_refused_while_one_runs(tmp_path):
    import fcntl

    (tmp_path / "p").mkdir()
    with (tmp_path / "p" / ".lock").open("w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        with pytest.raises(SystemExit):
            paired.main(["--out", str(tmp_path / "p"), "--worlds", "eb/corridor_asym",
                         "--arm", "a", "--arm", "b"])
    assert not (tmp_path / "p" / "runs.jsonl").exists()


def test_one_arm_reports_absolute_figures_and_no_arm_is_refused(tmp_path, capsys):
    out = tmp_path / "p"
    out.mkdir()
    rows = [_row("cur", "eb/corridor_asym", 0, 90.0), _row("cur", "eb/corridor_asym", 1, 110.0,
                                                          collisions=1)]
    (out / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    args = ["--out", str(out), "--worlds", "eb/corridor_asym", "--seeds", "0-1", "--no-runs"]
    assert paired.main(args + ["--arm", "cur"]) == 0
    assert "| eb/corridor_asym | paper | cur | 2/2 | 1 | 100.0 | 1 | - |" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        paired.main(args)


def test_parse_seeds():
    assert paired.parse_seeds("0-2,5,1") == [0, 1, 2, 5]


def test_tiny_comparison_end_to_end(tmp_path):
    """Two arms on one short run: a 1 s decision period cannot give the same run as the
    default, the kept runs are not run again, and a reused arm name is refused."""
    os.environ.setdefault("EXPLORE_SEG_STRICT", "1")
    out = tmp_path / "p"
    args = ["--out", str(out), "--worlds", "eb/corridor_asym", "--seeds", "0",
            "--max-sim-time", "30", "--jobs", "1", "--arm", "ref",
            "--arm", "slow:lockstep.decision_period_s=3"]
    assert paired.main(args + ["--md", str(out / "r.md"), "--title", "tiny"]) == 0
    md = (out / "r.md").read_text()
    assert md.startswith("### tiny\n") and "--arm ref" in md and "| eb/corridor_asym | paper | slow |" in md
    assert "Runs made with code " in md and "(2 runs)" in md
    rows = [json.loads(x) for x in (out / "runs.jsonl").read_text().splitlines()]
    assert sorted(r["arm"] for r in rows) == ["ref", "slow"]
    assert all(r["code"] for r in rows)
    by = {r["arm"]: r for r in rows}
    assert by["ref"]["goals_sent"] != by["slow"]["goals_sent"] or \
        by["ref"]["path_length_m"] != by["slow"]["path_length_m"]
    assert paired.main(args) == 0
    assert len((out / "runs.jsonl").read_text().splitlines()) == 2
    assert paired.main(args[:5] + ["0-3", "--no-runs"] + args[6:]) == 0   # seeds 1-3: none run
    assert len((out / "runs.jsonl").read_text().splitlines()) == 2
    with pytest.raises(SystemExit):
        paired.main(args[:-1] + ["slow:lockstep.decision_period_s=2"])


_SHORT = ["--worlds", "small_house", "--strategies", "nearest", "--max-sim-time", "15",
          "--jobs", "1", "--arm", "cur"]


def _seeds(out: Path) -> list[int]:
    return sorted(int(json.loads(x)["seed"]) for x in (out / "runs.jsonl").read_text().splitlines())


def test_a_failing_run_is_reported_and_the_others_go_on(tmp_path, monkeypatch, capsys):
    real = paired.run_exploration
    monkeypatch.setattr(paired, "run_exploration", failing_on_seed(real, 1))   # forks inherit it
    out = tmp_path / "fail"
    args = ["--out", str(out), *_SHORT, "--seeds", "0-2"]
    assert paired.main(args) == 1
    assert _seeds(out) == [0, 2]
    assert "cur/small_house/nearest/1: ValueError: boom" in capsys.readouterr().err
    monkeypatch.setattr(paired, "run_exploration", real)
    assert paired.main(args) == 0                            # runs only the missing one
    assert _seeds(out) == [0, 1, 2]


def test_sigusr1_finishes_the_run_in_flight_and_starts_no_new_one(tmp_path):
    import signal
    import subprocess
    import time

    out = tmp_path / "drain"
    cmd = [sys.executable, str(ROOT / "bench" / "paired.py"), "--out", str(out), *_SHORT,
           "--seeds", "0-4"]
    proc = subprocess.Popen(cmd, cwd=ROOT, env=dict(os.environ, OMP_NUM_THREADS="1"),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    jl = out / "runs.jsonl"
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120 and not (jl.is_file() and jl.read_text().count("\n")):
        time.sleep(0.05)
    proc.send_signal(signal.SIGUSR1)
    report, err = proc.communicate(timeout=120)
    if proc.returncode == 0:
        pytest.skip("the comparison finished before the signal")
    assert proc.returncode == 128 + signal.SIGUSR1, err
    assert "finishing the 1 run(s) in flight" in err and "stopped after 2 of 5 runs" in err
    # seed 0 was written after seed 1 had been started: seed 1 finished, none after it
    assert _seeds(out) == [0, 1], err
    row = next(x for x in report.splitlines() if x.startswith("| small_house | nearest | cur |"))
    assert row.split("|")[4].strip().endswith("/2")        # the report covers the 2 runs
    assert paired.main(["--out", str(out), *_SHORT, "--seeds", "0-4"]) == 0
    assert _seeds(out) == [0, 1, 2, 3, 4]


def test_a_plugin_module_s_strategy_is_compared(tmp_path):
    """``--plugin MODULE`` imports a module that registers a strategy; without it the
    strategy is refused by name."""
    from explore_seg.core.selection.strategy import unregister

    out = tmp_path / "p"
    args = ["--out", str(out), "--worlds", "small_house", "--strategies",
            "farthest_first_plugin", "--seeds", "0", "--max-sim-time", "10", "--jobs", "1",
            "--arm", "cur"]
    sys.modules.pop("farthest_first_plugin", None)
    with pytest.raises(SystemExit):
        paired.main(args)
    with pytest.raises(SystemExit):
        paired.main(args + ["--plugin", "no_such_plugin_module"])
    try:
        assert paired.main(args + ["--plugin", "farthest_first_plugin"]) == 0
    finally:
        unregister("farthest_first_plugin")
        sys.modules.pop("farthest_first_plugin", None)
    rows = [json.loads(x) for x in (out / "runs.jsonl").read_text().splitlines()]
    assert [r["strategy"] for r in rows] == ["farthest_first_plugin"]
    assert rows[0]["goals_sent"] >= 1
