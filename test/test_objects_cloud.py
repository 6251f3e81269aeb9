"""Point-cloud steps of the object pipeline (explore_seg.core.objects.cloud)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.objects import (box_mask, euclidean_clusters, statistical_outlier_mask,
                                      voxel_downsample)


def test_statistical_outlier_removal_drops_injected_outliers():
    rng = np.random.default_rng(0)
    cloud = rng.uniform(0, 0.5, (800, 3))
    outliers = rng.uniform(3, 4, (10, 3)) * rng.choice([-1, 1], (10, 3))
    keep = statistical_outlier_mask(np.vstack([cloud, outliers]), k=8, std_ratio=1.5)
    assert not keep[800:].any()
    assert keep[:800].mean() > 0.95


def test_euclidean_clusters_separates_two_objects():
    rng = np.random.default_rng(1)
    a = rng.uniform(0, 0.3, (300, 3))
    b = rng.uniform(0, 0.3, (200, 3)) + [0.6, 0, 0]
    lone = np.array([[5.0, 5.0, 5.0]])
    labels = euclidean_clusters(np.vstack([a, b, lone]), 0.08, 10)
    assert set(labels[:300]) == {0}
    assert set(labels[300:500]) == {1}
    assert labels[500] == -1


def test_voxel_downsample_keeps_one_point_per_voxel():
    pts = np.array([[0.01, 0.01, 0.01], [0.02, 0.02, 0.02], [0.5, 0.0, 0.0]])
    np.testing.assert_array_equal(voxel_downsample(pts, 0.1), [0, 2])
    np.testing.assert_array_equal(voxel_downsample(pts, 0.0), [0, 1, 2])


@pytest.mark.parametrize("box, match", [
    ((700, 10, 800, 20), "outside"),
    ((10, 20, 5, 30), "x0 <= x1"),
    ((0, 0, float("nan"), 3), "finite"),
    ((0, 0, 3), "4 finite"),
])
def test_box_mask_rejects_bad_boxes(box, match):
    with pytest.raises(ValueError, match=match):
        box_mask(box, (480, 640))


def test_box_mask_clips_to_image():
    m = box_mask((-10, 470, 5, 900), (480, 640))
    assert m.sum() == 6 * 10 and m[479, 0] and m[470, 5]
