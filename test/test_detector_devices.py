"""detector.device: torch on CUDA / onnxruntime GPU providers when present, else the CPU with
one note (explore_seg.core.detector.devices). The machine running these has no GPU: the
fallback is what is tested for real; the GPU branches through the plan functions."""

from __future__ import annotations

import numpy as np
import pytest

from detector_support import MODEL_DIR, frame, needs_weights
from detector_support import torch_backend  # noqa: F401 - a fixture
from explore_seg.core.detector import Detector, DetectorParams, OnnxBackend, letterbox
from explore_seg.core.detector.backends import TorchBackend
from explore_seg.core.detector.devices import (DevicePlan, onnx_plan, session_note,
                                               torch_plan)

ORT_GPU = ["TensorrtExecutionProvider", "CUDAExecutionProvider", "CPUExecutionProvider"]


@pytest.mark.parametrize("device,cuda,half,expected", [
    ("cpu", True, False, DevicePlan("cpu")),
    ("cuda", True, False, DevicePlan("cuda")),
    ("auto", True, True, DevicePlan("cuda", True)),
])
def test_torch_plan_uses_cuda_when_present(device, cuda, half, expected):
    assert torch_plan(device, half, cuda) == expected


@pytest.mark.parametrize("device", ["cuda", "auto"])
def test_torch_plan_falls_back_to_cpu_with_one_note(device):
    plan = torch_plan(device, True, cuda_available=False)
    assert plan.target == "cpu" and not plan.half
    assert plan.note == (f"detector.device '{device}': torch sees no CUDA device "
                         "(torch.cuda.is_available() is False): running on the CPU")
    assert "fp32" in torch_plan("cpu", True, cuda_available=True).note


def test_onnx_plan_prefers_tensorrt_then_cuda_then_cpu():
    assert onnx_plan("cpu", ORT_GPU).target == ("CPUExecutionProvider",)
    assert onnx_plan("auto", ORT_GPU).target == tuple(ORT_GPU)
    assert onnx_plan("cuda", ORT_GPU[1:]).target == tuple(ORT_GPU[1:])
    plan = onnx_plan("cuda", ["CPUExecutionProvider"])
    assert plan.target == ("CPUExecutionProvider",) and "onnxruntime-gpu" in plan.note


def test_session_note_when_onnxruntime_drops_the_gpu_provider():
    plan = onnx_plan("cuda", ORT_GPU)
    assert session_note(plan, ORT_GPU) == ""
    assert "could not start TensorrtExecutionProvider" in session_note(
        plan, ["CPUExecutionProvider"])


def test_device_is_validated():
    with pytest.raises(ValueError, match=r"device must be one of \('cpu', 'cuda', 'auto'\), "
                                         r"got 'gpu'"):
        DetectorParams(device="gpu")
    with pytest.raises(ValueError, match="device must be one of"):
        torch_plan("tpu", False, True)


@needs_weights
@pytest.mark.parametrize("device", ["cuda", "auto"])
def test_torch_backend_on_a_machine_without_cuda_runs_on_the_cpu(torch_backend, device):
    import torch

    if torch.cuda.is_available():
        pytest.skip("this machine has CUDA: the fallback is not exercised")
    gpu = TorchBackend(MODEL_DIR, 416, num_threads=2, device=device, half=True)
    assert gpu.device.target == "cpu" and "running on the CPU" in gpu.device.note
    blob, _ = letterbox(frame("tum_fr3_office"), 416)
    np.testing.assert_array_equal(gpu.infer(blob), torch_backend.infer(blob))


@needs_weights
def test_onnx_backend_without_gpu_providers_runs_on_the_cpu(tmp_path):
    import onnxruntime as ort

    if set(ort.get_available_providers()) & set(ORT_GPU[:2]):
        pytest.skip("this onnxruntime has GPU providers: the fallback is not exercised")
    be = OnnxBackend(MODEL_DIR, 320, num_threads=1, cache_dir=tmp_path, device="cuda")
    assert be.device.target == ("CPUExecutionProvider",)
    assert "install onnxruntime-gpu" in be.device.note


@needs_weights
def test_detector_reports_device_name_and_note():
    import torch

    if torch.cuda.is_available():
        pytest.skip("this machine has CUDA")
    det = Detector(DetectorParams(backend="torch", device="auto", input_size=320))
    assert det.device_name == "cpu" and "torch sees no CUDA device" in det.device_note
    assert Detector(DetectorParams(backend="torch", input_size=320)).device_note == ""
