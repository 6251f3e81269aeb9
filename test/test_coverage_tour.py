"""Full-knowledge coverage tour (sim_bridge.coverage_tour): the benchmark's lower bound."""

from __future__ import annotations

import numpy as np
import pytest

from sim_bridge.coverage_tour import (TourParams, coverage_tour, coverage_tours, greedy_cover,
                                      tour_order)
from sim_bridge.worlds import default_world, ground_truth


def test_coverage_tour_sees_everything_coverable():
    w = default_world("small_house")
    gt = ground_truth(w)
    tour = coverage_tour(w, ground_truth=gt)
    assert tour.coverable_fraction > 0.99
    assert len(tour.viewpoints_xy) >= 2
    steps = np.hypot(*np.diff(tour.path_xy, axis=0).T)
    assert steps.sum() >= tour.length_m - 1e-6             # ends at 99 %, at the latest at its end
    assert np.hypot(*(tour.path_xy[0] - np.asarray(w.start_pose[:2]))) <= 0.05
    r, c = gt.lidar.world_to_cells(tour.path_xy[:, 0], tour.path_xy[:, 1])
    assert gt.inside[r, c].all()                           # every vertex on explorable floor


@pytest.mark.parametrize("points, expected", [
    ([0.0, 3.0, 1.0, 2.0], [0, 2, 3, 1]),
    ([0.0, -1.0, 5.0, 2.0], [0, 1, 3, 2]),
    ([4.0, 0.0, 9.0], [0, 1, 2]),
])
def test_tour_order_on_a_line(points, expected):
    x = np.asarray(points)
    order = tour_order(np.abs(x[:, None] - x[None, :]), max_sweeps=10)
    assert order == expected


def test_two_opt_never_lengthens_nearest_neighbour():
    rng = np.random.default_rng(4)
    for _ in range(5):
        pts = rng.uniform(0, 10, (9, 2))
        d = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1))
        nn = tour_order(d, max_sweeps=0)
        opt = tour_order(d, max_sweeps=20)
        length = lambda o: sum(d[o[i], o[i + 1]] for i in range(len(o) - 1))  # noqa: E731
        assert sorted(opt) == list(range(9)) and opt[0] == 0
        assert length(opt) <= length(nn) + 1e-9


def test_greedy_cover_covers_every_coverable_target():
    sets = [np.array([0, 1, 2]), np.array([2, 3]), np.array([3, 4, 5, 6]), np.array([1]),
            np.array([], dtype=np.int64)]
    chosen = greedy_cover(sets, 8)            # target 7 is seen by no set
    assert chosen == [2, 0]
    covered = set(np.concatenate([sets[i] for i in chosen]).tolist())
    assert covered == {0, 1, 2, 3, 4, 5, 6}


@pytest.mark.parametrize("field, value, match", [
    ("sensor_range_m", 0.0, "sensor_range_m must be finite and > 0"),
    ("clearance_m", -0.1, "clearance_m must be finite and >= 0"),
    ("num_beams", 2, "num_beams must be >= 3"),
    ("target_stride_cells", 0, "target_stride_cells must be an integer >= 1"),
    ("coverage_fraction", 0.0, "coverage_fraction must be in"),
])
def test_tour_params_validation(field, value, match):
    with pytest.raises(ValueError, match=match):
        TourParams(**{field: value})


def test_coverage_tour_rejects_a_start_outside():
    w = default_world("small_house")
    with pytest.raises(ValueError, match="outside the world raster"):
        coverage_tour(w, start_xy=(100.0, 0.0))


def test_tours_to_several_fractions_in_one_go_equal_separate_tours():
    w = default_world("small_house")
    gt = ground_truth(w)
    both = coverage_tours(w, (0.99, 0.8), ground_truth=gt)
    for got, fraction in zip(both, (0.99, 0.8)):
        alone = coverage_tour(w, params=TourParams(coverage_fraction=fraction), ground_truth=gt)
        assert got.length_m == alone.length_m
        np.testing.assert_array_equal(got.viewpoints_xy, alone.viewpoints_xy)
        np.testing.assert_array_equal(got.path_xy, alone.path_xy)
    assert both[1].length_m < both[0].length_m
    with pytest.raises(ValueError, match="fractions"):
        coverage_tours(w, (0.9, 1.5), ground_truth=gt)
