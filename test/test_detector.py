"""The Detector facade (explore_seg.core.detector.facade): real frames through the ONNX
network, and the input checks of ``detect``. The network is loaded once per module."""

from __future__ import annotations

import numpy as np
import pytest

from detector_support import HAVE_WEIGHTS, SIM_IDS, frame, needs_weights
from explore_seg.core.detector import (COCO_NAMES, DEFAULT_CLASSES, Detector, DetectorParams,
                                       box_iou)
from rgbd_data import EXTRA_FRAMES, LICENSED_FRAMES, annotations

@pytest.fixture(scope="module")
def detector():
    if not HAVE_WEIGHTS:
        pytest.skip("YOLOv3-tiny files absent")
    return Detector(DetectorParams(backend="onnx", input_size=416))



# --------------------------------------------------------------------------- real frames

# (frame, index in frames.yaml objects, expected COCO class): the detections YOLOv3-tiny
# at 416 with the default threshold really makes (IoU with the hand box > 0.3).
# Known misses, not asserted: every TUM desk (tum_fr3_office, tum_fr2_desk_a/b) is never
# reported as "dining table" at 320 or 416; in nyu_home_1 the two far backrest-only
# chairs and the nearest chair (side view, occluded) are missed or badly boxed, and the
# near-left chair only reaches IoU 0.35; in nyu_home_2 the far backrest-only chair is
# missed. At 320, the nyu_home_2 table is missed too.
REAL_HITS = [
    ("tum_fr3_office", 1, "chair"),
    ("tum_fr3_office", 2, "chair"),
    ("nyu_home_1", 0, "dining table"),
    ("nyu_home_1", 3, "chair"),
    ("nyu_home_1", 5, "chair"),
    ("nyu_home_1", 7, "chair"),
    ("nyu_home_2", 0, "chair"),
    ("nyu_home_2", 1, "dining table"),
    ("nyu_home_2", 2, "chair"),
    ("nyu_home_2", 3, "chair"),
]


@pytest.fixture(scope="module")
def real_detections(detector):
    """{frame name: detections} of the frames present (the licensed ones always)."""
    cache: dict = {}

    def get(name: str):
        if name not in cache:
            cache[name] = detector.detect(frame(name))
        return cache[name]
    return get


@needs_weights
@pytest.mark.parametrize("frame, index, cls", REAL_HITS)
def test_real_frame_objects_detected(real_detections, frame, index, cls):
    obj = annotations([frame])[frame]["objects"][index]
    x0, y0, x1, y1 = obj["bbox_px"]
    truth = [x0, y0, x1 + 1, y1 + 1]  # inclusive pixel box -> continuous corners
    boxes = [d.box_xyxy for d in real_detections(frame) if d.cls_name == cls]
    assert boxes, f"no {cls} in {frame}: {real_detections(frame)}"
    assert box_iou(boxes, truth).max() > 0.3


@needs_weights
@pytest.mark.parametrize("frame", ["tum_fr2_desk_a", "tum_fr2_desk_b"])
def test_real_frames_without_chairs_report_none(real_detections, frame):
    assert [d for d in real_detections(frame) if d.cls_name == "chair"] == []


@needs_weights
@pytest.mark.parametrize("names", [LICENSED_FRAMES, EXTRA_FRAMES], ids=["tum", "nyu"])
def test_real_detections_respect_params(real_detections, names):
    dets = [d for name in annotations(names) for d in real_detections(name)]
    assert dets
    assert all(d.cls_name in DEFAULT_CLASSES and COCO_NAMES[d.class_id] == d.cls_name
               for d in dets)
    assert all(0.25 < d.score <= 1.0 for d in dets)
    assert all(0 <= d.box_xyxy[0] < d.box_xyxy[2] <= 640 and
               0 <= d.box_xyxy[1] < d.box_xyxy[3] <= 480 for d in dets)



# ---------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("rgb, match", [
    ([[0, 0, 0]], "numpy array"),
    (np.zeros((4, 4, 3), np.float32), "dtype uint8, got float32"),
    (np.zeros((4, 4), np.uint8), "shape \\(H, W, 3\\).*got \\(4, 4\\)"),
    (np.zeros((4, 4, 4), np.uint8), "got \\(4, 4, 4\\)"),
    (np.zeros((0, 4, 3), np.uint8), "got \\(0, 4, 3\\)"),
])
def test_bad_rgb_rejected(rgb, match):
    det = Detector(DetectorParams(backend="oracle"), sim_class_ids=SIM_IDS)
    with pytest.raises(ValueError, match=match):
        det.detect(rgb, semantic=np.zeros((4, 4), np.uint8))


@pytest.mark.parametrize("kwargs, match", [
    ({}, "needs a semantic image"),
    ({"semantic": np.zeros((4, 5), np.uint8)}, "semantic must have shape \\(4, 4\\)"),
    ({"semantic": np.zeros((4, 4), np.float32)}, "integer dtype, got float32"),
    ({"semantic": [[0]]}, "semantic must be a numpy array"),
    ({"semantic": np.zeros((4, 4), np.uint8), "instance": np.zeros((3, 4), np.int32)},
     "instance must have shape"),
])
def test_bad_oracle_images_rejected(kwargs, match):
    det = Detector(DetectorParams(backend="oracle"), sim_class_ids=SIM_IDS)
    with pytest.raises(ValueError, match=match):
        det.detect(np.zeros((4, 4, 3), np.uint8), **kwargs)


@pytest.mark.parametrize("ids, match", [
    (None, "needs sim_class_ids"),
    ({"sofa_xyz": 1}, "names none of the simulator's classes"),
])
def test_oracle_needs_class_ids(ids, match):
    with pytest.raises(ValueError, match=match):
        Detector(DetectorParams(backend="oracle"), sim_class_ids=ids)
