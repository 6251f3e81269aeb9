"""Shared by the test_detector_* files: model and frame locations, the torch network
fixture and the oracle's class table. Tests that need the YOLOv3-tiny files skip when they
are absent (fetch them with ``python scripts/fetch_weights.py``). Real frames come from
:mod:`rgbd_data` (the TUM frames ship in test/data/rgbd; a test on an NYU frame skips
when it is absent)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from explore_seg.core.detector import TorchBackend, default_model_dir
from rgbd_data import color_path

ROOT = Path(__file__).resolve().parents[1]
MODEL_DIR = default_model_dir()
HAVE_WEIGHTS = all(p.is_file() for p in (MODEL_DIR / "yolov3-tiny.cfg",
                                         MODEL_DIR / "yolov3-tiny.weights",
                                         MODEL_DIR / "coco.names"))
needs_weights = pytest.mark.skipif(
    not HAVE_WEIGHTS, reason=f"YOLOv3-tiny files absent from {MODEL_DIR} "
                             "(run scripts/fetch_weights.py)")


def frame(name: str) -> np.ndarray:
    """RGB uint8 image of a real frame (skips the test when the frame is absent)."""
    return cv2.cvtColor(cv2.imread(str(color_path(name)), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)


@pytest.fixture(scope="module")
def torch_backend():
    if not HAVE_WEIGHTS:
        pytest.skip("YOLOv3-tiny files absent")
    return TorchBackend(MODEL_DIR, 416, num_threads=2)


SIM_IDS = {"floor": 1, "wall": 2, "chair": 3, "table": 4, "lamp": 5}
