"""Incremental DuDe (docs/dude.md §11) and persistent region ids (§12)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.segmentation.eval import evaluate
from explore_seg.core.segmentation import IncrementalSegmenter, SegmentationParams, segment
from test_segmentation import (RES, Canvas, assert_coverage, corridor_with_rooms, region_ids,
                               two_rooms)

TAU = 2.5


def _reveal(grid: GridMap, x_max_m: float) -> GridMap:
    """The grid with every cell right of ``x_max_m`` unknown."""
    data = grid.data.copy()
    data[:, round(x_max_m / grid.resolution_m):] = -1
    return grid.with_data(data)


def _room_id(labels: np.ndarray, x_m: float, y_m: float) -> int:
    return int(labels[round(y_m / RES), round(x_m / RES)])


def test_growth_keeps_ids_of_completed_rooms_and_matches_batch():
    full = corridor_with_rooms().grid()
    p = SegmentationParams(tau_m=TAU)
    seg = IncrementalSegmenter(p)
    room_ids: dict[int, int] = {}
    modes = []
    labels = None
    for step in range(1, 11):
        x_max = 0.3 + 17.2 * step / 10
        labels = seg.update(_reveal(full, x_max))
        modes.append(seg.last_update_info.mode)
        assert seg.last_update_info.time_s >= 0
        for k in range(4):
            if x_max > 0.5 + 4.0 * (k + 1) + 0.3:         # room k completely seen
                rid = _room_id(labels, 2.5 + 4.0 * k, 4.5)
                assert rid > 0
                assert room_ids.setdefault(k, rid) == rid, f"room {k} changed id"
    assert len(room_ids) == 4
    assert "incremental" in modes
    batch = segment(full, p)
    e = evaluate(labels, batch)
    assert e["recall"] >= 0.95 and e["precision"] >= 0.95, (e["recall"], e["precision"])
    assert_coverage(full, labels, p)


def test_unchanged_map_keeps_every_id():
    g = two_rooms()
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(g)
    b = seg.update(g)
    assert seg.last_update_info.mode == "unchanged"
    np.testing.assert_array_equal(a, b)


def test_origin_shift_with_padding_keeps_ids_in_world_cells():
    g = two_rooms()
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(g)
    pad = round(1.0 / RES)
    data = np.full((g.height + 7, g.width + pad), -1, np.int8)
    data[:g.height, pad:] = g.data
    shifted = GridMap(data, RES, (g.origin_xy_m[0] - 1.0, g.origin_xy_m[1]))
    b = seg.update(shifted)
    np.testing.assert_array_equal(b[:g.height, pad:], a)
    assert (b[:, :pad] == 0).all() and (b[g.height:] == 0).all()
    # shift back and crop: still the same ids
    c = seg.update(g)
    np.testing.assert_array_equal(c, a)


def test_non_integer_shift_runs_full_and_matches_ids():
    g = two_rooms()
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(g)
    moved = GridMap(g.data, RES, (0.02, 0.0))
    b = seg.update(moved)
    assert seg.last_update_info.mode == "full"
    assert region_ids(b) == region_ids(a)
    assert _room_id(b, 2.5, 2.5) == _room_id(a, 2.5, 2.5)


def test_new_room_gets_a_fresh_id_and_old_rooms_keep_theirs():
    c = corridor_with_rooms(n_rooms=3)
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    first = seg.update(_reveal(c.grid(), 8.7))         # two rooms + half the corridor
    r0, r1 = _room_id(first, 2.5, 4.5), _room_id(first, 6.5, 4.5)
    second = seg.update(c.grid())                       # third room revealed
    assert _room_id(second, 2.5, 4.5) == r0
    assert _room_id(second, 6.5, 4.5) == r1
    r2 = _room_id(second, 10.5, 4.5)
    assert r2 > 0 and r2 not in region_ids(first)
    assert r2 >= seg.next_id - len(region_ids(second)) - 5


def test_ids_are_never_reused_after_a_room_disappears():
    g = two_rooms()
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(g)
    closed = g.data.copy()
    closed[:, round(5.5 / RES):] = -1                  # right room forgotten
    b = seg.update(g.with_data(closed))
    gone = set(region_ids(a)) - set(region_ids(b))
    assert len(gone) == 1
    c = seg.update(g)                                   # seen again: a new id
    assert set(region_ids(c)).isdisjoint(gone)
    assert _room_id(c, 2.5, 2.5) == _room_id(a, 2.5, 2.5)


def test_new_wall_splitting_a_room_is_redone():
    g = Canvas(11.0, 6.0).room(0.3, 0.3, 10.5, 5.3).grid()
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(g)
    assert len(region_ids(a)) == 1
    data = g.data.copy()
    data[round(0.9 / RES):, round(5.3 / RES):round(5.5 / RES)] = 100   # wall, door below
    b = seg.update(g.with_data(data))
    assert len(region_ids(b)) == 2
    assert _room_id(b, 2.5, 3.0) != _room_id(b, 8.0, 3.0)


def test_disconnected_new_blob_is_segmented():
    c = Canvas(20.0, 6.0).room(0.3, 0.3, 5.3, 5.3)
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(c.grid())
    c.room(10.0, 0.3, 15.0, 5.3)                        # seen through a window, say
    b = seg.update(c.grid())
    assert _room_id(b, 2.5, 2.5) == _room_id(a, 2.5, 2.5)
    assert _room_id(b, 12.5, 2.5) > 0
    assert len(region_ids(b)) == 2


def test_resolution_change_and_reset():
    g = two_rooms()
    seg = IncrementalSegmenter(SegmentationParams(tau_m=TAU))
    a = seg.update(g)
    coarse = GridMap(g.data[::2, ::2].copy(), 2 * RES, g.origin_xy_m)
    b = seg.update(coarse)
    assert seg.last_update_info.mode == "full"
    assert b[round(2.5 / (2 * RES)), round(2.5 / (2 * RES))] == _room_id(a, 2.5, 2.5)
    seg.reset()
    c = seg.update(g)
    assert set(region_ids(c)).isdisjoint(region_ids(a))


@pytest.mark.parametrize("frac", [0.0, 1.0])
def test_escape_hatch_and_full_incremental_agree_on_room_count(frac):
    full = corridor_with_rooms().grid()
    p = SegmentationParams(tau_m=TAU, inc_full_frac=frac)
    seg = IncrementalSegmenter(p)
    for x in (6.0, 11.0, 17.5):
        lab = seg.update(_reveal(full, x))
    assert len(region_ids(lab)) == 5
    if frac == 0.0:
        assert seg.last_update_info.mode == "full"


@pytest.mark.parametrize("seed", range(3))
def test_random_reveals_keep_invariants(seed):
    """Seeded random rooms revealed by growing discs: coverage, minimum area and ids
    that never come back once retired, after every update."""
    rng = np.random.default_rng(seed)
    c = Canvas(14.0, 10.0)
    for _ in range(5):
        x0, y0 = rng.uniform(0.5, 9.0), rng.uniform(0.5, 5.5)
        c.room(x0, y0, x0 + rng.uniform(1.5, 4.5), y0 + rng.uniform(1.5, 4.0))
    full = c.grid()
    p = SegmentationParams(tau_m=float(rng.uniform(1.5, 2.5)))
    seg = IncrementalSegmenter(p)
    rr, cc = np.indices(full.shape)
    known = np.zeros(full.shape, bool)
    alive: set[int] = set()
    retired: set[int] = set()
    free_rc = np.argwhere(full.data == 0)
    for _ in range(8):
        r, q = free_rc[rng.integers(len(free_rc))]
        known |= (rr - r) ** 2 + (cc - q) ** 2 <= round(3.0 / RES) ** 2
        g = full.with_data(np.where(known, full.data, -1).astype(np.int8))
        lab = seg.update(g)
        assert_coverage(g, lab, p)
        ids = set(region_ids(lab))
        assert not ids & retired, f"ids {ids & retired} came back"
        retired |= alive - ids
        alive = ids
