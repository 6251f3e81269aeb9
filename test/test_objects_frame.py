"""The depth frame and its pixel-level steps (explore_seg.core.objects.frame)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.objects import DepthFrame, view_cut
from objects_scene import K


def test_depth_frame_rejects_mismatched_inputs():
    with pytest.raises(ValueError, match="does not match camera info"):
        DepthFrame(np.zeros((10, 10), np.float32), K, np.eye(4))
    with pytest.raises(ValueError, match="4x4"):
        DepthFrame(np.zeros((480, 640), np.float32), K, np.eye(3))


def test_view_cut_marks_the_image_border_and_occluded_points():
    from explore_seg.core.objects import view_cut

    depth = np.full((K.height, K.width), 3.0, dtype=np.float32)
    depth[:, 100:110] = 1.0                                   # an occluder in front
    frame = DepthFrame(depth, K, np.eye(4))
    uv = np.array([[1, 50], [112, 50], [200, 50], [200, K.height - 1], [94, 50]], float)
    got = view_cut(frame, uv, np.full(5, 3.0), 4, 0.08)
    np.testing.assert_array_equal(got, [True, True, False, True, False])
