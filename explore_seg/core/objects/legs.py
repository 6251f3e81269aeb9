"""Unclassified objects (furniture the detector misses) from the 2D laser scan: leg-like
clusters grouped into pieces of furniture with depth points of a top above them, and
posts (a bin, a pedestal) with depth points overhanging them."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Iterable, Sequence

import cv2
import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from explore_seg.core.objects.boxes import Object3D, fit_box
from explore_seg.core.objects.cloud import euclidean_clusters, statistical_outlier_mask
from explore_seg.core.objects.frame import DepthFrame, frame_points
from explore_seg.core.objects.geometry import (footprint_orientation, points_in_rect,
                                               top_cover, top_fraction)
from explore_seg.core.objects.params import UNKNOWN_CLASS, ObjectParams
from explore_seg.core.objects.priors import SizePrior
from explore_seg.core.objects.walls import WallMask


#: Scan points, their cluster labels, and per cluster the point count and extent.
_ScanClusters = tuple[npt.NDArray[np.float64], npt.NDArray[np.intp], npt.NDArray[np.intp],
                      npt.NDArray[np.float64]]


def scan_legs(scan_xy: npt.NDArray[np.floating], params: ObjectParams,
              robot_xy: Sequence[float] | None = None,
              _clusters: _ScanClusters | None = None) -> npt.NDArray[np.float64]:
    """Centres of leg-like clusters in a 2D scan.

    A leg is a cluster (link distance ``leg_cluster_gap_m``) of ``leg_min_points`` or
    more points whose extent is within [``leg_min_width_m``, ``leg_max_width_m``] and
    with no other scan point within ``leg_isolation_m`` of its centre (walls, boxes and
    people's bodies are wider or not isolated).

    Parameters
    ----------
    scan_xy : ndarray, shape (N, 2)
        Scan points (any planar frame, usually map).
    params : ObjectParams
    robot_xy : sequence of 2 float, optional
        Points farther than ``leg_max_range_m`` from it are ignored.

    Returns
    -------
    ndarray of float64, shape (M, 2)

    Raises
    ------
    ValueError
        If ``scan_xy`` is not (N, 2).
    """
    pts, labels, counts, widths = (_clusters if _clusters is not None
                                   else _scan_clusters(scan_xy, params, robot_xy))
    if len(pts) == 0:
        return np.zeros((0, 2))
    candidates = np.flatnonzero((counts >= params.leg_min_points)
                                & (widths >= params.leg_min_width_m)
                                & (widths <= params.leg_max_width_m))
    if candidates.size == 0:
        return np.zeros((0, 2))
    # Each cluster's points in scan order: one stable sort instead of a mask per cluster.
    order = np.argsort(labels, kind="stable")
    first = np.cumsum(counts) - counts
    centres = _segment_means(pts[order], first[candidates], counts[candidates])
    radii = params.leg_isolation_m + 0.5 * widths[candidates]
    near = cKDTree(pts).query_ball_point(centres, radii, return_length=True)
    return centres[near <= counts[candidates]].reshape(-1, 2)


def _segment_means(pts: npt.NDArray[np.float64], first: npt.NDArray[np.intp],
                   counts: npt.NDArray[np.intp]) -> npt.NDArray[np.float64]:
    """Mean of ``pts[first[i]:first[i] + counts[i]]`` for every i (counts >= 1), equal
    bit for bit to ``.mean(axis=0)`` of each: the points are summed in order, all
    segments at once (``np.add.reduceat`` sums in another order), then divided by the
    count."""
    sums = pts[first].copy()
    for j in range(1, int(counts.max(initial=0))):
        more = np.flatnonzero(counts > j)
        sums[more] += pts[first[more] + j]
    return (sums / counts[:, None]).reshape(-1, 2)


def _scan_clusters(scan_xy: npt.ArrayLike, params: ObjectParams,
                   robot_xy: Sequence[float] | None) -> _ScanClusters:
    """Finite scan points within ``leg_max_range_m`` of ``robot_xy``, their cluster labels
    (link ``leg_cluster_gap_m``), and each cluster's point count and extent (diagonal of
    its bounding box)."""
    pts = np.asarray(scan_xy, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"scan_xy must have shape (N, 2), got {pts.shape}")
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if robot_xy is not None and len(pts):
        near = np.hypot(pts[:, 0] - robot_xy[0], pts[:, 1] - robot_xy[1]) <= params.leg_max_range_m
        pts = pts[near]
    if len(pts) == 0:
        empty = np.zeros(0, dtype=np.intp)
        return pts.reshape(0, 2), empty, empty, np.zeros(0)
    labels = euclidean_clusters(pts, params.leg_cluster_gap_m, 1)
    # Size and width of every cluster at once (walls give many clusters, few are legs).
    order = np.argsort(labels, kind="stable")
    counts = np.bincount(labels)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ptp = np.maximum.reduceat(pts[order], starts) - np.minimum.reduceat(pts[order], starts)
    return pts, labels, counts, np.hypot(ptp[:, 0], ptp[:, 1])


def scan_posts(scan_xy: npt.NDArray[np.floating], params: ObjectParams,
               robot_xy: Sequence[float] | None = None,
               _clusters: _ScanClusters | None = None
               ) -> tuple[list[npt.NDArray[np.float64]], npt.NDArray[np.float64]]:
    """Isolated compact clusters of a 2D scan wider than a leg: posts.

    A post is a cluster (as in :func:`scan_legs`) of ``leg_min_points`` or more points
    whose extent lies in (``leg_max_width_m``, ``post_max_width_m``] with no other scan
    point within ``leg_isolation_m`` of its points.

    Returns
    -------
    posts : list of ndarray, shape (K, 2)
        The points of every post.
    others : ndarray, shape (M, 2)
        The remaining scan points (within ``leg_max_range_m``).

    Raises
    ------
    ValueError
        If ``scan_xy`` is not (N, 2).
    """
    pts, labels, counts, widths = (_clusters if _clusters is not None
                                   else _scan_clusters(scan_xy, params, robot_xy))
    if len(pts) == 0 or params.post_max_width_m <= params.leg_max_width_m:
        return [], pts
    candidates = np.flatnonzero((counts >= params.leg_min_points)
                                & (widths > params.leg_max_width_m)
                                & (widths <= params.post_max_width_m))
    if candidates.size == 0:
        return [], pts
    tree = cKDTree(pts)
    posts, used = [], np.zeros(len(pts), dtype=bool)
    for lab in candidates:
        mine = labels == lab
        near = tree.query_ball_point(pts[mine], params.leg_isolation_m)
        if any(not mine[j] for idx in near for j in idx):
            continue
        posts.append(pts[mine])
        used |= mine
    return posts, pts[~used]


def group_legs(legs_xy: npt.NDArray[np.floating], max_distance_m: float, min_legs: int
               ) -> list[npt.NDArray[np.float64]]:
    """Group legs closer than ``max_distance_m`` (single linkage).

    Returns
    -------
    list of ndarray, each shape (K, 2), K >= ``min_legs``
        Largest group first.
    """
    legs = np.asarray(legs_xy, dtype=np.float64).reshape(-1, 2)
    if len(legs) == 0:
        return []
    labels = euclidean_clusters(legs, max_distance_m, min_legs)
    return [legs[labels == lab] for lab in range(int(labels.max()) + 1)] if labels.max() >= 0 \
        else []


def unknown_objects(frame: DepthFrame, scan_xy_map: npt.NDArray[np.floating],
                    params: ObjectParams, known: Iterable[Object3D] = (),
                    prior: SizePrior | None = None,
                    walls: WallMask | None = None) -> list[Object3D]:
    """Unclassified objects: leg groups in the scan with depth points above them, and
    posts (:func:`scan_posts`) with depth points overhanging them.

    Depth points (every ``unknown_pixel_stride``-th pixel) between
    ``unknown_min_height_m`` and ``unknown_max_height_m`` inside the legs' minimum-area
    rectangle grown by ``unknown_radius_m``, and farther than ``leg_max_width_m`` from
    every leg (the legs alone are no top), make the object when there are at least
    ``unknown_min_points`` of them; its box spans them and the legs.

    Parameters
    ----------
    frame : DepthFrame
    scan_xy_map : ndarray, shape (N, 2)
        Laser points in the map frame.
    params : ObjectParams
    known : iterable of Object3D
        Objects already found; leg groups lying inside one of them (grown by
        ``unknown_radius_m``) and posts whose centre lies inside one (grown by
        ``leg_isolation_m``) are skipped.
    prior : SizePrior, optional
        Prior of the ``unknown`` class (clamps the boxes).
    walls : WallMask, optional
        Of the current 2D map: a post's depth points overhang it only over cells the map
        knows as free; without it, every one farther than ``post_overhang_m`` from the
        post's laser points does (and either way they must lie mostly within
        ``post_band_m`` of height).

    Returns
    -------
    list of Object3D
        With ``cls == UNKNOWN_CLASS`` and score 1.0.
    """
    cam_xy = frame.camera_xyz[:2]
    known = list(known)
    clusters = _scan_clusters(scan_xy_map, params, cam_xy)
    legs = scan_legs(scan_xy_map, params, cam_xy, clusters)
    # Legs of objects already found are no evidence of another object (and would join
    # two neighbouring desks into one group spanning the floor between them).
    for obj in known:
        if len(legs) == 0:
            break
        legs = legs[~points_in_rect(legs, obj.center_xyz[:2], obj.size_xyz[:2], obj.yaw,
                                    params.unknown_radius_m)]
    kept = group_legs(legs, params.leg_group_distance_m, params.min_legs)
    posts, others = (scan_posts(scan_xy_map, params, cam_xy, clusters)
                     if params.post_max_width_m > 0
                     else ([], np.zeros((0, 2))))
    # Posts of objects already found (their face lies on the box's edge) are skipped.
    posts = [g for g in posts
             if not any(points_in_rect(g.mean(axis=0, keepdims=True), o.center_xyz[:2],
                                       o.size_xyz[:2], o.yaw, params.leg_isolation_m)[0]
                        for o in known)]
    if not kept and not posts:
        return []
    stride = params.unknown_pixel_stride
    mask = np.zeros(frame.depth_m.shape, dtype=bool)
    mask[::stride, ::stride] = True
    pts, _, _ = frame_points(frame, mask, params.max_depth_m)
    band = (pts[:, 2] >= params.unknown_min_height_m) & (pts[:, 2] <= params.unknown_max_height_m)
    pts = pts[band]
    out = []
    for i, g in enumerate(posts):
        rest = np.vstack([others] + [h for j, h in enumerate(posts) if j != i])
        obj = _post_object(g, pts, rest, params, prior, cam_xy, walls)
        if obj is not None:
            out.append(obj)
    for g in kept:
        if len(g) >= 3:
            (rcx, rcy), (w, h), ang = cv2.minAreaRect(g.astype(np.float32))
            rc, rs, ryaw = (rcx, rcy), (w, h), math.radians(ang)
        else:
            rc, rs, ryaw = footprint_orientation(g, "pca")
        if prior is not None and max(rs) > prior.max_xy_m:
            continue  # legs of several objects: the rectangle spans open floor
        sel = pts[points_in_rect(pts[:, :2], rc, rs, ryaw, params.unknown_radius_m)]
        # The legs themselves are not evidence of a top: drop points right above them.
        if len(sel):
            on_leg = cKDTree(g).query(sel[:, :2], distance_upper_bound=params.leg_max_width_m)[0]
            sel = sel[~np.isfinite(on_leg)]
        if len(sel) < params.unknown_min_points:
            continue
        if top_fraction(sel[:, 2], params.unknown_top_band_m) < params.unknown_top_fraction:
            continue  # a vertical surface (wall, door jamb, cabinet front): no table top
        inl = statistical_outlier_mask(sel, params.sor_k, params.sor_std)
        sel = sel[inl]
        if top_cover(sel[:, :2], rc, rs, ryaw, params.unknown_cover_cell_m) \
                < params.unknown_min_top_cover:
            continue  # no top over most of the legs' rectangle (open floor between them)
        legs3d = np.column_stack([g, np.full(len(g), float(sel[:, 2].min()))])
        obj = fit_box(np.vstack([sel, legs3d]), UNKNOWN_CLASS, 1.0, prior, params, cam_xy)
        out.append(replace(obj, n_points=int(len(sel))))
    return out


def _post_object(post: npt.NDArray[np.float64], pts: npt.NDArray[np.float64],
                 others: npt.NDArray[np.float64], params: ObjectParams,
                 prior: SizePrior | None, cam_xy: Sequence[float],
                 walls: WallMask | None = None) -> Object3D | None:
    """An unclassified object over a post (see :func:`scan_posts`) when at least
    ``unknown_min_points`` depth points above it (``pts``, already in the height band)
    overhang its laser points (a bin's rim, a pedestal table's top); None otherwise.

    Overhanging: farther than ``post_overhang_m`` from every laser point of the post and,
    with the map (``walls``), over a cell the map knows as free, i.e. where the lidar sees
    through under it (the faces of a pillar that this scan does not see are no overhang).
    Like a table top over legs, the overhanging points must be mostly at one height
    (``unknown_top_fraction`` of them within ``post_band_m``): a face spread over all
    heights is a wall or pillar side, whichever map cell it falls into.
    Depth points within ``leg_isolation_m`` of other scan points belong to what the lidar
    sees there and are left out."""
    lo, hi = post.min(axis=0), post.max(axis=0)
    r = params.unknown_radius_m
    near = np.all((pts[:, :2] >= lo - r) & (pts[:, :2] <= hi + r), axis=1)
    sel = pts[near]
    if len(sel) and len(others):
        d_other = cKDTree(others).query(sel[:, :2], distance_upper_bound=params.leg_isolation_m)[0]
        sel = sel[~np.isfinite(d_other)]
    if len(sel) < params.unknown_min_points:
        return None
    # Only what hangs together with the post (in plan view) is its overhang: a table top
    # beside a bin is not the bin's rim.
    both = np.vstack([post, sel[:, :2]])
    labels = euclidean_clusters(both, params.post_link_m, 1)
    sel = sel[np.isin(labels[len(post):], labels[:len(post)])]
    if len(sel) < params.unknown_min_points:
        return None
    over = cKDTree(post).query(sel[:, :2])[0] > params.post_overhang_m
    if walls is not None:
        over &= walls.free(sel[:, :2])
    if np.count_nonzero(over) < params.unknown_min_points:
        return None
    if top_fraction(sel[over, 2], params.post_band_m) < params.unknown_top_fraction:
        return None  # a face spread over all heights (a pillar side the scan missed)
    # No outlier filter: the top seen at a grazing angle is sparse next to the dense
    # faces and would be cut off; the selection is bounded by the post's grown box.
    base = np.column_stack([post, np.full(len(post), float(sel[:, 2].min()))])
    obj = fit_box(np.vstack([sel, base]), UNKNOWN_CLASS, 1.0, prior, params, cam_xy)
    return replace(obj, n_points=int(len(sel)))
