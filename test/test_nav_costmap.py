"""The navigation stand-in's costmap updated in windows (sim_bridge.navigation.costmap)
equals the whole-map cost_grid bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from sim_bridge.lockstep import LockstepParams, run_exploration
from sim_bridge.navigation import costmap
from sim_bridge.navigation.costmap import CostGridCache, influence_cells
from sim_bridge.navigation.params import NavParams
from sim_bridge.navigation.planner import cost_grid
from sim_bridge.worlds import default_world

RES = 0.05


def _random_map(rng, shape=(240, 300)):
    blocked = rng.random(shape) < 0.002
    blocked[0, :] = blocked[-1, :] = True
    blocked[60:64, 20:200] = True                          # a wall
    unknown = np.zeros(shape, bool)
    unknown[:, 200:] = True
    return blocked, unknown


@pytest.mark.parametrize("allow_unknown", [True, False])
def test_updates_in_windows_equal_the_whole_map(allow_unknown):
    rng = np.random.default_rng(3)
    params = NavParams()
    blocked, unknown = _random_map(rng)
    cache = CostGridCache()
    partial = 0
    for step in range(12):
        blocked, unknown = blocked.copy(), unknown.copy()
        r, c = rng.integers(0, 240), rng.integers(0, 300)     # a scan reveals and marks
        unknown[max(0, r - 30):r + 30, max(0, c - 30):c + 30] = False
        blocked[max(0, r - 25):r + 25, c:c + 2] = rng.random() < 0.7
        if step == 5:
            blocked[-1, -1] = not blocked[-1, -1]             # one cell in a far corner
        u = unknown if allow_unknown else None
        got = cache.cost(blocked, u, RES, params)
        np.testing.assert_array_equal(got, cost_grid(blocked, u, RES, params))
        if step:
            assert cache.last_recomputed_cells < blocked.size
            partial += cache.last_recomputed_cells > 0
    assert partial >= 8
    got[0, 0] = 7.0                                           # the caller's own copy
    assert cache.cost(blocked, u, RES, params)[0, 0] != 7.0
    assert cache.last_recomputed_cells == 0


def test_a_change_recomputes_only_its_neighbourhood_and_a_new_frame_all():
    rng = np.random.default_rng(4)
    params = NavParams()
    blocked, unknown = _random_map(rng, (400, 400))
    cache = CostGridCache()
    cache.cost(blocked, unknown, RES, params)
    assert cache.last_recomputed_cells == blocked.size
    b2 = blocked.copy()
    b2[200, 200] = True
    cache.cost(b2, unknown, RES, params)
    reach = influence_cells(params, RES)
    side = (2 * (-(-reach // costmap.TILE_CELLS)) + 1) * costmap.TILE_CELLS
    assert 0 < cache.last_recomputed_cells <= side * side
    cache.cost(b2, unknown, RES, params, geometry=((1.0, 0.0), 0.0))   # moved origin
    assert cache.last_recomputed_cells == blocked.size
    wider = NavParams(inflation_radius_m=1.0)                          # other parameters
    np.testing.assert_array_equal(cache.cost(b2, unknown, RES, wider),
                                  cost_grid(b2, unknown, RES, wider))
    assert cache.last_recomputed_cells == blocked.size


def test_a_lock_step_run_plans_on_the_same_costmap_as_the_whole_map_rebuild(monkeypatch):
    """Every plan of a run with the object layer: the windowed costmap equals cost_grid
    of the same masks, and many plans recomputed only part of the map."""
    partial = []
    plain = CostGridCache.cost

    def checked(self, blocked, unknown, resolution_m, params, geometry=()):
        out = plain(self, blocked, unknown, resolution_m, params, geometry)
        np.testing.assert_array_equal(out, cost_grid(blocked, unknown, resolution_m, params))
        partial.append(self.last_recomputed_cells < blocked.size)
        return out

    monkeypatch.setattr(CostGridCache, "cost", checked)
    run_exploration(default_world("house_cluttered"), "paper", 0,
                    params=LockstepParams(max_sim_time_s=60.0))
    assert len(partial) >= 20 and np.mean(partial) > 0.3, (len(partial), np.mean(partial))
