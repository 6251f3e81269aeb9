"""DuDe room segmentation, batch: the synthetic cases of docs/dude.md §18 and invariants.

Distances in metres at 0.05 m/cell unless a test says otherwise. The map builders here
are shared with the other ``test_segmentation_*`` files.
"""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.segmentation import IncrementalSegmenter, SegmentationParams, segment

RES = 0.05
WALL_M = 0.2


class Canvas:
    """Occupancy drawing in metres (row = y): starts unknown; rooms are free boxes
    with walls around; ``door`` opens a wall."""

    def __init__(self, w_m: float, h_m: float, res: float = RES) -> None:
        self.res = res
        self.data = np.full((round(h_m / res), round(w_m / res)), -1, np.int8)

    def _sl(self, x0: float, y0: float, x1: float, y1: float) -> tuple[slice, slice]:
        r = self.res
        return (slice(round(y0 / r), round(y1 / r)), slice(round(x0 / r), round(x1 / r)))

    def fill(self, x0: float, y0: float, x1: float, y1: float, v: int) -> "Canvas":
        self.data[self._sl(x0, y0, x1, y1)] = v
        return self

    def room(self, x0: float, y0: float, x1: float, y1: float, wall: float = WALL_M
             ) -> "Canvas":
        """Free box [x0, x1] x [y0, y1] with walls outside it (walls never overwrite free)."""
        sl_out = self._sl(x0 - wall, y0 - wall, x1 + wall, y1 + wall)
        block = self.data[sl_out]
        block[block != 0] = 100
        return self.fill(x0, y0, x1, y1, 0)

    def door(self, x0: float, y0: float, x1: float, y1: float) -> "Canvas":
        return self.fill(x0, y0, x1, y1, 0)

    def grid(self, origin=(0.0, 0.0)) -> GridMap:
        return GridMap(self.data.copy(), self.res, origin)


def two_rooms(door_at_end: bool = True) -> GridMap:
    """Two 5 x 5 m rooms sharing a 0.2 m wall with a 0.9 m door (end or middle)."""
    c = Canvas(11.0, 6.0).room(0.3, 0.3, 5.3, 5.3).room(5.5, 0.3, 10.5, 5.3)
    if door_at_end:
        c.door(5.3, 0.3, 5.5, 1.2)
    else:
        c.door(5.3, 2.35, 5.5, 3.25)
    return c.grid()


def corridor_with_rooms(n_rooms: int = 4) -> Canvas:
    """A 16 x 1.5 m corridor (y 0.5..2.0) with 4 x 4 m rooms above, 0.9 m doors."""
    c = Canvas(17.5, 7.0).room(0.5, 0.5, 0.5 + 4.0 * n_rooms, 2.0)
    for k in range(n_rooms):
        x0 = 0.5 + 4.0 * k
        c.room(x0 + (0.1 if k else 0.0), 2.2, x0 + 4.0 - (0.1 if k < n_rooms - 1 else 0.0),
               6.2)
        c.door(x0 + 1.5, 2.0, x0 + 2.4, 2.2)
    return c


def l_corridor() -> GridMap:
    c = Canvas(9.0, 9.0).room(0.5, 0.5, 8.5, 2.0).room(0.5, 0.5, 2.0, 8.5)
    c.fill(0.5, 0.5, 8.5, 2.0, 0).fill(0.5, 0.5, 2.0, 8.5, 0)
    return c.grid()


def room_with_block(side_m: float) -> GridMap:
    c = Canvas(9.0, 9.0).room(0.5, 0.5, 8.5, 8.5)
    lo, hi = 4.5 - side_m / 2, 4.5 + side_m / 2
    return c.fill(lo, lo, hi, hi, 100).grid()


def region_ids(labels: np.ndarray) -> list[int]:
    return sorted(int(v) for v in np.unique(labels) if v > 0)


def assert_coverage(grid: GridMap, labels: np.ndarray, params: SegmentationParams) -> None:
    """Every free cell labelled (except isolated specks below the minimum area), no
    region below the minimum area, and no label off the free cells but on free-standing
    furniture the cleaning counts as room (``clean_state(...).shown``)."""
    from explore_seg.core.segmentation.cleaning import clean_state
    free = (grid.data >= 0) & (grid.data < params.free_max_occupancy)
    min_cells = params.min_region_area_m2 / grid.resolution_m ** 2
    ids, counts = np.unique(labels[labels > 0], return_counts=True)
    assert np.all(counts >= min_cells), dict(zip(ids.tolist(), counts.tolist()))
    shown = clean_state(grid.data, params, grid.resolution_m).shown
    assert np.all(labels[~shown] == 0)
    import cv2
    n, comp = cv2.connectedComponents((free & (labels == 0)).astype(np.uint8), connectivity=8)
    for k in range(1, n):
        speck = comp == k
        # an unlabelled free part is allowed only as a speck of its own free component
        _, fcomp = cv2.connectedComponents(free.astype(np.uint8), connectivity=8)
        whole = fcomp == fcomp[speck][0]
        assert not (labels[whole] > 0).any() and whole.sum() < min_cells, \
            f"{int(speck.sum())} free cells unlabelled"


# ------------------------------------------------------------------------- §18 cases


def test_two_rooms_with_door_at_the_end_give_two_regions():
    g = two_rooms(door_at_end=True)
    p = SegmentationParams(tau_m=2.5)
    lab = segment(g, p)
    assert len(region_ids(lab)) == 2
    # no region spans both sides of the shared wall (x 5.3..5.5 m); the doorway and the
    # inflation margin beside it (0.3 m) may go either way
    left = lab[:, :round(5.0 / RES)]
    right = lab[:, round(5.8 / RES):]
    assert set(region_ids(left)).isdisjoint(region_ids(right))
    assert_coverage(g, lab, p)


@pytest.mark.parametrize("tau_m, expected", [(2.5, 1), (1.5, 2)])
def test_door_in_the_middle_follows_tau(tau_m, expected):
    # the two wall stubs are 2.05 m deep: jambs are notches only when tau < 2.05 m
    lab = segment(two_rooms(door_at_end=False), SegmentationParams(tau_m=tau_m))
    assert len(region_ids(lab)) == expected


def test_corridor_with_side_rooms_gives_five_regions_and_one_corridor():
    g = corridor_with_rooms().grid()
    lab = segment(g, SegmentationParams(tau_m=2.5))
    assert len(region_ids(lab)) == 5
    # interiors, 0.3 m away from the walls (the cut between inflated door jambs lies up
    # to the inflation radius inside the corridor)
    corridor = lab[round(0.8 / RES):round(1.7 / RES), round(0.8 / RES):round(16.2 / RES)]
    assert len(region_ids(corridor)) == 1
    rooms = [lab[round(2.5 / RES):round(6 / RES),
                 round((1.0 + 4 * k) / RES):round((4.0 + 4 * k) / RES)] for k in range(4)]
    room_ids = [region_ids(r) for r in rooms]
    assert all(len(r) == 1 for r in room_ids)
    assert len({r[0] for r in room_ids} | set(region_ids(corridor))) == 5


@pytest.mark.parametrize("merge, passage, expected",
                         [(False, 0.0, 2), (True, 0.0, 1), (False, 0.7, 1)])
def test_l_corridor_is_over_segmented_unless_merged(merge, passage, expected):
    """DuDe cuts the corner of an L corridor; the corridor merge or the passage merge join
    the two legs."""
    lab = segment(l_corridor(), SegmentationParams(tau_m=2.5, corridor_merge=merge,
                                                   passage_merge_ratio=passage))
    assert len(region_ids(lab)) == expected


def test_pillar_is_noise_and_a_big_block_is_bridged():
    """DuDe bridges the ring round a big block with cuts; the passage merge joins the
    parts again: the ring round a block is one room."""
    assert len(region_ids(segment(room_with_block(0.4), SegmentationParams(tau_m=2.5)))) == 1
    no_merge = SegmentationParams(tau_m=2.5, passage_merge_ratio=0.0)
    assert len(region_ids(segment(room_with_block(4.0), no_merge))) >= 2
    merged = SegmentationParams(tau_m=2.5, passage_merge_ratio=0.7)
    assert len(region_ids(segment(room_with_block(4.0), merged))) == 1


def test_scan_noise_and_free_rays_are_cleaned():
    g = two_rooms(door_at_end=True)
    data = g.data.copy()
    rng = np.random.default_rng(5)
    free = np.argwhere(data == 0)
    salt = free[rng.choice(len(free), size=len(free) // 100, replace=False)]
    data[salt[:, 0], salt[:, 1]] = 100
    # one-cell free rays through the shared wall and through the outer wall
    data[round(3.0 / RES), round(5.2 / RES):round(5.6 / RES)] = 0
    data[round(4.0 / RES), round(9.0 / RES):round(11.0 / RES)] = 0
    data[round(2.0 / RES):, round(2.0 / RES)] = np.where(
        data[round(2.0 / RES):, round(2.0 / RES)] == 100, 0,
        data[round(2.0 / RES):, round(2.0 / RES)])
    noisy = g.with_data(data)
    p = SegmentationParams(tau_m=2.5)
    lab = segment(noisy, p)
    assert len(region_ids(lab)) == 2
    assert_coverage(noisy, lab, p)


@pytest.mark.parametrize("builder", [
    lambda: two_rooms(True), lambda: two_rooms(False), lambda: corridor_with_rooms().grid(),
    l_corridor, lambda: room_with_block(4.0)], ids=["two", "mid", "corridor", "L", "block"])
def test_coverage_and_minimum_region_area(builder):
    g = builder()
    p = SegmentationParams(tau_m=2.0)
    assert_coverage(g, segment(g, p), p)


# ---------------------------------------------------------------------- bad inputs


@pytest.mark.parametrize("data, n_regions", [
    (np.full((40, 60), -1, np.int8), 0),                      # all unknown
    (np.zeros((200, 300), np.int8), 1),                       # all free, no walls
    (np.zeros((1, 1), np.int8), 0),                           # one free cell: a speck
    (np.full((1, 1), 100, np.int8), 0),
    (np.zeros((0, 0), np.int8), 0),                           # empty array
    (np.full((50, 50), 50, np.int8), 0),                      # undecided occupancy
], ids=["unknown", "no-walls", "one-cell", "one-wall", "empty", "undecided"])
def test_degenerate_maps_give_defined_results(data, n_regions):
    g = GridMap(data, RES)
    lab = segment(g)
    assert lab.shape == data.shape and lab.dtype == np.int32
    assert len(region_ids(lab)) == n_regions


def test_one_huge_room_is_one_region():
    g = Canvas(60.0, 40.0, res=0.1).room(0.5, 0.5, 59.5, 39.5).grid()
    lab = segment(g)
    assert len(region_ids(lab)) == 1
    assert (lab[g.data == 0] > 0).all()


def test_segment_rejects_a_non_grid():
    with pytest.raises(TypeError, match="GridMap"):
        IncrementalSegmenter().update(np.zeros((3, 3)))


# ------------------------------------------------------------------------- ascii


def test_ascii_rooms_at_coarse_resolution():
    g, _ = grid_from_ascii("""
    ###########################
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #...........#.............#
    #.........................#
    #.........................#
    ###########################
    """, resolution_m=0.25)
    # the decomposition alone: at 0.25 m a 2-cell gap under the wall end is too coarse
    # for the passage merge's free-width test (the cut runs along the wall end)
    p = SegmentationParams(tau_m=1.5, obstacle_inflation_m=0.0, free_close_m=0.0,
                           min_region_area_m2=0.5, passage_merge_ratio=0.0)
    lab = segment(g, p)
    assert len(region_ids(lab)) == 2
    assert_coverage(g, lab, p)


# -------------------------------------------------------------------- invariants


@pytest.mark.parametrize("seed", range(4))
def test_random_maps_invariants(seed):
    """Random rooms and blocks: labels only on free cells, coverage, minimum area."""
    rng = np.random.default_rng(seed)
    c = Canvas(12.0, 10.0)
    for _ in range(4):
        x0, y0 = rng.uniform(0.5, 8.0), rng.uniform(0.5, 6.0)
        c.room(x0, y0, x0 + rng.uniform(1.0, 4.0), y0 + rng.uniform(1.0, 4.0))
    for _ in range(6):
        x0, y0 = rng.uniform(0.5, 11.0), rng.uniform(0.5, 9.0)
        c.fill(x0, y0, x0 + rng.uniform(0.05, 0.6), y0 + rng.uniform(0.05, 0.6), 100)
    g = c.grid()
    p = SegmentationParams(tau_m=float(rng.uniform(1.5, 3.0)))
    lab = segment(g, p)
    assert_coverage(g, lab, p)
    assert region_ids(lab) == list(range(1, len(region_ids(lab)) + 1))
