"""Decomposition of a free-space mask into nearly convex pieces
(explore_seg.core.segmentation.dude)."""

from __future__ import annotations

import numpy as np
import pytest

from explore_seg.core.segmentation import DudeSettings, decompose_mask, find_cuts

ST = DudeSettings(tau_px=4.0, simplify_eps_px=1.0, min_component_px=10)


def l_shape() -> np.ndarray:
    mask = np.zeros((60, 60), bool)
    mask[5:55, 5:20] = True
    mask[40:55, 5:55] = True
    return mask


def test_convex_piece_is_one_piece_without_cuts():
    mask = np.zeros((30, 40), bool)
    mask[5:25, 5:35] = True
    pieces, n = decompose_mask(mask, ST)
    assert n == 1
    np.testing.assert_array_equal(pieces > 0, mask)
    assert find_cuts(np.pad(mask[5:25, 5:35].astype(np.uint8), 1), ST) == []


def test_l_shape_is_cut_and_pieces_stay_inside_the_mask():
    mask = l_shape()
    pieces, n = decompose_mask(mask, ST)
    assert n >= 2
    assert set(np.unique(pieces[pieces > 0]).tolist()) == set(range(1, n + 1))
    assert not (pieces[~mask] > 0).any()
    # only cut lines are left unlabelled
    assert (mask & (pieces == 0)).sum() < 0.05 * mask.sum()


@pytest.mark.parametrize("mask, n", [(np.zeros((0, 0), bool), 0), (np.zeros((5, 5), bool), 0)],
                         ids=["empty", "no-free-cell"])
def test_empty_masks_give_no_piece(mask, n):
    pieces, got = decompose_mask(mask, ST)
    assert got == n and pieces.shape == mask.shape and not pieces.any()


def test_decompose_mask_rejects_a_non_2d_mask():
    with pytest.raises(ValueError, match="mask must be 2D"):
        decompose_mask(np.zeros((3, 3, 3), bool), ST)
