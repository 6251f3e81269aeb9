"""COCO names, the oracle class map and Detection (explore_seg.core.detector.coco)."""

from __future__ import annotations

import pytest

from explore_seg.core.detector import Detection, parse_oracle_class_map


def test_parse_oracle_class_map():
    assert parse_oracle_class_map(["chair:chair", " desk : dining table"]) == {
        "chair": "chair", "desk": "dining table"}



def test_detection_is_frozen():
    d = Detection("chair", 56, 0.5, (0.0, 0.0, 1.0, 1.0))
    with pytest.raises(AttributeError):
        d.score = 1.0  # type: ignore[misc]
