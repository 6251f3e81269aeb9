"""Output side of the network detector: box IoU, (class-aware) NMS and the decoding of
raw network rows into :class:`~explore_seg.core.detector.coco.Detection` lists."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.detector.coco import COCO_NAMES, Detection
from explore_seg.core.detector.params import DetectorParams
from explore_seg.core.detector.preprocess import Letterbox


def box_iou(a: npt.ArrayLike, b: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Pairwise IoU of ``(N, 4)`` and ``(M, 4)`` xyxy boxes; ``(N, M)`` float64.

    Empty boxes (zero area) have IoU 0 with everything.
    """
    a = np.asarray(a, dtype=np.float64).reshape(-1, 4)
    b = np.asarray(b, dtype=np.float64).reshape(-1, 4)
    iw = (np.minimum(a[:, None, 2], b[None, :, 2])
          - np.maximum(a[:, None, 0], b[None, :, 0])).clip(min=0.0)
    ih = (np.minimum(a[:, None, 3], b[None, :, 3])
          - np.maximum(a[:, None, 1], b[None, :, 1])).clip(min=0.0)
    inter = iw * ih
    area_a = ((a[:, 2] - a[:, 0]).clip(min=0.0) * (a[:, 3] - a[:, 1]).clip(min=0.0))
    area_b = ((b[:, 2] - b[:, 0]).clip(min=0.0) * (b[:, 3] - b[:, 1]).clip(min=0.0))
    union = area_a[:, None] + area_b[None, :] - inter
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def nms(boxes_xyxy: npt.ArrayLike, scores: npt.ArrayLike,
        iou_threshold: float) -> npt.NDArray[np.int64]:
    """Greedy non-maximum suppression.

    Parameters
    ----------
    boxes_xyxy : array_like, shape (N, 4)
    scores : array_like, shape (N,)
    iou_threshold : float
        A box is dropped when its IoU with a kept, higher-scored box is above this.

    Returns
    -------
    ndarray of int64
        Indices of the kept boxes, by decreasing score (ties: lower index first).

    Raises
    ------
    ValueError
        If the shapes do not match.
    """
    boxes = np.asarray(boxes_xyxy, dtype=np.float64)
    scores = np.asarray(scores, dtype=np.float64)
    if boxes.ndim != 2 or boxes.shape[1] != 4 or scores.shape != (boxes.shape[0],):
        raise ValueError(f"expected boxes (N, 4) and scores (N,), got {boxes.shape} and "
                         f"{scores.shape}")
    order = np.argsort(-scores, kind="stable")
    keep: list[int] = []
    while order.size:
        i = int(order[0])
        keep.append(i)
        if order.size == 1:
            break
        ious = box_iou(boxes[i], boxes[order[1:]])[0]
        order = order[1:][ious <= iou_threshold]
    return np.asarray(keep, dtype=np.int64)


def batched_nms(boxes_xyxy: npt.ArrayLike, scores: npt.ArrayLike, class_ids: npt.ArrayLike,
                iou_threshold: float) -> npt.NDArray[np.int64]:
    """Class-aware NMS: boxes only suppress boxes of the same class.

    Each class's boxes are shifted by ``class_id * (span + 1)`` so that boxes of different
    classes never overlap, then :func:`nms` runs once.

    Parameters
    ----------
    boxes_xyxy, scores, iou_threshold
        As :func:`nms`.
    class_ids : array_like of int, shape (N,)

    Returns
    -------
    ndarray of int64
        Kept indices, by decreasing score.

    Raises
    ------
    ValueError
        If the shapes do not match.
    """
    boxes = np.asarray(boxes_xyxy, dtype=np.float64)
    ids = np.asarray(class_ids)
    if boxes.ndim != 2 or boxes.shape[1] != 4 or ids.shape != (boxes.shape[0],):
        raise ValueError(f"expected boxes (N, 4) and class_ids (N,), got {boxes.shape} and "
                         f"{ids.shape}")
    if boxes.size == 0:
        return np.zeros(0, dtype=np.int64)
    span = float(boxes.max() - boxes.min()) + 1.0
    shifted = boxes + (ids.astype(np.float64) * span)[:, None]
    return nms(shifted, scores, iou_threshold)


def decode(raw: npt.NDArray[np.float32], geometry: Letterbox, params: DetectorParams,
           class_names: Sequence[str] = COCO_NAMES) -> list[Detection]:
    """Turn raw network rows into detections in original-image pixels.

    Parameters
    ----------
    raw : ndarray of float32, shape (N, 5 + C)
        Rows ``cx, cy, w, h`` (network-input pixels), objectness, class scores already
        multiplied by the objectness (the :mod:`explore_seg.core.detector.darknet` layout).
    geometry : Letterbox
        Of the frame the rows come from.
    params : DetectorParams
        ``conf_threshold``, ``nms_iou``, ``max_detections``, ``classes``.
    class_names : sequence of str
        ``C`` names, by class id.

    Returns
    -------
    list of Detection
        By decreasing score. A box may be reported for several classes that each pass the
        threshold (as Darknet does); NMS is per class.

    Raises
    ------
    ValueError
        If ``raw`` is not ``(N, 5 + len(class_names))``.
    """
    n_cls = len(class_names)
    if raw.ndim != 2 or raw.shape[1] != 5 + n_cls:
        raise ValueError(f"raw must have shape (N, {5 + n_cls}), got {raw.shape}")
    wanted = (np.arange(n_cls) if not params.classes
              else np.array(sorted(class_names.index(c) for c in params.classes)))
    rows = raw[raw[:, 4] > params.conf_threshold]
    scores = rows[:, 5 + wanted]
    r, c = np.nonzero(scores > params.conf_threshold)
    if r.size == 0:
        return []
    cand_scores = scores[r, c]
    cand_ids = wanted[c]
    cx, cy, w, h = (rows[r, k].astype(np.float64) for k in range(4))
    boxes = np.stack((cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2), axis=1)
    boxes = geometry.to_original(boxes)
    valid = (boxes[:, 2] > boxes[:, 0]) & (boxes[:, 3] > boxes[:, 1])
    boxes, cand_scores, cand_ids = boxes[valid], cand_scores[valid], cand_ids[valid]
    keep = batched_nms(boxes, cand_scores, cand_ids, params.nms_iou)[:params.max_detections]
    return [Detection(class_names[int(cand_ids[i])], int(cand_ids[i]), float(cand_scores[i]),
                      tuple(float(v) for v in boxes[i]))  # type: ignore[arg-type]
            for i in keep]
