"""Darknet cfg parser, torch module and weights loader (explore_seg.core.detector.darknet),
and the loaded YOLOv3-tiny against OpenCV's Darknet reader."""

from __future__ import annotations

import struct

import cv2
import numpy as np
import pytest

from detector_support import MODEL_DIR, frame, needs_weights
from detector_support import torch_backend  # noqa: F401 - a fixture
from explore_seg.core.detector import darknet, letterbox

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

    pool = darknet.MaxPool(darknet.CfgSection("maxpool", {"size": "2", "stride": "1"}))
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

    rgb = frame("tum_fr3_office")
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
