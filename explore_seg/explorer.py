"""``explorer``: the whole exploration pipeline in one process.

Runs the DuDe segmentation, object costmap and target selector nodes in one executor (the
target selector detects frontiers itself and publishes them, so the standalone
``frontier_detector`` is not run here: one detection per map), single-threaded by default:
rclpy's MultiThreadedExecutor busy-waits while a callback of a mutually exclusive group runs
(its entity stays ready), and that loop, holding the GIL, starves the object costmap in this
process (docs/experiments.md#explorer-single-threaded-executor). Each node
reads its parameters from ``config/explorer.yaml`` (installed to
``share/explore_seg/config``) unless ``--ros-args --params-file FILE`` is given; a caller's
``-p name:=value`` then overrides that file for every node (rcl lets a file's node section
beat a ``-p``, which applies to ``/**``: the overrides are also written to a file of node
sections that follows the default one). Each node is also runnable alone
(``frontier_detector``, ``segmentation``, ``target_selector``, ``object_costmap``).

Usage::

    explorer [--without object_costmap] [--without segmentation] [--threads N] [--ros-args ...]
"""

from __future__ import annotations

import argparse
import copy
import importlib
import os
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from explore_seg.node_util import config_file, run


@dataclass(frozen=True)
class Component:
    """One node of the pipeline: its default name, module and class."""

    name: str
    module: str
    cls: str


COMPONENTS: tuple[Component, ...] = (
    Component("segmentation", "explore_seg.segmentation_node", "SegmentationNode"),
    Component("object_costmap", "explore_seg.object_costmap_node", "ObjectCostmapNode"),
    Component("target_selector", "explore_seg.selector_node", "TargetSelectorNode"),
)


def default_params_file() -> Path | None:
    """config/explorer.yaml from the installed share folder, else from the source tree."""
    return config_file("explorer.yaml")


def node_classes(without: set[str]) -> list[type]:
    """The node classes to run, in pipeline order, minus the ones named in ``without``."""
    unknown = without - {c.name for c in COMPONENTS}
    if unknown:
        raise ValueError(f"unknown component(s) {sorted(unknown)}; "
                         f"known: {[c.name for c in COMPONENTS]}")
    return [getattr(importlib.import_module(c.module), c.cls)
            for c in COMPONENTS if c.name not in without]


def build_args(argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """Split our options from ROS arguments; add the default params file if none is given."""
    if "--ros-args" in argv:
        i = argv.index("--ros-args")
        ours, ros = argv[:i], argv[i:]
    else:
        ours, ros = argv, []
    ap = argparse.ArgumentParser(prog="explorer", description=__doc__.split("\n\n")[0])
    ap.add_argument("--without", action="append", default=[],
                    help="leave out a component (object_costmap, segmentation)")
    ap.add_argument("--threads", type=int, default=1,
                    help="executor threads (1 = single-threaded, the default; more use "
                         "rclpy's MultiThreadedExecutor, see the module docstring)")
    opts = ap.parse_args(ours)
    opts.overrides_file = None
    if "--params-file" not in ros:
        pf = default_params_file()
        if pf is not None:
            # First, and the caller's -p overrides again as node sections after it: a node
            # section of a file beats a -p (which rcl files under /**).
            ros = ["--ros-args", "--params-file", str(pf)] + ros[1:]
            overrides = cli_overrides(ros)
            if overrides:
                opts.overrides_file = write_overrides(overrides)
                ros[3:3] = ["--params-file", opts.overrides_file]
    return opts, ros


def cli_overrides(ros: list[str]) -> dict[str, Any]:
    """``name -> value`` of the ``-p`` / ``--param`` arguments (values parsed as YAML, as rcl
    does)."""
    out: dict[str, Any] = {}
    for flag, arg in zip(ros, ros[1:]):
        if flag in ("-p", "--param") and ":=" in arg:
            name, value = arg.split(":=", 1)
            out[name] = yaml.safe_load(value) if value else ""
    return out


def write_overrides(overrides: dict[str, Any]) -> str:
    """A params file with ``overrides`` in the section of every explorer node; its path."""
    nested: dict[str, Any] = {}
    for name, value in overrides.items():
        *heads, last = name.split(".")
        d = nested
        for h in heads:
            d = d.setdefault(h, {})
        d[last] = value
    # a copy per section: rcl's parser rejects YAML aliases
    doc = {c.name: {"ros__parameters": copy.deepcopy(nested)} for c in COMPONENTS}
    fd, path = tempfile.mkstemp(prefix="explorer_overrides_", suffix=".yaml")
    with os.fdopen(fd, "w") as f:
        yaml.safe_dump(doc, f)
    return path


def main(args: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if args is None else args)
    opts, ros = build_args(argv)
    try:
        classes = node_classes(set(opts.without))
        return run(classes, args=[sys.argv[0]] + ros, num_threads=max(1, opts.threads))
    finally:
        if opts.overrides_file:
            Path(opts.overrides_file).unlink(missing_ok=True)


if __name__ == "__main__":
    sys.exit(main())
