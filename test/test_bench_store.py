"""bench/store.py: the files of a benchmark folder besides its run records (no runs)."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import records, store  # noqa: E402


def _rec(seed: int, strategy: str = "nearest") -> dict:
    return {"world": "w", "strategy": strategy, "seed": seed, "wall_time_s": float(seed)}


def test_csv_round_trip_keeps_every_column_in_order_of_appearance(tmp_path):
    p = tmp_path / "t.csv"
    store.write_csv(p, [{"a": 1, "b": 2}, {"b": 3, "c": 4}])
    assert store.read_csv(p) == [{"a": "1", "b": "2", "c": ""}, {"a": "", "b": "3", "c": "4"}]
    store.write_csv(p, [])
    assert store.read_csv(p) == [] and store.read_csv(tmp_path / "absent.csv") == []


def test_backup_never_overwrites_an_earlier_copy(tmp_path):
    p = tmp_path / "runs.jsonl"
    p.write_text("1")
    assert store.backup(p).name == "runs.jsonl.bak"
    p.write_text("2")
    assert store.backup(p).name == "runs.jsonl.bak1"
    assert (tmp_path / "runs.jsonl.bak").read_text() == "1"


def test_parts_settings_and_meta(tmp_path):
    old = {"command": "c", "started": "s", "wall_s": 2.0}          # before "parts" existed
    assert store.parts_of(old) == [{"command": "c", "started": "s", "runs_run": None,
                                    "wall_s": 2.0}]
    assert store.parts_of({}) == []
    assert store.same_settings({"max_sim_time": 0.0},
                               {"max_sim_time": 0.0, "nav_inflation_margin_m": 0.0})
    assert not store.same_settings(None, {}) and not store.same_settings(
        {"nav_inflation_margin_m": 0.03}, {"nav_inflation_margin_m": 0.0})
    store.write_meta(tmp_path, {"runs": 1}, old, {"command": "d", "wall_s": 3.0})
    meta = store.read_json(tmp_path / "meta.json")
    assert [p["command"] for p in meta["parts"]] == ["c", "d"] and meta["wall_s"] == 5.0
    (tmp_path / "bad.json").write_text("[1]")
    assert store.read_json(tmp_path / "bad.json") == {}
    assert store.slug("shared/house.v2") == "shared_house_v2"


def test_resume_keeps_the_runs_asked_for_and_copies_the_others(tmp_path):
    records.write_compact(tmp_path, [_rec(0), _rec(1), _rec(5), _rec(0, "paper")])
    tasks = [("w", "nearest", k, 10.0, None, None, None) for k in range(3)]
    tasks += [("w", "paper", 0, 10.0, None, None, None)]
    kept, todo = store.resume(tmp_path, tasks, [(None, "paper")])
    assert sorted((d["strategy"], d["seed"]) for d in kept) == [("nearest", 0), ("nearest", 1)]
    assert [(t[1], t[2]) for t in todo] == [("nearest", 2), ("paper", 0)]
    assert (tmp_path / (records.COMPACT + ".bak")).is_file()     # seed 5 and paper/0 aside
