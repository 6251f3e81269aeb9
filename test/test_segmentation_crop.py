"""The segmenter works on the known cells' bounding box (issue 54, finding 4): its labels,
ids and update modes are exactly those of a run on the whole grid, for batch runs and
for explorations, on a fixed-size mostly unknown grid and on a growing SLAM-like map."""

from __future__ import annotations

import time

import numpy as np
import pytest

from explore_seg.core.grid import GridMap
from explore_seg.core.segmentation import IncrementalSegmenter, SegmentationParams
from explore_seg.core.segmentation.incremental import (crop_grid, crop_margin_cells,
                                                       known_crop)

P = SegmentationParams(tau_m=1.6)


def _whole(seg: IncrementalSegmenter, grid: GridMap) -> np.ndarray:
    """The reference: the segmenter on the whole grid, no crop."""
    return seg._update_grid(grid, time.perf_counter())                 # noqa: SLF001


def _embed(inner: GridMap, shape: tuple[int, int], at: tuple[int, int],
           yaw: float = 0.0) -> GridMap:
    """``inner``'s cells placed at ``at`` (row, col) in an unknown grid of ``shape``."""
    data = np.full(shape, -1, np.int8)
    h, w = inner.shape
    data[at[0]:at[0] + h, at[1]:at[1] + w] = inner.data
    return GridMap(data, inner.resolution_m, (-7.3, 2.1), yaw)


def _house(seed: int, cluttered: bool = False) -> GridMap:
    from sim_bridge.worlds import generate_house, ground_truth

    return ground_truth(generate_house(seed, size_m=(20.0, 20.0),
                                       cluttered=cluttered)).as_map("lidar")


def _reveals(grid: GridMap, steps: int, radius_cells: int, seed: int):
    """Maps of a progressive reveal: discs around random free cells, nearest first."""
    rng = np.random.default_rng(seed)
    free_r, free_c = np.nonzero(grid.data == 0)
    pick = rng.choice(free_r.size, size=steps, replace=False)
    centres = sorted(zip(free_r[pick], free_c[pick]),
                     key=lambda rc: (rc[0] - free_r[pick[0]]) ** 2
                     + (rc[1] - free_c[pick[0]]) ** 2)
    rr, cc = np.ogrid[:grid.height, :grid.width]
    known = np.zeros(grid.shape, bool)
    for r, c in centres:
        known |= (rr - r) ** 2 + (cc - c) ** 2 <= radius_cells ** 2
        yield grid.with_data(np.where(known, grid.data, -1).astype(np.int8))


def test_known_crop_keeps_the_margin_and_snaps_to_chunks():
    data = np.full((1000, 700), -1, np.int8)
    assert known_crop(data, 10) is None
    data[500:520, 300:310] = 0
    rows, cols = known_crop(data, 10, chunk=64)
    assert rows.start <= 490 and rows.stop >= 530 and cols.start <= 290 and cols.stop >= 320
    assert rows.start % 64 == 0 and rows.stop % 64 == 0 and cols.start % 64 == 0
    data[0, 699] = 100                                  # known cells at the corner: clipped
    rows, cols = known_crop(data, 10, chunk=64)
    assert (rows.start, cols.stop) == (0, 700)
    grid = GridMap(data, 0.05, (1.0, 2.0), 0.4)
    sub = crop_grid(grid, (slice(64, 128), slice(192, 256)))
    np.testing.assert_allclose(sub.cell_to_world(3, 5), grid.cell_to_world(67, 197))


@pytest.mark.parametrize("seed, cluttered, yaw", [(1, False, 0.0), (2, True, 0.3)])
def test_a_cropped_batch_run_equals_the_whole_grid_run(seed, cluttered, yaw):
    # half explored: free cells border the unknown, where the cleaning grows free space
    house = list(_reveals(_house(seed, cluttered), 6, 90, seed))[-1]
    big = _embed(house, (house.height + 700, house.width + 900), (333, 517), yaw)
    out = IncrementalSegmenter(P).update(big)
    ref = _whole(IncrementalSegmenter(P), big)
    assert out.max() >= 4, "a house has rooms"
    np.testing.assert_array_equal(out, ref)


def test_known_cells_at_the_grid_border_are_segmented_as_without_crop():
    house = _house(3)
    big = _embed(house, (house.height + 150, house.width + 40), (150, 40))
    np.testing.assert_array_equal(IncrementalSegmenter(P).update(big),
                                  _whole(IncrementalSegmenter(P), big))


def test_an_exploration_of_a_fixed_size_grid_gives_the_labels_ids_and_modes_of_no_crop():
    house = _house(4)
    big = _embed(house, (house.height + 600, house.width + 500), (271, 133))
    crop_seg, ref_seg = IncrementalSegmenter(P), IncrementalSegmenter(P)
    modes = []
    for grid in _reveals(big, 12, 90, seed=4):
        out = crop_seg.update(grid)
        ref = _whole(ref_seg, grid)
        np.testing.assert_array_equal(out, ref)
        assert crop_seg.last_update_info.mode == ref_seg.last_update_info.mode
        assert crop_seg.next_id == ref_seg.next_id
        modes.append(crop_seg.last_update_info.mode)
    assert "incremental" in modes and out.max() >= 4


def test_an_exploration_of_a_growing_map_gives_the_labels_of_no_crop():
    # slam_toolbox-like: every map is the known cells plus 10 cells, the origin moves
    house = _house(5, cluttered=True)
    crop_seg, ref_seg = IncrementalSegmenter(P), IncrementalSegmenter(P)
    for grid in _reveals(house, 10, 80, seed=5):
        (r0, r1), (c0, c1) = [(s.start, s.stop) for s in known_crop(grid.data, 10, 1)]
        slam = crop_grid(grid, (slice(r0, r1), slice(c0, c1)))
        slam = GridMap(slam.data.copy(), slam.resolution_m, slam.origin_xy_m)
        np.testing.assert_array_equal(crop_seg.update(slam), _whole(ref_seg, slam))
        assert crop_seg.last_update_info.mode == ref_seg.last_update_info.mode


def test_the_margin_covers_the_cleaning_reach():
    for res in (0.02, 0.05, 0.1):
        from explore_seg.core.segmentation.cleaning import clean_influence_cells

        assert crop_margin_cells(P, res) > clean_influence_cells(P, res)
