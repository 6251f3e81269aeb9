"""sim_bridge node over real topics: clock, sensors, map, goals, bad input."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from rclpy.parameter import Parameter

from explore_seg import convert
from explore_seg.qos import MAP_QOS, RELIABLE_QOS, SENSOR_QOS


@pytest.fixture
def sim(ros, tmp_path):
    from sim_bridge.node import SimBridgeNode

    node = SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"),
        Parameter("real_time_factor", value=10.0),
        Parameter("map_update_interval_s", value=0.5),
        Parameter("output_dir", value=str(tmp_path)),
    ])
    return ros.add(node)


class Inbox:
    """Latest message and count per topic of a helper node."""

    def __init__(self, ros) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from nav_msgs.msg import OccupancyGrid, Odometry
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import LaserScan

        self.node = ros.node("sim_test_probe")
        self.last: dict[str, object] = {}
        self.count: dict[str, int] = {}
        for topic, typ, qos in (("/clock", Clock, RELIABLE_QOS), ("scan", LaserScan, SENSOR_QOS),
                                ("odom", Odometry, RELIABLE_QOS), ("map", OccupancyGrid, MAP_QOS),
                                ("sim/metrics", DiagnosticArray, RELIABLE_QOS)):
            self.node.create_subscription(typ, topic, self._cb(topic), qos)

    def _cb(self, topic: str):
        def cb(msg) -> None:
            self.last[topic] = msg
            self.count[topic] = self.count.get(topic, 0) + 1
        return cb

    def has(self, *topics: str) -> bool:
        return all(t in self.last for t in topics)

    def clock_s(self) -> float:
        return convert.stamp_to_ns(self.last["/clock"].clock) / 1e9

    def odom_xy(self) -> tuple[float, float]:
        x, y, _ = convert.pose2d_from_odometry(self.last["odom"])
        return x, y

    def metric(self, key: str) -> str:
        values = self.last["sim/metrics"].status[0].values
        return {kv.key: kv.value for kv in values}[key]


def test_node_publishes_clock_scan_odom_map(ros, sim):
    inbox = Inbox(ros)
    ros.spin_until(lambda: inbox.has("/clock", "scan", "odom", "map", "sim/metrics")
                   and (convert.grid_from_msg(inbox.last["map"]).data >= 65).any(),
                   what="/clock, scan, odom, sim/metrics and a map with the first scan")
    scan = inbox.last["scan"]
    assert scan.header.frame_id == "base_scan"
    assert len(scan.ranges) == sim.engine.scan_geometry.num_beams
    assert scan.angle_min == pytest.approx(-math.pi)
    odom = inbox.last["odom"]
    assert (odom.header.frame_id, odom.child_frame_id) == ("map", "base_footprint")
    assert convert.pose2d_from_odometry(odom)[:2] == pytest.approx(
        sim.engine.world.start_pose[:2], abs=1e-6)
    grid = convert.grid_from_msg(inbox.last["map"])
    assert grid.frame_id == "map" and (grid.data >= 65).any() and (grid.data == 0).any()
    t0 = inbox.clock_s()
    ros.spin_until(lambda: inbox.clock_s() > t0 + 1.0, what="sim time to advance 1 s")
    # Stamps are sim time.
    assert convert.stamp_to_ns(inbox.last["odom"].header.stamp) / 1e9 <= inbox.clock_s() + 1e-9


def _free_point_ahead(engine, dist_m: float) -> tuple[float, float]:
    """An explorable point about dist_m from the start with 0.5 m clearance."""
    import cv2

    gt = engine.ground_truth
    free = (gt.inside & (gt.footprint_tall.data < 65)).astype(np.uint8)
    clear = cv2.distanceTransform(free, cv2.DIST_L2, 5) * gt.resolution_m >= 0.5
    rows, cols = np.nonzero(clear)
    xs, ys = gt.lidar.cells_to_world(rows, cols)
    sx, sy, _ = engine.world.start_pose
    i = int(np.argmin(np.abs(np.hypot(xs - sx, ys - sy) - dist_m)))
    return float(xs[i]), float(ys[i])


def test_goal_pose_from_a_publisher_moves_the_robot_towards_it(ros, sim):
    from geometry_msgs.msg import PoseStamped

    inbox = Inbox(ros)
    pub = inbox.node.create_publisher(PoseStamped, "goal_pose", RELIABLE_QOS)
    ros.spin_until(lambda: inbox.has("odom", "map") and pub.get_subscription_count() > 0,
                   what="odom, map and the goal_pose subscriber")
    gx, gy = _free_point_ahead(sim.engine, 1.5)
    d0 = math.hypot(gx - inbox.odom_xy()[0], gy - inbox.odom_xy()[1])
    pub.publish(convert.pose_stamped(gx, gy, 0.0, "map"))
    ros.spin_until(lambda: math.hypot(gx - inbox.odom_xy()[0], gy - inbox.odom_xy()[1])
                   < d0 - 0.8, timeout_s=20.0, what="odom to approach the goal by 0.8 m")
    assert sim.engine.metrics.goals_received == 1
    assert sim.engine.metrics.n_collisions == 0


def test_sim_time_runs_at_the_startup_factor_until_the_first_goal(ros, sim):
    """Before any goal_pose the clock advances at startup_real_time_factor (1): sim time
    never runs ahead of wall time while the explorer starts; after one, at 10x."""
    from geometry_msgs.msg import PoseStamped

    p = sim._p.params
    assert p.startup_real_time_factor == 1.0 and p.real_time_factor == 10.0
    inbox = Inbox(ros)
    pub = inbox.node.create_publisher(PoseStamped, "goal_pose", RELIABLE_QOS)
    ros.spin_until(lambda: inbox.has("/clock", "odom") and pub.get_subscription_count() > 0,
                   what="/clock, odom and the goal_pose subscriber")
    t0, w0 = inbox.clock_s(), time.monotonic()
    ros.spin_until(lambda: time.monotonic() - w0 > 1.0, what="1 s of wall time")
    assert inbox.clock_s() - t0 <= (time.monotonic() - w0) + 0.1
    sx, sy, _ = sim.engine.world.start_pose
    pub.publish(convert.pose_stamped(sx, sy, 0.0, "map"))
    ros.spin_until(lambda: sim.engine.metrics.goals_received == 1, what="the goal")
    t1, w1 = inbox.clock_s(), time.monotonic()
    ros.spin_until(lambda: time.monotonic() - w1 > 1.0, what="1 s of wall time")
    assert inbox.clock_s() - t1 > 2.0 * (time.monotonic() - w1)


def test_nan_goal_and_bad_layer_are_rejected_and_the_node_keeps_publishing(ros, sim):
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import OccupancyGrid

    inbox = Inbox(ros)
    pub = inbox.node.create_publisher(PoseStamped, "goal_pose", RELIABLE_QOS)
    layer_pub = inbox.node.create_publisher(OccupancyGrid, "object_costmap", MAP_QOS)
    ros.spin_until(lambda: inbox.has("/clock", "odom") and pub.get_subscription_count() > 0
                   and layer_pub.get_subscription_count() > 0, what="clock, odom, subscribers")
    bad = convert.pose_stamped(0.0, 0.0, 0.0, "map")
    bad.pose.position.x = math.nan
    pub.publish(bad)
    pub.publish(convert.pose_stamped(0.5, 0.5, 0.0, "odom_frame_nobody_has"))
    broken = OccupancyGrid()
    broken.header.frame_id = "map"
    broken.info.width, broken.info.height, broken.info.resolution = 10, 10, 0.05
    broken.data = [0] * 7                                   # 7 cells, not 100
    layer_pub.publish(broken)
    ros.spin_until(lambda: sim.engine.metrics.goals_rejected == 2, what="two rejected goals")
    t0 = inbox.clock_s()
    n_odom = inbox.count["odom"]
    ros.spin_until(lambda: inbox.clock_s() > t0 + 1.0 and inbox.count["odom"] > n_odom + 5,
                   what="clock and odom to keep coming")
    ros.spin_until(lambda: inbox.has("sim/metrics") and inbox.metric("goals_rejected") == "2",
                   what="sim/metrics to report the rejections")
    assert sim.engine.metrics.goals_received == 0
    assert sim.engine.layers == {}
    assert sim.engine.nav_status.state.value == "idle"


def test_save_metrics_service_writes_json_and_png(ros, sim, tmp_path):
    from std_srvs.srv import Trigger

    probe = ros.node("sim_test_client")
    cli = probe.create_client(Trigger, "sim/save_metrics")
    ros.spin_until(cli.service_is_ready, what="sim/save_metrics service")
    ros.spin_until(lambda: sim.engine.time_s > 0.5, what="some sim time")
    fut = cli.call_async(Trigger.Request())
    ros.spin_until(fut.done, what="save_metrics response")
    res = fut.result()
    assert res.success, res.message
    assert (tmp_path / "small_house_metrics.json").is_file()
    assert (tmp_path / "small_house_map.png").is_file()


def test_lockstep_mode_advances_fixed_sim_steps(ros, tmp_path):
    from sim_bridge.node import SimBridgeNode

    node = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"), Parameter("lockstep", value=True),
        Parameter("lockstep_dt_s", value=0.1), Parameter("tick_period_s", value=0.005),
        Parameter("output_dir", value=str(tmp_path))]))
    inbox = Inbox(ros)
    ros.spin_until(lambda: inbox.has("/clock") and inbox.clock_s() >= 2.0,
                   what="2 s of lock-step sim time")
    t = inbox.clock_s()
    assert t * 10 == pytest.approx(round(t * 10), abs=1e-6)   # whole 0.1 s steps
    assert node.engine.time_s >= t


def test_parameters_change_at_run_time_and_read_only_ones_are_refused(ros, sim):
    ok = sim.set_parameters([Parameter("real_time_factor", value=5.0),
                             Parameter("nav_goal_tolerance_xy_m", value=0.4)])
    assert all(r.successful for r in ok)
    assert sim.engine.params.real_time_factor == 5.0
    assert sim.engine.navigator.params.goal_tolerance_xy_m == 0.4
    bad = sim.set_parameters([Parameter("real_time_factor", value=-1.0)])
    assert not bad[0].successful and "real_time_factor" in bad[0].reason
    frozen = sim.set_parameters([Parameter("world", value="maze")])
    assert not frozen[0].successful
    assert sim.engine.world.name == "small_house"


@pytest.mark.parametrize("encoding", [None, "32FC1"])
def test_camera_topics_carry_rgb_depth_semantic_and_info(ros, tmp_path, encoding):
    from sensor_msgs.msg import CameraInfo, Image

    from sim_bridge.node import SimBridgeNode

    extra = [] if encoding is None else [Parameter("camera_depth_encoding", value=encoding)]
    ros.add(SimBridgeNode(context=ros.context, parameter_overrides=extra + [
        Parameter("world", value="small_cluttered"), Parameter("enable_camera", value=True),
        Parameter("camera_width_px", value=160), Parameter("camera_height_px", value=120),
        Parameter("camera_fx_px", value=131.0), Parameter("camera_fy_px", value=131.0),
        Parameter("camera_cx_px", value=79.5), Parameter("camera_cy_px", value=59.5),
        Parameter("output_dir", value=str(tmp_path))]))
    probe = ros.node("sim_camera_probe")
    got: dict[str, object] = {}
    for topic, typ in (("camera/color/image_raw", Image), ("camera/depth/image_raw", Image),
                       ("camera/semantic/image_raw", Image),
                       ("camera/color/camera_info", CameraInfo)):
        probe.create_subscription(typ, topic, lambda m, t=topic: got.__setitem__(t, m),
                                  SENSOR_QOS)
    ros.spin_until(lambda: len(got) == 4, what="the four camera topics")
    rgb, depth, sem = (got[f"camera/{k}/image_raw"] for k in ("color", "depth", "semantic"))
    assert (rgb.encoding, depth.encoding, sem.encoding) == ("rgb8", encoding or "16UC1", "mono8")
    assert (rgb.width, rgb.height) == (160, 120)
    assert rgb.header.stamp == depth.header.stamp == sem.header.stamp
    d = convert.depth_from_msg(depth)
    assert np.isfinite(d).any() and np.nanmin(d) > 0
    k = convert.intrinsics_from_msg(got["camera/color/camera_info"])
    assert (k.fx, k.cx, k.width, k.height) == (131.0, 79.5, 160, 120)


def test_map_is_published_at_map_update_interval_s_and_the_rates_reach_the_engine(
        ros, tmp_path):
    from nav_msgs.msg import OccupancyGrid

    from sim_bridge.node import SimBridgeNode

    node = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=[
        Parameter("world", value="small_house"), Parameter("lockstep", value=True),
        Parameter("lockstep_dt_s", value=0.1), Parameter("tick_period_s", value=0.005),
        Parameter("map_update_interval_s", value=1.0),
        Parameter("nav_controller_rate_hz", value=10.0),
        Parameter("mapping_keyframe_travel_m", value=0.3),
        Parameter("output_dir", value=str(tmp_path))]))
    p = node.engine.params
    assert (p.map_update_interval_s, p.nav_controller_rate_hz,
            p.mapping_keyframe_travel_m) == (1.0, 10.0, 0.3)
    probe = ros.node("sim_rates_probe")
    stamps: list[float] = []
    probe.create_subscription(OccupancyGrid, "map", lambda m: stamps.append(
        convert.stamp_to_ns(m.header.stamp) / 1e9), MAP_QOS)
    ros.spin_until(lambda: len(stamps) >= 4, timeout_s=20.0, what="4 maps")
    assert np.diff(stamps[:4]) == pytest.approx([1.0, 1.0, 1.0])
    node.set_parameters([Parameter("map_update_interval_s", value=0.5)])
    n = len(stamps)
    ros.spin_until(lambda: len(stamps) >= n + 4, timeout_s=20.0, what="4 more maps")
    assert np.diff(stamps[n + 1:n + 4]) == pytest.approx([0.5, 0.5])
