"""Bormann et al. (IPA) recall / precision of a segmentation
(explore_seg.core.segmentation.eval)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.segmentation.eval import evaluate


def _blocks(*widths: int, height: int = 20) -> np.ndarray:
    """Label image of side-by-side blocks of the given widths, ids 1..n."""
    return np.concatenate([np.full((height, w), k + 1, np.int32)
                           for k, w in enumerate(widths)], axis=1)


def test_identical_segmentation_scores_one():
    gt = _blocks(10, 15, 20)
    e = evaluate(gt * 7, gt, min_segment_px=0)
    assert e["recall"] == 1.0 and e["precision"] == 1.0
    assert e["n_rooms"] == 3 and e["n_segments"] == 3


def test_merging_two_rooms_lowers_precision_only():
    gt = _blocks(10, 10)                           # two rooms of 200 cells
    pred = np.ones_like(gt)
    e = evaluate(pred, gt, min_segment_px=0)
    assert e["recall"] == 1.0
    assert e["precision"] == 0.5
    assert e["segments"][1]["best_room"] in (1, 2)


def test_splitting_a_room_lowers_recall_only():
    gt = np.ones((20, 20), np.int32)
    pred = _blocks(5, 15)                          # 100 + 300 cells
    e = evaluate(pred, gt, min_segment_px=0)
    assert e["recall"] == pytest.approx(0.75)
    assert e["precision"] == 1.0
    assert e["rooms"][1] == {"size": 400, "best_segment": 2, "overlap": 300, "recall": 0.75}


def test_small_rooms_and_segments_are_ignored():
    gt = _blocks(10, 5)                            # 200 and 100 cells
    pred = _blocks(10, 5) * 3
    e = evaluate(pred, gt)                         # IPA drops sizes <= 100
    assert e["n_rooms"] == 1 and e["n_segments"] == 1


def test_weighted_versions_and_unlabelled_cells():
    gt = _blocks(10, 30)                           # 200 and 600 cells
    pred = gt.copy()
    pred[:, 10:25] = 9                             # room 2 split 300 / 300
    e = evaluate(pred, gt, min_segment_px=0)
    assert e["recall"] == pytest.approx((1.0 + 0.5) / 2)
    assert e["recall_weighted"] == pytest.approx((200 + 300) / 800)
    assert e["precision_weighted"] == 1.0
    pred[:, :] = 0
    e = evaluate(pred, gt, min_segment_px=0)
    assert e["recall"] == 0.0 and math.isnan(e["precision"])


def test_connected_components_ground_truth():
    gt = np.zeros((20, 41), np.int32)
    gt[:, :20] = 255
    gt[:, 21:] = 255                               # two rooms drawn in one colour
    pred = np.ones_like(gt)
    e = evaluate(pred, gt, min_segment_px=0, gt_connected=True)
    assert e["n_rooms"] == 2 and e["precision"] == pytest.approx(400 / 820)


@pytest.mark.parametrize("labels, gt, min_px, match", [
    (np.zeros((3, 3)), np.zeros((3, 4)), 0, "differs"),
    (np.zeros(3), np.zeros(3), 0, "2D"),
    (np.zeros((3, 3)), np.zeros((3, 3)), -1, "min_segment_px"),
])
def test_bad_inputs(labels, gt, min_px, match):
    with pytest.raises(ValueError, match=match):
        evaluate(labels, gt, min_segment_px=min_px)
