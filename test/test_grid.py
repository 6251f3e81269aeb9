"""GridMap: validation, ASCII helper, conversions, layer alignment."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.grid import GridMap, grid_from_ascii


def test_ascii_helper_rows_are_y_up_and_marks_are_reported():
    g, marks = grid_from_ascii("""
    #?G
    .R#
    """)
    assert g.data.tolist() == [[0, 0, 100], [100, -1, 0]]
    assert marks == {"R": [(0, 1)], "G": [(1, 2)]}


def test_ascii_helper_rejects_ragged_and_empty():
    with pytest.raises(ValueError, match="differ in length"):
        grid_from_ascii("..\n...")
    with pytest.raises(ValueError, match="empty"):
        grid_from_ascii("   \n")


@pytest.mark.parametrize("kwargs, match", [
    ({"data": np.zeros(3, np.int8)}, "must be 2D"),
    ({"resolution_m": 0.0}, "resolution_m must be finite and > 0, got 0.0"),
    ({"resolution_m": float("inf")}, "resolution_m must be finite"),
    ({"origin_xy_m": (float("nan"), 0.0)}, "origin must be finite"),
    ({"data": np.full((2, 2), 120)}, "-1..100, got 120..120"),
])
def test_gridmap_validation(kwargs, match):
    args = {"data": np.zeros((2, 2), np.int8), "resolution_m": 0.05, "origin_xy_m": (0.0, 0.0)}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        GridMap(**args)


def test_cell_world_conversions_known_values():
    g = GridMap(np.zeros((4, 5), np.int8), 0.5, (1.0, -1.0))
    assert g.cell_to_world(0, 0) == pytest.approx((1.25, -0.75))
    assert g.cell_to_world(3, 4) == pytest.approx((3.25, 0.75))
    assert g.world_to_cell(1.01, -0.99) == (0, 0)
    assert g.world_to_cell(0.99, -0.99) == (0, -1)  # outside: negative col
    assert not g.in_bounds(0, -1) and g.in_bounds(3, 4)


def test_rotated_origin_quarter_turn():
    g = GridMap(np.zeros((2, 2), np.int8), 1.0, (0.0, 0.0), np.pi / 2)
    # +col goes along world +y, +row along world -x
    assert g.cell_to_world(0, 1) == pytest.approx((-0.5, 1.5))
    assert g.world_to_cell(-0.5, 1.5) == (0, 1)


def test_resample_to_shifted_and_grown_map():
    small = GridMap(np.array([[100, 0], [0, -1]], np.int8), 0.05, (0.0, 0.0))
    big = GridMap(np.full((4, 4), -1, np.int8), 0.05, (-0.05, -0.05))
    out = small.resample_to(big)
    assert out.tolist() == [[-1, -1, -1, -1], [-1, 100, 0, -1], [-1, 0, -1, -1], [-1, -1, -1, -1]]
    assert small.resample_to(small).tolist() == small.data.tolist()


def test_random_round_trip_invariant():
    rng = np.random.default_rng(0)
    for _ in range(5):
        g = GridMap(np.zeros((30, 40), np.int8), float(rng.uniform(0.01, 0.2)),
                    tuple(rng.uniform(-10, 10, 2)), float(rng.uniform(-3, 3)))
        r, c = rng.integers(0, 30, 100), rng.integers(0, 40, 100)
        x, y = g.cells_to_world(r, c)
        rr, cc = g.world_to_cells(x, y)
        assert (rr == r).all() and (cc == c).all()


def test_resample_array_carries_int32_labels_to_a_grown_map():
    from explore_seg.core.grid import resample_array

    old = GridMap(np.zeros((2, 3), np.int8), 0.05, (0.0, 0.0))
    labels = np.array([[1, 1, 700], [2, 2, 700]], np.int32)
    grown = GridMap(np.zeros((3, 4), np.int8), 0.05, (-0.05, 0.0))
    out = resample_array(labels, old, grown, fill=0)
    assert out.dtype == np.int32
    assert out.tolist() == [[0, 1, 1, 700], [0, 2, 2, 700], [0, 0, 0, 0]]
    with pytest.raises(ValueError, match=r"values shape \(3, 3\) differs from source grid \(2, 3\)"):
        resample_array(np.zeros((3, 3), np.int32), old, grown)
