"""The headless demo launcher: sim_bridge + explorer processes watched by the monitor."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy")

from conftest import DOMAIN_ID, ROOT  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue  # noqa: E402
from visualization_msgs.msg import Marker, MarkerArray  # noqa: E402

from scripts.demo_lib import DemoConfig, boxes_from_markers, explorer_command, \
    metrics_from_diagnostics, nav_outcomes, sim_command  # noqa: E402

DEMO = ROOT / "scripts" / "demo.py"


def _demo(out: Path, *args: str, timeout_s: float = 120.0) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    # Own domain: the demo's processes must not meet other tests' nodes.
    env["ROS_DOMAIN_ID"] = str((DOMAIN_ID + 50) % 100 + 1)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    return subprocess.run([sys.executable, str(DEMO), str(out), *args],
                          cwd=str(ROOT), env=env, capture_output=True, text=True,
                          timeout=timeout_s)


def test_demo_explores_small_house_through_ros(tmp_path):
    out = tmp_path / "demo"
    proc = _demo(out, "--world", "small_house", "--rtf", "6", "--max-sim-time", "60",
                 "--wall-timeout", "100")
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-3000:]
    assert "[demo] wall" in proc.stdout                      # progress lines
    for name, magic in (("final_map.png", b"\x89PNG"), ("coverage.png", b"\x89PNG"),
                        ("exploration.gif", b"GIF8")):
        data = (out / name).read_bytes()
        assert data[:4] == magic, name
    m = json.loads((out / "metrics.json").read_text())
    assert m["stop_reason"] in ("sim_time_limit", "exploration_done")
    cov = [c for _, c in m["coverage_history"]]
    assert len(cov) >= 2 and cov[-1] > cov[0]
    assert m["goals_sent"] >= 1 and m["path_length_m"] > 0.5
    assert m["sim_time_s"] >= 50.0
    assert isinstance(m["objects"], list) and len(m["objects"]) == m["n_objects"]
    hist = out / "object_history.jsonl"
    for line in (hist.read_text().splitlines() if hist.is_file() else []):
        h = json.loads(line)
        assert 0.0 <= h["t"] <= m["sim_time_s"] + 1.0
        assert all(np.asarray(b).shape == (4, 2) for b in h["boxes"])
    # The node's own frame counts and navigation's goal outcomes reach the metrics.
    assert 0 <= m["object_frames_received_processed"] <= m["object_frames_received"]
    nav = m["nav_outcomes"]
    assert sum(nav["counts"].values()) >= 1 and len(nav["abort_wait_s"]) == nav["counts"]["aborted"]
    for log in ("sim_bridge.log", "explorer.log"):
        # Both stop on SIGINT without a traceback (rclpy's shutdown race included).
        assert "Traceback" not in (out / "logs" / log).read_text(), log


def test_ctrl_c_stops_the_demo_and_its_children(tmp_path):
    import signal
    import time

    out = tmp_path / "int"
    env = dict(os.environ)
    env["ROS_DOMAIN_ID"] = str((DOMAIN_ID + 51) % 100 + 1)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    proc = subprocess.Popen([sys.executable, str(DEMO), str(out), "--world", "small_house",
                             "--rtf", "2", "--max-sim-time", "600"], cwd=str(ROOT), env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        end = time.monotonic() + 60
        while time.monotonic() < end and "[demo] wall" not in proc.stdout.readline():
            pass
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=40)
    finally:
        if proc.poll() is None:
            proc.kill()
    m = json.loads((out / "metrics.json").read_text())
    assert m["stop_reason"] == "interrupted", m.get("error")
    assert m["sim_time_s"] < 590.0
    for log in ("sim_bridge.log", "explorer.log"):
        assert "Traceback" not in (out / "logs" / log).read_text(), log


def test_demo_fails_clearly_when_a_child_dies(tmp_path):
    proc = _demo(tmp_path / "bad", "--world", "small_house", "--no-explorer",
                 "--sim-arg=-p", "--sim-arg=world:=no_such_world", timeout_s=60.0)
    assert proc.returncode == 1
    assert "FAILED: sim_bridge exited" in proc.stderr
    assert (tmp_path / "bad" / "metrics.json").is_file()


def test_metrics_from_diagnostics():
    st = DiagnosticStatus(name="sim_bridge", values=[
        KeyValue(key="coverage_pct", value="12.500"), KeyValue(key="nav_state", value="active"),
        KeyValue(key="collisions", value="2")])
    other = DiagnosticStatus(name="other")
    m = metrics_from_diagnostics(DiagnosticArray(status=[other, st]))
    assert m == {"coverage_pct": 12.5, "nav_state": "active", "collisions": 2.0}
    with pytest.raises(ValueError, match="no 'sim_bridge' status"):
        metrics_from_diagnostics(DiagnosticArray(status=[other]))


def test_nav_outcomes_tells_preempted_from_given_up_goals():
    # (status, end s, a new goal in the same status): 6 = ABORTED, 4 = SUCCEEDED,
    # 5 = CANCELED.
    ends = [(6, 10.0, True),    # replaced by a newer goal: preempted by the explorer
            (6, 20.0, False),   # navigation gave up; the next goal came 30 s later
            (4, 30.0, False), (5, 60.0, True),
            (6, 70.0, False)]   # given up, no goal after it
    out = nav_outcomes(ends, [1.9, 5.0, 11.5, 50.0, 54.0])
    assert out["counts"] == {"succeeded": 1, "canceled": 1, "aborted": 2, "preempted": 1}
    assert out["abort_wait_s"] == [30.0, None]
    assert out["abort_wait_mean_s"] == 30.0 and out["abort_wait_median_s"] == 30.0
    assert nav_outcomes([], [1.0])["abort_wait_mean_s"] is None


def test_boxes_from_markers():
    cube = Marker(ns="objects", type=Marker.CUBE, action=Marker.ADD)
    cube.pose.position.x, cube.pose.position.y = 1.0, 2.0
    cube.pose.orientation.z, cube.pose.orientation.w = math.sin(math.pi / 4), math.cos(math.pi / 4)
    cube.scale.x, cube.scale.y, cube.scale.z = 2.0, 1.0, 0.7
    label = Marker(ns="labels", type=Marker.TEXT_VIEW_FACING, action=Marker.ADD)
    clear = Marker(action=Marker.DELETEALL)
    boxes = boxes_from_markers(MarkerArray(markers=[clear, cube, label]))
    assert len(boxes) == 1
    b = boxes[0]
    assert b.shape == (4, 2)
    assert sorted(b[:, 0].round(6).tolist()) == [0.5, 0.5, 1.5, 1.5]   # turned 90 degrees
    assert sorted(b[:, 1].round(6).tolist()) == [1.0, 1.0, 3.0, 3.0]


@pytest.mark.parametrize("strategy, without, params", [
    ("paper", [], ["strategy:=paper", "use_regions:=true", "frontier.use_object_costmap:=true"]),
    ("paper_noobj", ["object_costmap"], ["use_regions:=true", "frontier.use_object_costmap:=false"]),
    ("nearest", ["object_costmap", "segmentation"], ["strategy:=nearest", "use_regions:=false"]),
    ("explore_lite", ["object_costmap", "segmentation"], ["strategy:=explore_lite"]),
])
def test_explorer_command_maps_the_strategy(strategy, without, params):
    cmd = explorer_command(DemoConfig(out_dir="x", strategy=strategy))
    ros = cmd.index("--ros-args")
    assert [cmd[i + 1] for i in range(ros) if cmd[i] == "--without"] == without
    assert "use_sim_time:=true" in cmd[ros:]
    for p in params:
        assert p in cmd[ros:], p


def test_sim_command_scales_the_camera():
    cmd = sim_command(DemoConfig(out_dir="/tmp/o", world="maze", strategy="nearest",
                                 camera_scale=0.5))
    args = dict(a.split(":=", 1) for a in cmd if ":=" in a)
    assert args["world"] == "maze" and args["enable_camera"] == "false"
    assert args["camera_width_px"] == "320" and args["camera_height_px"] == "240"
    assert float(args["camera_fx_px"]) == pytest.approx(262.5)
    assert args["output_dir"] == "/tmp/o/sim"


@pytest.mark.parametrize("real_robot", [True, False])
def test_demo_runs_the_real_robot_pose_contract_by_default(real_robot):
    cfg = DemoConfig(out_dir="x", real_robot_pose=real_robot)
    sim = dict(a.split(":=", 1) for a in sim_command(cfg) if ":=" in a)
    expl = dict(a.split(":=", 1) for a in explorer_command(cfg) if ":=" in a)
    if real_robot:
        assert sim["odom_frame"] == "odom" and sim["slam_pose"] == "true"
        assert float(sim["odom_drift_scale"]) > 0 and float(sim["slam_min_travel_m"]) > 0
        assert expl["pose_topic_type"] == "fused"
    else:
        assert "odom_frame" not in sim and "slam_pose" not in sim
        assert expl["pose_topic_type"] == "odom"
    assert DemoConfig(out_dir="x").real_robot_pose


@pytest.mark.parametrize("field, value, match", [
    ("strategy", "greedy", "strategy must be one of"),
    ("real_time_factor", 0.0, "real_time_factor must be finite and > 0"),
    ("camera_scale", 1.5, "camera_scale must be <= 1"),
    ("gif_max_frames", 1, "gif_max_frames must be >= 2"),
])
def test_demo_config_validation(field, value, match):
    with pytest.raises(ValueError, match=match):
        DemoConfig(out_dir="x", **{field: value})
