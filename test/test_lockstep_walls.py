"""The lock step's object pipeline reuses the wall mask while the occupied cells stay."""

from __future__ import annotations

import numpy as np

from explore_seg.core.objects import WALL_OCCUPIED_THRESHOLD, ObjectParams, wall_mask
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.lockstep import LockstepParams
from sim_bridge.object_pipeline import ObjectPipeline
from sim_bridge.worlds import default_world


def test_wall_mask_per_map_version_equals_a_fresh_one():
    # The map changes at every scan (no keyframes, no publishing interval): many versions.
    eng = SimEngine(default_world("small_house"), SimParams(
        seed=2, enable_camera=True, compute_coverage=False, map_update_interval_s=0.0,
        mapping_keyframe_travel_m=0.0, mapping_keyframe_turn_rad=0.0))
    pipe = ObjectPipeline(eng, ObjectParams(), 2, LockstepParams())
    eng.set_cmd_vel(0.0, 0.6)                     # turn in place: walls seen again and again
    reused = computed = 0
    last = None
    for _ in range(60):
        eng.step(0.1)
        walls = pipe._wall_mask()
        fresh = wall_mask(eng.map, pipe.params, WALL_OCCUPIED_THRESHOLD)
        assert walls.grid is eng.map and np.array_equal(walls.mask, fresh.mask)
        if last is not None and last is not walls:
            reused += walls.mask is last.mask
            computed += walls.mask is not last.mask
        last = walls
    assert reused > 0 and computed > 0
