"""bench/quick.py: the subset's time-to-95 % ratios against the full run's."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import quick  # noqa: E402


def _row(world: str, strategy: str, seed: int, t95: float | None) -> dict[str, str]:
    return {"world": world, "strategy": strategy, "seed": str(seed),
            "time_to_95_s": "" if t95 is None else str(t95)}


def _full() -> list[dict[str, str]]:
    rows = []
    for seed, (p, n, lite) in enumerate([(100, 200, 100), (100, 200, 100),
                                         (300, 200, 100), (300, 200, 100)]):
        rows += [_row("w", "paper", seed, p), _row("w", "nearest", seed, n),
                 _row("w", "explore_lite", seed, lite)]
    return rows


def test_ratios_per_seed_subset_and_runs_that_never_got_there():
    full = _full() + [_row("w", "explore_lite", 9, None)]
    assert quick.t95_ratios(full, subject="paper") == {("w", "nearest"): 1.0,
                                                      ("w", "explore_lite"): 2.0}
    assert quick.t95_ratios(full, {0, 1}, subject="paper") == {("w", "nearest"): 0.5,
                                                              ("w", "explore_lite"): 1.0}


def test_comparison_states_how_far_the_subset_was_from_the_full_run():
    full = _full()
    sub = [r for r in full if int(r["seed"]) < 2]
    text = "\n".join(quick.comparison(sub, full, "paper"))
    assert "| w | nearest | 0.50 | 1.00 | 0.50 | -0.50 |" in text
    assert "| w | explore_lite | 1.00 | 2.00 | 1.00 | -1.00 |" in text
    assert "mean |quick - full| = 0.75 over 2" in text
    assert "faster (ratio < 1) in 1 of 2" in text


def test_the_default_subject_is_the_default_strategy_and_a_full_run_without_it_says_so():
    assert quick.DEFAULT_SUBJECT == "routed"
    full = _full()                                      # paper and the baselines only
    sub = [dict(r, strategy="routed") if r["strategy"] == "paper" else r
           for r in full if int(r["seed"]) < 2]
    text = "\n".join(quick.comparison(sub, full))
    assert "| w | nearest | 0.50 | - | - | - |" in text
    assert "The full run has no `routed` runs" in text


def test_list_prints_the_subsets_worlds_and_runs_nothing(tmp_path, capsys):
    out = tmp_path / "quick"
    assert quick.main(["--list", "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == (f"[bench] {len(quick.QUICK_WORLDS)} worlds x 3 strategies "
                        f"({quick.DEFAULT_SUBJECT}, explore_lite, nearest) x {quick.QUICK_RUNS} runs:")
    listed = dict(line.split("\t") for line in lines[1:])
    assert tuple(listed) == quick.QUICK_WORLDS
    root = Path(__file__).resolve().parents[1] / "worlds"
    assert listed["shared/house"] == str(root / "house.world.yaml")
    assert listed["eb/corner"] == str(root / "explore_bench" / "corner.yaml")
    assert all(v == "(generated)" or Path(v).is_file() for v in listed.values())
    assert not out.exists()
