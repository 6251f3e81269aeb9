"""``make demo LIVE=1``: scripts/run_demo.sh's live mode (argument handling, through its
DEMO_DRY_RUN), and config/explore_seg.rviz against what the demo's processes publish.

RViz itself is never started: the rviz config's displays are matched against the
publishers of the nodes the demo runs (sim_bridge and the explorer's nodes, built with the
demo's own parameters), by topic, message type and QoS.
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "run_demo.sh"
RVIZ = ROOT / "config" / "explore_seg.rviz"


def _run(env_extra: dict[str, str], *args: str,
         unset: tuple[str, ...] = ()) -> subprocess.CompletedProcess:
    """scripts/run_demo.sh as a dry run, with ``env_extra`` set and ``unset`` removed."""
    drop = {"LIVE", "DEMO_RTF", "DEMO_MAX_SIM_TIME", "DEMO_WORLD", *unset}
    env = {k: v for k, v in os.environ.items() if k not in drop}
    env.update({"DEMO_DRY_RUN": "1", **env_extra})
    return subprocess.run(["bash", str(SCRIPT), "/tmp/explore_seg_live_test", *args],
                          env=env, capture_output=True, text=True, timeout=30)


def _would_run(out: str) -> list[str]:
    line = next(ln for ln in out.splitlines() if ln.startswith("[demo] would run:"))
    return line.split(":", 1)[1].split()


def _opt(cmd: list[str], name: str) -> str | None:
    """The value of the last ``name`` option (argparse keeps the last)."""
    vals = [cmd[i + 1] for i, a in enumerate(cmd[:-1]) if a == name]
    return vals[-1] if vals else None


def test_live_runs_at_real_time_on_a_printed_domain_without_a_namespace():
    r = _run({"LIVE": "1", "ROS_DOMAIN_ID": "57"})
    assert r.returncode == 0, r.stdout + r.stderr
    cmd = _would_run(r.stdout)
    assert _opt(cmd, "--rtf") == "1"
    assert _opt(cmd, "--wall-timeout") == "1800"    # 1500 s of sim time at 1x, plus 300 s
    assert "ROS_DOMAIN_ID=57" in r.stdout and "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST" in r.stdout
    assert "unshare" not in r.stdout and "namespace (unshare" not in r.stdout
    rviz = next(ln for ln in r.stdout.splitlines() if "rviz2 -d" in ln).split()
    assert rviz[:2] == ["ROS_DOMAIN_ID=57", "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST"]
    assert Path(rviz[rviz.index("-d") + 1]) == RVIZ
    assert "use_sim_time:=true" in rviz


def test_live_picks_and_prints_a_domain_when_none_is_set():
    r = _run({"LIVE": "1"}, unset=("ROS_DOMAIN_ID",))
    assert r.returncode == 0, r.stderr
    ids = set(re.findall(r"ROS_DOMAIN_ID=(\d+)", r.stdout))
    assert len(ids) == 1 and 0 <= int(ids.pop()) <= 101, r.stdout


@pytest.mark.parametrize("env,rtf,wall", [
    ({"LIVE": "1", "DEMO_RTF": "2"}, "2", "1050"),
    ({"LIVE": "1", "DEMO_RTF": "0.5", "DEMO_MAX_SIM_TIME": "100"}, "0.5", "500"),
    ({}, "4", None),                    # headless: 4x, the monitor's own wall limit
    ({"LIVE": "0"}, "4", None),
])
def test_real_time_factor_and_wall_limit(env, rtf, wall):
    r = _run(env)
    assert r.returncode == 0, r.stdout + r.stderr
    cmd = _would_run(r.stdout)
    assert _opt(cmd, "--rtf") == rtf and _opt(cmd, "--wall-timeout") == wall
    assert ("rviz2" in r.stdout) == (env.get("LIVE") == "1")


def test_extra_options_reach_the_demo_after_the_defaults():
    r = _run({"LIVE": "1"}, "--strategy", "nearest", "--rtf", "3")
    cmd = _would_run(r.stdout)
    assert _opt(cmd, "--strategy") == "nearest" and _opt(cmd, "--rtf") == "3"


@pytest.mark.parametrize("env,what", [
    ({"LIVE": "yes"}, "LIVE must be 0 or 1"),
    ({"LIVE": "1", "DEMO_RTF": "0"}, "must be numbers > 0"),
    ({"DEMO_RTF": "fast"}, "must be numbers > 0"),
    ({"LIVE": "1", "DEMO_MAX_SIM_TIME": "-5"}, "must be numbers > 0"),
])
def test_bad_settings_are_refused(env, what):
    r = _run(env)
    assert r.returncode == 2 and what in r.stderr, r.stdout + r.stderr


def test_make_passes_live_to_the_script():
    r = subprocess.run(["make", "-n", "demo", "LIVE=1", "OUT=/tmp/x"], cwd=ROOT,
                       capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stderr
    assert "LIVE=1 bash scripts/run_demo.sh /tmp/x" in r.stdout


# --- config/explore_seg.rviz against the demo's publishers -------------------------------

#: rviz_default_plugins display class -> the message type it subscribes to.
RVIZ_TYPES = {
    "Map": "nav_msgs/msg/OccupancyGrid", "PointCloud2": "sensor_msgs/msg/PointCloud2",
    "MarkerArray": "visualization_msgs/msg/MarkerArray", "Pose": "geometry_msgs/msg/PoseStamped",
    "PoseWithCovariance": "geometry_msgs/msg/PoseWithCovarianceStamped",
    "Odometry": "nav_msgs/msg/Odometry", "Path": "nav_msgs/msg/Path",
    "LaserScan": "sensor_msgs/msg/LaserScan",
}


def _rviz_displays() -> list[dict]:
    data = yaml.safe_load(RVIZ.read_text())
    out = []
    for d in data["Visualization Manager"]["Displays"]:
        if "Topic" in d:
            out.append({"class": d["Class"].split("/")[-1], "topic": d["Topic"]["Value"],
                        "durability": d["Topic"].get("Durability Policy", "Volatile"),
                        "reliability": d["Topic"].get("Reliability Policy", "Reliable")})
    return out


def test_rviz_config_shows_only_what_the_demo_publishes(ros, tmp_path):
    from rclpy.qos import DurabilityPolicy, ReliabilityPolicy

    from explore_seg.explorer import COMPONENTS, cli_overrides, node_classes
    from explore_seg.params import overrides_from_dict
    from scripts.demo_lib import DemoConfig, explorer_command, sim_command
    from sim_bridge.node import SimBridgeNode

    cfg = DemoConfig(out_dir=str(tmp_path))
    sim = ros.add(SimBridgeNode(context=ros.context,
                                parameter_overrides=overrides_from_dict(
                                    cli_overrides(sim_command(cfg)))))
    ecmd = explorer_command(cfg)
    assert "--without" not in ecmd, "the demo's default strategy runs every explorer node"
    eparams = cli_overrides(ecmd)
    nodes = [sim] + [ros.add(cls(context=ros.context,
                                 parameter_overrides=overrides_from_dict(eparams)))
                     for cls in node_classes(set())]
    assert len(nodes) == 1 + len(COMPONENTS)
    published: dict[str, list] = {}
    for n in nodes:
        for pub in n.publishers:
            published.setdefault(pub.topic_name, []).append(pub)

    displays = _rviz_displays()
    assert displays, "no display with a topic in the rviz config"
    for d in displays:
        pubs = published.get(d["topic"])
        assert pubs, f"rviz shows {d['topic']}, which no demo process publishes"
        want = RVIZ_TYPES[d["class"]]
        for pub in pubs:
            mt = pub.msg_type
            got = f"{mt.__module__.split('.')[0]}/msg/{mt.__name__}"
            assert got == want, f"{d['topic']}: rviz {d['class']} takes {want}, published {got}"
            q = pub.qos_profile
            if d["reliability"] == "Reliable":
                assert q.reliability == ReliabilityPolicy.RELIABLE, (
                    f"{d['topic']}: rviz subscribes reliable, the publisher is best effort")
            if d["durability"] == "Transient Local":
                assert q.durability == DurabilityPolicy.TRANSIENT_LOCAL, (
                    f"{d['topic']}: rviz subscribes transient local, the publisher is volatile")
