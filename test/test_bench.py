"""bench/run_bench.py end to end on a tiny budget: outputs, reproducibility, --resume."""

from __future__ import annotations

import json
import time
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import run_bench, tasks  # noqa: E402
from bench_support import failing_on_seed  # noqa: E402

ARGS = ["--worlds", "small_house", "--strategies", "nearest", "--jobs", "1",
        "--max-sim-time", "20", "--no-tour", "--yolo-frames", "0"]


def _runs(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]


def _copy_results(src: Path, dst: Path) -> Path:
    """A new output folder holding ``src``'s runs and meta (what --resume reads)."""
    dst.mkdir()
    for name in ("runs.jsonl", "meta.json"):
        (dst / name).write_text((src / name).read_text())
    return dst


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    md = out / "B.md"
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(out), "--md", str(md)]) == 0
    return out, md


def test_outputs(first):
    out, md = first
    runs = _runs(out)
    assert [(r["world"], r["strategy"], r["seed"]) for r in runs] == [
        ("small_house", "nearest", 0)]
    assert runs[0]["sim_time_s"] <= 20.5
    assert (out / "runs.csv").is_file() and (out / "maps" / "small_house_nearest.png").is_file()
    meta = json.loads((out / "meta.json").read_text())
    assert len(meta["parts"]) == 1 and meta["parts"][0]["runs_run"] == 1
    text = md.read_text()
    assert "### small_house" in text and "| nearest | 1 | " in text
    assert "Run in" not in text                                 # one part: no list


def test_resume_runs_only_the_missing_seeds(first, tmp_path):
    out, _ = first
    res = _copy_results(out, tmp_path / "res")
    kept = _runs(res)[0]
    md = res / "B.md"
    assert run_bench.main(ARGS + ["--runs", "2", "--out", str(res), "--md", str(md),
                                  "--resume"]) == 0
    runs = _runs(res)
    assert [r["seed"] for r in runs] == [0, 1]
    assert runs[0] == kept                              # seed 0 was not run again
    meta = json.loads((res / "meta.json").read_text())
    assert [p["runs_run"] for p in meta["parts"]] == [1, 1]
    assert meta["wall_s"] == pytest.approx(sum(p["wall_s"] for p in meta["parts"]), abs=0.2)
    text = md.read_text()
    assert "Run in 2 parts" in text and "--resume" in text
    assert "| nearest | 2 | " in text


def test_same_seed_same_run(first, tmp_path):
    out, _ = first
    again = tmp_path / "again"
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(again), "--md", ""]) == 0
    a, b = _runs(out)[0], _runs(again)[0]
    for k in ("coverage_pct", "sim_time_s", "path_length_m", "goals_sent", "collisions"):
        assert a[k] == b[k], k


def _start_and_wait_for_a_run(out: Path, runs: int):
    """The benchmark as a process with ``runs`` runs to do, once its first run is in
    ``out/runs.jsonl`` (or after 2 minutes)."""
    import os
    import subprocess
    import time

    cmd = [sys.executable, str(ROOT / "bench" / "run_bench.py"), *ARGS, "--runs", str(runs),
           "--out", str(out), "--md", str(out / "B.md")]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    jl = out / "runs.jsonl"
    t0 = time.monotonic()
    while time.monotonic() - t0 < 120:
        if jl.is_file() and jl.read_text().count("\n") >= 1:
            break
        time.sleep(0.05)
    return proc


def test_sigterm_reports_what_ran_and_resume_finishes(tmp_path):
    import signal

    out = tmp_path / "int"
    proc = _start_and_wait_for_a_run(out, 4)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:  # all four runs finished before the signal: nothing to test
        pytest.skip("the benchmark finished before it could be interrupted")
    assert proc.returncode == 128 + signal.SIGTERM, err
    meta = json.loads((out / "meta.json").read_text())
    done = len(_runs(out))
    assert 1 <= done < 4 and meta["parts"][0]["interrupted"] is True
    assert meta["parts"][0]["runs_run"] == done
    from bench import records
    # every run written to runs.jsonl is in runs.jsonl.gz too (the signal waited for it)
    assert len(records.read_jsonl(out / records.COMPACT)) == done
    assert "(interrupted)" not in (out / "B.md").read_text()   # one part: no parts list
    assert run_bench.main(ARGS + ["--runs", "4", "--out", str(out), "--md",
                                  str(out / "B.md"), "--resume"]) == 0
    assert sorted(r["seed"] for r in _runs(out)) == [0, 1, 2, 3]
    text = (out / "B.md").read_text()
    assert "Run in 2 parts" in text and "(interrupted)" in text


def test_sigusr1_finishes_the_run_in_flight_and_starts_no_new_one(tmp_path):
    import signal

    out = tmp_path / "drain"
    proc = _start_and_wait_for_a_run(out, 5)
    proc.send_signal(signal.SIGUSR1)
    _, err = proc.communicate(timeout=120)
    if proc.returncode == 0:
        pytest.skip("the benchmark finished before the signal")
    assert proc.returncode == 128 + signal.SIGUSR1, err
    assert "finishing the 1 run(s) in flight" in err
    # run 1 was written after run 2 had been started: run 2 was finished, none after it
    assert sorted(r["seed"] for r in _runs(out)) == [0, 1], err
    meta = json.loads((out / "meta.json").read_text())
    assert meta["parts"][0]["interrupted"] is True and meta["parts"][0]["runs_run"] == 2
    assert run_bench.main(ARGS + ["--runs", "3", "--out", str(out), "--md", "",
                                  "--resume"]) == 0
    assert sorted(r["seed"] for r in _runs(out)) == [0, 1, 2]


def test_a_failing_run_is_reported_and_the_others_go_on(tmp_path, monkeypatch):
    real = tasks.run_exploration
    monkeypatch.setattr(tasks, "run_exploration", failing_on_seed(real, 1))   # forks inherit it
    out = tmp_path / "fail"
    assert run_bench.main(ARGS + ["--runs", "3", "--out", str(out), "--md",
                                  str(out / "B.md")]) == 1
    assert sorted(r["seed"] for r in _runs(out)) == [0, 2]
    part = json.loads((out / "meta.json").read_text())["parts"][0]
    assert part["failed"] == ["small_house/nearest/1: ValueError: boom"]
    assert part["runs_run"] == 2 and "interrupted" not in part
    monkeypatch.setattr(tasks, "run_exploration", real)
    assert run_bench.main(ARGS + ["--runs", "3", "--out", str(out), "--md", str(out / "B.md"),
                                  "--resume"]) == 0
    assert sorted(r["seed"] for r in _runs(out)) == [0, 1, 2]
    assert "(1 runs failed: `small_house/nearest/1: ValueError: boom`)" in (
        out / "B.md").read_text()


def test_resume_refuses_other_settings_and_unasked_runs(first, tmp_path, capsys):
    out, _ = first
    res = _copy_results(out, tmp_path / "res2")
    args = [x if x != "20" else "25" for x in ARGS]          # another --max-sim-time
    assert run_bench.main(args + ["--runs", "1", "--out", str(res), "--md", "", "--resume"]) == 2
    # same settings, another strategy: refused, naming the run it would drop
    other = [x if x != "nearest" else "explore_lite" for x in ARGS]
    before = (res / "runs.jsonl").read_text()
    capsys.readouterr()
    assert run_bench.main(other + ["--runs", "1", "--out", str(res), "--md", "", "--resume"]) == 2
    assert "holds 1 run (nearest x 1) in 1 world, seed 0, which this command does not ask" \
        in capsys.readouterr().err
    assert (res / "runs.jsonl").read_text() == before and not (res / "runs.jsonl.bak").exists()
    with pytest.raises(SystemExit):
        run_bench.main(other + ["--runs", "1", "--out", str(res), "--prune"])  # needs --resume
    # with --prune: the nearest run is dropped from the report, kept aside
    assert run_bench.main(other + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                   "--prune"]) == 0
    assert [r["strategy"] for r in _runs(res)] == ["explore_lite"]
    assert "nearest" in (res / "runs.jsonl.bak").read_text()


def test_redo_runs_the_named_strategy_again_and_keeps_the_old_runs_aside(first, tmp_path):
    out, _ = first
    res = _copy_results(out, tmp_path / "res3")
    runs = _runs(res)
    runs[0]["coverage_pct"] = -1.0        # marks the old run: a redone run cannot have it
    (res / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in runs))
    with pytest.raises(SystemExit):       # --redo without --resume, unknown strategy
        run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--redo", "nearest"])
    for bad in ("x", "explore_lite", "small_cluttered:nearest"):  # not asked for: an error
        with pytest.raises(SystemExit):
            run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--resume", "--redo", bad])
    assert [r["coverage_pct"] for r in _runs(res)] == [-1.0]
    (res / "runs.jsonl.bak").write_text("an earlier copy\n")
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--redo", "small_house:nearest"]) == 0
    redone = _runs(res)
    assert len(redone) == 1 and redone[0]["coverage_pct"] >= 0
    assert redone[0]["coverage_pct"] == _runs(out)[0]["coverage_pct"]   # same seed, same run
    assert (res / "runs.jsonl.bak").read_text() == "an earlier copy\n"   # not overwritten
    assert '"coverage_pct": -1.0' in (res / "runs.jsonl.bak1").read_text()
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--redo", "nearest"]) == 0                # every world
    assert _runs(res)[0]["coverage_pct"] == redone[0]["coverage_pct"]
    assert (res / "runs.jsonl.bak2").is_file()
    meta = json.loads((res / "meta.json").read_text())
    assert [p["runs_run"] for p in meta["parts"]] == [1, 1, 1]


def test_report_has_the_lockstep_vs_ros_table_with_object_frames(first, tmp_path):
    from bench import report

    out = _copy_results(first[0], tmp_path / "ros")
    (out / "runs.csv").write_text((first[0] / "runs.csv").read_text())
    rows = [{"seed": 0, "mode": "lock-step", "stop": "coverage", "coverage_pct": 99.1,
             "sim_time_s": 700.0, "path_length_m": 160.0, "collisions": 0, "goals": 80,
             "objects": 84, "object_frames": "every frame"},
            {"seed": 0, "mode": "ROS", "stop": "coverage", "coverage_pct": 99.2,
             "sim_time_s": 650.0, "path_length_m": 150.0, "collisions": 1.0, "goals": 90,
             "objects": 70, "object_frames": "500 of 1300"}]
    # (the ROS runs' counts come from the metrics topic as floats: printed as integers)
    (out / "ros.json").write_text(json.dumps({"note": "n", "rows": rows}))
    md = report.write_all(out, tmp_path / "B.md", command="x")
    text = md.read_text()
    assert "| goals | objects | object frames |" in text
    assert "| 0 | ROS | coverage | 99.2 | 650.0 | 150.0 | 1 | 90 | 70 | 500 of 1300 |" in text


def test_no_runs_keeps_every_run_and_adds_a_part(first, tmp_path):
    out = _copy_results(first[0], tmp_path / "keep")
    before = (out / "runs.jsonl").read_text()
    md = tmp_path / "K.md"
    assert run_bench.main(ARGS + ["--runs", "3", "--out", str(out), "--md", str(md),
                                  "--resume", "--no-runs"]) == 0
    assert (out / "runs.jsonl").read_text() == before           # nothing run, nothing dropped
    parts = json.loads((out / "meta.json").read_text())["parts"]
    assert len(parts) == 2 and parts[-1]["runs_run"] == 0 and "--no-runs" in parts[-1]["command"]
    assert "| nearest | 1 | " in md.read_text()
    # runs of a world the command does not name: refused, not dropped
    other = ARGS[:1] + ["house"] + ARGS[2:]
    assert run_bench.main(other + ["--out", str(out), "--md", "", "--resume", "--no-runs"]) == 2
    assert (out / "runs.jsonl").read_text() == before
    with pytest.raises(SystemExit):
        run_bench.main(ARGS + ["--out", str(out), "--no-runs"])      # needs --resume


def test_nav_margin_is_a_setting_and_earlier_folders_ran_on_zero(first, tmp_path):
    out, _ = first
    meta = json.loads((out / "meta.json").read_text())
    assert meta["settings"]["nav_inflation_margin_m"] == 0.0
    res = _copy_results(out, tmp_path / "margin")
    # a folder of a version that did not record the setting ran on 0.0: it still resumes
    del meta["settings"]["nav_inflation_margin_m"]
    (res / "meta.json").write_text(json.dumps(meta))
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--no-runs"]) == 0
    # the same folder with another margin: refused (its runs used the default)
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--nav-margin", "0.03"]) == 2
    # the default given explicitly is the same setting
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--nav-margin", "0", "--no-runs"]) == 0
    m = tmp_path / "m"
    md = m / "B.md"
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(m), "--md", str(md),
                                  "--nav-margin", "0.03"]) == 0
    assert json.loads((m / "meta.json").read_text())["settings"]["nav_inflation_margin_m"] == 0.03
    assert "the robot radius + 0.03 m" in md.read_text()
    for bad in ("-1", "0.5"):      # negative; beyond the inflation radius (0.6 - 0.22)
        with pytest.raises(SystemExit):
            run_bench.main(ARGS + ["--out", str(m), "--nav-margin", bad])
    assert run_bench.sim_params_for(None, 0.03).nav_inflation_margin_m == 0.03


def test_mapping_noise_is_a_setting_and_earlier_folders_ran_without(first, tmp_path):
    out, _ = first
    meta = json.loads((out / "meta.json").read_text())
    assert meta["settings"]["mapping_error"] == "none"
    res = _copy_results(out, tmp_path / "noise")
    del meta["settings"]["mapping_error"]
    (res / "meta.json").write_text(json.dumps(meta))
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--no-runs"]) == 0
    # its runs had no mapping error: resuming them with one is refused
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--mapping-noise", "realistic"]) == 2
    with pytest.raises(SystemExit):
        run_bench.main(ARGS + ["--out", str(tmp_path / "bad"), "--mapping-noise", "wild"])
    assert run_bench.sim_params_for(None, None, "harsh").mapping_error == "harsh"
    # a task carrying the profile runs with it
    task = ("small_house", "nearest", 0, 20.0, None, None, None, "harsh")
    plain = task[:7] + ("none",)

    def result(t):
        return {k: v for k, v in tasks.run_task(t).items()
                if k not in ("wall_time_s", "timings_ms", "cpu_time_s")}

    assert result(task) != result(plain)
    assert result(plain) == result(plain[:7])


@pytest.mark.parametrize("name", ["nav_inflation_soft_margin_m", "nav_arc_check_edges"])
def test_navigation_safety_setting_is_recorded_and_folders_that_did_not_record_it_ran_without(
        first, tmp_path, name):
    from sim_bridge.engine import SimParams

    out, _ = first
    meta = json.loads((out / "meta.json").read_text())
    value = getattr(SimParams(), name)
    assert value
    assert meta["settings"][name] == value
    same = _copy_results(out, tmp_path / "same")
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(same), "--md", "", "--resume",
                                  "--no-runs"]) == 0
    # a folder of a version that did not record it ran without it (0): not mixed with these
    res = _copy_results(out, tmp_path / "old")
    del meta["settings"][name]
    (res / "meta.json").write_text(json.dumps(meta))
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(res), "--md", "", "--resume",
                                  "--no-runs"]) == 2


def test_stop_signals_wait_for_the_end_of_a_deferred_block():
    import os
    import signal

    from bench.tasks import stop_signals_deferred
    before = signal.getsignal(signal.SIGTERM)
    done = []
    with pytest.raises(KeyboardInterrupt) as err:
        with stop_signals_deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)                       # the handler ran: the block goes on
            done.append(1)
    assert done == [1] and err.value.args == (signal.SIGTERM,)
    assert signal.getsignal(signal.SIGTERM) is before           # handler restored
    with stop_signals_deferred():                  # no signal: nothing raised
        done.append(2)
    assert done == [1, 2]


def _run_row(path95: float, path99: float) -> dict:
    return {"world": "w", "strategy": "s", "seed": 0, "completed": True,
            "stop_reason": "coverage", "collisions": 0, "goals_sent": 3, "goal_switches": 0,
            "wall_time_s": 1.0,
            "time_to_s": {"50": 10.0, "90": 20.0, "95": 30.0, "99": 40.0},
            "path_to_m": {"50": 1.0, "90": 2.0, "95": path95, "99": path99}}


def test_world_table_divides_the_median_path_to_99_by_the_tour():
    from bench import report

    runs = [_run_row(9.0, 12.0), dict(_run_row(11.0, 14.0), seed=1),
            dict(_run_row(11.0, None), seed=2, completed=False)]
    g = {("w", "s"): runs}
    head, _, row = report.world_table("w", g, ["s"], 10.0, None, {})
    cols = [c.strip() for c in head.split("|")]
    vals = [c.strip() for c in row.split("|")]
    assert vals[cols.index("path / tour")] == "1.30 (2)"     # median(12, 14) / 10, 2 of 3
    assert vals[cols.index("complete")] == "2/3"
    assert "code" not in cols and not any("routed" in c for c in cols)  # no routed runs
    _, _, no_tour = report.world_table("w", g, ["s"], None, None, {})
    assert [c.strip() for c in no_tour.split("|")][cols.index("path / tour")] == "-"


def test_tour_task_gives_the_95_tour_no_longer_than_the_99_one():
    row = tasks.tour_task("small_house")
    assert 0.0 < row["tour95_m"] <= row["tour_m"]
    assert 1 <= row["viewpoints95"]
