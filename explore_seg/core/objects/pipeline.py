"""One frame's detections + depth (+ scan) -> the 3D boxes to fuse (:func:`process_frame`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np
import numpy.typing as npt

from explore_seg.core.objects.boxes import Object3D
from explore_seg.core.objects.detections import (DetectionClusters, assign_clusters,
                                                 cluster_detection, fit_cluster)
from explore_seg.core.objects.frame import BoxDetection, DepthFrame
from explore_seg.core.objects.legs import unknown_objects
from explore_seg.core.objects.params import UNKNOWN_CLASS, ObjectParams
from explore_seg.core.objects.priors import SizePrior
from explore_seg.core.objects.walls import WallMask


@dataclass
class FrameResult:
    """Objects found in one frame and the boxes dropped on the way (with reasons)."""

    objects: list[Object3D]
    unknown: list[Object3D]
    dropped: list[str]


def process_frame(frame: DepthFrame, detections: Iterable[BoxDetection],
                  priors: dict[str, SizePrior], params: ObjectParams,
                  scan_xy_map: npt.NDArray[np.floating] | None = None,
                  walls: WallMask | None = None) -> FrameResult:
    """Detections + depth (+ scan) of one frame -> 3D boxes in the map frame.

    Detections below ``min_score`` or of classes without a prior are skipped; malformed
    or out-of-image boxes are dropped and named in ``FrameResult.dropped``.

    Parameters
    ----------
    frame : DepthFrame
    detections : iterable of BoxDetection
    priors : dict of str to SizePrior
    params : ObjectParams
    scan_xy_map : ndarray, shape (N, 2), optional
        Laser points in the map frame; None or empty skips unclassified objects.
    walls : WallMask, optional
        From :func:`wall_mask` of the current 2D map: depth points on walls are dropped
        before clustering (``drop_wall_points``), so a desk against a wall is not merged
        with it and a chair seen through a doorway is not the jamb; a post's overhang
        must lie over free map cells (:func:`unknown_objects`).

    Returns
    -------
    FrameResult
    """
    objects: list[Object3D] = []
    dropped: list[str] = []
    dets: list[BoxDetection] = []
    segs: list[DetectionClusters | None] = []
    for det in detections:
        if det.score < params.min_score or det.cls_name == UNKNOWN_CLASS \
                or det.cls_name not in priors:
            continue
        try:
            seg = cluster_detection(frame, det.box_xyxy, params, walls, priors[det.cls_name])
        except ValueError as err:
            dropped.append(f"{det.cls_name}: {err}")
            continue
        dets.append(det)
        segs.append(seg)
    for det, seg, first in zip(dets, segs, assign_clusters(segs, params)):
        if seg is None or first < 0:
            continue
        for lab in seg.ranked[first:]:
            fit = fit_cluster(seg, lab, frame, det.cls_name, det.score,
                               priors[det.cls_name], params)
            if fit is not None:
                objects.append(fit[0])
                break
    unknown: list[Object3D] = []
    if params.unknown_enabled and scan_xy_map is not None and len(scan_xy_map):
        unknown = unknown_objects(frame, scan_xy_map, params, objects,
                                  priors.get(UNKNOWN_CLASS), walls)
    return FrameResult(objects, unknown, dropped)
