"""Where the detector network runs: ``detector.device`` (``cpu`` | ``cuda`` | ``auto``).

The torch backend runs on ``cuda`` when ``torch.cuda.is_available()`` (optionally in half
precision, ``detector.half``); onnxruntime gets the TensorRT and CUDA execution providers
that its build offers, before the CPU one. When the requested GPU is not there the network
runs on the CPU and :class:`DevicePlan` carries one sentence saying so (the node logs it
once). ``cpu`` is the default and the tested path.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

#: Values of ``DetectorParams.device``.
DEVICES = ("cpu", "cuda", "auto")
#: onnxruntime GPU execution providers, preferred first.
ONNX_GPU_PROVIDERS = ("TensorrtExecutionProvider", "CUDAExecutionProvider")
CPU_PROVIDER = "CPUExecutionProvider"


@dataclass(frozen=True)
class DevicePlan:
    """The device a backend uses and, when it is not what was asked for, why."""

    #: torch device string (``cpu`` / ``cuda``) or onnxruntime providers, preferred first.
    target: str | tuple[str, ...]
    #: Half precision in use (torch on CUDA only).
    half: bool = False
    #: One log line when the request could not be met ('' otherwise).
    note: str = ""

    def describe(self) -> str:
        """Short text for the backend name (``cuda fp16``, ``CUDAExecutionProvider``)."""
        head = self.target if isinstance(self.target, str) else self.target[0]
        return head + (" fp16" if self.half else "")


def torch_plan(device: str, half: bool, cuda_available: bool) -> DevicePlan:
    """The torch device for ``device`` given whether CUDA is available.

    Examples
    --------
    >>> torch_plan("auto", True, cuda_available=False).target
    'cpu'
    >>> torch_plan("cuda", True, cuda_available=True)
    DevicePlan(target='cuda', half=True, note='')
    """
    _check(device)
    if device == "cpu":
        note = "detector.half applies on CUDA only: running in fp32 on the CPU" if half else ""
        return DevicePlan("cpu", False, note)
    if cuda_available:
        return DevicePlan("cuda", half)
    return DevicePlan("cpu", False, f"detector.device '{device}': torch sees no CUDA device "
                                    "(torch.cuda.is_available() is False): running on the CPU")


def onnx_plan(device: str, available: Sequence[str]) -> DevicePlan:
    """onnxruntime providers for ``device`` given ``ort.get_available_providers()``.

    Examples
    --------
    >>> onnx_plan("auto", ["CUDAExecutionProvider", "CPUExecutionProvider"]).target
    ('CUDAExecutionProvider', 'CPUExecutionProvider')
    >>> onnx_plan("cuda", ["CPUExecutionProvider"]).note[:40]
    "detector.device 'cuda': this onnxruntime"
    """
    _check(device)
    if device == "cpu":
        return DevicePlan((CPU_PROVIDER,))
    gpu = tuple(p for p in ONNX_GPU_PROVIDERS if p in available)
    if gpu:
        return DevicePlan(gpu + (CPU_PROVIDER,))
    return DevicePlan((CPU_PROVIDER,), False, (
        f"detector.device '{device}': this onnxruntime offers none of {ONNX_GPU_PROVIDERS} "
        f"(available: {list(available)}; install onnxruntime-gpu): running on the CPU"))


def session_note(plan: DevicePlan, used: Sequence[str]) -> str:
    """A note when onnxruntime dropped the GPU providers it was given (e.g. no CUDA
    libraries at run time); '' when the session uses the first one asked for."""
    if plan.note or not used or used[0] == plan.target[0]:
        return plan.note
    return (f"onnxruntime could not start {plan.target[0]} (session uses {list(used)}): "
            "running on the CPU")


def _check(device: str) -> None:
    if device not in DEVICES:
        raise ValueError(f"device must be one of {DEVICES}, got {device!r}")
