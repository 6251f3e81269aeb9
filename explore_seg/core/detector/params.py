"""Parameters of the detector (:class:`DetectorParams`) and their bounds."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from explore_seg.core.detector.devices import DEVICES
from explore_seg.core.detector.coco import (COCO_NAMES, DARKNET_NAME_ALIASES, DEFAULT_CLASSES,
                                            DEFAULT_ORACLE_CLASS_MAP, parse_oracle_class_map)
from explore_seg.core.fields import param_meta

#: Network input sizes must be multiples of the YOLOv3-tiny stride.
NETWORK_STRIDE = 32
MAX_INPUT_SIZE = 1024
BACKENDS = ("auto", "torch", "onnx", "oracle")


@dataclass(frozen=True)
class DetectorParams:
    """Parameters of :class:`Detector` (and of the detector node).

    Raises
    ------
    ValueError
        From ``__post_init__`` on any out-of-range value, naming the field, the
        expected range and the value got.
    """

    backend: str = field(default="auto", metadata=param_meta(
        "inference backend: auto (onnx when onnxruntime imports, else torch), torch, onnx, "
        "or oracle (boxes from the simulator's semantic image)"))
    input_size: int = field(default=416, metadata=param_meta(
        "square network input side; multiple of 32 (320 is faster, 416 finds more)", "px",
        range=(NETWORK_STRIDE, MAX_INPUT_SIZE)))
    conf_threshold: float = field(default=0.25, metadata=param_meta(
        "minimum score objectness * P(class) of a reported detection, in (0, 1]",
        range=(0.0, 1.0)))
    nms_iou: float = field(default=0.45, metadata=param_meta(
        "IoU above which a lower-scored box of the same class is suppressed, in (0, 1]",
        range=(0.0, 1.0)))
    max_detections: int = field(default=100, metadata=param_meta(
        "at most this many detections per frame (highest scores kept), >= 1",
        range=(1, 2**31 - 1)))
    classes: tuple[str, ...] = field(default=DEFAULT_CLASSES, metadata=param_meta(
        "COCO class names to report; empty = all 80"))
    num_threads: int = field(default=2, metadata=param_meta(
        "CPU threads of the network (torch.set_num_threads is process-wide; onnxruntime "
        "intra-op threads), >= 1", range=(1, 2**31 - 1)))
    device: str = field(default="cpu", metadata=param_meta(
        "where the network runs: cpu, cuda (torch on CUDA; onnxruntime with the TensorRT / "
        "CUDA execution providers) or auto (cuda when present); falls back to the CPU with "
        "one log line"))
    half: bool = field(default=False, metadata=param_meta(
        "torch on CUDA: half-precision (fp16) inference"))
    model_dir: str = field(default="", metadata=param_meta(
        "folder with yolov3-tiny.cfg/.weights and coco.names; empty = "
        "$EXPLORE_SEG_MODEL_DIR, <repo>/models/yolov3-tiny, ~/.cache/explore_seg/yolov3-tiny"))
    letterbox_fill: float = field(default=0.5, metadata=param_meta(
        "grey level of the letterbox padding, in [0, 1]", range=(0.0, 1.0)))
    oracle_class_map: tuple[str, ...] = field(
        default=DEFAULT_ORACLE_CLASS_MAP, metadata=param_meta(
        "oracle: 'sim_class:coco_name' pairs; sim classes absent from the simulator's "
        "class-id table are ignored"))
    oracle_miss_prob: float = field(default=0.0, metadata=param_meta(
        "oracle: probability that an object is not reported, in [0, 1]",
        range=(0.0, 1.0)))
    oracle_jitter_px: float = field(default=0.0, metadata=param_meta(
        "oracle: standard deviation of the Gaussian noise added to each box corner, >= 0",
        "px", range=(0.0, math.inf)))
    oracle_score: float = field(default=0.9, metadata=param_meta(
        "oracle: score given to every oracle detection, in (0, 1]", range=(0.0, 1.0)))
    oracle_min_area_px: int = field(default=50, metadata=param_meta(
        "oracle: objects with fewer visible pixels are not reported, >= 1", "px",
        range=(1, 2**31 - 1)))
    oracle_seed: int = field(default=0, metadata=param_meta(
        "oracle: seed of the random generator (misses, jitter)"))

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {self.backend!r}")
        if self.device not in DEVICES:
            raise ValueError(f"device must be one of {DEVICES}, got {self.device!r}")
        if (not NETWORK_STRIDE <= self.input_size <= MAX_INPUT_SIZE
                or self.input_size % NETWORK_STRIDE):
            raise ValueError(f"input_size must be a multiple of {NETWORK_STRIDE} in "
                             f"[{NETWORK_STRIDE}, {MAX_INPUT_SIZE}], got {self.input_size}")
        for name in ("conf_threshold", "nms_iou", "oracle_score"):
            value = getattr(self, name)
            if not 0.0 < value <= 1.0:
                raise ValueError(f"{name} must be in (0, 1], got {value}")
        for name in ("oracle_miss_prob", "letterbox_fill"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {value}")
        for name in ("max_detections", "num_threads", "oracle_min_area_px"):
            value = getattr(self, name)
            if value < 1:
                raise ValueError(f"{name} must be >= 1, got {value}")
        if not self.oracle_jitter_px >= 0.0:
            raise ValueError(f"oracle_jitter_px must be >= 0, got {self.oracle_jitter_px}")
        unknown = [c for c in self.classes if c not in COCO_NAMES]
        if unknown:
            hints = {a: n for a, n in DARKNET_NAME_ALIASES.items() if a in unknown}
            raise ValueError(f"classes must be COCO names, got unknown {unknown}"
                             + (f" (use {hints})" if hints else ""))
        parse_oracle_class_map(self.oracle_class_map)
