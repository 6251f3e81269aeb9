"""Network backends: onnxruntime against torch, and the ONNX export cache
(explore_seg.core.detector.backends)."""

from __future__ import annotations

import numpy as np
import pytest

from detector_support import HAVE_WEIGHTS, MODEL_DIR, frame, needs_weights
from detector_support import torch_backend  # noqa: F401 - a fixture
from explore_seg.core.detector import DetectorParams, OnnxBackend, decode, letterbox, onnx_source


@pytest.fixture(scope="module")
def onnx_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("onnx_cache")


@pytest.fixture(scope="module")
def onnx_backend(onnx_cache):
    if not HAVE_WEIGHTS:
        pytest.skip("YOLOv3-tiny files absent")
    return OnnxBackend(MODEL_DIR, 416, num_threads=2, cache_dir=onnx_cache)


@needs_weights
def test_onnx_backend_matches_torch(torch_backend, onnx_backend):
    rgb = frame("tum_fr3_office")
    blob, geo = letterbox(rgb, 416)
    raw_t, raw_o = torch_backend.infer(blob), onnx_backend.infer(blob)
    assert raw_t.shape == raw_o.shape == (507 + 2028, 85)
    np.testing.assert_allclose(raw_o, raw_t, rtol=1e-5, atol=1e-4)  # boxes in px: rtol
    params = DetectorParams(classes=())
    det_t, det_o = decode(raw_t, geo, params), decode(raw_o, geo, params)
    assert [d.cls_name for d in det_o] == [d.cls_name for d in det_t]
    np.testing.assert_allclose([d.box_xyxy for d in det_o], [d.box_xyxy for d in det_t],
                               atol=1e-2)


@needs_weights
def test_onnx_cache_reused_and_stale_file_reexported(onnx_backend, onnx_cache):
    path = onnx_backend.onnx_path
    digest = onnx_source(path)
    assert path.parent == onnx_cache and digest is not None
    stamp = path.stat().st_mtime_ns
    OnnxBackend(MODEL_DIR, 416, num_threads=1, cache_dir=onnx_cache)
    assert path.stat().st_mtime_ns == stamp  # same digest: not exported again
    path.write_bytes(b"not an onnx file")
    again = OnnxBackend(MODEL_DIR, 416, num_threads=1, cache_dir=onnx_cache)
    assert again.onnx_path == path and onnx_source(path) == digest
