"""Round trips and error branches of explore_seg.convert (messages <-> numpy)."""

from __future__ import annotations

import array
import math

import numpy as np
import pytest
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, LaserScan, PointCloud2, PointField

from explore_seg import convert
from explore_seg.core.camera import CameraIntrinsics
from explore_seg.core.grid import GridMap, grid_from_ascii, quaternion_from_yaw

RNG = np.random.default_rng(7)


# ------------------------------------------------------------------ occupancy grid
def _grid(yaw: float = 0.0) -> GridMap:
    data = RNG.integers(-1, 101, size=(7, 11)).astype(np.int8)
    return GridMap(data, 0.05, (-3.25, 1.5), yaw, "map", 1_234_567_890_123)


@pytest.mark.parametrize("yaw", [0.0, 0.7, -2.5])
def test_grid_round_trip_keeps_data_geometry_frame_stamp(yaw):
    g = _grid(yaw)
    back = convert.grid_from_msg(convert.grid_to_msg(g))
    np.testing.assert_array_equal(back.data, g.data)
    assert back.resolution_m == pytest.approx(0.05)
    assert back.origin_xy_m == pytest.approx(g.origin_xy_m)
    assert back.origin_yaw_rad == pytest.approx(yaw)
    assert back.frame_id == "map"
    assert back.stamp_ns == g.stamp_ns


def test_grid_msg_layout_is_row_major_with_row_y():
    g, _ = grid_from_ascii("""
    ?..
    #..
    """)
    msg = convert.grid_to_msg(g)
    # row 0 (bottom line "#..") comes first in OccupancyGrid.data
    assert list(msg.data) == [100, 0, 0, -1, 0, 0]
    assert (msg.info.width, msg.info.height) == (3, 2)


def test_grid_world_cell_round_trip_with_yaw():
    g = _grid(0.9)
    rows = RNG.integers(0, g.height, 50)
    cols = RNG.integers(0, g.width, 50)
    x, y = g.cells_to_world(rows, cols)
    r2, c2 = g.world_to_cells(x, y)
    np.testing.assert_array_equal(r2, rows)
    np.testing.assert_array_equal(c2, cols)


def _bad_grid_msg(**change):
    msg = convert.grid_to_msg(_grid())
    for k, v in change.items():
        if k == "data":
            msg.data = v
        elif k == "resolution":
            msg.info.resolution = v
        elif k == "origin_x":
            msg.info.origin.position.x = v
        elif k == "quat_w":
            msg.info.origin.orientation.w = v
    return msg


@pytest.mark.parametrize("change, match", [
    ({"data": array.array("b", [0] * 5)}, r"5 cells, expected width\*height=11\*7=77"),
    ({"resolution": 0.0}, r"resolution must be finite and > 0, got 0.0"),
    ({"resolution": float("nan")}, r"resolution must be finite and > 0, got nan"),
    ({"origin_x": float("nan")}, r"origin must be finite"),
    ({"quat_w": 3.0}, r"unit length"),
    ({"data": array.array("b", [101] * 77)}, r"-1..100, got 101..101"),
])
def test_grid_from_msg_rejects_malformed(change, match):
    with pytest.raises(ValueError, match=match):
        convert.grid_from_msg(_bad_grid_msg(**change))


def test_labels_round_trip_over_100_regions():
    g = _grid()
    labels = np.arange(g.height * g.width, dtype=np.int32).reshape(g.shape) * 37
    img, info = convert.labels_to_msgs(labels, g)
    back, geom = convert.labels_from_msgs(img, info)
    np.testing.assert_array_equal(back, labels)
    assert geom.same_geometry(g)
    assert convert.stamp_to_ns(info.map_load_time) == g.stamp_ns


def test_labels_from_msgs_rejects_size_mismatch_and_encoding():
    g = _grid()
    img, info = convert.labels_to_msgs(np.zeros(g.shape, np.int32), g)
    info.width = 3
    with pytest.raises(ValueError, match="map info says 3x7"):
        convert.labels_from_msgs(img, info)
    img.encoding = "mono8"
    with pytest.raises(ValueError, match="must be 32SC1"):
        convert.labels_from_msgs(img, info)


# -------------------------------------------------------------------------- images
@pytest.mark.parametrize("encoding, dtype, channels", [
    ("rgb8", np.uint8, 3), ("bgr8", np.uint8, 3), ("mono8", np.uint8, 1),
    ("mono16", np.uint16, 1), ("16UC1", np.uint16, 1), ("32FC1", np.float32, 1),
    ("32SC1", np.int32, 1),
])
def test_image_round_trip(encoding, dtype, channels):
    shape = (5, 7, channels) if channels > 1 else (5, 7)
    arr = (RNG.random(shape) * 1000).astype(dtype)
    msg = convert.image_to_msg(arr, encoding)
    back = convert.image_from_msg(msg)
    np.testing.assert_array_equal(back, arr)
    assert back.dtype == np.dtype(dtype)


def _padded_image(arr: np.ndarray, encoding: str, pad: int, bigendian: bool = False) -> Image:
    h, w = arr.shape[:2]
    be = arr.astype(arr.dtype.newbyteorder(">" if bigendian else "<"))
    rows = be.reshape(h, -1).view(np.uint8)
    padded = np.zeros((h, rows.shape[1] + pad), np.uint8)
    padded[:, :rows.shape[1]] = rows
    msg = Image(height=h, width=w, encoding=encoding, is_bigendian=int(bigendian),
                step=padded.shape[1])
    msg.data = padded.tobytes()
    return msg


@pytest.mark.parametrize("bigendian", [False, True])
def test_image_row_padding_and_endianness(bigendian):
    depth = (RNG.random((4, 6)) * 5000).astype(np.uint16)
    msg = _padded_image(depth, "16UC1", pad=6, bigendian=bigendian)
    np.testing.assert_array_equal(convert.image_from_msg(msg), depth)


def test_depth_from_16uc1_mm_and_32fc1_m_mark_invalid_nan():
    mm = np.array([[0, 1000], [2500, 65535]], np.uint16)
    d = convert.depth_from_msg(convert.image_to_msg(mm, "16UC1"))
    assert math.isnan(d[0, 0])
    np.testing.assert_allclose(d[0, 1:], [1.0])
    np.testing.assert_allclose(d[1], [2.5, 65.535], rtol=1e-6)
    m = np.array([[0.0, np.inf], [np.nan, 1.25]], np.float32)
    d2 = convert.depth_from_msg(convert.image_to_msg(m, "32FC1"))
    assert np.isnan(d2[0]).all() and np.isnan(d2[1, 0]) and d2[1, 1] == pytest.approx(1.25)


def test_depth_to_msg_round_trips_both_encodings():
    d = np.array([[np.nan, 0.0, -1.0, np.inf], [0.0004, 0.0006, 1.2344, 70.0]])
    mm = convert.depth_to_msg(d, "16UC1")
    assert mm.encoding == "16UC1" and mm.step == 8
    np.testing.assert_array_equal(convert.image_from_msg(mm), [[0, 0, 0, 0], [0, 1, 1234, 0]])
    back = convert.depth_from_msg(mm)
    assert np.isnan(back[0]).all() and np.isnan(back[1, [0, 3]]).all()
    np.testing.assert_allclose(back[1, 1:3], [0.001, 1.234], rtol=1e-6)
    m = convert.depth_to_msg(d, "32FC1")
    back = convert.depth_from_msg(m)
    assert np.isnan(back[0]).all()
    np.testing.assert_allclose(back[1], d[1].astype(np.float32))
    with pytest.raises(ValueError, match="16UC1 or 32FC1"):
        convert.depth_to_msg(d, "mono8")
    with pytest.raises(ValueError, match=r"shape \(H, W\)"):
        convert.depth_to_msg(np.zeros(3), "16UC1")


def test_rgb_from_bgr_swaps_channels():
    rgb = RNG.integers(0, 255, (3, 4, 3)).astype(np.uint8)
    bgr_msg = convert.image_to_msg(rgb[:, :, ::-1].copy(), "bgr8")
    np.testing.assert_array_equal(convert.rgb_from_msg(bgr_msg), rgb)


def test_image_errors_name_expected_and_got():
    msg = convert.image_to_msg(np.zeros((4, 6), np.uint16), "16UC1")
    msg.encoding = "yuv422"
    with pytest.raises(ValueError, match="unsupported image encoding 'yuv422'"):
        convert.image_from_msg(msg)
    msg = convert.image_to_msg(np.zeros((4, 6), np.uint16), "16UC1")
    msg.step = 5
    with pytest.raises(ValueError, match=r"step 5 too small, expected >= width\*channels\*size=12"):
        convert.image_from_msg(msg)
    msg = convert.image_to_msg(np.zeros((4, 6), np.uint16), "16UC1")
    msg.data = bytes(10)
    with pytest.raises(ValueError, match=r"10 bytes, expected step\*height=12\*4=48"):
        convert.image_from_msg(msg)
    msg.height = 0
    with pytest.raises(ValueError, match="size must be positive"):
        convert.image_from_msg(msg)
    with pytest.raises(ValueError, match="needs dtype uint8"):
        convert.image_to_msg(np.zeros((2, 2), np.float32), "mono8")
    with pytest.raises(ValueError, match="depth image must be"):
        convert.depth_from_msg(convert.image_to_msg(np.zeros((2, 2), np.uint8), "mono8"))


# --------------------------------------------------------------------- point clouds
def test_cloud_round_trip_mixed_fields():
    dt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("intensity", "<f4"),
                   ("ring", "<u2"), ("label", "<u4")])
    pts = np.zeros(20, dt)
    for name in dt.names:
        pts[name] = RNG.random(20) * 100
    pts["x"][3] = np.nan
    msg = convert.cloud_to_msg(pts, convert.make_header("map", 5))
    assert not msg.is_dense and msg.point_step == 22
    back = convert.cloud_from_msg(msg)
    for name in dt.names:
        np.testing.assert_array_equal(back[name], pts[name])


@pytest.mark.parametrize("bigendian", [False, True])
def test_cloud_with_padding_endianness_and_organised(bigendian):
    h, w, step = 2, 3, 16  # x, y, z float32 + 4 padding bytes per point
    xyz = RNG.random((h, w, 3)).astype(np.float32)
    order = ">" if bigendian else "<"
    buf = np.zeros((h, w, step), np.uint8)
    buf[:, :, :12] = xyz.astype(order + "f4").view(np.uint8).reshape(h, w, 12)
    row = np.zeros((h, w * step + 8), np.uint8)  # 8 bytes of row padding
    row[:, :w * step] = buf.reshape(h, -1)
    msg = PointCloud2(height=h, width=w, is_bigendian=bigendian, point_step=step,
                      row_step=w * step + 8, is_dense=True)
    msg.fields = [PointField(name=n, offset=4 * i, datatype=PointField.FLOAT32, count=1)
                  for i, n in enumerate("xyz")]
    msg.data = row.tobytes()
    back = convert.cloud_from_msg(msg)
    assert back.shape == (h, w)
    np.testing.assert_array_equal(back["y"], xyz[:, :, 1])
    np.testing.assert_array_equal(convert.xyz_from_cloud(back), xyz.reshape(-1, 3))


def test_cloud_errors():
    msg = convert.cloud_to_msg(convert.xyz_cloud(np.zeros((4, 3))))
    msg.data = bytes(7)
    with pytest.raises(ValueError, match=r"7 bytes, expected row_step\*height=48\*1=48"):
        convert.cloud_from_msg(msg)
    msg = convert.cloud_to_msg(convert.xyz_cloud(np.zeros((4, 3))))
    msg.point_step = 8
    with pytest.raises(ValueError, match="point_step 8 too small, fields need 12"):
        convert.cloud_from_msg(msg)
    msg = convert.cloud_to_msg(convert.xyz_cloud(np.zeros((4, 3))))
    msg.fields[0].datatype = 42
    with pytest.raises(ValueError, match="unknown datatype 42"):
        convert.cloud_from_msg(msg)
    with pytest.raises(ValueError, match="structured array"):
        convert.cloud_to_msg(np.zeros((3, 3)))


# ---------------------------------------------------------------- scan, camera, pose
def test_scan_to_points_in_map_frame_drops_invalid():
    ranges = [1.0, float("nan"), 10.0, 0.01, 2.0]
    msg = convert.scan_to_msg(ranges, -math.pi / 2, math.pi / 4, 0.12, 5.0)
    pts = convert.scan_to_points(msg, pose=(1.0, 2.0, math.pi / 2))
    # beams 0 (-90 deg, 1 m) and 4 (+90 deg, 2 m); robot at (1, 2) facing +y
    np.testing.assert_allclose(pts, [[2.0, 2.0], [-1.0, 2.0]], atol=1e-6)


def test_scan_ranges_tell_no_reading_from_no_return():
    msg = convert.scan_to_msg([1.0, float("nan"), 10.0, 0.0, float("inf")], 0.0, 0.1, 0.12, 5.0)
    angles, r = convert.scan_ranges(msg)
    np.testing.assert_allclose(angles, [0.0, 0.1, 0.2, 0.3, 0.4], atol=1e-6)
    # a driver's 0 (below range_min) is no reading, as NaN; beyond range_max: no return
    assert r[0] == 1.0 and np.isnan(r[1]) and np.isnan(r[3])
    assert np.isposinf(r[2]) and np.isposinf(r[4])


def test_scan_errors():
    msg = LaserScan()
    with pytest.raises(ValueError, match="no ranges"):
        convert.scan_ranges(msg)
    msg = convert.scan_to_msg([1.0], 0.0, 0.0, 0.1, 5.0)
    with pytest.raises(ValueError, match="increment != 0"):
        convert.scan_ranges(msg)


def test_camera_info_round_trip_and_errors():
    intr = CameraIntrinsics(fx=525.0, fy=520.0, cx=319.5, cy=239.5, width=640, height=480)
    assert convert.intrinsics_from_msg(convert.intrinsics_to_msg(intr)) == intr
    bad = CameraInfo()
    bad.k = [0.0] * 9
    bad.width, bad.height = 640, 480
    with pytest.raises(ValueError):
        convert.intrinsics_from_msg(bad)


def test_pose_from_odometry_and_covariance_stamped():
    odom = Odometry()
    odom.pose.pose = convert.pose_from_2d(1.0, -2.0, 2.0)
    assert convert.pose2d_from_odometry(odom) == pytest.approx((1.0, -2.0, 2.0))
    pwc = PoseWithCovarianceStamped()
    pwc.pose.pose = convert.pose_from_2d(0.5, 0.25, -1.0)
    assert convert.pose2d_from_pose_msg(pwc) == pytest.approx((0.5, 0.25, -1.0))
    odom.pose.pose.position.x = float("nan")
    with pytest.raises(ValueError, match="position must be finite"):
        convert.pose2d_from_odometry(odom)
    odom.pose.pose = convert.pose_from_2d(0.0, 0.0, 0.0)
    odom.pose.pose.orientation.w = 0.0
    with pytest.raises(ValueError, match="unit length"):
        convert.pose2d_from_odometry(odom)


def test_quaternion_yaw_round_trip():
    for yaw in np.linspace(-3.1, 3.1, 13):
        q = quaternion_from_yaw(float(yaw))
        from explore_seg.core.grid import yaw_from_quaternion
        assert yaw_from_quaternion(*q) == pytest.approx(yaw)


def test_odometry_and_path_messages():
    odom = convert.odometry_msg((1.0, 2.0, 0.5), (0.2, -0.1), "map", "base_footprint", 3_000_000_001)
    assert convert.pose2d_from_odometry(odom) == pytest.approx((1.0, 2.0, 0.5))
    assert (odom.header.frame_id, odom.child_frame_id) == ("map", "base_footprint")
    assert odom.twist.twist.linear.x == pytest.approx(0.2)
    assert convert.stamp_to_ns(odom.header.stamp) == 3_000_000_001
    path = convert.path_msg([[0, 0], [1, 0], [1, 1]], "map", 5)
    yaws = [convert.pose2d_from_pose(p.pose)[2] for p in path.poses]
    assert yaws == pytest.approx([0.0, np.pi / 2, np.pi / 2])
    assert convert.path_msg(np.zeros((0, 2)), "map").poses == []
