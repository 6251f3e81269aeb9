"""ParamBinding: declaration from a dataclass, validation on set, pass-through."""

from __future__ import annotations

from dataclasses import dataclass, field

from pathlib import Path

import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter

from explore_seg.core.fields import param_meta
from explore_seg.params import ParamBinding, load_node_params, overrides_from_dict


@dataclass(frozen=True)
class DemoParams:
    rate_hz: float = field(default=2.0, metadata=param_meta("tick rate", "Hz"))
    strategy: str = field(default="paper", metadata=param_meta("paper | nearest"))
    layers: tuple[str, ...] = field(default=(), metadata=param_meta("extra layers"))
    mount_xy_m: tuple[float, ...] = field(default=(0.1, -0.2), metadata=param_meta("mount", "m"))
    enabled: bool = field(default=True, metadata=param_meta("on/off"))
    max_items: int = field(default=5, metadata=param_meta("bound", range=(1, 10)))
    gain: float = field(default=0.5, metadata=param_meta("a fraction", range=(0.0, 1.0)))
    connectivity: int = field(default=4, metadata=param_meta("4 or 8", range=(4, 8, 4)))
    table: dict = field(default_factory=dict, metadata=param_meta("internal", ros=False))

    def __post_init__(self) -> None:
        if not self.rate_hz > 0:
            raise ValueError(f"rate_hz must be > 0, got {self.rate_hz}")
        if self.strategy not in ("paper", "nearest"):
            raise ValueError(f"strategy must be paper or nearest, got {self.strategy!r}")


def test_declares_every_field_with_description(ros):
    node = ros.add(Node("p1", context=ros.context))
    b = ParamBinding(node, DemoParams())
    assert b.params == DemoParams()
    names = {p for p in node._parameters}
    assert {"rate_hz", "strategy", "layers", "mount_xy_m", "enabled", "max_items"} <= names
    assert "table" not in names
    desc = node.describe_parameter("rate_hz")
    assert desc.description == "tick rate [Hz]"


def test_overrides_are_coerced_and_validated(ros):
    node = ros.add(Node("p2", context=ros.context, parameter_overrides=overrides_from_dict(
        {"rate_hz": 5, "layers": ["object_costmap"], "mount_xy_m": [0.0, 0.0]})))
    b = ParamBinding(node, DemoParams())
    assert b.params.rate_hz == 5.0 and isinstance(b.params.rate_hz, float)
    assert b.params.layers == ("object_costmap",)
    assert b.params.mount_xy_m == (0.0, 0.0)


def test_invalid_initial_override_raises(ros):
    node = ros.add(Node("p3", context=ros.context,
                        parameter_overrides=[Parameter("strategy", value="bogus")]))
    with pytest.raises(ValueError, match="strategy must be paper or nearest, got 'bogus'"):
        ParamBinding(node, DemoParams())


def test_set_rejects_invalid_and_keeps_old_values(ros):
    node = ros.add(Node("p4", context=ros.context))
    b = ParamBinding(node, DemoParams())
    seen = []
    b.on_change(lambda old, new: seen.append((old.rate_hz, new.rate_hz)))
    res = node.set_parameters([Parameter("rate_hz", value=-1.0)])
    assert not res[0].successful and "rate_hz must be > 0, got -1.0" in res[0].reason
    assert b.params.rate_hz == 2.0 and seen == []
    res = node.set_parameters([Parameter("max_items", value="many")])
    assert not res[0].successful and "expects an int" in res[0].reason
    res = node.set_parameters([Parameter("rate_hz", value=4.0)])
    assert res[0].successful and b.params.rate_hz == 4.0 and seen == [(2.0, 4.0)]


def test_foreign_parameters_pass_through(ros):
    node = ros.add(Node("p5", context=ros.context))
    ParamBinding(node, DemoParams())
    res = node.set_parameters([Parameter("use_sim_time", value=True)])
    assert res[0].successful


def test_load_node_params_merges_wildcard(tmp_path):
    f = tmp_path / "p.yaml"
    f.write_text("/**:\n  ros__parameters:\n    use_sim_time: true\n"
                 "target_selector:\n  ros__parameters:\n    strategy: nearest\n    sub:\n      a: 1\n")
    assert load_node_params(f, "target_selector") == {
        "use_sim_time": True, "strategy": "nearest", "sub.a": 1}
    f.write_text("target_selector: {}\n")
    with pytest.raises(ValueError, match="lacks 'ros__parameters'"):
        load_node_params(f, "target_selector")


def test_load_node_params_sees_an_edited_file_and_returns_own_values(tmp_path):
    """The parsed file is cached, but an edit (new size or time) is read again, and a
    caller changing the values it got does not change what the next caller gets."""
    import os

    f = tmp_path / "p.yaml"
    f.write_text("n:\n  ros__parameters:\n    a: [1, 2]\n    b: 1\n")
    got = load_node_params(f, "n")
    got["a"].append(3)
    assert load_node_params(f, "n") == {"a": [1, 2], "b": 1}
    st = f.stat()
    f.write_text("n:\n  ros__parameters:\n    a: [1, 2]\n    b: 2\n")   # same size
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
    assert load_node_params(f, "n")["b"] == 2
    f.write_text("n:\n  ros__parameters:\n    b: 30\n")
    assert load_node_params(f, "n") == {"b": 30}


def test_explorer_puts_its_default_params_file_before_the_callers_overrides():
    """rcl applies parameter arguments in order (the last wins): the default file must
    come first so that a caller's ``-p detector.backend:=oracle`` is not overridden."""
    from explore_seg.explorer import build_args, default_params_file

    pf = default_params_file()
    assert pf is not None
    opts, ros = build_args(["--threads", "2", "--ros-args", "-p", "detector.backend:=oracle"])
    assert ros[:3] == ["--ros-args", "--params-file", str(pf)]
    assert ros.index("--params-file") < ros.index("detector.backend:=oracle")
    assert ros[3:5] == ["--params-file", opts.overrides_file]
    Path(opts.overrides_file).unlink()
    _, ros = build_args([])
    assert ros == ["--ros-args", "--params-file", str(pf)]
    _, ros = build_args(["--ros-args", "--params-file", "mine.yaml"])
    assert ros == ["--ros-args", "--params-file", "mine.yaml"]


def test_explorer_cli_overrides_beat_the_default_files_node_sections():
    """explorer.yaml sets detector.backend, strategy and pose_topic_type in node sections;
    rcl lets those beat a plain ``-p`` (filed under /**): the demo's oracle detector and
    strategy were silently replaced by the file's (onnx YOLO, paper)."""
    import rclpy
    from rclpy.context import Context

    from conftest import DOMAIN_ID
    from explore_seg.explorer import build_args
    from explore_seg.object_costmap_node import ObjectCostmapNode
    from explore_seg.selector_node import TargetSelectorNode

    opts, args = build_args(["--ros-args", "-p", "detector.backend:=oracle", "-p",
                             "strategy:=nearest", "-p", "pose_topic_type:=fused"])
    ctx = Context()
    rclpy.init(args=["explorer"] + args, context=ctx, domain_id=DOMAIN_ID)
    try:
        cm = ObjectCostmapNode(context=ctx)
        sel = TargetSelectorNode(context=ctx)
        assert cm.get_parameter("detector.backend").value == "oracle"
        assert cm.params.pose_topic_type == sel.params.pose_topic_type == "fused"
        assert sel.params.strategy == "nearest"
        cm.destroy_node()
        sel.destroy_node()
    finally:
        rclpy.try_shutdown(context=ctx)
        Path(opts.overrides_file).unlink()


def test_ranges_become_descriptor_ranges_that_rclpy_enforces(ros):
    node = ros.add(Node("p_range", context=ros.context))
    b = ParamBinding(node, DemoParams())
    ir = node.describe_parameter("max_items").integer_range[0]
    assert (ir.from_value, ir.to_value, ir.step) == (1, 10, 0)
    fr = node.describe_parameter("gain").floating_point_range[0]
    assert (fr.from_value, fr.to_value) == (0.0, 1.0)
    assert not node.describe_parameter("rate_hz").floating_point_range
    for name, value in (("max_items", 11), ("gain", 1.5), ("connectivity", 6)):
        res = node.set_parameters([Parameter(name, value=value)])
        assert not res[0].successful, name
    assert (b.params.max_items, b.params.gain, b.params.connectivity) == (5, 0.5, 4)
    res = node.set_parameters([Parameter("connectivity", value=8),
                               Parameter("gain", value=1.0)])
    assert all(r.successful for r in res)
    assert (b.params.connectivity, b.params.gain) == (8, 1.0)


def test_param_meta_rejects_a_malformed_range():
    with pytest.raises(ValueError, match="range must be"):
        param_meta("x", range=(2.0, 1.0))
    with pytest.raises(ValueError, match="range must be"):
        param_meta("x", range=(0.0,))
