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


# ------------------------------------------- against Open3D, on the pipeline's own clouds
# The cloud steps stay in numpy/scipy (each function's docstring says why); Open3D's
# versions are their reference. The inputs are the arguments the object pipeline passes
# while it processes simulator frames and the synthetic room (bench/bench_libraries.py).


@pytest.fixture(scope="module")
def pipeline_calls():
    pytest.importorskip("open3d")
    from bench.bench_libraries import record_cloud_calls
    calls = record_cloud_calls("small_cluttered", max_views=8)
    assert len(calls["voxel"]) >= 20 and len(calls["sor"]) >= 10, \
        {k: len(v) for k, v in calls.items()}
    return calls


def test_voxel_downsample_equals_open3d_voxel_trace_on_pipeline_clouds(pipeline_calls):
    from bench.bench_libraries import voxel_open3d
    for args, kwargs in pipeline_calls["voxel"]:
        ours, theirs = voxel_downsample(*args, **kwargs), voxel_open3d(*args, **kwargs)
        assert bool(kwargs.get("return_inverse", False)) == isinstance(ours, tuple)
        for a, b in zip(ours, theirs) if isinstance(ours, tuple) else [(ours, theirs)]:
            np.testing.assert_array_equal(a, b)


def test_statistical_outlier_mask_equals_open3d_on_pipeline_clouds(pipeline_calls):
    from bench.bench_libraries import sor_open3d
    dropped = 0
    for args, kwargs in pipeline_calls["sor"]:
        ours = statistical_outlier_mask(*args, **kwargs)
        np.testing.assert_array_equal(ours, sor_open3d(*args, **kwargs))
        dropped += int((~ours).sum())
    assert dropped > 0                       # the comparison covers the outlier branch


def test_euclidean_clusters_equal_open3d_dbscan_on_pipeline_clouds(pipeline_calls):
    from bench.bench_libraries import clusters_open3d
    with_links = 0
    for args, kwargs in pipeline_calls["clusters"]:
        ours, theirs = euclidean_clusters(*args, **kwargs), clusters_open3d(*args, **kwargs)
        np.testing.assert_array_equal(ours < 0, theirs < 0)
        pairs = np.unique(np.stack([ours, theirs], axis=1), axis=0)   # same partition
        assert len(pairs) == len(np.unique(ours)) == len(np.unique(theirs))
        edges = args[3] if len(args) > 3 else kwargs.get("extra_edges")
        with_links += edges is not None and len(edges) > 0
    assert 0 < with_links < len(pipeline_calls["clusters"])


def test_statistical_outlier_mask_keeps_coincident_points_and_accepts_ratio_zero():
    """Where Open3D's removal differs: it drops points whose neighbours all coincide with
    them and refuses std_ratio 0."""
    rng = np.random.default_rng(2)
    cloud = rng.normal(0.0, 0.1, (200, 3))
    stack = np.repeat([[0.05, 0.0, 0.0]], 12, axis=0)        # one point seen 12 times
    keep = statistical_outlier_mask(np.vstack([cloud, stack]), k=8, std_ratio=2.0)
    assert keep[200:].all()
    keep0 = statistical_outlier_mask(cloud, k=8, std_ratio=0.0)
    assert 0 < keep0.sum() < len(cloud)


def test_euclidean_clusters_link_points_exactly_at_the_tolerance():
    """Open3D's DBSCAN links only points closer than its radius."""
    pts = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.5, 0.0, 0.0]])
    np.testing.assert_array_equal(euclidean_clusters(pts, 0.5, 1), [0, 0, 1])


def test_connected_labels_equal_scipy_connected_components_on_random_graphs():
    """The hand-written components (used by euclidean_clusters) equal scipy's, numbering
    included, on random graphs: sparse and dense, with repeated edges and self loops."""
    from scipy import sparse
    from scipy.sparse.csgraph import connected_components

    from explore_seg.core.objects.cloud import connected_labels
    rng = np.random.default_rng(49)
    for _ in range(400):
        n = int(rng.integers(1, 300))
        e = int(rng.integers(0, 3 * n))
        a, b = rng.integers(0, n, e), rng.integers(0, n, e)
        graph = sparse.coo_matrix((np.ones(e, np.int8), (a, b)), shape=(n, n))
        want = connected_components(graph, directed=False)[1]
        assert np.array_equal(connected_labels(n, a, b), want)
    # A long chain in scrambled order (the most rounds of hooking).
    perm = rng.permutation(500)
    got = connected_labels(500, perm[:-1], perm[1:])
    assert np.array_equal(got, np.zeros(500))
