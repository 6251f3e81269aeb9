"""Defaults live only in the dataclasses: generated files, node declarations and profiles agree."""

from __future__ import annotations

import dataclasses
import importlib
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
import param_docs  # noqa: E402
from param_ranges import assert_range_enforced, ranged_fields  # noqa: E402

from explore_seg.params import flatten_params, coerce_value, ros_fields  # noqa: E402

NODE_CLASSES = {
    "frontier_detector": ("explore_seg.frontier_node", "FrontierDetectorNode"),
    "segmentation": ("explore_seg.segmentation_node", "SegmentationNode"),
    "object_costmap": ("explore_seg.object_costmap_node", "ObjectCostmapNode"),
    "target_selector": ("explore_seg.selector_node", "TargetSelectorNode"),
    "sim_bridge": ("sim_bridge.node", "SimBridgeNode"),
}


@pytest.mark.parametrize("path", list(param_docs.expected_files()), ids=lambda p: p.name)
def test_generated_files_are_up_to_date(path):
    want = param_docs.expected_files()[path]
    assert path.exists(), f"{path} missing: run python scripts/param_docs.py --write"
    assert path.read_text() == want, f"{path.name} is stale: run python scripts/param_docs.py --write"


@pytest.mark.parametrize("node_name", sorted(NODE_CLASSES))
def test_node_declares_exactly_the_documented_parameters(ros, node_name):
    mod, cls = NODE_CLASSES[node_name]
    node = ros.add(getattr(importlib.import_module(mod), cls)(context=ros.context))
    declared = {n for n in node._parameters
                if n not in ("use_sim_time", "start_type_description_service")}
    documented = {name for name, *_ in param_docs.declared_fields(node_name)}
    assert declared == documented, (f"undocumented: {sorted(declared - documented)}; "
                                    f"not declared: {sorted(documented - declared)}")


def _validate_profile(path: Path) -> None:
    data = yaml.safe_load(path.read_text())
    for node, section in data.items():
        key = "/**" if node.strip("/") == "**" else node.strip("/")
        assert key in param_docs.NODE_PARAMS, f"{path.name}: unknown node {node!r}"
        values = flatten_params(section["ros__parameters"])
        values.pop("use_sim_time", None)
        for prefix, spec in param_docs.NODE_PARAMS[key]:
            cls = param_docs.load_class(spec)
            fields = {prefix + f.name: (f, kind) for f, kind in ros_fields(cls)}
            changes = {}
            for name in list(values):
                if name in fields:
                    f, kind = fields[name]
                    changes[f.name] = coerce_value(kind, name, values.pop(name),
                                                   as_tuple=isinstance(f.default, tuple))
            dataclasses.replace(cls(), **changes)  # raises ValueError when invalid
        assert not values, f"{path.name}: {node} has unknown parameters {sorted(values)}"


PARAM_FILES = sorted(p for p in (ROOT / "config").glob("*.yaml") if p.name != "object_priors.yaml")


@pytest.mark.parametrize("path", PARAM_FILES, ids=lambda p: p.name)
def test_parameter_files_hold_only_known_valid_parameters(path):
    _validate_profile(path)


def _ranged(spec: str):
    cls = param_docs.load_class(spec)
    return [(cls, name) for name in ranged_fields(cls)]


RANGED = sorted({(spec, name) for sections in param_docs.NODE_PARAMS.values()
                 for _prefix, spec in sections for _cls, name in _ranged(spec)})


def test_every_node_has_ranged_parameters():
    """The descriptors carry ranges: each documented class declares some."""
    specs = {spec for sections in param_docs.NODE_PARAMS.values() for _p, spec in sections}
    assert all(_ranged(spec) for spec in specs), [s for s in specs if not _ranged(s)]


@pytest.mark.parametrize("spec,name", RANGED, ids=[f"{s.split(':')[1]}.{n}" for s, n in RANGED])
def test_declared_ranges_agree_with_validation(spec, name):
    """A range is no looser than the dataclass: values just outside it are rejected
    (the message may name a sub-parameter: SimParams validates through LidarParams etc.)."""
    assert_range_enforced(param_docs.load_class(spec), name, match=None)
