"""Point-cloud steps of the detection -> 3D box pipeline: pixel sampling of a 2D box,
voxel downsampling, statistical outlier removal and Euclidean clustering.

Everything here works on plain arrays (points, pixels, depths): no frames, no objects.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree


def box_mask(box_xyxy: Sequence[float], shape: tuple[int, int], stride: int = 1
             ) -> npt.NDArray[np.bool_]:
    """Pixel mask of a 2D box (inclusive corners, clipped to the image).

    Parameters
    ----------
    box_xyxy : sequence of 4 float
        ``(x0, y0, x1, y1)`` pixel corners, x = column, y = row.
    shape : tuple of int
        Image ``(H, W)``.
    stride : int
        Only every ``stride``-th row and column (counted from the image origin) is set.

    Returns
    -------
    ndarray of bool, shape (H, W)

    Raises
    ------
    ValueError
        If the box is not 4 finite numbers, is inverted or lies entirely outside the image.
    """
    b = np.asarray(box_xyxy, dtype=np.float64).reshape(-1)
    if b.shape != (4,) or not np.all(np.isfinite(b)):
        raise ValueError(f"box must be 4 finite numbers (x0, y0, x1, y1), got {box_xyxy!r}")
    x0, y0, x1, y1 = b
    if x1 < x0 or y1 < y0:
        raise ValueError(f"box must have x0 <= x1 and y0 <= y1, got {tuple(b)}")
    h, w = shape
    c0, r0 = max(int(math.floor(x0)), 0), max(int(math.floor(y0)), 0)
    c1, r1 = min(int(math.ceil(x1)), w - 1), min(int(math.ceil(y1)), h - 1)
    if c0 > c1 or r0 > r1:
        raise ValueError(f"box {tuple(b)} lies outside the {w}x{h} image")
    mask = np.zeros((h, w), dtype=bool)
    r0s = r0 + (-r0) % stride
    c0s = c0 + (-c0) % stride
    mask[r0s:r1 + 1:stride, c0s:c1 + 1:stride] = True
    return mask


def box_stride(box_xyxy: Sequence[float], min_stride: int, max_samples: int) -> int:
    """Pixel stride for a box: at least ``min_stride``, larger for boxes that would
    otherwise give more than ``max_samples`` pixels."""
    b = np.asarray(box_xyxy, dtype=np.float64).reshape(-1)
    area = max(float(b[2] - b[0] + 1), 1.0) * max(float(b[3] - b[1] + 1), 1.0) \
        if b.shape == (4,) and np.all(np.isfinite(b)) else 1.0
    return max(int(min_stride), int(math.ceil(math.sqrt(area / max(max_samples, 1)))))


def voxel_downsample(points: npt.NDArray[np.floating], voxel_m: float,
                     return_inverse: bool = False
                     ) -> npt.NDArray[np.int64] | tuple[npt.NDArray[np.int64],
                                                        npt.NDArray[np.int64]]:
    """Indices of one point per occupied voxel (the first in input order).

    Open3D's ``voxel_down_sample_and_trace`` gives the same indices at about 4 times the
    time on the pipeline's clouds (``bench/bench_libraries.py``); its ``voxel_down_sample``
    returns centroids, not input points.

    Parameters
    ----------
    points : ndarray, shape (N, 3)
    voxel_m : float
        Voxel edge; ``<= 0`` keeps every point.
    return_inverse : bool
        Also return, for every input point, the position of its voxel's representative
        in the returned index array.

    Returns
    -------
    keep : ndarray of int64, shape (M,)
        Sorted indices into ``points``.
    inverse : ndarray of int64, shape (N,)
        Only with ``return_inverse``: ``points[keep[inverse[i]]]`` shares point i's voxel.
    """
    n = len(points)
    if voxel_m <= 0 or n == 0:
        keep = np.arange(n, dtype=np.int64)
        return (keep, keep.copy()) if return_inverse else keep
    keys = np.floor(np.asarray(points, dtype=np.float64) / voxel_m).astype(np.int64)
    keys -= keys.min(axis=0)
    dims = keys.max(axis=0) + 1
    if np.prod(dims.astype(np.float64)) < 2.0**62:
        flat = np.ravel_multi_index(keys.T, dims)
    else:
        flat = np.unique(keys, axis=0, return_inverse=True)[1].reshape(-1)
    _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    keep = first[order].astype(np.int64)
    if not return_inverse:
        return keep
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return keep, rank[inverse.reshape(-1)].astype(np.int64)


def pixel_grid_edges(pixels_uv: npt.NDArray[np.floating], points: npt.NDArray[np.floating],
                     depth_m: npt.NDArray[np.floating], stride: int, link_m: float,
                     link_ratio: float) -> npt.NDArray[np.int64]:
    """Links between points of neighbouring sampled pixels that are close in 3D.

    Surfaces seen at a grazing angle (a table top from a low camera) are sampled in
    strips farther apart than any fixed clustering distance; neighbouring pixels on them
    are still linked when their 3D distance is at most ``max(link_m, link_ratio * depth)``.

    Parameters
    ----------
    pixels_uv : ndarray, shape (N, 2)
        Pixel (column, row) of each point, on a grid of step ``stride``.
    points : ndarray, shape (N, 3)
    depth_m : ndarray, shape (N,)
    stride : int
    link_m, link_ratio : float

    Returns
    -------
    ndarray of int64, shape (E, 2)
        Index pairs into the inputs (right and down neighbours).
    """
    n = len(points)
    if n == 0:
        return np.zeros((0, 2), dtype=np.int64)
    gc = (np.asarray(pixels_uv[:, 0]) // stride).astype(np.int64)
    gr = (np.asarray(pixels_uv[:, 1]) // stride).astype(np.int64)
    gc -= gc.min()
    gr -= gr.min()
    index = np.full((gr.max() + 2, gc.max() + 2), -1, dtype=np.int64)
    index[gr, gc] = np.arange(n)
    pairs = []
    for dr, dc in ((0, 1), (1, 0)):
        j = index[gr + dr, gc + dc]
        ok = j >= 0
        i, j = np.flatnonzero(ok), j[ok]
        dist = np.linalg.norm(points[i] - points[j], axis=1)
        near = dist <= np.maximum(link_m, link_ratio * np.minimum(depth_m[i], depth_m[j]))
        pairs.append(np.stack([i[near], j[near]], axis=1))
    return np.vstack(pairs).astype(np.int64)


def statistical_outlier_mask(points: npt.NDArray[np.floating], k: int, std_ratio: float
                             ) -> npt.NDArray[np.bool_]:
    """Statistical outlier removal (as PCL / Open3D): keep points whose mean distance to
    their ``k`` nearest neighbours is at most ``mean + std_ratio * std`` over the cloud.

    Open3D's ``remove_statistical_outlier`` matches it on the pipeline's clouds at about 0.7
    times the time (``bench/bench_libraries.py``), but drops points whose neighbours all
    coincide with them and refuses ``std_ratio = 0``, which ``sor_std`` allows.

    Parameters
    ----------
    points : ndarray, shape (N, 3)
    k : int
        Neighbours (>= 1).
    std_ratio : float
        Threshold in standard deviations.

    Returns
    -------
    ndarray of bool, shape (N,)
        True for inliers. Clouds of at most ``k`` points are kept whole.

    Raises
    ------
    ValueError
        If ``k < 1``.
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n <= k:
        return np.ones(n, dtype=bool)
    dist, _ = cKDTree(pts).query(pts, k=k + 1)
    mean_d = dist[:, 1:].mean(axis=1)
    return mean_d <= mean_d.mean() + std_ratio * mean_d.std()


def connected_labels(n: int, a: npt.NDArray[np.integer], b: npt.NDArray[np.integer]
                     ) -> npt.NDArray[np.intp]:
    """Connected components of the undirected graph on nodes ``0 .. n-1`` with edges
    ``(a[i], b[i])``, numbered 0, 1, ... in the order of each component's smallest node
    (the numbering of scipy's ``connected_components``).

    Hand-written: scipy's ``connected_components`` spends most of its time building and
    validating a sparse matrix, about 350 us on a scan's few hundred points, where this
    takes about 70 us (measured on a 360-point chain); it runs thousands of times per
    run. On 20000 points with 30000 links the two take about the same.

    Minimum-label hooking with pointer jumping: every node points to a smaller node of
    its component, each round hooks the root of every edge's larger end to the other
    end's root, then flattens the pointers; the smallest node of a component is its
    final root.

    Examples
    --------
    >>> connected_labels(5, np.array([3, 1]), np.array([4, 0])).tolist()
    [0, 0, 1, 2, 2]
    """
    lab = np.arange(n)
    a = np.asarray(a, dtype=np.intp)
    b = np.asarray(b, dtype=np.intp)
    while a.size:
        la, lb = lab[a], lab[b]
        span = la != lb
        if not span.any():
            break
        a, b, la, lb = a[span], b[span], la[span], lb[span]   # joined edges stay joined
        np.minimum.at(lab, np.maximum(la, lb), np.minimum(la, lb))
        while True:
            up = lab[lab]
            if np.array_equal(up, lab):
                break
            lab = up
    return np.unique(lab, return_inverse=True)[1].reshape(-1)


def euclidean_clusters(points: npt.NDArray[np.floating], tolerance_m: float, min_points: int,
                       extra_edges: npt.NDArray[np.integer] | None = None
                       ) -> npt.NDArray[np.int64]:
    """Euclidean clustering: connected components of the graph linking points at most
    ``tolerance_m`` apart.

    Open3D's ``cluster_dbscan`` (one point per core) links only points closer than its
    radius and takes no extra links; with the links joined afterwards it takes about 1.4
    times as long on the detection clouds (``bench/bench_libraries.py``).

    Parameters
    ----------
    points : ndarray, shape (N, D)
    tolerance_m : float
        Link distance (> 0).
    min_points : int
        Clusters with fewer points get label -1.
    extra_edges : ndarray of int, shape (E, 2), optional
        Further links (index pairs), e.g. from :func:`pixel_grid_edges`.

    Returns
    -------
    ndarray of int64, shape (N,)
        Labels 0, 1, ... ordered by decreasing cluster size; -1 for small clusters.

    Raises
    ------
    ValueError
        If ``tolerance_m <= 0``.
    """
    if not tolerance_m > 0:
        raise ValueError(f"tolerance_m must be > 0, got {tolerance_m}")
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    pairs = cKDTree(pts).query_pairs(tolerance_m, output_type="ndarray").reshape(-1, 2)
    if extra_edges is not None and len(extra_edges):
        pairs = np.vstack([pairs, np.asarray(extra_edges, dtype=pairs.dtype).reshape(-1, 2)])
    comp = connected_labels(n, pairs[:, 0], pairs[:, 1])
    counts = np.bincount(comp)
    order = np.argsort(-counts, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    labels = rank[comp].astype(np.int64)
    labels[counts[comp] < min_points] = -1
    return labels
