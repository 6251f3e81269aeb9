"""``object_costmap`` node: synthetic RGB-D + odom + map in, object layer out (oracle)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.parameter import Parameter
from sensor_msgs.msg import CameraInfo, Image, LaserScan

from explore_seg import convert
from explore_seg.core.camera import CameraIntrinsics
from explore_seg.core.grid import GridMap
from explore_seg.object_costmap_node import ObjectCostmapNode, State
from explore_seg.qos import MAP_QOS, RELIABLE_QOS, SENSOR_QOS
from objects_scene import box_parts, camera_pose, leg_scan, render_depth, table_parts

K = CameraIntrinsics(fx=525.0, fy=525.0, cx=319.5, cy=239.5, width=640, height=480)
CAM_Z_M = 0.6
CAM_PITCH_RAD = 0.3
CHAIR_ID = 2
ROBOT = (0.5, -0.2, 0.1)


def _node(ros, **extra):
    params = {"detector.backend": "oracle", "rate_hz": 10.0, "camera_x_m": 0.0,
              "camera_z_m": CAM_Z_M, "camera_pitch_rad": CAM_PITCH_RAD, "lidar_x_m": 0.0,
              "sync_tolerance_s": 0.02, **extra}
    overrides = [Parameter(k, value=v) for k, v in params.items()]
    return ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=overrides))


def _scene(parts_with_ids):
    """Depth (32FC1 m) and semantic (mono8) images of boxes seen from ROBOT."""
    pose = camera_pose(*ROBOT, z=CAM_Z_M, pitch=CAM_PITCH_RAD)
    parts = [p for p, _ in parts_with_ids]
    depth = render_depth(parts, pose, K)
    semantic = np.zeros(depth.shape, np.uint8)
    for part, cid in parts_with_ids:
        alone = render_depth([part], pose, K, floor=False)
        semantic[np.isclose(alone, depth, atol=1e-4) & np.isfinite(alone)] = cid
    return depth, semantic


class Feeder:
    """Publishes a frame set (info, colour, depth, semantic, odom, scan) on a timer."""

    def __init__(self, ros):
        self.node = ros.node("feeder")
        n = self.node
        self.info = n.create_publisher(CameraInfo, "camera/color/camera_info", SENSOR_QOS)
        self.color = n.create_publisher(Image, "camera/color/image_raw", SENSOR_QOS)
        self.depth = n.create_publisher(Image, "camera/depth/image_raw", SENSOR_QOS)
        self.sem = n.create_publisher(Image, "camera/semantic/image_raw", SENSOR_QOS)
        self.odom = n.create_publisher(Odometry, "odom", RELIABLE_QOS)
        self.scan = n.create_publisher(LaserScan, "scan", SENSOR_QOS)
        self.map = n.create_publisher(OccupancyGrid, "map", MAP_QOS)
        self.frame = None            # (depth msg builder, colour, semantic) arrays
        self.send_info = True
        self.scan_msg = None
        self.grids: list = []
        n.create_subscription(OccupancyGrid, "object_costmap", self.grids.append, MAP_QOS)
        n.create_timer(0.05, self._tick)

    def _tick(self):
        if self.frame is None:
            return
        stamp = self.node.get_clock().now().to_msg()
        header = convert.make_header("camera_color_optical_frame", stamp)
        depth_msg, rgb, sem = self.frame
        if self.send_info:
            self.info.publish(convert.intrinsics_to_msg(K, header))
        color = convert.image_to_msg(rgb, "rgb8", header)
        depth = depth_msg(header)
        self.color.publish(color)
        self.depth.publish(depth)
        self.sem.publish(convert.image_to_msg(sem, "mono8", header))
        odom = Odometry()
        odom.header = convert.make_header("map", stamp)
        odom.pose.pose = convert.pose_from_2d(*ROBOT)
        self.odom.publish(odom)
        if self.scan_msg is not None:
            self.scan_msg.header = convert.make_header("base_scan", stamp)
            self.scan.publish(self.scan_msg)


def _map_grid():
    data = np.zeros((80, 100), np.int8)
    return GridMap(data, 0.05, (0.0, -2.0))


def _good(depth, sem):
    rgb = np.zeros(depth.shape + (3,), np.uint8)
    return (lambda h: convert.image_to_msg(depth, "32FC1", h)), rgb, sem


def test_chair_becomes_occupied_cells_in_the_object_layer(ros):
    node = _node(ros)
    feed = Feeder(ros)
    chair = box_parts((2.5, 0.2), (0.5, 0.5, 0.9))
    depth, sem = _scene([(chair, CHAIR_ID)])
    assert (sem == CHAIR_ID).sum() > 1000
    grid = _map_grid()
    feed.map.publish(convert.grid_to_msg(grid))
    feed.frame = _good(depth, sem)
    ros.spin_until(lambda: any((np.asarray(g.data) == 100).any() for g in feed.grids),
                   timeout_s=20, what="an object_costmap with occupied cells")
    layer = convert.grid_from_msg(next(g for g in feed.grids if (np.asarray(g.data) == 100).any()))
    assert layer.same_geometry(grid)
    assert layer.data[layer.world_to_cell(2.5, 0.2)] == 100
    assert layer.data[layer.world_to_cell(2.6, 0.3)] == 100
    assert layer.data[layer.world_to_cell(1.0, 0.0)] == 0
    assert layer.data[layer.world_to_cell(4.0, 1.5)] == 0
    assert [o.cls for o in node.objects()] == ["chair"]
    assert node.state is State.RUNNING


def test_cloud_and_markers_go_to_their_subscribers(ros):
    from sensor_msgs.msg import PointCloud2
    from visualization_msgs.msg import Marker, MarkerArray

    node = _node(ros)
    feed = Feeder(ros)
    clouds, markers = [], []
    feed.node.create_subscription(PointCloud2, "object_costmap/cloud", clouds.append, 1)
    feed.node.create_subscription(MarkerArray, "object_costmap/markers", markers.append, 1)
    chair = box_parts((2.5, 0.2), (0.5, 0.5, 0.9))
    depth, sem = _scene([(chair, CHAIR_ID)])
    feed.map.publish(convert.grid_to_msg(_map_grid()))
    feed.frame = _good(depth, sem)
    ros.spin_until(lambda: node.objects() and any(c.width > 0 for c in clouds)
                   and any(len(m.markers) > 1 for m in markers), timeout_s=20,
                   what="a virtual cloud and markers of the chair")
    cloud = next(c for c in clouds if c.width > 0)
    xyz = np.frombuffer(bytes(cloud.data), np.float32).reshape(-1, cloud.point_step // 4)[:, :3]
    assert np.all(np.abs(xyz[:, :2] - (2.5, 0.2)) < 0.6)
    cubes = [m for m in next(m for m in markers if len(m.markers) > 1).markers
             if m.type == Marker.CUBE]
    assert len(cubes) == 1 and abs(cubes[0].pose.position.x - 2.5) < 0.2


def test_a_frame_is_taken_at_most_every_0_9_periods(ros):
    node = _node(ros, rate_hz=2.0)
    s = 1_000_000_000

    def frame(t_ns):
        header = convert.make_header("camera_color_optical_frame", convert.ns_to_stamp(t_ns))
        img = convert.image_to_msg(np.zeros((2, 2), np.uint8), "mono8", header)
        node._depths.append(img)
        node._colors.append(img)
        node._semantics.append(img)

    node._last_depth_ns = 10 * s
    frame(10 * s + s // 10 * 3)                   # 0.3 s after the last one: too soon
    assert node._newest_pair() is None
    frame(10 * s + s // 2)                        # 0.5 s = one period of a 2 Hz camera
    assert convert.stamp_to_ns(node._newest_pair()[0].header.stamp) == 10 * s + s // 2
    node._last_depth_ns = 10 * s + s // 2         # ... processed
    assert node._newest_pair() is None


def test_lag_warning_when_most_frames_go_unprocessed(ros):
    node = _node(ros)
    warned = []
    node._warn_lag = lambda key, msg: warned.append(msg)
    now = node.get_clock().now().nanoseconds
    node._lag_mark = (now - int(25e9), 0, 0, 0, 0)
    node.frames_received, node.frames_processed = 50, 40      # 40 of min(50, 25 s * 2 Hz)
    node._check_lag()
    assert warned == []
    node._lag_mark = (now - int(25e9), 50, 40, 0, 0)
    node.frames_received, node.frames_processed = 100, 50     # 10 of 50 possible
    node._check_lag()
    assert len(warned) == 1 and "processed 10 of 50 camera frames" in warned[0]
    node.frames_received = 110                  # the window restarted: too short to judge
    node._check_lag()
    assert len(warned) == 1


def test_unclassified_table_from_scan_legs(ros):
    node = _node(ros)
    feed = Feeder(ros)
    table = table_parts((2.6, -0.2), 1.2, 0.8, 0.75)
    depth, sem = _scene([(p, 0) for p in table])      # the detector sees nothing
    feed.map.publish(convert.grid_to_msg(_map_grid()))
    # scan in base_scan (= base_link here) of the 4 legs from ROBOT
    x, y, yaw = ROBOT
    legs = leg_scan([p[0][:2] for p in table[1:]])
    rel = legs - [x, y]
    c, s = math.cos(-yaw), math.sin(-yaw)
    local = rel @ np.array([[c, -s], [s, c]]).T
    ang = np.arctan2(local[:, 1], local[:, 0])
    rng = np.hypot(local[:, 0], local[:, 1])
    inc = math.radians(0.25)
    ranges = np.full(1440, np.inf)
    ranges[np.round((ang + math.pi) / inc).astype(int) % 1440] = rng
    feed.scan_msg = convert.scan_to_msg(ranges, -math.pi, inc, 0.1, 10.0)
    feed.frame = _good(depth, sem)
    ros.spin_until(lambda: any(o.cls == "unknown" for o in node.objects()), timeout_s=20,
                   what="an unknown object from the laser legs")
    obj = next(o for o in node.objects() if o.cls == "unknown")
    np.testing.assert_allclose(obj.center_xyz[:2], (2.6, -0.2), atol=0.1)


def test_malformed_inputs_are_dropped_and_the_node_keeps_running(ros):
    node = _node(ros)
    feed = Feeder(ros)
    chair = box_parts((2.5, 0.2), (0.5, 0.5, 0.9))
    depth, sem = _scene([(chair, CHAIR_ID)])
    rgb = np.zeros(depth.shape + (3,), np.uint8)
    feed.map.publish(convert.grid_to_msg(_map_grid()))

    feed.send_info = False
    feed.frame = _good(depth, sem)
    ros.spin_until(lambda: "CameraInfo" in node.last_drop.get("frame", ""), timeout_s=10,
                   what="a frame dropped for missing CameraInfo")
    assert node.state is State.WAITING_FOR_CAMERA_INFO
    feed.send_info = True

    bad_frames = [
        ((lambda h: convert.image_to_msg(depth[::2, ::2].copy(), "32FC1", h)),
         rgb[::2, ::2], sem[::2, ::2], "CameraInfo says"),
        ((lambda h: convert.image_to_msg(depth, "32FC1", h)), rgb[:240], sem, "differ in size"),
        ((lambda h: convert.image_to_msg(np.full_like(depth, np.nan), "32FC1", h)), rgb, sem,
         "no valid pixel"),
        ((lambda h: _with_encoding(convert.image_to_msg(depth, "32FC1", h), "yuv422")), rgb, sem,
         "unsupported image encoding"),
    ]
    for depth_fn, color, semantic, match in bad_frames:
        feed.frame = (depth_fn, color, semantic)
        ros.spin_until(lambda: match in node.last_drop.get("frame", ""), timeout_s=10,
                       what=f"a frame dropped with {match!r}")
    empty = convert.scan_to_msg([], 0.0, 0.01, 0.1, 10.0)
    feed.scan_msg = empty
    feed.frame = _good(depth, sem)
    ros.spin_until(lambda: "no ranges" in node.last_drop.get("scan", ""), timeout_s=10,
                   what="an empty scan dropped")
    ros.spin_until(lambda: any((np.asarray(g.data) == 100).any() for g in feed.grids),
                   timeout_s=20, what="an object layer after the bad frames")
    assert node.frames_processed >= 1


def _with_encoding(msg, encoding):
    msg.encoding = encoding
    return msg


def test_invalid_parameter_is_rejected(ros):
    node = _node(ros)
    res = node.set_parameters([Parameter("rate_hz", value=-1.0)])
    assert not res[0].successful and "rate_hz" in res[0].reason
    res = node.set_parameters([Parameter("rate_hz", value=4.0)])
    assert res[0].successful and node.params.rate_hz == pytest.approx(4.0)
