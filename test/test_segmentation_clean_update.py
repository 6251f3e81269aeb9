"""The staged incremental cleaning (:mod:`explore_seg.core.segmentation.clean_update`):
each stage redone only within its own reach of the change, the masks equal a full
cleaning of the new map, with the furnished rules on and off."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.segmentation import IncrementalSegmenter, SegmentationParams
from explore_seg.core.segmentation.clean_update import update_clean_state
from explore_seg.core.segmentation.cleaning import CleanState, clean_state
from explore_seg.core.segmentation.furniture import FillCache
from explore_seg.core.segmentation.labels import bbox

RES = 0.05
ON = dict(furniture_min_thickness_m=0.7, passage_merge_ratio=0.7, small_object_max_m=0.5)


def assert_same(got: CleanState, want: CleanState, what: str) -> None:
    for name in ("free_raw", "free_clean", "occ", "shown", "base", "clutter"):
        assert np.array_equal(getattr(got, name), getattr(want, name)), f"{name}: {what}"
    if want.bulge is None:
        assert got.bulge is None, what
    else:
        assert np.array_equal(got.bulge, want.bulge), f"bulge: {what}"


@pytest.mark.parametrize("rules", ["on", "off"])
def test_local_edits_of_a_furnished_office_equal_a_full_cleaning(rules):
    """Obstacle blocks put into and taken out of a real-office style map one after the
    other (a chair, a desk against a wall, a wall piece closing a door, a block removed):
    after every edit the masks updated in place equal a full cleaning."""
    from sim_bridge.worlds.furnished import furnished_map

    p = SegmentationParams(**(ON if rules == "on" else {}))
    data = furnished_map(1003, "real_office").furnished.data.copy()
    cache = FillCache()
    st = clean_state(data, p, RES, fill_cache=cache)
    rng = np.random.default_rng(7)
    h, w = data.shape
    for step in range(12):
        r, c = int(rng.integers(10, h - 40)), int(rng.integers(10, w - 40))
        dh, dw = int(rng.integers(2, 30)), int(rng.integers(2, 30))
        new = data.copy()
        new[r:r + dh, c:c + dw] = (100, 0, -1)[step % 3]
        box = bbox(new != data, 0)
        if box is None:
            continue
        st = update_clean_state(st, new, box, p, RES, cache, (0, 0))
        data = new
        assert_same(st, clean_state(data, p, RES), f"edit {step} at {r}, {c}")


@pytest.mark.parametrize("rules", ["on", "off"])
def test_exploring_a_cluttered_house_keeps_the_masks_of_a_full_cleaning(rules):
    """A cluttered 20 m house revealed disc by disc, the map cropped to what is known (it
    grows and shifts): every update's masks equal a full cleaning, and most updates are
    incremental."""
    from bench.bench_segmentation import exploration_maps
    from sim_bridge.worlds import generate_house, ground_truth

    p = SegmentationParams(inc_full_frac=1.0, **(ON if rules == "on" else {}))
    world = generate_house(1004, size_m=(20.0, 20.0), cluttered=True)
    gt = ground_truth(world)
    seg = IncrementalSegmenter(p)
    modes = []
    for grid, _off in exploration_maps(gt.as_map("lidar"), gt.start_cell, 4.0, 3.0):
        seg.update(grid)
        want = clean_state(seg._data, p, RES)
        for name in ("free_raw", "free_clean", "occ", "shown"):
            assert np.array_equal(getattr(seg, f"_{name}"), getattr(want, name)), \
                f"{name}: update {len(modes)}"
        if want.bulge is not None:
            assert np.array_equal(seg._bulge, want.bulge), f"bulge: update {len(modes)}"
        modes.append(seg.last_update_info.mode)
    assert modes.count("incremental") >= 10


@pytest.mark.parametrize("gap", [1, 4, 8])
def test_an_object_joined_to_a_wall_changes_the_object_beside_it(gap):
    """Two small objects (1 x 9 cells) on a wall's line, the first ``gap`` cells from the
    wall's end, the second 8 cells past the first: when the gap closes, the first is part
    of the wall, so the second, near it, is inflated again. The update reaches that far
    (the second object's inflation ends 30 cells from the change)."""
    p = SegmentationParams(small_object_max_m=0.5)
    data = np.zeros((120, 300), np.int8)
    data[60, 10:100] = 100
    data[60, 100 + gap:109 + gap] = 100
    data[60, 117 + gap:126 + gap] = 100
    cache = FillCache()
    st = clean_state(data, p, RES, fill_cache=cache)
    new = data.copy()
    new[60, 100:100 + gap] = 100
    box = bbox(new != data, 0)
    assert box is not None
    st = update_clean_state(st, new, box, p, RES, cache, (0, 0))
    want = clean_state(new, p, RES)
    assert_same(st, want, f"gap {gap}")
    # the second object is an obstacle (inflated) after the change, not before
    assert want.occ[60, 120 + gap] and not clean_state(data, p, RES).occ[60, 120 + gap]
