"""Parameters of the object costmap (explore_seg.core.objects.params)."""

from __future__ import annotations

import dataclasses

import pytest

from explore_seg.core.objects import ObjectCostmapNodeParams, ObjectParams


@pytest.mark.parametrize("kwargs, match", [
    (dict(sor_k=0), "sor_k"),
    (dict(merge_iou=1.5), "merge_iou"),
    (dict(floor_height_m=3.0), "below ceiling_height_m"),
    (dict(unknown_min_height_m=2.0), "below unknown_max_height_m"),
    (dict(leg_min_width_m=0.5), "must not exceed leg_max_width_m"),
    (dict(orientation_method="ransac"), "orientation_method"),
    (dict(object_value=101), "object_value"),
    (dict(background_value=-2), "background_value"),
    (dict(wall_min_length_m=-0.1), "wall_min_length_m"),
])
def test_object_params_validation(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ObjectParams(**kwargs)
    with pytest.raises(ValueError, match=match):       # the node's params validate them too
        ObjectCostmapNodeParams(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    (dict(rate_hz=0.0), "rate_hz"),
    (dict(pose_topic_type="tf"), "pose_topic_type"),
    (dict(camera_z_m=float("inf")), "camera_z_m"),
    (dict(map_frame=""), "map_frame"),
])
def test_node_params_validation(kwargs, match):
    """The node's own settings are validated by the node's class and are not the pipeline's."""
    with pytest.raises(ValueError, match=match):
        ObjectCostmapNodeParams(**kwargs)
    assert not set(kwargs) & {f.name for f in dataclasses.fields(ObjectParams)}
