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

Class names are the official COCO names; :mod:`.coco` lists them and the Darknet
spellings translated when ``coco.names`` is read.

Modules: :mod:`.params`, :mod:`.coco` (class names, :class:`Detection`),
:mod:`.preprocess` (input checks, letterbox), :mod:`.postprocess` (NMS, decoding),
:mod:`.model_files`, :mod:`.darknet` (the torch module), :mod:`.backends` (torch,
onnxruntime, ONNX export), :mod:`.oracle` and :mod:`.facade` (:class:`Detector`).

Model files (``yolov3-tiny.cfg``, ``yolov3-tiny.weights``, ``coco.names``) are fetched
by ``scripts/fetch_weights.py``; see :func:`default_model_dir` for where they are looked
for. ``torch`` is imported only when a network must be built (not by the oracle, nor by
the ONNX backend once its cached ONNX file exists).
"""

from explore_seg.core.detector.backends import (ONNX_EXPORT_VERSION, ONNX_FILE_MODE,
                                                ONNX_OPSET, NetworkBackend, OnnxBackend,
                                                TorchBackend, export_onnx, onnx_source)
from explore_seg.core.detector.coco import (COCO_NAMES, DARKNET_NAME_ALIASES, DEFAULT_CLASSES,
                                            DEFAULT_ORACLE_CLASS_MAP, Detection,
                                            parse_oracle_class_map)
from explore_seg.core.detector.facade import Detector
from explore_seg.core.detector.model_files import (CFG_FILE, MODEL_DIR_ENV, NAMES_FILE,
                                                   WEIGHTS_FILE, default_model_dir,
                                                   model_files, read_class_names)
from explore_seg.core.detector.oracle import OracleBackend
from explore_seg.core.detector.params import (BACKENDS, MAX_INPUT_SIZE, NETWORK_STRIDE,
                                              DetectorParams)
from explore_seg.core.detector.postprocess import batched_nms, box_iou, decode, nms
from explore_seg.core.detector.preprocess import (Letterbox, letterbox, validate_label_image,
                                                  validate_rgb)

__all__ = [
    "BACKENDS", "CFG_FILE", "COCO_NAMES", "DARKNET_NAME_ALIASES", "DEFAULT_CLASSES",
    "DEFAULT_ORACLE_CLASS_MAP", "MAX_INPUT_SIZE", "MODEL_DIR_ENV", "NAMES_FILE",
    "NETWORK_STRIDE", "ONNX_EXPORT_VERSION", "ONNX_FILE_MODE", "ONNX_OPSET", "WEIGHTS_FILE",
    "Detection", "Detector", "DetectorParams", "Letterbox", "NetworkBackend", "OnnxBackend",
    "OracleBackend", "TorchBackend", "batched_nms", "box_iou", "decode", "default_model_dir",
    "export_onnx", "letterbox", "model_files", "nms", "onnx_source", "parse_oracle_class_map",
    "read_class_names", "validate_label_image", "validate_rgb",
]
