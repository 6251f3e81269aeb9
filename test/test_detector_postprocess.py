"""Box IoU, NMS and decoding (explore_seg.core.detector.postprocess)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.detector import (COCO_NAMES, DetectorParams, Letterbox, batched_nms, box_iou,
                                       decode, nms)


def test_nms_hand_made_boxes():
    boxes = [[0, 0, 10, 10], [1, 1, 11, 11], [20, 20, 30, 30], [0, 0, 10, 5], [21, 20, 31, 30]]
    scores = [0.9, 0.8, 0.7, 0.95, 0.3]
    # IoU(3,0) = 0.5, IoU(3,1) = 36/114 = 0.32, IoU(0,1) = 81/119 = 0.68, IoU(2,4) = 0.82
    assert nms(boxes, scores, 0.45).tolist() == [3, 1, 2]
    assert nms(boxes, scores, 0.6).tolist() == [3, 0, 2]
    assert nms(boxes, scores, 0.9).tolist() == [3, 0, 1, 2, 4]
    assert nms(np.zeros((0, 4)), [], 0.5).tolist() == []


def test_batched_nms_is_class_aware():
    boxes = [[0, 0, 10, 10], [1, 1, 11, 11], [0, 0, 10, 10]]
    assert batched_nms(boxes, [0.9, 0.8, 0.7], [0, 0, 1], 0.45).tolist() == [0, 2]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_batched_nms_invariants_on_random_boxes(seed):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 100, (80, 2))
    boxes = np.hstack([xy, xy + rng.uniform(5, 40, (80, 2))])
    scores = rng.random(80)
    ids = rng.integers(0, 3, 80)
    keep = batched_nms(boxes, scores, ids, 0.4)
    assert np.all(np.diff(scores[keep]) <= 0)
    iou = box_iou(boxes, boxes)
    for c in range(3):
        kept_c = keep[ids[keep] == c]
        sub = iou[np.ix_(kept_c, kept_c)]
        assert np.all(sub[~np.eye(len(kept_c), dtype=bool)] <= 0.4)
    for i in sorted(set(range(80)) - set(keep.tolist())):
        killers = keep[(ids[keep] == ids[i]) & (scores[keep] >= scores[i])]
        assert np.any(iou[i, killers] > 0.4)


def test_nms_shape_error():
    with pytest.raises(ValueError, match="expected boxes \\(N, 4\\) and scores"):
        nms([[0, 0, 1, 1]], [0.5, 0.4], 0.5)


def test_batched_nms_shape_error():
    with pytest.raises(ValueError, match="expected boxes \\(N, 4\\) and class_ids"):
        batched_nms([[0, 0, 1, 1]], [0.5], [0, 1], 0.5)


def _raw_row(cx, cy, w, h, obj, cls_probs: dict[str, float]) -> np.ndarray:
    row = np.zeros(85, np.float32)
    row[:5] = (cx, cy, w, h, obj)
    for name, p in cls_probs.items():
        row[5 + COCO_NAMES.index(name)] = p * obj
    return row


def test_decode_threshold_classes_nms_and_mapping():
    geo = Letterbox.fit((480, 640), 416)  # network px = 0.65 * original + (0, 52)
    raw = np.stack([
        _raw_row(208, 208, 65, 65, 0.9, {"chair": 0.9}),         # chair 0.81 at image centre
        _raw_row(210, 208, 65, 65, 0.8, {"chair": 0.9}),         # suppressed by the first
        _raw_row(208, 208, 65, 65, 0.9, {"dining table": 0.5}),  # other class: kept
        _raw_row(100, 100, 20, 20, 0.9, {"person": 0.99}),       # not a wanted class
        _raw_row(300, 300, 20, 20, 0.2, {"bed": 1.0}),           # objectness under threshold
    ])
    dets = decode(raw, geo, DetectorParams())
    assert [(d.cls_name, d.class_id) for d in dets] == [("chair", 56), ("dining table", 60)]
    assert dets[0].score == pytest.approx(0.81)
    np.testing.assert_allclose(dets[0].box_xyxy, [270, 190, 370, 290], atol=1e-4)
    everything = decode(raw, geo, DetectorParams(classes=(), max_detections=2))
    assert [d.cls_name for d in everything] == ["person", "chair"]


def test_decode_shape_error():
    with pytest.raises(ValueError, match="raw must have shape \\(N, 85\\)"):
        decode(np.zeros((3, 84), np.float32), Letterbox.fit((4, 4), 32), DetectorParams())
