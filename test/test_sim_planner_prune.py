"""The navigation stand-in's pruned planning gives exactly the whole-window result."""

from __future__ import annotations

import numpy as np
import pytest

from sim_bridge.navigation import NavParams, cost_grid, plan_path
from sim_bridge.navigation import planner


def _random_map(rng: np.random.Generator) -> np.ndarray:
    """A cost grid with random clutter, wall pieces and an unknown part."""
    h, w = (int(v) for v in rng.integers(40, 120, 2))
    blocked = rng.random((h, w)) < rng.uniform(0.0, 0.03)
    for _ in range(int(rng.integers(1, 6))):
        if rng.random() < 0.5:
            r = int(rng.integers(0, h))
            blocked[r, int(rng.integers(0, w // 2)):int(rng.integers(w // 2, w))] = True
        else:
            c = int(rng.integers(0, w))
            blocked[int(rng.integers(0, h // 2)):int(rng.integers(h // 2, h)), c] = True
    unknown = np.zeros((h, w), bool)
    unknown[:, int(rng.integers(0, w)):] = True
    return cost_grid(blocked, unknown, 0.05, NavParams())


def _compare(seed: int) -> int:
    """Plans on random maps with and without pruning must be bit-identical; returns how
    many plans the pruned search gave (certified)."""
    rng = np.random.default_rng(seed)
    pruned = 0
    orig = planner._pruned_search

    def counting(*a):
        nonlocal pruned
        out = orig(*a)
        pruned += out[0] is not None
        return out

    planner._pruned_search = counting
    try:
        for _ in range(6):
            cost = _random_map(rng)
            free = np.argwhere(np.isfinite(cost))
            for _ in range(6):
                s = tuple(int(v) for v in free[rng.integers(len(free))])
                g = tuple(int(v) for v in free[rng.integers(len(free))])
                ref = plan_path(cost, s, g, 0.05, 0.5, prune=False)
                hint = None if ref is None else ref[1] * float(rng.uniform(0.3, 2.0))
                for h in (None, hint):
                    got = plan_path(cost, s, g, 0.05, 0.5, cost_hint=h)
                    assert (ref is None) == (got is None)
                    if ref is not None:
                        assert got[1] == ref[1]                   # same float, not approx
                        assert np.array_equal(got[0], ref[0])
    finally:
        planner._pruned_search = orig
    return pruned


@pytest.mark.parametrize("seed", range(4))
def test_pruned_plan_is_bit_identical_to_the_whole_window_search(seed):
    _compare(seed)


def test_pruned_search_is_used():
    """Over the random maps of two seeds the pruned search certifies some plans (the
    identity above is not vacuous)."""
    assert sum(_compare(seed) for seed in (0, 1)) > 0


def test_pruned_search_declines_what_it_cannot_certify():
    """A wall between start and goal: the bound of the straight line holds no path, and
    the search returns no cells (the caller searches on)."""
    cost = np.ones((40, 40))
    cost[5:40, 20] = np.inf
    cells, g, _ = planner._pruned_search(cost, (30, 5), (30, 35), 0.05, 1.8)
    assert cells is None and g == np.inf
    ref = plan_path(cost, (30, 5), (30, 35), 0.05, 0.5, prune=False)
    got = plan_path(cost, (30, 5), (30, 35), 0.05, 0.5)
    assert got[1] == ref[1] and np.array_equal(got[0], ref[0])
    assert ref[0][:, 0].min() < 5                          # around the wall's end


def test_windows_below_the_pruned_lower_bound_are_skipped(monkeypatch):
    """A wall makes the path a long detour: the pruned searches prove the first windows'
    budgets too small, so fewer windows are searched, with the same result."""
    cost = np.ones((60, 60))
    cost[0:55, 30] = np.inf
    calls = {"n": 0}
    real = planner.cost_distance_field

    def counting(*a, **k):
        calls["n"] += 1
        return real(*a, **k)

    monkeypatch.setattr(planner, "cost_distance_field", counting)
    ref = plan_path(cost, (5, 25), (5, 35), 0.05, 0.5, prune=False)
    windows_ref = calls["n"]
    searched = []
    real_pruned = planner._pruned_search
    monkeypatch.setattr(planner, "_pruned_search",
                        lambda *a: searched.append(1) or real_pruned(*a))
    calls["n"] = 0
    got = plan_path(cost, (5, 25), (5, 35), 0.05, 0.5)
    windows_got = calls["n"] - len(searched)
    assert got[1] == ref[1] and np.array_equal(got[0], ref[0])
    assert ref[0][:, 0].max() >= 55                        # around the wall's end
    assert windows_ref >= 3 and windows_got < windows_ref
