"""Parameters of the segmentation (explore_seg.core.segmentation.params)."""

from __future__ import annotations

import dataclasses

import pytest

from explore_seg.core.segmentation import (DudeSettings, SegmentationNodeParams,
                                           SegmentationParams)
from explore_seg.core.segmentation.params import dude_settings
from param_ranges import assert_range_enforced, ranged_fields


@pytest.mark.parametrize("field, value, match", [
    ("tau_m", 0.0, "tau_m"), ("tau_m", float("nan"), "tau_m"),
    ("obstacle_inflation_m", -0.1, "obstacle_inflation_m"),
    ("free_max_occupancy", 0, "free_max_occupancy"),
    ("occupied_min_occupancy", 100, "occupied_min_occupancy"),
    ("max_rounds", 0, "max_rounds"), ("inc_touch_cells", -1, "inc_touch_cells"),
    ("id_keep_frac", 1.5, "id_keep_frac"), ("max_door_width_m", 0.0, "max_door_width_m"),
])
def test_params_validation(field, value, match):
    with pytest.raises(ValueError, match=match):
        SegmentationParams(**{field: value})


def test_node_params_validation_and_docs():
    with pytest.raises(ValueError, match="process_period_s"):
        SegmentationNodeParams(process_period_s=0.0)
    for f in dataclasses.fields(SegmentationNodeParams):
        assert f.metadata.get("doc"), f.name


RANGED = ranged_fields(SegmentationNodeParams)


def test_every_bounded_number_has_a_range():
    assert set(RANGED) == {f.name for f in dataclasses.fields(SegmentationNodeParams)
                           if f.type in ("int", "float")}


@pytest.mark.parametrize("name", sorted(RANGED))
def test_range_holds_the_default_and_its_ends_are_enforced(name):
    assert_range_enforced(SegmentationNodeParams, name)


@pytest.mark.parametrize("field, value, match", [
    ("tau_px", 0.0, "tau_px"), ("simplify_eps_px", -1.0, "simplify_eps_px"),
    ("max_rounds", 0, "max_rounds"),
])
def test_dude_settings_validation(field, value, match):
    kwargs = {"tau_px": 1.0, field: value}
    with pytest.raises(ValueError, match=match):
        DudeSettings(**kwargs)


def test_dude_settings_in_pixels():
    st = dude_settings(SegmentationParams(tau_m=1.5, min_component_area_m2=1.0), 0.05)
    assert st.tau_px == pytest.approx(30.0)
    assert st.min_component_px == 400
