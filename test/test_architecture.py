"""Imports flow one way: nodes -> convert -> core; sim_bridge -> core; core imports no ROS."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ROS_MODULES = ("rclpy", "rcl_interfaces", "builtin_interfaces", "std_msgs", "std_srvs",
               "geometry_msgs", "nav_msgs", "sensor_msgs", "visualization_msgs",
               "diagnostic_msgs", "rosgraph_msgs", "ament_index_python")


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    mods: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            mods.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            mods.add(node.module)
    return mods


def _files(sub: str) -> list[Path]:
    return sorted((ROOT / sub).rglob("*.py"))


@pytest.mark.parametrize("path", _files("explore_seg/core"), ids=lambda p: p.name)
def test_core_imports_no_ros_and_nothing_outside_core(path):
    for mod in _imports(path):
        top = mod.split(".")[0]
        assert top not in ROS_MODULES, f"{path.name} imports {mod}"
        assert top != "sim_bridge", f"{path.name} imports the simulator ({mod})"
        if top == "explore_seg":
            assert mod.startswith("explore_seg.core"), f"{path.name} imports {mod}"


@pytest.mark.parametrize("path", [p for p in _files("sim_bridge") if p.name != "node.py"],
                         ids=lambda p: p.name)
def test_sim_engine_is_ros_free(path):
    for mod in _imports(path):
        assert mod.split(".")[0] not in ROS_MODULES, f"{path.name} imports {mod}"


@pytest.mark.parametrize("path", _files("explore_seg"), ids=lambda p: p.name)
def test_package_never_imports_the_simulator(path):
    for mod in _imports(path):
        assert mod.split(".")[0] != "sim_bridge", f"{path} imports {mod}"


def test_only_convert_builds_arrays_from_message_buffers():
    offenders = []
    for path in _files("explore_seg") + _files("sim_bridge"):
        if path.name == "convert.py":
            continue
        text = path.read_text()
        if "np.frombuffer(msg" in text or "frombuffer(msg.data" in text:
            offenders.append(str(path.relative_to(ROOT)))
    assert offenders == []
