"""Cleaning of a grid into free-space masks (explore_seg.core.segmentation.cleaning)."""

from __future__ import annotations

import dataclasses

from explore_seg.core.grid import grid_from_ascii
from explore_seg.core.segmentation import SegmentationParams, clean_free_space


def test_clean_free_space_inflates_walls_and_grows_free():
    g, _ = grid_from_ascii("""
    ??????????
    ?........?
    ?....#...?
    ?........?
    ??????????
    """, resolution_m=0.05)
    p = SegmentationParams(obstacle_inflation_m=0.05, free_close_m=0.05,
                           obstacle_speck_area_m2=0.0)
    free_raw, free_clean = clean_free_space(g, p)
    assert free_raw.sum() == 23
    assert not free_clean[1:4, 4:7].any()       # the wall cell and its 1-cell inflation
    assert free_clean[0, 0] and free_clean[4, 9]  # free grown 1 cell into unknown
    speckless = dataclasses.replace(p, obstacle_speck_area_m2=0.0025)
    _, clean2 = clean_free_space(g, speckless)
    assert clean2[2, 5]                          # a 1-cell obstacle is a speck
