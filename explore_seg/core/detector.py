"""2D object detector: YOLOv3-tiny (Darknet weights) on torch or onnxruntime, or an oracle.

Pipeline of :meth:`Detector.detect` for the network backends:

1. :func:`letterbox` the RGB frame into a square ``input_size`` canvas (aspect kept,
   bilinear resize, grey 0.5 padding, as Darknet does);
2. run the network (:class:`TorchBackend` eager torch or :class:`OnnxBackend`
   onnxruntime on an ONNX file exported once from the torch module);
3. :func:`decode` every (box, class) pair whose score ``objectness * P(class)`` passes
   ``conf_threshold`` among the wanted ``classes``, class-aware :func:`batched_nms`,
   and map the boxes back into the original image.

The :class:`OracleBackend` instead reads boxes off the simulator's semantic class-id image
(and optional instance image), with configurable misses, jitter and score: the same
:class:`Detection` output without a network, for fast simulation.

Class names are the official COCO names (``"dining table"``, ``"couch"``, ``"tv"``,
``"potted plant"``); the older Darknet spellings found in ``coco.names``
(``diningtable``, ``sofa``, ``tvmonitor``, ``pottedplant``, ``motorbike``, ``aeroplane``)
are translated when the file is read.

Model files (``yolov3-tiny.cfg``, ``yolov3-tiny.weights``, ``coco.names``) are fetched
by ``scripts/fetch_weights.py``; see :func:`default_model_dir` for where they are looked
for. ``torch`` is imported only when a network must be built (not by the oracle, nor by
the ONNX backend once its cached ONNX file exists).
"""

from __future__ import annotations

import hashlib
import logging
import os
import tempfile
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np
import numpy.typing as npt
from explore_seg.core.fields import param_meta as _doc

LOG = logging.getLogger(__name__)

#: Environment variable naming the folder with the model files.
MODEL_DIR_ENV = "EXPLORE_SEG_MODEL_DIR"
CFG_FILE = "yolov3-tiny.cfg"
WEIGHTS_FILE = "yolov3-tiny.weights"
NAMES_FILE = "coco.names"
#: Bumped whenever the exported graph changes, so stale ONNX caches are re-exported.
ONNX_EXPORT_VERSION = "1"
ONNX_OPSET = 17
_ONNX_META_KEY = "explore_seg_source"
ONNX_FILE_MODE = 0o644
#: Network input sizes must be multiples of the YOLOv3-tiny stride.
NETWORK_STRIDE = 32
MAX_INPUT_SIZE = 1024
BACKENDS = ("auto", "torch", "onnx", "oracle")

#: The 80 COCO class names in YOLO's class-id order (official 2017 spellings).
COCO_NAMES: tuple[str, ...] = (
    "person", "bicycle", "car", "motorcycle", "airplane", "bus", "train", "truck", "boat",
    "traffic light", "fire hydrant", "stop sign", "parking meter", "bench", "bird", "cat",
    "dog", "horse", "sheep", "cow", "elephant", "bear", "zebra", "giraffe", "backpack",
    "umbrella", "handbag", "tie", "suitcase", "frisbee", "skis", "snowboard", "sports ball",
    "kite", "baseball bat", "baseball glove", "skateboard", "surfboard", "tennis racket",
    "bottle", "wine glass", "cup", "fork", "knife", "spoon", "bowl", "banana", "apple",
    "sandwich", "orange", "broccoli", "carrot", "hot dog", "pizza", "donut", "cake", "chair",
    "couch", "potted plant", "bed", "dining table", "toilet", "tv", "laptop", "mouse",
    "remote", "keyboard", "cell phone", "microwave", "oven", "toaster", "sink",
    "refrigerator", "book", "clock", "vase", "scissors", "teddy bear", "hair drier",
    "toothbrush",
)
#: Darknet ``coco.names`` spellings -> official COCO names.
DARKNET_NAME_ALIASES: Mapping[str, str] = {
    "motorbike": "motorcycle", "aeroplane": "airplane", "sofa": "couch",
    "pottedplant": "potted plant", "diningtable": "dining table", "tvmonitor": "tv",
}

#: Default classes for an indoor robot: furniture and large appliances that are static
#: obstacles a 2D lidar sees badly (table/chair legs, overhangs) or that name a room
#: (bed, toilet, couch, oven, refrigerator, sink). People and small objects are left out:
#: they move, or are not obstacles.
DEFAULT_CLASSES: tuple[str, ...] = (
    "chair", "couch", "bed", "dining table", "toilet", "bench", "potted plant", "tv",
    "refrigerator", "oven", "sink",
)
#: Default simulator class name -> COCO name map of the oracle (``"sim:coco"`` pairs).
DEFAULT_ORACLE_CLASS_MAP: tuple[str, ...] = (
    "chair:chair", "table:dining table", "desk:dining table", "sofa:couch", "couch:couch",
    "bed:bed", "toilet:toilet", "tv:tv", "plant:potted plant", "bench:bench",
    "fridge:refrigerator", "refrigerator:refrigerator", "oven:oven", "sink:sink",
)



@dataclass(frozen=True)
class DetectorParams:
    """Parameters of :class:`Detector` (and of the detector node).

    Raises
    ------
    ValueError
        From ``__post_init__`` on any out-of-range value, naming the field, the
        expected range and the value got.
    """

    backend: str = field(default="auto", metadata=_doc(
        "inference backend: auto (onnx when onnxruntime imports, else torch), torch, onnx, "
        "or oracle (boxes from the simulator's semantic image)"))
    input_size: int = field(default=416, metadata=_doc(
        "square network input side; multiple of 32 (320 is faster, 416 finds more)", "px"))
    conf_threshold: float = field(default=0.25, metadata=_doc(
        "minimum score objectness * P(class) of a reported detection, in (0, 1]"))
    nms_iou: float = field(default=0.45, metadata=_doc(
        "IoU above which a lower-scored box of the same class is suppressed, in (0, 1]"))
    max_detections: int = field(default=100, metadata=_doc(
        "at most this many detections per frame (highest scores kept), >= 1"))
    classes: tuple[str, ...] = field(default=DEFAULT_CLASSES, metadata=_doc(
        "COCO class names to report; empty = all 80"))
    num_threads: int = field(default=2, metadata=_doc(
        "CPU threads of the network (torch.set_num_threads is process-wide; onnxruntime "
        "intra-op threads), >= 1"))
    model_dir: str = field(default="", metadata=_doc(
        "folder with yolov3-tiny.cfg/.weights and coco.names; empty = "
        "$EXPLORE_SEG_MODEL_DIR, <repo>/models/yolov3-tiny, ~/.cache/explore_seg/yolov3-tiny"))
    letterbox_fill: float = field(default=0.5, metadata=_doc(
        "grey level of the letterbox padding, in [0, 1]"))
    oracle_class_map: tuple[str, ...] = field(default=DEFAULT_ORACLE_CLASS_MAP, metadata=_doc(
        "oracle: 'sim_class:coco_name' pairs; sim classes absent from the simulator's "
        "class-id table are ignored"))
    oracle_miss_prob: float = field(default=0.0, metadata=_doc(
        "oracle: probability that an object is not reported, in [0, 1]"))
    oracle_jitter_px: float = field(default=0.0, metadata=_doc(
        "oracle: standard deviation of the Gaussian noise added to each box corner, >= 0",
        "px"))
    oracle_score: float = field(default=0.9, metadata=_doc(
        "oracle: score given to every oracle detection, in (0, 1]"))
    oracle_min_area_px: int = field(default=50, metadata=_doc(
        "oracle: objects with fewer visible pixels are not reported, >= 1", "px"))
    oracle_seed: int = field(default=0, metadata=_doc(
        "oracle: seed of the random generator (misses, jitter)"))

    def __post_init__(self) -> None:
        if self.backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {self.backend!r}")
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


@dataclass(frozen=True)
class Detection:
    """One detected object.

    Parameters
    ----------
    cls_name : str
        COCO class name (``"chair"``).
    class_id : int
        Index of ``cls_name`` in :data:`COCO_NAMES`.
    score : float
        Confidence in (0, 1].
    box_xyxy : tuple of 4 float
        ``(x0, y0, x1, y1)`` in pixels of the ORIGINAL image; continuous coordinates
        (pixel ``(u, v)`` spans ``[u, u + 1) x [v, v + 1)``), clipped to the image.
    """

    cls_name: str
    class_id: int
    score: float
    box_xyxy: tuple[float, float, float, float]


@dataclass(frozen=True)
class Letterbox:
    """Geometry of a letterbox resize, and the mapping between its two pixel frames.

    Parameters
    ----------
    src_hw : tuple of int
        Original image height, width.
    size : int
        Side of the square network input.
    resized_hw : tuple of int
        Size of the resized image inside the canvas.
    offset_xy : tuple of int
        Canvas position of the resized image's top-left corner.
    """

    src_hw: tuple[int, int]
    size: int
    resized_hw: tuple[int, int]
    offset_xy: tuple[int, int]

    @classmethod
    def fit(cls, src_hw: tuple[int, int], size: int) -> Letterbox:
        """Darknet's letterbox geometry: scale to fit, centre, integer sizes/offsets."""
        h, w = src_hw
        if w >= h:  # the long side fills the canvas exactly
            new_w, new_h = size, max(1, min(size, int(h * size / w)))
        else:
            new_w, new_h = max(1, min(size, int(w * size / h))), size
        return cls((h, w), size, (new_h, new_w), ((size - new_w) // 2, (size - new_h) // 2))

    def to_original(self, boxes_xyxy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Map ``(N, 4)`` boxes from network-input to original pixels and clip to the image."""
        b = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
        sx = self.resized_hw[1] / self.src_hw[1]
        sy = self.resized_hw[0] / self.src_hw[0]
        out = np.empty_like(b)
        out[:, [0, 2]] = (b[:, [0, 2]] - self.offset_xy[0]) / sx
        out[:, [1, 3]] = (b[:, [1, 3]] - self.offset_xy[1]) / sy
        out[:, [0, 2]] = out[:, [0, 2]].clip(0.0, self.src_hw[1])
        out[:, [1, 3]] = out[:, [1, 3]].clip(0.0, self.src_hw[0])
        return out

    def to_network(self, boxes_xyxy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Map ``(N, 4)`` boxes from original to network-input pixels (inverse, no clip)."""
        b = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
        sx = self.resized_hw[1] / self.src_hw[1]
        sy = self.resized_hw[0] / self.src_hw[0]
        out = np.empty_like(b)
        out[:, [0, 2]] = b[:, [0, 2]] * sx + self.offset_xy[0]
        out[:, [1, 3]] = b[:, [1, 3]] * sy + self.offset_xy[1]
        return out


def validate_rgb(rgb: object) -> npt.NDArray[np.uint8]:
    """Check that ``rgb`` is an ``(H, W, 3)`` uint8 array; return it.

    Raises
    ------
    ValueError
        Naming the expected and the received type, dtype or shape.
    """
    if not isinstance(rgb, np.ndarray):
        raise ValueError(f"rgb must be a numpy array (H, W, 3) uint8, got {type(rgb).__name__}")
    if rgb.dtype != np.uint8:
        raise ValueError(f"rgb must have dtype uint8, got {rgb.dtype}")
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[0] < 1 or rgb.shape[1] < 1:
        raise ValueError(f"rgb must have shape (H, W, 3) with H, W >= 1, got {rgb.shape}")
    return rgb


def letterbox(rgb: npt.NDArray[np.uint8], size: int,
              fill: float = 0.5) -> tuple[npt.NDArray[np.float32], Letterbox]:
    """Resize an RGB image into a square network input, keeping its aspect ratio.

    Parameters
    ----------
    rgb : ndarray of uint8, shape (H, W, 3)
        RGB image.
    size : int
        Side of the square output.
    fill : float
        Value of the padding, in [0, 1] (Darknet uses 0.5).

    Returns
    -------
    blob : ndarray of float32, shape (1, 3, size, size)
        RGB in [0, 1], channels first.
    geometry : Letterbox
        To map boxes back with :meth:`Letterbox.to_original`.

    Raises
    ------
    ValueError
        On a bad image (see :func:`validate_rgb`) or ``size < 1``.
    """
    validate_rgb(rgb)
    if size < 1:
        raise ValueError(f"size must be >= 1, got {size}")
    geo = Letterbox.fit((rgb.shape[0], rgb.shape[1]), size)
    new_h, new_w = geo.resized_hw
    resized = cv2.resize(rgb, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    blob = np.full((1, 3, size, size), fill, dtype=np.float32)
    x0, y0 = geo.offset_xy
    blob[0, :, y0:y0 + new_h, x0:x0 + new_w] = resized.transpose(2, 0, 1) / np.float32(255)
    return blob, geo


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
        multiplied by the objectness (the :mod:`explore_seg.core.darknet` layout).
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


# --------------------------------------------------------------------------- model files


def default_model_dir(explicit: str | os.PathLike[str] | None = None) -> Path:
    """Folder that holds (or should hold) the YOLOv3-tiny model files.

    Resolution order: ``explicit`` (when non-empty) > ``$EXPLORE_SEG_MODEL_DIR`` >
    ``<repo>/models/yolov3-tiny`` > ``~/.cache/explore_seg/yolov3-tiny``. Among the last two
    the first one holding the weights wins; when neither does, the repository folder is
    returned (where ``scripts/fetch_weights.py`` puts them by default).

    Parameters
    ----------
    explicit : str or PathLike, optional

    Returns
    -------
    Path
    """
    if explicit:
        return Path(explicit).expanduser()
    env = os.environ.get(MODEL_DIR_ENV, "")
    if env:
        return Path(env).expanduser()
    repo = Path(__file__).resolve().parents[2] / "models" / "yolov3-tiny"
    cache = Path.home() / ".cache" / "explore_seg" / "yolov3-tiny"
    for candidate in (repo, cache):
        if (candidate / WEIGHTS_FILE).is_file():
            return candidate
    return repo


def model_files(model_dir: Path) -> tuple[Path, Path, Path]:
    """``(cfg, weights, names)`` paths in ``model_dir``.

    Raises
    ------
    FileNotFoundError
        Naming the missing files and how to fetch them.
    """
    paths = (model_dir / CFG_FILE, model_dir / WEIGHTS_FILE, model_dir / NAMES_FILE)
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise FileNotFoundError(
            f"missing {missing} in {model_dir}; run `python scripts/fetch_weights.py "
            f"--dest {model_dir}` (or set ${MODEL_DIR_ENV})")
    return paths


def read_class_names(path: Path) -> tuple[str, ...]:
    """Class names of a Darknet names file, Darknet spellings mapped to COCO ones.

    Raises
    ------
    ValueError
        If the names are not the 80 COCO classes in YOLO order.
    """
    names = tuple(DARKNET_NAME_ALIASES.get(n.strip(), n.strip())
                  for n in path.read_text(encoding="utf-8").splitlines() if n.strip())
    if names != COCO_NAMES:
        diff = [(i, n) for i, n in enumerate(names) if i >= len(COCO_NAMES) or n != COCO_NAMES[i]]
        raise ValueError(f"{path}: expected the {len(COCO_NAMES)} COCO names in order, got "
                         f"{len(names)} names, first mismatches {diff[:3]}")
    return names


# --------------------------------------------------------------------------- backends


class NetworkBackend(Protocol):
    """A YOLO network: ``(1, 3, S, S)`` float32 blob -> ``(N, 5 + C)`` raw rows."""

    name: str
    input_size: int

    def infer(self, blob: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        """Run the network on one letterboxed blob."""
        ...


class TorchBackend:
    """Eager torch inference of the Darknet module.

    Parameters
    ----------
    model_dir : Path
        Folder with the model files.
    input_size : int
        Network input side.
    num_threads : int
        Passed to ``torch.set_num_threads`` (process-wide).
    """

    name = "torch"

    def __init__(self, model_dir: Path, input_size: int, num_threads: int) -> None:
        import torch

        from explore_seg.core.darknet import load_darknet

        cfg, weights, names = model_files(model_dir)
        self.class_names = read_class_names(names)
        self.input_size = input_size
        torch.set_num_threads(num_threads)
        self._torch = torch
        self.net = load_darknet(cfg, weights)

    def infer(self, blob: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        with self._torch.inference_mode():
            heads = self.net(self._torch.from_numpy(blob))
        return np.concatenate([h[0].numpy() for h in heads], axis=0)


def _source_digest(cfg: Path, weights: Path, input_size: int) -> str:
    """Identity of an ONNX export: export version, input size, cfg and weights content."""
    digest = hashlib.sha256()
    digest.update(f"{ONNX_EXPORT_VERSION}:{input_size}:".encode())
    digest.update(cfg.read_bytes())
    with weights.open("rb") as stream:
        for chunk in iter(lambda: stream.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def export_onnx(cfg: Path, weights: Path, input_size: int, path: Path, source: str) -> None:
    """Export the Darknet module to ONNX at ``path`` (atomically), tagging its source digest.

    Raises
    ------
    OSError
        If ``path``'s folder is not writable.
    """
    import onnx
    import torch

    from explore_seg.core.darknet import load_darknet

    net = load_darknet(cfg, weights)
    dummy = torch.zeros(1, 3, input_size, input_size)
    n_heads = len(net(dummy))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        with warnings.catch_warnings():
            # Tracing fixes the input size on purpose (one file per size): silence the
            # tracer's warnings about shapes turned into constants.
            warnings.simplefilter("ignore")
            torch.onnx.export(net, (dummy,), tmp, dynamo=False, opset_version=ONNX_OPSET,
                              input_names=["images"],
                              output_names=[f"head{i}" for i in range(n_heads)])
        model = onnx.load(tmp)
        entry = model.metadata_props.add()
        entry.key, entry.value = _ONNX_META_KEY, source
        onnx.save(model, tmp)
        os.chmod(tmp, ONNX_FILE_MODE)
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


class OnnxBackend:
    """onnxruntime inference of the Darknet module, exported once to an ONNX cache file.

    The file ``yolov3-tiny_<size>.onnx`` lives next to the weights, or in
    ``<tmp>/explore_seg_onnx`` when that folder is not writable. It carries a digest of
    the cfg, weights, input size and export version and is re-exported when that differs.

    Parameters
    ----------
    model_dir : Path
        Folder with the model files.
    input_size : int
        Network input side.
    num_threads : int
        onnxruntime intra-op threads.
    cache_dir : Path, optional
        Where to keep the ONNX file (default: ``model_dir``, falling back to a temp dir).
    """

    name = "onnx"

    def __init__(self, model_dir: Path, input_size: int, num_threads: int,
                 cache_dir: Path | None = None) -> None:
        import onnxruntime as ort

        cfg, weights, names = model_files(model_dir)
        self.class_names = read_class_names(names)
        self.input_size = input_size
        source = _source_digest(cfg, weights, input_size)
        file_name = f"{cfg.stem}_{input_size}.onnx"
        dirs = [cache_dir] if cache_dir else [
            model_dir, Path(tempfile.gettempdir()) / "explore_seg_onnx"]
        self.onnx_path = self._ensure_export(cfg, weights, input_size, source, file_name, dirs)
        options = ort.SessionOptions()
        options.intra_op_num_threads = num_threads
        options.inter_op_num_threads = 1
        options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        self._session = ort.InferenceSession(str(self.onnx_path), options,
                                             providers=["CPUExecutionProvider"])
        self._input = self._session.get_inputs()[0].name

    @staticmethod
    def _ensure_export(cfg: Path, weights: Path, input_size: int, source: str, file_name: str,
                       dirs: list[Path]) -> Path:
        for d in dirs:
            if _onnx_source(d / file_name) == source:
                return d / file_name
        errors = []
        for d in dirs:
            try:
                export_onnx(cfg, weights, input_size, d / file_name, source)
                LOG.info("exported %s", d / file_name)
                return d / file_name
            except OSError as err:
                errors.append(f"{d}: {err}")
        raise OSError(f"cannot write the ONNX export anywhere: {errors}")

    def infer(self, blob: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        heads = self._session.run(None, {self._input: blob})
        return np.concatenate([h[0] for h in heads], axis=0)


def _onnx_source(path: Path) -> str | None:
    """The source digest stored in an exported ONNX file, or None if absent/unreadable."""
    if not path.is_file():
        return None
    import onnx

    from google.protobuf.message import DecodeError

    try:
        model = onnx.load(str(path), load_external_data=False)
    except (OSError, ValueError, RuntimeError, DecodeError) as err:  # corrupt: re-export
        LOG.warning("ignoring unreadable ONNX cache %s: %s", path, err)
        return None
    return next((p.value for p in model.metadata_props if p.key == _ONNX_META_KEY), None)


def parse_oracle_class_map(pairs: Sequence[str]) -> dict[str, str]:
    """Parse ``"sim_class:coco_name"`` pairs into a dict.

    Raises
    ------
    ValueError
        On a pair without exactly one ``:``, an empty side, a COCO name not in
        :data:`COCO_NAMES` or a sim class listed twice.
    """
    out: dict[str, str] = {}
    for pair in pairs:
        parts = pair.split(":")
        if len(parts) != 2 or not parts[0].strip() or not parts[1].strip():
            raise ValueError(f"oracle_class_map entries must be 'sim_class:coco_name', "
                             f"got {pair!r}")
        sim, coco = parts[0].strip(), parts[1].strip()
        if coco not in COCO_NAMES:
            raise ValueError(f"oracle_class_map: {coco!r} (in {pair!r}) is not a COCO name")
        if sim in out:
            raise ValueError(f"oracle_class_map: sim class {sim!r} listed twice")
        out[sim] = coco
    return out


def _validate_label_image(name: str, image: object, hw: tuple[int, int]) -> npt.NDArray:
    if not isinstance(image, np.ndarray):
        raise ValueError(f"{name} must be a numpy array (H, W) of integers, "
                         f"got {type(image).__name__}")
    if not np.issubdtype(image.dtype, np.integer):
        raise ValueError(f"{name} must have an integer dtype, got {image.dtype}")
    if image.shape != hw:
        raise ValueError(f"{name} must have shape {hw} (the rgb's H, W), got {image.shape}")
    return image


class OracleBackend:
    """Detections read from the simulator's semantic (and instance) image.

    Parameters
    ----------
    params : DetectorParams
        ``oracle_*`` fields and ``classes``.
    sim_class_ids : mapping of str to int
        The simulator's class name -> id table (``sim_bridge.sensors.CLASS_IDS``); passed
        in so the core never imports the simulator.

    Raises
    ------
    ValueError
        If no entry of ``oracle_class_map`` names a class of ``sim_class_ids``.
    """

    name = "oracle"

    def __init__(self, params: DetectorParams, sim_class_ids: Mapping[str, int]) -> None:
        self.params = params
        mapping = parse_oracle_class_map(params.oracle_class_map)
        allowed = set(params.classes) if params.classes else set(COCO_NAMES)
        self.ignored_sim_classes = tuple(sorted(s for s in mapping if s not in sim_class_ids))
        self._id_to_coco = {int(sim_class_ids[s]): c for s, c in mapping.items()
                            if s in sim_class_ids and c in allowed}
        if not any(s in sim_class_ids for s in mapping):
            raise ValueError(f"oracle_class_map names none of the simulator's classes "
                             f"{sorted(sim_class_ids)}; got {sorted(mapping)}")
        self._rng = np.random.default_rng(params.oracle_seed)

    def detect(self, semantic: npt.NDArray[np.integer],
               instance: npt.NDArray[np.integer] | None = None) -> list[Detection]:
        """Boxes of the mapped objects in a semantic image.

        Each object is one instance id within a class when ``instance`` is given, else one
        8-connected component of the class mask. The box spans the object's pixels
        (``x1 = last column + 1``), gets Gaussian jitter of ``oracle_jitter_px`` per
        corner, is clipped to the image, and is dropped with ``oracle_miss_prob``.

        Parameters
        ----------
        semantic : ndarray of int, shape (H, W)
            Simulator class id per pixel.
        instance : ndarray of int, shape (H, W), optional
            Object instance id per pixel.

        Returns
        -------
        list of Detection
            Ordered by sim class id, then instance id / component.
        """
        p = self.params
        h, w = semantic.shape
        out: list[Detection] = []
        if semantic.dtype.kind == "u" and semantic.dtype.itemsize <= 2:  # fast path
            present = set(np.flatnonzero(np.bincount(semantic.ravel())).tolist())
        else:
            present = set(np.unique(semantic).tolist())
        for sim_id in sorted(self._id_to_coco):
            if sim_id not in present:
                continue
            mask = semantic == sim_id
            coco = self._id_to_coco[sim_id]
            for box, area in self._objects(mask, None if instance is None else instance[mask]):
                if area < p.oracle_min_area_px:
                    continue
                if self._rng.random() < p.oracle_miss_prob:
                    continue
                if p.oracle_jitter_px > 0:
                    box = box + self._rng.normal(0.0, p.oracle_jitter_px, 4)
                x0, x1 = sorted((float(np.clip(box[0], 0, w)), float(np.clip(box[2], 0, w))))
                y0, y1 = sorted((float(np.clip(box[1], 0, h)), float(np.clip(box[3], 0, h))))
                if x1 <= x0 or y1 <= y0:
                    continue
                out.append(Detection(coco, COCO_NAMES.index(coco), p.oracle_score,
                                     (x0, y0, x1, y1)))
        return out

    @staticmethod
    def _objects(mask: npt.NDArray[np.bool_], instance_values: npt.NDArray | None):
        """Yield ``(box_xyxy float64 (4,), pixel count)`` per object of a class mask."""
        if instance_values is None:
            n, _, stats, _ = cv2.connectedComponentsWithStats(
                mask.astype(np.uint8), connectivity=8)
            for k in range(1, n):
                x, y, bw, bh, area = stats[k]
                yield np.array([x, y, x + bw, y + bh], dtype=np.float64), int(area)
            return
        rows, cols = np.nonzero(mask)
        for inst in np.unique(instance_values):
            sel = instance_values == inst
            r, c = rows[sel], cols[sel]
            yield (np.array([c.min(), r.min(), c.max() + 1, r.max() + 1], dtype=np.float64),
                   int(sel.sum()))


# --------------------------------------------------------------------------- detector


def _make_network(params: DetectorParams, model_dir: Path) -> NetworkBackend:
    """The network backend of ``params.backend``; ``auto`` falls back to torch when
    onnxruntime or onnx cannot be imported."""
    if params.backend in ("auto", "onnx"):
        try:
            return OnnxBackend(model_dir, params.input_size, params.num_threads)
        except ImportError as err:
            if params.backend == "onnx":
                raise
            LOG.info("onnx backend unavailable (%s): using torch", err)
    return TorchBackend(model_dir, params.input_size, params.num_threads)


class Detector:
    """2D object detector producing :class:`Detection` lists.

    Parameters
    ----------
    params : DetectorParams, optional
        Defaults when omitted.
    sim_class_ids : mapping of str to int, optional
        Simulator class name -> id table; required by the ``oracle`` backend.

    Raises
    ------
    FileNotFoundError
        When a network backend cannot find its model files.
    ValueError
        When the oracle backend gets no (usable) ``sim_class_ids``, or the names file is
        not COCO.

    Examples
    --------
    >>> det = Detector(DetectorParams(backend="oracle"), sim_class_ids={"chair": 3})
    >>> sem = np.zeros((40, 60), np.uint8); sem[10:30, 5:25] = 3
    >>> [(d.cls_name, d.box_xyxy) for d in det.detect(np.zeros((40, 60, 3), np.uint8),
    ...                                                semantic=sem)]
    [('chair', (5.0, 10.0, 25.0, 30.0))]
    """

    def __init__(self, params: DetectorParams | None = None, *,
                 sim_class_ids: Mapping[str, int] | None = None) -> None:
        self.params = params or DetectorParams()
        self.model_dir = default_model_dir(self.params.model_dir)
        self._network: NetworkBackend | None = None
        self._oracle: OracleBackend | None = None
        if self.params.backend == "oracle":
            if not sim_class_ids:
                raise ValueError("backend 'oracle' needs sim_class_ids (sim class name -> id), "
                                 f"got {sim_class_ids!r}")
            self._oracle = OracleBackend(self.params, sim_class_ids)
            self.backend_name = OracleBackend.name
        else:
            self._network = _make_network(self.params, self.model_dir)
            self.backend_name = self._network.name

    @property
    def network(self) -> NetworkBackend | None:
        """The network backend (None for the oracle)."""
        return self._network

    def detect(self, rgb: npt.NDArray[np.uint8], *,
               semantic: npt.NDArray[np.integer] | None = None,
               instance: npt.NDArray[np.integer] | None = None) -> list[Detection]:
        """Detect objects in one frame.

        Parameters
        ----------
        rgb : ndarray of uint8, shape (H, W, 3)
            RGB image (R first).
        semantic : ndarray of int, shape (H, W), optional
            Simulator class ids; required (and only used) by the oracle backend.
        instance : ndarray of int, shape (H, W), optional
            Simulator instance ids (oracle only).

        Returns
        -------
        list of Detection
            Boxes in ``rgb`` pixels, by decreasing score for the network backends.

        Raises
        ------
        ValueError
            On a wrong type, dtype or shape of an input, or a missing ``semantic`` for
            the oracle.
        """
        validate_rgb(rgb)
        hw = (rgb.shape[0], rgb.shape[1])
        if self._oracle is not None:
            if semantic is None:
                raise ValueError("the oracle backend needs a semantic image (H, W), got None")
            _validate_label_image("semantic", semantic, hw)
            if instance is not None:
                _validate_label_image("instance", instance, hw)
            return self._oracle.detect(semantic, instance)
        if self._network is None:  # unreachable: one of the two backends is always set
            raise RuntimeError("detector has no backend")
        blob, geo = letterbox(rgb, self.params.input_size, self.params.letterbox_fill)
        return decode(self._network.infer(blob), geo, self.params)
