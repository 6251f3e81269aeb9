"""Furniture against walls and passages (issue #53): wall-standing furniture does not cut
a room, a door between two rooms still does, a corridor round a block is one region, and
the ids stay stable while such a map is revealed."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.segmentation import IncrementalSegmenter, SegmentationParams, segment
from explore_seg.core.segmentation.cleaning import clean_masks
from explore_seg.core.segmentation.eval import evaluate
from explore_seg.core.segmentation.furniture import furniture_cells
from explore_seg.core.segmentation.passages import border_spans, inscribed_diameters
from test_segmentation import RES, Canvas, assert_coverage, region_ids, two_rooms


def desk_room() -> GridMap:
    """An 8 x 4 m room with a 1.6 x 0.8 m desk against the middle of its bottom wall."""
    c = Canvas(9.0, 5.0).room(0.5, 0.5, 8.5, 4.5)
    return c.fill(3.7, 0.5, 5.3, 1.3, 100).grid()


def thick_wall_rooms(t: float = 0.8) -> GridMap:
    """Two 5 x 5 m rooms separated by a ``t`` m thick wall with a 0.9 m door."""
    c = Canvas(11.0 + t, 6.0).room(0.3, 0.3, 5.3, 5.3).room(5.3 + t, 0.3, 10.3 + t, 5.3)
    c.fill(5.3, 0.3, 5.3 + t, 5.3, 100)
    return c.door(5.3, 2.35, 5.3 + t, 3.25).grid()


def ring_with_rooms() -> GridMap:
    """A 1.5 m corridor round a 6 x 6 m block, four rooms off it behind 0.9 m doors."""
    c = Canvas(16.0, 16.0).room(3.5, 3.5, 12.5, 12.5)
    c.fill(5.0, 5.0, 11.0, 11.0, 100)
    c.room(3.5, 12.7, 7.5, 15.5).door(5.0, 12.5, 5.9, 12.7)
    c.room(8.5, 12.7, 12.5, 15.5).door(10.0, 12.5, 10.9, 12.7)
    c.room(0.5, 3.5, 3.3, 7.5).door(3.3, 5.0, 3.5, 5.9)
    c.room(12.7, 8.5, 15.5, 12.5).door(12.5, 10.0, 12.7, 10.9)
    return c.grid()


#: The furniture fill, the passage merge and the small objects on, as for real scans.
ON = {"furniture_min_thickness_m": 0.7, "passage_merge_ratio": 0.7, "small_object_max_m": 0.5}
#: All three off (the defaults), named so that the tests do not hang on the defaults.
OFF = {k: 0.0 for k in ON}


def _at(labels: np.ndarray, x_m: float, y_m: float) -> int:
    return int(labels[round(y_m / RES), round(x_m / RES)])


def test_the_rules_are_on_by_default():
    p = SegmentationParams()
    assert {k: getattr(p, k) for k in ON} == ON


def test_desk_against_a_wall_does_not_cut_the_room():
    """At tau 0.8 m the desk's corners (1 m deep with the inflation) cut the room in
    three without the furniture fill; with it the room is one region."""
    p = SegmentationParams(tau_m=0.8, furniture_min_thickness_m=0.7)
    assert len(region_ids(segment(desk_room(), p))) == 1
    off = SegmentationParams(tau_m=0.8, passage_merge_ratio=0.0,
                             furniture_min_thickness_m=0.0)
    assert len(region_ids(segment(desk_room(), off))) == 3
    assert_coverage(desk_room(), segment(desk_room(), p), p)


def test_free_standing_furniture_carries_the_room_label_and_walls_none():
    """A free-standing table (clutter fill, on by default) and a solid 1 x 1 m cabinet
    block (a clutter hole with the rules on) are part of the room in the published
    labels: their cells get the room's id. The walls keep 0, and so does the desk
    against the wall (the furniture fill opens it for the decomposition, but desk and
    wall are one obstacle there)."""
    table = Canvas(9.0, 5.0).room(0.5, 0.5, 8.5, 4.5).fill(5.8, 2.6, 6.8, 3.4, 100)
    block = Canvas(9.0, 5.0).room(0.5, 0.5, 8.5, 4.5).fill(3.0, 2.0, 4.8, 3.0, 100)
    for grid, params, cell_m in ((table.grid(), SegmentationParams(**OFF), (6.3, 3.0)),
                                 (block.grid(), SegmentationParams(**ON), (3.9, 2.5))):
        lab = segment(grid, params)
        assert len(region_ids(lab)) == 1
        assert grid.data[round(cell_m[1] / RES), round(cell_m[0] / RES)] == 100
        assert _at(lab, *cell_m) == region_ids(lab)[0]
        wall = grid.data == 100
        wall[round(0.7 / RES):round(4.3 / RES), round(0.7 / RES):round(8.3 / RES)] = False
        assert wall.sum() > 1000 and (lab[wall] == 0).all()
        assert_coverage(grid, lab, params)
    g = desk_room()
    lab = segment(g, SegmentationParams(tau_m=0.8, **ON))
    assert len(region_ids(lab)) == 1 and (lab[g.data == 100] == 0).all()


def test_incremental_cleaning_equals_batch_while_a_real_office_is_explored():
    """Exploring a furnished office (real_office style) with the rules on, every update's
    cleaned mask and furniture bulges, though kept between updates and redone only round
    changed cells, equal a full cleaning of that map."""
    from bench.bench_segmentation import exploration_maps

    from explore_seg.core.segmentation.cleaning import clean_state
    from sim_bridge.worlds.furnished import furnished_map

    fm = furnished_map(1003, "real_office")
    p = SegmentationParams(inc_full_frac=1.0, **ON)
    seg = IncrementalSegmenter(p)
    modes = []
    for grid, _off in exploration_maps(fm.furnished, fm.start_cell, 4.0, 3.0):
        seg.update(grid)
        batch = clean_state(seg._data, p, RES)
        assert np.array_equal(seg._free_clean, batch.free_clean), f"update {len(modes)}"
        assert np.array_equal(seg._bulge, batch.bulge), f"update {len(modes)}"
        assert np.array_equal(seg._shown, batch.shown), f"update {len(modes)}"
        modes.append(seg.last_update_info.mode)
    assert modes.count("incremental") >= 5


def test_desk_is_a_bulge_and_thin_walls_are_not():
    g = desk_room()
    occ = (g.data > 90).astype(np.uint8)
    bulge = furniture_cells(occ, SegmentationParams(**ON), RES)
    rows, cols = np.nonzero(bulge)
    assert rows.size > 0
    # inside the desk's footprint (x 3.7..5.3 m), nowhere along the thin walls
    assert cols.min() * RES >= 3.7 - 0.05 and (cols.max() + 1) * RES <= 5.3 + 0.05
    assert not bulge[:, : round(3.0 / RES)].any()
    assert not furniture_cells(occ, SegmentationParams(furniture_min_thickness_m=0.0),
                               RES).any()


def test_door_between_two_rooms_still_cuts():
    for door_at_end in (True, False):
        lab = segment(two_rooms(door_at_end), SegmentationParams(**ON))
        assert len(region_ids(lab)) == 2
        assert _at(lab, 2.8, 2.8) != _at(lab, 8.0, 2.8)


def test_thick_wall_beside_a_door_is_not_opened():
    """A 0.8 m wall is a bulge (thicker than furniture_min_thickness_m) with a room on
    either side and a door beside it: it is never filled, the door still cuts."""
    g = thick_wall_rooms()
    p = SegmentationParams(**ON)
    _raw, filled = clean_masks(g.data, p, RES)
    _raw, plain = clean_masks(g.data, SegmentationParams(furniture_min_thickness_m=0.0), RES)
    assert np.array_equal(filled, plain)
    lab = segment(g, p)
    assert len(region_ids(lab)) == 2
    assert _at(lab, 2.8, 2.8) != _at(lab, 8.8, 2.8)


def test_ring_corridor_is_one_region_and_its_rooms_stay_apart():
    g = ring_with_rooms()
    for ratio, ring_parts in ((0.0, 4), (ON["passage_merge_ratio"], 1)):
        lab = segment(g, SegmentationParams(**(ON | {"passage_merge_ratio": ratio})))
        ring = {_at(lab, x, y) for x, y in ((4.2, 8.0), (11.8, 8.0), (8.0, 4.2), (8.0, 11.8),
                                            (4.2, 4.2), (11.8, 11.8), (4.2, 11.8))}
        rooms = [_at(lab, 5.5, 14.0), _at(lab, 10.5, 14.0), _at(lab, 1.9, 5.5),
                 _at(lab, 14.1, 10.5)]
        assert 0 not in ring and 0 not in rooms
        assert len(ring) >= ring_parts if ratio == 0.0 else len(ring) == ring_parts
        assert len(set(rooms)) == 4 and not set(rooms) & ring


def test_border_spans_and_inscribed_diameters():
    lab = np.zeros((12, 20), np.int32)
    lab[1:11, 1:10] = 1
    lab[1:11, 10:19] = 2
    spans = border_spans(lab, np.full(lab.shape, 2.0, np.float32))
    assert spans == {(1, 2): (10.0, 2.0)}
    w = inscribed_diameters(lab)
    assert 8.0 <= w[1] <= 10.0 and 8.0 <= w[2] <= 10.0


def test_border_pairs_count_as_pair_counts():
    """The passage merge's border pairs give the merge the same border lengths, keys in
    the same order, as pair_counts (the merge's ties follow that order)."""
    import cv2

    from explore_seg.core.segmentation.labels import pair_counts
    from explore_seg.core.segmentation.passages import BorderPairs

    rng = np.random.default_rng(3)
    for _ in range(50):
        coarse = rng.integers(0, 7, (5, 6)).astype(np.uint8)
        size = (int(rng.integers(4, 40)), int(rng.integers(4, 40)))
        lab = cv2.resize(coarse, size, interpolation=cv2.INTER_NEAREST).astype(np.int32)
        want = pair_counts(lab)
        got = BorderPairs(lab).counts()
        assert got == want and list(got) == list(want)


def _reveal(grid: GridMap, y_max_m: float) -> GridMap:
    data = grid.data.copy()
    data[round(y_max_m / grid.resolution_m):, :] = -1
    return grid.with_data(data)


def test_ids_stay_stable_while_a_furnished_ring_is_revealed():
    """Reveal the ring map from the bottom up, with a desk against a wall of the left
    room: a room seen completely keeps its id, the final labels match the batch run."""
    full = ring_with_rooms()
    data = full.data.copy()
    data[round(3.5 / RES):round(4.3 / RES), round(0.5 / RES):round(2.0 / RES)] = 100  # desk
    full = full.with_data(data)
    p = SegmentationParams(**ON)
    seg = IncrementalSegmenter(p)
    seen: dict[str, int] = {}
    modes = []
    labels = None
    for step in range(1, 9):
        y_max = 2.0 * step
        labels = seg.update(_reveal(full, y_max))
        modes.append(seg.last_update_info.mode)
        for name, (x, y, top) in {"left": (1.9, 5.5, 7.7), "right": (14.1, 10.5, 12.7),
                                  "top_left": (5.5, 14.0, 15.7)}.items():
            if y_max > top:
                rid = _at(labels, x, y)
                assert rid > 0
                assert seen.setdefault(name, rid) == rid, f"{name} changed id"
    assert "incremental" in modes
    assert len(seen) == 3
    e = evaluate(labels, segment(full, p))
    assert e["recall"] >= 0.9 and e["precision"] >= 0.9, (e["recall"], e["precision"])
    assert_coverage(full, labels, p)


def chair_ring_room() -> GridMap:
    """A 8 x 5 m room with a ring of 0.3 m chairs (0.3 m apart) round a 6.6 x 3.2 m
    table area: inflated, the chairs close the ring."""
    c = Canvas(9.0, 6.0).room(0.5, 0.5, 8.5, 5.5)
    size, gap, x0, y0, x1, y1 = 0.3, 0.3, 1.2, 1.4, 7.8, 4.6
    x = x0
    while x + size <= x1 + 1e-9:
        c.fill(x, y0, x + size, y0 + size, 100).fill(x, y1 - size, x + size, y1, 100)
        x += size + gap
    y = y0 + size + gap
    while y + size <= y1 - size - 1e-9:
        c.fill(x0, y, x0 + size, y + size, 100).fill(x - gap - size, y, x - gap, y + size, 100)
        y += size + gap
    return c.grid()


def test_ring_of_chairs_does_not_cut_the_room():
    g = chair_ring_room()
    inside, outside = (4.5, 3.0), (4.5, 1.0)
    off = segment(g, SegmentationParams(**OFF))
    assert len(region_ids(off)) > 1
    assert _at(off, *inside) != _at(off, *outside)
    p = SegmentationParams(small_object_max_m=0.5)
    on = segment(g, p)
    assert len(region_ids(on)) == 1
    assert_coverage(g, on, p)


def test_small_objects_count_as_free_unless_near_a_wall():
    """A chair in the open is free space for the decomposition; one whose inflation
    touches a wall's (a piece of a broken wall, a cabinet row) keeps it."""
    c = Canvas(9.0, 6.0).room(0.5, 0.5, 8.5, 5.5)
    c.fill(4.0, 3.0, 4.3, 3.3, 100)           # chair in the open
    c.fill(2.0, 0.75, 2.3, 1.05, 100)         # chair 0.25 m off the bottom wall
    g = c.grid()
    no_clutter = {"clutter_max_extent_m": 0.0}     # the clutter fill would fill the chair
    _raw, off = clean_masks(g.data, SegmentationParams(**OFF, **no_clutter), RES)
    _raw, on = clean_masks(g.data, SegmentationParams(small_object_max_m=0.5, **no_clutter),
                           RES)
    chair = (slice(round(3.0 / RES), round(3.3 / RES)),
             slice(round(4.0 / RES), round(4.3 / RES)))
    assert not off[chair].any() and on[chair].all()
    near = (slice(0, round(1.6 / RES)), slice(round(1.4 / RES), round(2.9 / RES)))
    assert np.array_equal(off[near], on[near])
    assert not on[round(0.9 / RES), round(2.15 / RES)]


def test_free_standing_solid_block_is_clutter_and_a_thin_wall_is_not():
    """A 2.2 x 0.9 m cabinet block in the open (diagonal over clutter_max_object_m) is
    filled as clutter when the furniture fill is on; a 2.2 x 0.15 m wall piece is not."""
    for thick, filled in ((0.9, True), (0.15, False)):
        g = Canvas(9.0, 6.0).room(0.5, 0.5, 8.5, 5.5).fill(3.4, 2.5, 5.6, 2.5 + thick,
                                                             100).grid()
        _raw, off = clean_masks(g.data, SegmentationParams(**OFF), RES)
        _raw, on = clean_masks(g.data, SegmentationParams(**(OFF | {
            "furniture_min_thickness_m": 0.7})), RES)
        mid = (round((2.5 + thick / 2) / RES), round(4.5 / RES))
        assert not off[mid]
        assert bool(on[mid]) is filled


def test_incremental_cleaning_equals_batch_with_the_furnished_rules_on():
    """A 3 m long cabinet block against a wall, seen first over 1.2 m (furniture: filled)
    then whole (longer than furniture_max_extent_m: structure): the masks the
    incremental segmenter recleans only round the changed cells equal a full cleaning,
    as far from the change as the fill reaches (clean_influence_cells covers it)."""
    c = Canvas(14.0, 8.0).room(0.5, 0.5, 13.5, 7.5)
    c.fill(3.0, 0.5, 6.0, 1.3, 100)                       # 3 x 0.8 m block on the wall
    full = c.grid()
    # never a full batch instead of an update (the room is small against the reveal)
    p = SegmentationParams(inc_full_frac=1.0, **ON)
    seg = IncrementalSegmenter(p)
    checked = 0
    for x_m in (4.2, 4.6, 5.0, 5.4, 6.4, 9.0, 14.0):
        data = full.data.copy()
        data[:, round(x_m / RES):] = -1
        seg.update(full.with_data(data))
        _raw, batch = clean_masks(seg._data, p, RES)
        assert np.array_equal(seg._free_clean, batch), f"revealed up to x = {x_m} m"
        checked += seg.last_update_info.mode == "incremental"
    assert checked >= 3
    # the block's footprint was filled while short, and is not once whole
    _raw, part = clean_masks(np.where(np.arange(full.shape[1]) < round(4.2 / RES), full.data,
                                      -1).astype(np.int8), p, RES)
    assert part[round(1.4 / RES), round(3.5 / RES)]
    assert not seg._free_clean[round(1.4 / RES), round(3.5 / RES)]


@pytest.mark.parametrize("door_m", [0.7, 1.0, 1.2])
def test_doorways_with_chairs_beside_them_still_cut(door_m):
    """A doorway 0.7 to 1.2 m wide, wall on both sides, with chairs standing near it on
    both sides: the rules on, the two rooms stay two regions."""
    c = Canvas(11.0, 6.0).room(0.3, 0.3, 5.3, 5.3).room(5.5, 0.3, 10.5, 5.3)
    y0 = 2.8 - door_m / 2
    c.door(5.3, y0, 5.5, y0 + door_m)
    for x, y in ((4.3, 1.6), (4.4, 3.7), (6.2, 1.8), (6.4, 3.6)):
        c.fill(x, y, x + 0.35, y + 0.35, 100)
    lab = segment(c.grid(), SegmentationParams(**ON))
    assert len(region_ids(lab)) == 2
    assert _at(lab, 2.8, 2.8) != _at(lab, 8.0, 2.8)
