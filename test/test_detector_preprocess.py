"""Input checks and the letterbox (explore_seg.core.detector.preprocess)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.detector import Letterbox, letterbox

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
