"""DetectorParams validation, docs and ranges (explore_seg.core.detector.params)."""

from __future__ import annotations

import dataclasses

import pytest

from explore_seg.core.detector import DetectorParams
from param_ranges import assert_range_enforced, ranged_fields


@pytest.mark.parametrize("kwargs, match", [
    ({"backend": "tensorrt"}, "backend must be one of"),
    ({"input_size": 400}, "input_size must be a multiple of 32"),
    ({"input_size": 0}, "input_size must be a multiple of 32"),
    ({"conf_threshold": 0.0}, "conf_threshold must be in \\(0, 1\\]"),
    ({"nms_iou": 1.5}, "nms_iou must be in \\(0, 1\\]"),
    ({"oracle_score": -0.1}, "oracle_score must be in"),
    ({"oracle_miss_prob": 1.1}, "oracle_miss_prob must be in \\[0, 1\\]"),
    ({"letterbox_fill": -0.5}, "letterbox_fill must be in"),
    ({"max_detections": 0}, "max_detections must be >= 1"),
    ({"num_threads": 0}, "num_threads must be >= 1"),
    ({"oracle_min_area_px": 0}, "oracle_min_area_px must be >= 1"),
    ({"oracle_jitter_px": -1.0}, "oracle_jitter_px must be >= 0"),
    ({"classes": ("chair", "sofa")}, "unknown \\['sofa'\\].*'sofa': 'couch'"),
    ({"oracle_class_map": ("chair",)}, "'sim_class:coco_name', got 'chair'"),
    ({"oracle_class_map": ("chair:throne",)}, "'throne'.*not a COCO name"),
    ({"oracle_class_map": ("chair:chair", "chair:bench")}, "listed twice"),
])
def test_params_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        DetectorParams(**kwargs)


def test_params_fields_are_documented():
    assert all(f.metadata.get("doc") for f in dataclasses.fields(DetectorParams))


@pytest.mark.parametrize("name", sorted(ranged_fields(DetectorParams)))
def test_range_holds_the_default_and_its_ends_are_enforced(name):
    assert_range_enforced(DetectorParams, name)
