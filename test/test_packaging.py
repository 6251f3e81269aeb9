"""colcon build of the package, then an installed executable starts, logs and exits on SIGINT.

Also checks that package.xml declares every ROS package the code imports.
"""

from __future__ import annotations

import ast
import os
import shutil
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
VENV_BIN = Path(sys.executable).parent


ROS_PKGS = {"rclpy", "rcl_interfaces", "builtin_interfaces", "std_msgs", "std_srvs",
            "geometry_msgs", "nav_msgs", "sensor_msgs", "visualization_msgs",
            "diagnostic_msgs", "rosgraph_msgs", "ament_index_python", "action_msgs"}
#: rosdep key -> the module it provides, for the Python libraries the project uses.
PY_KEYS = {"python3-numpy": "numpy", "python3-scipy": "scipy", "python3-opencv": "cv2",
           "python3-yaml": "yaml", "python3-pil": "PIL", "python3-torch": "torch",
           "python3-shapely": "shapely", "python3-sklearn": "sklearn",
           "python3-matplotlib": "matplotlib", "python3-pytest": "pytest"}
#: Modules without a rosdep key (pip, see package.xml's comments); google = protobuf (onnx).
PIP_ONLY = {"onnx", "onnxruntime", "google", "open3d"}
#: What the run time is: the installed packages (setup.py's find_packages).
RUN_TIME = ("explore_seg", "sim_bridge")


def _imports(*dirs: str) -> set[str]:
    """Top-level names of every absolute import (module level or in a function) under
    ``dirs``."""
    found = set()
    for d in dirs:
        for path in (ROOT / d).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                names = []
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                    names = [node.module]
                found.update(n.split(".")[0] for n in names)
    return found


def _ros_imports() -> set[str]:
    return _imports(*RUN_TIME) & ROS_PKGS


def _depends(*tags: str) -> set[str]:
    return {e.text for e in ET.parse(ROOT / "package.xml").getroot() if e.tag in tags}


def test_package_xml_declares_every_imported_ros_package():
    tree = ET.parse(ROOT / "package.xml")
    assert tree.getroot().get("format") == "3"
    deps = {e.text for e in tree.getroot() if e.tag in ("exec_depend", "depend")}
    missing = _ros_imports() - deps
    assert not missing, f"package.xml lacks exec_depend on {sorted(missing)}"
    assert tree.find("export/build_type").text == "ament_python"


def test_exec_depend_lists_exactly_the_python_libraries_imported_at_run_time():
    """A library only tests or bench/ import is a test_depend, not a run-time dependency."""
    third_party = _imports(*RUN_TIME) - set(sys.stdlib_module_names) - ROS_PKGS \
        - set(RUN_TIME)
    unknown = third_party - set(PY_KEYS.values()) - PIP_ONLY
    assert not unknown, f"run-time imports without a rosdep key or pip note: {sorted(unknown)}"
    wanted = {key for key, mod in PY_KEYS.items() if mod in third_party}
    declared = {d for d in _depends("exec_depend", "depend") if d in PY_KEYS}
    assert declared == wanted, (f"exec_depend lacks {sorted(wanted - declared)}, "
                                f"lists unimported {sorted(declared - wanted)}")


def test_test_depend_covers_the_libraries_only_tests_and_bench_import():
    rest = _imports("test", "bench", "scripts") - _imports(*RUN_TIME)
    wanted = {key for key, mod in PY_KEYS.items() if mod in rest}
    missing = wanted - _depends("test_depend", "depend", "exec_depend")
    assert not missing, f"package.xml lacks test_depend on {sorted(missing)}"


@pytest.mark.skipif(shutil.which("colcon", path=str(VENV_BIN)) is None, reason="colcon not installed")
def test_colcon_build_and_installed_executable_exits_cleanly_on_sigint(tmp_path):
    env = dict(os.environ)
    env.pop("_ROS_WHEELS_BOOTSTRAP_COMPLETE", None)
    env["PATH"] = f"{VENV_BIN}:{env.get('PATH', '')}"
    build = subprocess.run(
        [str(VENV_BIN / "colcon"), "build", "--base-paths", str(ROOT),
         "--build-base", str(tmp_path / "build"), "--install-base", str(tmp_path / "install")],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=240)
    assert build.returncode == 0, build.stdout + build.stderr
    exe = tmp_path / "install" / "explore_seg" / "lib" / "explore_seg" / "explorer"
    assert exe.exists(), sorted(p.name for p in exe.parent.iterdir())
    # the worlds, subfolders included, are installed, and the installed loader finds them
    share = tmp_path / "install" / "explore_seg" / "share" / "explore_seg" / "worlds"
    shipped = sorted(str(p.relative_to(ROOT / "worlds")) for p in (ROOT / "worlds").rglob("*")
                     if p.is_file())
    assert sorted(str(p.relative_to(share)) for p in share.rglob("*") if p.is_file()) == shipped
    found = subprocess.run(
        ["sh", "-c", f". {tmp_path / 'install' / 'setup.sh'} && exec {sys.executable} -c "
         "'from sim_bridge.worlds import world_file; print(world_file(\"eb/room\"))'"],
        cwd=tmp_path, env={k: v for k, v in env.items() if k != "PYTHONPATH"},
        capture_output=True, text=True, timeout=60)
    assert found.stdout.strip() == str(share / "explore_bench" / "room.yaml"), (
        found.stdout + found.stderr)
    proc = subprocess.Popen(
        ["sh", "-c", f". {tmp_path / 'install' / 'setup.sh'} && exec {exe}"],
        cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        start_new_session=True)
    lines = []
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
            if "running" in line:
                break
        assert any("running" in ln for ln in lines), "".join(lines)
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(timeout=20)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    out = "".join(lines) + (proc.stdout.read() or "")
    assert rc == 0, out
    assert "Traceback" not in out, out
