"""Plane geometry of the DuDe polygon stage (explore_seg.core.segmentation.polygon)."""

from __future__ import annotations

import numpy as np

from explore_seg.core.segmentation.polygon import (crosses_any, dp_keep, hull_indices,
                                                   point_segment_dist, signed_area)

SQUARE = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]])


def test_signed_area_follows_the_orientation():
    assert signed_area(SQUARE) == 16.0
    assert signed_area(SQUARE[::-1]) == -16.0


def test_point_segment_distance_clamps_to_the_ends():
    d = point_segment_dist(np.array([[2.0, 3.0], [-3.0, 4.0]]), SQUARE[0], SQUARE[1])
    np.testing.assert_allclose(d, [3.0, 5.0])


def test_douglas_peucker_keeps_the_ends_and_the_corner():
    line = np.array([[0.0, 0.0], [1.0, 0.01], [2.0, 0.0], [2.0, 1.0], [2.0, 2.0]])
    assert dp_keep(line, 0.1).tolist() == [0, 2, 4]


def test_hull_keeps_points_on_straight_hull_edges_and_drops_inner_ones():
    pts = np.array([[0.0, 0.0], [2.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 1.0], [0.0, 4.0]])
    assert hull_indices(pts).tolist() == [0, 1, 2, 3, 5]


def test_crossing_needs_a_proper_intersection():
    b0 = np.array([[0.0, 2.0], [4.0, 0.0]])
    b1 = np.array([[4.0, 2.0], [4.0, 4.0]])
    assert crosses_any(np.array([2.0, 0.0]), np.array([2.0, 4.0]), b0, b1)
    # ending on a shared point is no crossing
    assert not crosses_any(np.array([4.0, 0.0]), np.array([0.0, 0.0]), b0[1:], b1[1:])
