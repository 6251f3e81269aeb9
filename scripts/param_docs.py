"""Parameter files and the parameter reference generated from the parameter dataclasses.

Defaults live only in the dataclasses of the core. This module renders them into
``config/explorer.yaml`` / ``config/sim_bridge.yaml`` (the default parameter files) and into
``docs/parameters.md`` (one table per node: name, type, default, range, meaning);
``test/test_param_docs.py`` fails when any of them is stale.

Usage::

    python scripts/param_docs.py --check   # exit 1 when a file is out of date
    python scripts/param_docs.py --write   # regenerate them
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from explore_seg.params import field_doc, ros_fields  # noqa: E402

#: node name (or ``/**``: every node) -> [(parameter prefix, "module:DataclassName")], in
#: the order they are bound.
_LIMITS = ("input.", "explore_seg.core.limits:InputLimits")
_POSE_FUSION = ("pose_fusion.", "explore_seg.core.pose_fusion:PoseFusionParams")
NODE_PARAMS: dict[str, list[tuple[str, str]]] = {
    "/**": [("frontier.", "explore_seg.core.frontiers:FrontierParams")],
    "frontier_detector": [("", "explore_seg.core.frontiers:FrontierNodeParams"), _LIMITS],
    "segmentation": [("", "explore_seg.core.segmentation:SegmentationNodeParams"), _LIMITS],
    "object_costmap": [("", "explore_seg.core.objects:ObjectCostmapNodeParams"),
                       ("detector.", "explore_seg.core.detector:DetectorParams"), _LIMITS,
                       _POSE_FUSION],
    "target_selector": [("", "explore_seg.core.selection:SelectorNodeParams"),
                        ("rrt.", "explore_seg.core.rrt:RrtParams"),
                        ("scan_overlay.", "explore_seg.core.scan_overlay:ScanOverlayParams"),
                        _LIMITS, _POSE_FUSION],
    "sim_bridge": [("", "sim_bridge.engine:SimParams")],
}
#: docs/parameters.md heading of a NODE_PARAMS key that is not a node.
SECTION_TITLES = {"/**": "`frontier.*`: frontier detection, shared by `target_selector` and "
                         "`frontier_detector` (the `/**` section of config/explorer.yaml)"}

#: ``/**`` sections: the nodes that bind them (besides their own parameters).
SHARED_BY: dict[str, tuple[str, ...]] = {"/**": ("frontier_detector", "target_selector")}

#: generated parameter file -> the nodes it configures
PARAM_FILES: dict[str, list[str]] = {
    "config/explorer.yaml": ["/**", "frontier_detector", "segmentation", "object_costmap",
                             "target_selector"],
    "config/sim_bridge.yaml": ["sim_bridge"],
}

#: The generated parameter reference (written whole; never edit it by hand).
PARAMS_DOC = "docs/parameters.md"


def load_class(spec: str) -> type:
    """Import ``module:Name``."""
    mod, name = spec.split(":")
    return getattr(importlib.import_module(mod), name)


def node_fields(node: str) -> list[tuple[str, str, Any, str, str]]:
    """(full name, kind, default, doc, range) of every ROS parameter of ``node``."""
    out = []
    for prefix, spec in NODE_PARAMS[node]:
        cls = load_class(spec)
        defaults = cls()
        for f, kind in ros_fields(cls):
            out.append((prefix + f.name, kind, getattr(defaults, f.name), field_doc(f),
                        _range_text(f.metadata.get("range"))))
    return out


def declared_fields(node: str) -> list[tuple[str, str, Any, str, str]]:
    """:func:`node_fields` of ``node`` plus those of the shared sections it binds."""
    shared = [f for sec, nodes in SHARED_BY.items() if node in nodes for f in node_fields(sec)]
    return shared + node_fields(node)


def _range_text(rng: Any) -> str:
    """``[lo, hi]`` (``step k``) of a field's metadata range; empty without one."""
    if rng is None:
        return ""
    ends = ["∞" if abs(float(v)) == float("inf") else
            ("max" if isinstance(v, int) and v >= 2 ** 31 - 1 else f"{v:g}") for v in rng[:2]]
    text = f"[{ends[0]}, {ends[1]}]"
    if len(rng) > 2 and rng[2]:
        text += f" step {rng[2]:g}"
    return text


def _yaml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_yaml_value(x) for x in v) + "]"
    if isinstance(v, float):
        r = repr(v)
        return r if ("." in r or "e" in r or "inf" in r or "nan" in r) else r + ".0"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    return str(v)


def render_param_file(nodes: list[str]) -> str:
    """A ROS 2 parameter YAML holding every parameter of ``nodes`` at its default."""
    lines = ["# Generated from the parameter dataclasses by `python scripts/param_docs.py --write`.",
             "# Defaults live in the code; copy this file and change values to configure a robot",
             "# (see config/turtlebot3.yaml). use_sim_time is left to the launcher.", ""]
    for node in nodes:
        lines += [f"{node}:", "  ros__parameters:"]
        groups: dict[str, list[tuple[str, Any, str]]] = {}
        for name, _kind, default, doc, _range in node_fields(node):
            head, _, leaf = name.rpartition(".")
            groups.setdefault(head, []).append((leaf, default, doc))
        for head, items in groups.items():
            indent = "    "
            if head:
                lines.append(f"    {head}:")
                indent = "      "
            for leaf, default, doc in items:
                if doc:
                    lines.append(f"{indent}# {doc}")
                lines.append(f"{indent}{leaf}: {_yaml_value(default)}")
        lines.append("")
    return "\n".join(lines)


def _md_value(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return "`[" + ", ".join(str(x) for x in v) + "]`"
    if isinstance(v, bool):
        return f"`{str(v).lower()}`"
    if isinstance(v, str):
        return f'`"{v}"`' if v else '`""`'
    return f"`{v}`"


def render_params_doc() -> str:
    """docs/parameters.md: a short preamble and one Markdown table per node."""
    out = ["# Parameters",
           "",
           "<!-- Generated by `python scripts/param_docs.py --write` from the parameter "
           "dataclasses; do not edit. -->",
           "",
           "Generated from the parameter dataclasses (defaults live only in the code) by",
           "`python scripts/param_docs.py --write`; `test/test_param_docs.py` fails when this",
           "page, `config/explorer.yaml` or `config/sim_bridge.yaml` is stale. Every parameter",
           "is declared with its range and validated by its dataclass: `ros2 param set` of a",
           "value outside it is refused with the reason, and such a value in a parameter file",
           "stops the node at start-up. Profiles for a robot set only what differs (see",
           "`config/turtlebot3.yaml`, `config/turtlebot3_no_camera.yaml` and",
           "[real_robot.md](real_robot.md)); the topics are in [ros_api.md](ros_api.md).",
           ""]
    for node in NODE_PARAMS:
        title = SECTION_TITLES.get(node, f"`{node}` parameters")
        out += [f"## {title}", "",
                "| name | type | default | range | meaning |", "|---|---|---|---|---|"]
        for name, kind, default, doc, rng in node_fields(node):
            doc = doc.replace("|", "\\|").replace("\n", " ")
            out.append(f"| `{name}` | {kind} | {_md_value(default)} | {rng} | {doc} |")
        out.append("")
    return "\n".join(out)


def expected_files() -> dict[Path, str]:
    """Every generated file and the text it should hold."""
    out = {ROOT / rel: render_param_file(nodes) for rel, nodes in PARAM_FILES.items()}
    out[ROOT / PARAMS_DOC] = render_params_doc()
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--check", action="store_true")
    g.add_argument("--write", action="store_true")
    a = ap.parse_args(argv)
    stale = []
    for path, text in expected_files().items():
        current = path.read_text() if path.exists() else None
        if current != text:
            stale.append(path)
            if a.write:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(text)
    for p in stale:
        print(("wrote " if a.write else "stale: ") + str(p.relative_to(ROOT)))
    return 1 if (stale and a.check) else 0


if __name__ == "__main__":
    sys.exit(main())
