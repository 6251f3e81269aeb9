"""One 2D detection -> the clusters of its depth points -> a 3D box (pipeline steps 1-8,
see :mod:`explore_seg.core.objects`), and the assignment of one cluster per detection
when several detections take the same points."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.objects.boxes import Object3D, fit_box, plausible_extent
from explore_seg.core.objects.cloud import (box_mask, box_stride, euclidean_clusters,
                                            pixel_grid_edges, statistical_outlier_mask,
                                            voxel_downsample)
from explore_seg.core.objects.frame import DepthFrame, frame_points, view_cut
from explore_seg.core.objects.geometry import points_in_rect
from explore_seg.core.objects.params import ObjectParams
from explore_seg.core.objects.priors import SizePrior
from explore_seg.core.objects.walls import WallMask


def rank_clusters(labels: npt.NDArray[np.integer], pixels_uv: npt.NDArray[np.floating],
                  depth_m: npt.NDArray[np.floating], box_xyxy: Sequence[float],
                  near_vote_share: float = 1.0) -> list[int]:
    """Clusters in the order in which they are taken to be the detected object.

    Every point votes for its cluster with a weight that falls linearly from 1 at the
    box centre to 0 at the box border in each image direction (a tent); detectors centre
    boxes on the object, while background shows at the borders and through gaps. Objects
    occlude what is behind them, and an object split into parts (a chair's back, seat and
    base) or seen through (legs) can get fewer votes than the wall behind it: clusters
    with at least ``near_vote_share`` of the top votes come first, nearest median depth
    first; the others follow by decreasing votes (ties to the nearest median depth).

    Parameters
    ----------
    labels : ndarray of int, shape (N,)
        Cluster labels (-1 = none).
    pixels_uv : ndarray, shape (N, 2)
        Pixel (column, row) of each point.
    depth_m : ndarray, shape (N,)
        Optical-axis depth of each point.
    box_xyxy : sequence of 4 float
    near_vote_share : float
        In [0, 1]; 1 ranks by votes alone.

    Returns
    -------
    list of int
        Every label >= 0 present in ``labels``, best first.
    """
    valid = labels >= 0
    if not np.any(valid):
        return []
    x0, y0, x1, y1 = (float(v) for v in box_xyxy)
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    hw, hh = max(0.5 * (x1 - x0), 0.5), max(0.5 * (y1 - y0), 0.5)
    weight = (np.clip(1.0 - np.abs(pixels_uv[:, 0] - cx) / hw, 0.0, 1.0)
              * np.clip(1.0 - np.abs(pixels_uv[:, 1] - cy) / hh, 0.0, 1.0))
    lab = labels[valid]
    votes = np.bincount(lab, weights=weight[valid])
    present = np.flatnonzero(np.bincount(lab))
    order = np.argsort(lab, kind="stable")
    bounds = np.searchsorted(lab[order], present)
    dv = np.asarray(depth_m)[valid][order]
    ends = np.append(bounds[1:], len(dv))
    med = {int(k): float(np.median(dv[a:b])) for k, a, b in zip(present, bounds, ends)}
    top = float(votes[present].max())
    share = min(max(float(near_vote_share), 0.0), 1.0)

    def key(k: int) -> tuple:
        v = float(votes[k])
        strong = top > 0 and v >= share * top - 1e-12
        return (0, med[k], -v) if strong else (1, -round(v, 9), med[k])

    return sorted((int(k) for k in present), key=key)


def select_cluster(labels: npt.NDArray[np.integer], pixels_uv: npt.NDArray[np.floating],
                   depth_m: npt.NDArray[np.floating], box_xyxy: Sequence[float],
                   near_vote_share: float = 1.0) -> int:
    """Pick the cluster that is the detected object (the first of :func:`rank_clusters`).

    Returns
    -------
    int
        Chosen label, -1 if there is no cluster.
    """
    ranked = rank_clusters(labels, pixels_uv, depth_m, box_xyxy, near_vote_share)
    return ranked[0] if ranked else -1


@dataclass
class DetectionClusters:
    """Clustered points under one detection box (:func:`cluster_detection`; used by
    :func:`~explore_seg.core.objects.pipeline.process_frame`)."""

    box_xyxy: tuple[float, float, float, float]
    pts: npt.NDArray[np.float64]       # (N, 3) map frame
    uv: npt.NDArray[np.float64]        # (N, 2) pixel (column, row)
    depth: npt.NDArray[np.float32]     # (N,) optical depth
    labels: npt.NDArray[np.int64]      # (N,) cluster labels, -1 = none
    ranked: list[int]                  # labels, best first (rank_clusters)


def cluster_detection(frame: DepthFrame, box_xyxy: Sequence[float], params: ObjectParams,
                      walls: WallMask | None = None, prior: SizePrior | None = None
                      ) -> DetectionClusters | None:
    """Steps 1-5 of the pipeline and the cluster ranking for one box (None: too few points).

    With ``walls`` (and ``drop_wall_points``), points over wall cells are dropped with the
    floor and the ceiling, before the pixel links and the clustering: the object's own
    points then form a cluster not merged with the wall behind or beside it. With
    ``prior``, clusters of implausible extent (:func:`plausible_extent`: far larger than
    the class, or a fragment of it) are left out of the ranking, so that they are neither
    taken for the object nor contested between two detections.

    Raises
    ------
    ValueError
        When the box is malformed or outside the image (see :func:`box_mask`).
    """
    stride = box_stride(box_xyxy, params.pixel_stride, params.max_box_samples)
    mask = box_mask(box_xyxy, frame.depth_m.shape, stride)
    pts, uv, depth = frame_points(frame, mask, params.max_depth_m)
    keep = (pts[:, 2] >= params.floor_height_m) & (pts[:, 2] <= params.ceiling_height_m)
    if walls is not None and params.drop_wall_points:
        keep &= ~walls.on(pts[:, :2])
    pts, uv, depth = pts[keep], uv[keep], depth[keep]
    # Links between neighbouring pixels (grazing surfaces), moved to voxel level.
    k = frame.intrinsics
    link_ratio = stride / (0.5 * (k.fx + k.fy)) / math.sin(params.min_grazing_angle_rad)
    pix_edges = pixel_grid_edges(uv, pts, depth, stride, params.cluster_tolerance_m, link_ratio)
    idx, voxel_of = voxel_downsample(pts, params.voxel_size_m, return_inverse=True)
    pts, uv, depth = pts[idx], uv[idx], depth[idx]
    if len(pts) < params.min_cluster_points:
        return None
    inl = statistical_outlier_mask(pts, params.sor_k, params.sor_std)
    new_index = np.cumsum(inl) - 1
    edges = voxel_of[pix_edges]
    edges = edges[(edges[:, 0] != edges[:, 1]) & inl[edges[:, 0]] & inl[edges[:, 1]]]
    pts, uv, depth = pts[inl], uv[inl], depth[inl]
    labels = euclidean_clusters(pts, params.cluster_tolerance_m, params.min_cluster_points,
                                new_index[edges])
    ranked = rank_clusters(labels, uv, depth, box_xyxy, params.near_vote_share)
    if prior is not None:
        ranked = [lab for lab in ranked if plausible_extent(pts[labels == lab], prior, params)]
    if not ranked:
        return None
    box = tuple(float(v) for v in np.asarray(box_xyxy, dtype=np.float64).reshape(-1))
    return DetectionClusters(box, pts, uv, depth, labels, ranked)


def fit_cluster(seg: DetectionClusters, best: int, frame: DepthFrame, cls: str, score: float,
                prior: SizePrior | None, params: ObjectParams
                ) -> tuple[Object3D, npt.NDArray[np.float64], npt.NDArray[np.float32]] | None:
    """Steps 6-8 for the cluster ``best`` of ``seg`` (None: implausible for the prior)."""
    pts, labels = seg.pts, seg.labels
    cam_xy = frame.camera_xyz[:2]
    chosen = labels == best
    if prior is not None and not plausible_extent(pts[chosen], prior, params):
        return None  # cluster merged with a wall or a neighbour: clamping would misplace it
    # Where the view cuts the object (image border, something in front): not its sides.
    cut = view_cut(frame, seg.uv, seg.depth,
                   box_stride(seg.box_xyxy, params.pixel_stride, params.max_box_samples),
                   params.cluster_tolerance_m)
    obj = fit_box(pts[chosen], cls, score, prior, params, cam_xy, cut[chosen])
    if params.merge_parts_fraction < 1.0 and labels.max() > 0:
        # Other parts of the same object (split at thin links) lie in the clamped box.
        lab = labels[labels >= 0]
        inside = points_in_rect(pts[labels >= 0, :2], obj.center_xyz[:2], obj.size_xyz[:2],
                                obj.yaw, params.cluster_tolerance_m)
        frac = np.bincount(lab, weights=inside) / np.bincount(lab)
        parts = np.flatnonzero(frac >= params.merge_parts_fraction)
        if len(parts) > 1 or (len(parts) == 1 and parts[0] != best):
            # Only the parts' points inside the box join: a cluster half inside (the edge
            # of a desk top beside a chair) must not stretch or turn the box.
            merged = labels == best
            merged[labels >= 0] |= np.isin(lab, parts) & inside
            if prior is None or plausible_extent(pts[merged], prior, params):
                chosen = merged
                obj = fit_box(pts[chosen], cls, score, prior, params, cam_xy, cut[chosen])
    return obj, pts[chosen], seg.depth[chosen]


def segment_detection(frame: DepthFrame, box_xyxy: Sequence[float], cls: str,
                      score: float, prior: SizePrior | None, params: ObjectParams
                      ) -> tuple[Object3D, npt.NDArray[np.float64], npt.NDArray[np.float32]] | None:
    """Run the detection -> 3D box pipeline for one 2D box, keeping the object's points.

    Parameters
    ----------
    frame : DepthFrame
    box_xyxy : sequence of 4 float
        Pixel box ``(x0, y0, x1, y1)``.
    cls : str
    score : float
    prior : SizePrior or None
    params : ObjectParams

    Returns
    -------
    (Object3D, points_map (N, 3) float64, depth_m (N,) float32) or None
        The box and the (downsampled, outlier-free) cluster points it was fitted to with
        their optical depth; None when no cluster of ``min_cluster_points`` remains.

    Raises
    ------
    ValueError
        When the box is malformed or outside the image (see :func:`box_mask`).
    """
    seg = cluster_detection(frame, box_xyxy, params, prior=prior)
    if seg is None:
        return None
    for lab in seg.ranked:
        out = fit_cluster(seg, lab, frame, cls, score, prior, params)
        if out is not None:
            return out
    return None


def object_from_detection(frame: DepthFrame, box_xyxy: Sequence[float], cls: str,
                          score: float, prior: SizePrior | None, params: ObjectParams
                          ) -> Object3D | None:
    """The box of :func:`segment_detection` alone (None when there is none).

    Raises
    ------
    ValueError
        When the box is malformed or outside the image (see :func:`box_mask`).
    """
    seg = segment_detection(frame, box_xyxy, cls, score, prior, params)
    return None if seg is None else seg[0]


def _voxel_keys(points: npt.NDArray[np.floating], voxel_m: float) -> npt.NDArray[np.int64]:
    """Sorted unique int64 codes of the voxels (edge ``voxel_m``) holding ``points``."""
    k = np.floor(np.asarray(points, dtype=np.float64) / voxel_m).astype(np.int64)
    k = np.clip(k + (1 << 20), 0, (1 << 21) - 1)
    return np.unique((k[:, 0] << 42) | (k[:, 1] << 21) | k[:, 2])


def _box_fit(seg: DetectionClusters, lab: int) -> float:
    """IoU of a cluster's pixel bounding box with the detection box (how well it fills it)."""
    uv = seg.uv[seg.labels == lab]
    x0, y0, x1, y1 = seg.box_xyxy
    u0, v0 = uv.min(axis=0)
    u1, v1 = uv.max(axis=0)
    iw = max(min(x1, u1) - max(x0, u0), 0.0)
    ih = max(min(y1, v1) - max(y0, v0), 0.0)
    inter = iw * ih
    union = (x1 - x0) * (y1 - y0) + (u1 - u0) * (v1 - v0) - inter
    return inter / union if union > 0 else 0.0


def assign_clusters(segs: list[DetectionClusters | None], params: ObjectParams) -> list[int]:
    """One cluster per detection, no cluster for two detections (index into ``ranked``).

    Each detection takes its best-ranked cluster. When two detections take the same
    points (more than half of the smaller cluster's voxels shared: a chair in front of a
    desk is the nearest cluster in both boxes), the detection whose box the cluster fills
    better (IoU of the cluster's pixel bounding box with the box) keeps it and the other
    moves on to its next cluster. Returns -1 for detections left without a cluster.
    """
    voxel = params.voxel_size_m if params.voxel_size_m > 0 else params.cluster_tolerance_m
    pick = [0 if s is not None else -1 for s in segs]
    cache: dict[tuple[int, int], tuple[npt.NDArray[np.int64], float]] = {}

    def info(i: int) -> tuple[npt.NDArray[np.int64], float]:
        key = (i, pick[i])
        if key not in cache:
            s = segs[i]
            lab = s.ranked[pick[i]]
            cache[key] = (_voxel_keys(s.pts[s.labels == lab], voxel), _box_fit(s, lab))
        return cache[key]

    changed = True
    while changed:
        changed = False
        for i in range(len(segs)):
            for j in range(i + 1, len(segs)):
                if pick[i] < 0 or pick[j] < 0:
                    continue
                ki, fi = info(i)
                kj, fj = info(j)
                shared = len(np.intersect1d(ki, kj, assume_unique=True))
                if shared <= 0.5 * min(len(ki), len(kj)):
                    continue
                loser = j if fi >= fj else i
                pick[loser] += 1
                if pick[loser] >= len(segs[loser].ranked):
                    pick[loser] = -1
                changed = True
    return pick
