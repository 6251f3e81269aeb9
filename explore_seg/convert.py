"""The one place where ROS messages become numpy arrays and back.

No cv_bridge, no sensor_msgs_py: everything is ``np.frombuffer`` with explicit dtypes,
strides and byte order. Every function raises ``ValueError`` naming what it expected and
what it got when a message is malformed; nodes catch it at the callback boundary.

Layout conventions: grids and region label images are in :class:`~explore_seg.core.grid.GridMap`
layout (row = y, i.e. ``OccupancyGrid.data`` reshaped to (height, width), not flipped);
camera images are in image layout (row 0 = top).
"""

from __future__ import annotations

import array
import math
from typing import Any

import numpy as np
import numpy.typing as npt
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Pose, PoseStamped, PoseWithCovarianceStamped
from nav_msgs.msg import MapMetaData, OccupancyGrid, Odometry, Path
from sensor_msgs.msg import CameraInfo, Image, LaserScan, PointCloud2, PointField
from std_msgs.msg import Header

from explore_seg.core.camera import CameraIntrinsics
from explore_seg.core.grid import GridMap, quaternion_from_yaw, yaw_from_quaternion
from explore_seg.core.limits import InputLimits, check_frame, normalize_frame  # noqa: F401

DEFAULT_LIMITS = InputLimits()

# --------------------------------------------------------------------------- time


def stamp_to_ns(stamp: Time) -> int:
    """builtin_interfaces/Time -> integer nanoseconds."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def checked_stamp_ns(stamp: Time, what: str) -> int:
    """:func:`stamp_to_ns`; ``ValueError`` on a negative stamp (no header could carry it)."""
    sec, nsec = int(stamp.sec), int(stamp.nanosec)
    if sec < 0 or not 0 <= nsec < 1_000_000_000:
        raise ValueError(f"{what}: header.stamp must be >= 0 with nanosec < 1e9, got "
                         f"sec={sec} nanosec={nsec}")
    return sec * 1_000_000_000 + nsec


def ns_to_stamp(ns: int) -> Time:
    """Integer nanoseconds (>= 0) -> builtin_interfaces/Time."""
    ns = int(ns)
    if ns < 0:
        raise ValueError(f"stamp must be >= 0 ns, got {ns}")
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def make_header(frame_id: str, stamp: Time | int | None = None) -> Header:
    """Header with ``frame_id`` and a stamp given as Time or nanoseconds (None = 0)."""
    h = Header()
    h.frame_id = frame_id
    if stamp is None:
        h.stamp = Time()
    elif isinstance(stamp, Time):
        h.stamp = stamp
    else:
        h.stamp = ns_to_stamp(int(stamp))
    return h


# -------------------------------------------------------------------------- poses


def _yaw_checked(q: Any, what: str) -> float:
    vals = (q.x, q.y, q.z, q.w)
    if not all(math.isfinite(v) for v in vals):
        raise ValueError(f"{what}: orientation must be finite, got {vals}")
    norm = math.sqrt(sum(v * v for v in vals))
    if not 0.9 < norm < 1.1:
        raise ValueError(f"{what}: orientation quaternion must be unit length, got norm {norm:.3f}")
    return yaw_from_quaternion(*(v / norm for v in vals))


def pose2d_from_pose(pose: Pose, what: str = "pose", limits: InputLimits = DEFAULT_LIMITS
                     ) -> tuple[float, float, float]:
    """(x, y, yaw) of a Pose; ValueError on NaN, |x|,|y| > max_coordinate_m, a bad quaternion."""
    x, y = float(pose.position.x), float(pose.position.y)
    limits.check_xy(x, y, what)
    return x, y, _yaw_checked(pose.orientation, what)


def pose2d_from_odometry(msg: Odometry, limits: InputLimits = DEFAULT_LIMITS
                         ) -> tuple[float, float, float]:
    """(x, y, yaw) of nav_msgs/Odometry's pose (in its header frame)."""
    return pose2d_from_pose(msg.pose.pose, "odometry", limits)


def pose2d_from_pose_msg(msg: PoseWithCovarianceStamped | PoseStamped,
                         limits: InputLimits = DEFAULT_LIMITS) -> tuple[float, float, float]:
    """(x, y, yaw) of a PoseStamped or PoseWithCovarianceStamped."""
    pose = msg.pose.pose if isinstance(msg, PoseWithCovarianceStamped) else msg.pose
    return pose2d_from_pose(pose, type(msg).__name__, limits)


def pose_from_2d(x: float, y: float, yaw: float) -> Pose:
    """geometry_msgs/Pose of a planar pose."""
    p = Pose()
    p.position.x, p.position.y, p.position.z = float(x), float(y), 0.0
    qx, qy, qz, qw = quaternion_from_yaw(float(yaw))
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = qx, qy, qz, qw
    return p


def pose_stamped(x: float, y: float, yaw: float, frame_id: str,
                 stamp: Time | int | None = None) -> PoseStamped:
    """PoseStamped of a planar pose (what Nav2's ``goal_pose`` takes)."""
    msg = PoseStamped()
    msg.header = make_header(frame_id, stamp)
    msg.pose = pose_from_2d(x, y, yaw)
    return msg


def odometry_msg(pose: tuple[float, float, float], velocity: tuple[float, float],
                 frame_id: str, child_frame_id: str, stamp: Time | int | None = None) -> Odometry:
    """nav_msgs/Odometry: planar pose in ``frame_id``, body twist (v, w) in ``child_frame_id``."""
    msg = Odometry()
    msg.header = make_header(frame_id, stamp)
    msg.child_frame_id = child_frame_id
    msg.pose.pose = pose_from_2d(*pose)
    msg.twist.twist.linear.x = float(velocity[0])
    msg.twist.twist.angular.z = float(velocity[1])
    return msg


def path_msg(xy: npt.ArrayLike, frame_id: str, stamp: Time | int | None = None) -> Path:
    """nav_msgs/Path through world points (N, 2); each pose heads to the next point."""
    pts = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    msg = Path()
    msg.header = make_header(frame_id, stamp)
    n = len(pts)
    if n == 0:
        return msg
    d = np.diff(pts, axis=0)
    yaws = np.arctan2(d[:, 1], d[:, 0]) if n > 1 else np.zeros(0)
    yaws = np.concatenate([yaws, yaws[-1:]]) if n > 1 else np.zeros(1)
    for (x, y), yaw in zip(pts, yaws):
        ps = PoseStamped()
        ps.header = msg.header
        ps.pose = pose_from_2d(float(x), float(y), float(yaw))
        msg.poses.append(ps)
    return msg


# ---------------------------------------------------------------------- occupancy


def _meta_checked(info: MapMetaData, limits: InputLimits = DEFAULT_LIMITS
                  ) -> tuple[float, float, float, float]:
    """(resolution, origin x, origin y, origin yaw) of MapMetaData, validated (size and
    resolution against ``limits`` too: nothing is allocated before this passes)."""
    res = float(info.resolution)
    if not (math.isfinite(res) and res > 0):
        raise ValueError(f"map resolution must be finite and > 0, got {res}")
    limits.check_map_size(info.width, info.height, res)
    ox, oy = float(info.origin.position.x), float(info.origin.position.y)
    if not (math.isfinite(ox) and math.isfinite(oy)):
        raise ValueError(f"map origin must be finite, got ({ox}, {oy})")
    limits.check_xy(ox, oy, "map origin")
    return res, ox, oy, _yaw_checked(info.origin.orientation, "map origin")


def grid_from_msg(msg: OccupancyGrid, limits: InputLimits = DEFAULT_LIMITS) -> GridMap:
    """nav_msgs/OccupancyGrid -> :class:`GridMap` (row = y, no flip; frame without a
    leading ``/``).

    Raises
    ------
    ValueError
        Wrong data length, a size or resolution beyond ``limits``, zero/negative/NaN
        resolution, NaN or absurd origin, bad orientation, a negative stamp, values
        outside -1..100.
    """
    info = msg.info
    w, h = int(info.width), int(info.height)
    n = len(msg.data)
    if n != w * h:
        raise ValueError(f"map data has {n} cells, expected width*height={w}*{h}={w * h}")
    res, ox, oy, yaw = _meta_checked(info, limits)
    stamp_ns = checked_stamp_ns(msg.header.stamp, "map")
    data = np.frombuffer(_as_bytes(msg.data), dtype=np.int8, count=n).reshape(h, w).copy()
    if data.size and (data.min() < -1 or data.max() > 100):
        raise ValueError(f"map values must be in -1..100, got {data.min()}..{data.max()}")
    return GridMap(data, res, (ox, oy), yaw, normalize_frame(msg.header.frame_id, "map"),
                   stamp_ns)


def map_meta(grid: GridMap, stamp: Time | int | None = None) -> MapMetaData:
    """nav_msgs/MapMetaData of a grid's geometry (``map_load_time`` = stamp)."""
    info = MapMetaData()
    info.map_load_time = make_header("", stamp if stamp is not None else grid.stamp_ns).stamp
    info.resolution = float(grid.resolution_m)
    info.width, info.height = grid.width, grid.height
    info.origin = pose_from_2d(grid.origin_xy_m[0], grid.origin_xy_m[1], grid.origin_yaw_rad)
    return info


def grid_to_msg(grid: GridMap, stamp: Time | int | None = None) -> OccupancyGrid:
    """:class:`GridMap` -> nav_msgs/OccupancyGrid (stamp defaults to the grid's)."""
    msg = OccupancyGrid()
    msg.header = make_header(grid.frame_id, stamp if stamp is not None else grid.stamp_ns)
    msg.info = map_meta(grid, msg.header.stamp)
    msg.data = array.array("b", np.ascontiguousarray(grid.data, dtype=np.int8).tobytes())
    return msg


def geometry_from_meta(info: MapMetaData, frame_id: str = "map",
                       limits: InputLimits = DEFAULT_LIMITS) -> GridMap:
    """An all-unknown :class:`GridMap` with the geometry of a MapMetaData (checked against
    ``limits`` before it is allocated)."""
    res, ox, oy, yaw = _meta_checked(info, limits)
    data = np.full((int(info.height), int(info.width)), -1, dtype=np.int8)
    return GridMap(data, res, (ox, oy), yaw, frame_id, stamp_to_ns(info.map_load_time))


def labels_to_msgs(labels: npt.NDArray[np.integer], grid: GridMap,
                   stamp: Time | int | None = None) -> tuple[Image, MapMetaData]:
    """Region labels aligned with ``grid`` -> (Image 32SC1, MapMetaData).

    The image is cell-for-cell the grid (row = y, not flipped), header = grid frame and
    stamp; the MapMetaData carries the geometry with ``map_load_time`` = the same stamp,
    so a subscriber can pair them and recover where every label lies.
    """
    if labels.shape != grid.shape:
        raise ValueError(f"labels shape {labels.shape} differs from grid shape {grid.shape}")
    st = stamp if stamp is not None else grid.stamp_ns
    img = image_to_msg(np.ascontiguousarray(labels, dtype=np.int32), "32SC1",
                       make_header(grid.frame_id, st))
    return img, map_meta(grid, img.header.stamp)


def labels_from_msgs(img: Image, info: MapMetaData, limits: InputLimits = DEFAULT_LIMITS
                     ) -> tuple[npt.NDArray[np.int32], GridMap]:
    """(Image 32SC1, MapMetaData) -> (labels int32 (H, W), grid geometry); the info's size
    is checked against the image's and ``limits`` before anything is allocated."""
    if img.encoding != "32SC1":
        raise ValueError(f"region labels must be 32SC1, got {img.encoding!r}")
    if (int(img.width), int(img.height)) != (int(info.width), int(info.height)):
        raise ValueError(f"labels image is {img.width}x{img.height}, "
                         f"map info says {info.width}x{info.height}")
    labels = image_from_msg(img)
    geom = geometry_from_meta(info, normalize_frame(img.header.frame_id, "map"), limits)
    return labels.astype(np.int32, copy=False), geom


# ------------------------------------------------------------------------- images

#: encoding -> (numpy base dtype, channels)
IMAGE_ENCODINGS: dict[str, tuple[str, int]] = {
    "rgb8": ("u1", 3), "bgr8": ("u1", 3), "rgba8": ("u1", 4), "bgra8": ("u1", 4),
    "mono8": ("u1", 1), "8UC1": ("u1", 1), "8UC3": ("u1", 3),
    "mono16": ("u2", 1), "16UC1": ("u2", 1), "16SC1": ("i2", 1),
    "32FC1": ("f4", 1), "32SC1": ("i4", 1), "64FC1": ("f8", 1),
}


def _as_bytes(data: Any) -> bytes | memoryview:
    if isinstance(data, (bytes, bytearray, memoryview)):
        return data
    if isinstance(data, array.array):
        return memoryview(data).cast("B")
    if isinstance(data, np.ndarray):
        return data.tobytes()
    return bytes(data)


def image_from_msg(msg: Image) -> np.ndarray:
    """sensor_msgs/Image -> array (H, W) or (H, W, C), native byte order, channel order as encoded.

    Handles row padding (``step`` > width * pixel size) and big-endian data.

    Raises
    ------
    ValueError
        Unknown encoding, zero size, ``step`` too small, wrong data length.
    """
    enc = msg.encoding
    if enc not in IMAGE_ENCODINGS:
        raise ValueError(f"unsupported image encoding {enc!r}, expected one of "
                         f"{sorted(IMAGE_ENCODINGS)}")
    base, ch = IMAGE_ENCODINGS[enc]
    h, w, step = int(msg.height), int(msg.width), int(msg.step)
    if h <= 0 or w <= 0:
        raise ValueError(f"image size must be positive, got {w}x{h}")
    dt = np.dtype(base).newbyteorder(">" if msg.is_bigendian else "<")
    row_bytes = w * ch * dt.itemsize
    if step < row_bytes:
        raise ValueError(f"image step {step} too small, expected >= width*channels*size={row_bytes}")
    buf = _as_bytes(msg.data)
    n = len(buf)
    if n != step * h:
        raise ValueError(f"image data has {n} bytes, expected step*height={step}*{h}={step * h}")
    raw = np.frombuffer(buf, dtype=np.uint8).reshape(h, step)[:, :row_bytes]
    arr = np.ascontiguousarray(raw).view(dt).reshape((h, w, ch) if ch > 1 else (h, w))
    return arr.astype(dt.newbyteorder("="), copy=True)


def rgb_from_msg(msg: Image) -> npt.NDArray[np.uint8]:
    """Colour image as (H, W, 3) uint8 in RGB order (rgb8, bgr8, rgba8, bgra8, mono8)."""
    arr = image_from_msg(msg)
    enc = msg.encoding
    if enc in ("rgb8", "8UC3"):
        return arr
    if enc == "bgr8":
        return arr[:, :, ::-1].copy()
    if enc == "rgba8":
        return arr[:, :, :3].copy()
    if enc == "bgra8":
        return arr[:, :, 2::-1].copy()
    if enc in ("mono8", "8UC1"):
        return np.repeat(arr[:, :, None], 3, axis=2)
    raise ValueError(f"colour image expected (rgb8, bgr8, rgba8, bgra8, mono8), got {enc!r}")


def depth_from_msg(msg: Image) -> npt.NDArray[np.float32]:
    """Depth image -> float32 metres, NaN where invalid.

    16UC1/mono16 are millimetres (0 = no reading); 32FC1 is metres (0, inf, NaN = none).
    """
    arr = image_from_msg(msg)
    if msg.encoding in ("16UC1", "mono16"):
        out = arr.astype(np.float32) * np.float32(0.001)
        out[arr == 0] = np.nan
        return out
    if msg.encoding == "32FC1":
        out = arr.astype(np.float32, copy=True)
        out[~np.isfinite(out) | (out <= 0)] = np.nan
        return out
    raise ValueError(f"depth image must be 16UC1, mono16 or 32FC1, got {msg.encoding!r}")


def depth_to_msg(depth_m: npt.ArrayLike, encoding: str = "16UC1",
                 header: Header | None = None) -> Image:
    """Float metres (NaN/inf/<= 0 = no reading) -> depth Image, the inverse of
    :func:`depth_from_msg`.

    16UC1 rounds to millimetres (0 = no reading; depths beyond 65.535 m read none);
    32FC1 keeps metres with NaN for no reading.

    Raises
    ------
    ValueError
        When the array is not 2-D or the encoding is neither 16UC1 nor 32FC1.
    """
    d = np.asarray(depth_m, dtype=np.float64)
    if d.ndim != 2:
        raise ValueError(f"depth image needs shape (H, W), got {d.shape}")
    valid = np.isfinite(d) & (d > 0)
    if encoding == "16UC1":
        mm = np.zeros(d.shape, dtype=np.uint16)
        v = np.rint(d[valid] * 1000.0)
        ok = (v >= 1) & (v <= 65535)
        idx = np.flatnonzero(valid)[ok]
        mm.reshape(-1)[idx] = v[ok].astype(np.uint16)
        return image_to_msg(mm, "16UC1", header)
    if encoding == "32FC1":
        out = np.where(valid, d, np.nan).astype(np.float32)
        return image_to_msg(out, "32FC1", header)
    raise ValueError(f"depth encoding must be 16UC1 or 32FC1, got {encoding!r}")


def image_to_msg(arr: np.ndarray, encoding: str, header: Header | None = None) -> Image:
    """Array -> sensor_msgs/Image (little endian, no row padding).

    Raises
    ------
    ValueError
        When the array's dtype or channel count does not fit the encoding.
    """
    if encoding not in IMAGE_ENCODINGS:
        raise ValueError(f"unsupported image encoding {encoding!r}")
    base, ch = IMAGE_ENCODINGS[encoding]
    a = np.asarray(arr)
    want_ndim = 3 if ch > 1 else 2
    if a.ndim != want_ndim or (ch > 1 and a.shape[2] != ch):
        raise ValueError(f"{encoding} needs shape (H, W{', ' + str(ch) if ch > 1 else ''}), "
                         f"got {a.shape}")
    if a.dtype != np.dtype(base):
        raise ValueError(f"{encoding} needs dtype {np.dtype(base)}, got {a.dtype}")
    a = np.ascontiguousarray(a.astype(np.dtype(base).newbyteorder("<"), copy=False))
    msg = Image()
    msg.header = header if header is not None else Header()
    msg.height, msg.width = int(a.shape[0]), int(a.shape[1])
    msg.encoding = encoding
    msg.is_bigendian = 0
    msg.step = int(a.shape[1] * ch * a.dtype.itemsize)
    msg.data = a.tobytes()
    return msg


# -------------------------------------------------------------------- point clouds

_PF_TO_NP = {
    PointField.INT8: "i1", PointField.UINT8: "u1", PointField.INT16: "i2",
    PointField.UINT16: "u2", PointField.INT32: "i4", PointField.UINT32: "u4",
    PointField.FLOAT32: "f4", PointField.FLOAT64: "f8",
}
_NP_TO_PF = {np.dtype(v).newbyteorder("=").str[1:]: k for k, v in _PF_TO_NP.items()}


def cloud_dtype(msg: PointCloud2) -> np.dtype:
    """Structured dtype of a PointCloud2 (fields at their offsets, itemsize = point_step)."""
    order = ">" if msg.is_bigendian else "<"
    names, formats, offsets = [], [], []
    for f in msg.fields:
        if f.datatype not in _PF_TO_NP:
            raise ValueError(f"point field {f.name!r} has unknown datatype {f.datatype}")
        base = np.dtype(order + _PF_TO_NP[f.datatype])
        count = max(1, int(f.count))
        names.append(f.name)
        formats.append(base if count == 1 else (base, (count,)))
        offsets.append(int(f.offset))
    if not names:
        raise ValueError("point cloud has no fields")
    dt_tmp = np.dtype({"names": names, "formats": formats, "offsets": offsets})
    need = max(off + dt_tmp.fields[n][0].itemsize for n, off in zip(names, offsets))
    if int(msg.point_step) < need:
        raise ValueError(f"point_step {msg.point_step} too small, fields need {need} bytes")
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": int(msg.point_step)})


def cloud_from_msg(msg: PointCloud2) -> np.ndarray:
    """sensor_msgs/PointCloud2 -> structured array in native byte order.

    Shape (width,) for unorganised clouds (height 1), (height, width) otherwise. Non-dense
    clouds keep their NaN points; padding bytes (point_step, row_step) are skipped.
    """
    dt = cloud_dtype(msg)
    h, w = int(msg.height), int(msg.width)
    ps, rs = int(msg.point_step), int(msg.row_step)
    if rs < w * ps:
        raise ValueError(f"row_step {rs} too small, expected >= width*point_step={w * ps}")
    buf = _as_bytes(msg.data)
    n = len(buf)
    if n != rs * h:
        raise ValueError(f"cloud data has {n} bytes, expected row_step*height={rs}*{h}={rs * h}")
    raw = np.frombuffer(buf, dtype=np.uint8).reshape(h, rs)[:, :w * ps]
    pts = np.ascontiguousarray(raw).view(dt).reshape(h, w)
    native = np.dtype({"names": list(dt.names),
                       "formats": [dt.fields[k][0].newbyteorder("=") for k in dt.names]})
    out = np.empty((h, w), dtype=native)
    for name in dt.names:
        out[name] = pts[name]
    return out[0] if h == 1 else out


def cloud_to_msg(points: np.ndarray, header: Header | None = None) -> PointCloud2:
    """Structured array (N,) or (H, W) -> sensor_msgs/PointCloud2 (little endian, packed)."""
    pts = np.asarray(points)
    if pts.dtype.names is None:
        raise ValueError(f"points must be a structured array with named fields, got {pts.dtype}")
    if pts.ndim == 1:
        h, w = 1, pts.shape[0]
    elif pts.ndim == 2:
        h, w = pts.shape
    else:
        raise ValueError(f"points must be 1D or 2D, got shape {pts.shape}")
    fields, formats, offset = [], [], 0
    for name in pts.dtype.names:
        fdt = pts.dtype.fields[name][0]
        base, count = (fdt.base, int(np.prod(fdt.shape))) if fdt.shape else (fdt, 1)
        key = base.newbyteorder("=").str[1:]
        if key not in _NP_TO_PF:
            raise ValueError(f"field {name!r} has unsupported dtype {base}")
        fields.append(PointField(name=name, offset=offset, datatype=_NP_TO_PF[key], count=count))
        le = base.newbyteorder("<")
        formats.append(le if count == 1 else (le, fdt.shape))
        offset += base.itemsize * count
    packed_dt = np.dtype({"names": list(pts.dtype.names), "formats": formats})
    packed = np.empty(pts.shape, dtype=packed_dt)
    for name in pts.dtype.names:
        packed[name] = pts[name]
    msg = PointCloud2()
    msg.header = header if header is not None else Header()
    msg.height, msg.width = h, w
    msg.fields = fields
    msg.is_bigendian = False
    msg.point_step = packed_dt.itemsize
    msg.row_step = packed_dt.itemsize * w
    msg.data = packed.tobytes()
    dense = True
    for name in pts.dtype.names:
        if np.issubdtype(pts.dtype.fields[name][0].base, np.floating):
            dense &= bool(np.isfinite(pts[name]).all())
    msg.is_dense = dense
    return msg


def xyz_cloud(xyz: npt.ArrayLike, extra: dict[str, npt.ArrayLike] | None = None) -> np.ndarray:
    """Structured float32 array with fields x, y, z (+ extra float32 fields) from (N, 3)."""
    a = np.asarray(xyz, dtype=np.float32).reshape(-1, 3)
    names = ["x", "y", "z"] + list((extra or {}).keys())
    out = np.empty(a.shape[0], dtype=[(n, "<f4") for n in names])
    out["x"], out["y"], out["z"] = a[:, 0], a[:, 1], a[:, 2]
    for k, v in (extra or {}).items():
        out[k] = np.asarray(v, dtype=np.float32).reshape(-1)
    return out


def xyz_from_cloud(points: np.ndarray, drop_nan: bool = True) -> npt.NDArray[np.float64]:
    """(N, 3) float64 x, y, z of a structured cloud (organised clouds are flattened)."""
    for k in ("x", "y", "z"):
        if points.dtype.names is None or k not in points.dtype.names:
            raise ValueError(f"cloud lacks field {k!r}; has {points.dtype.names}")
    flat = points.reshape(-1)
    xyz = np.stack([flat["x"], flat["y"], flat["z"]], axis=1).astype(np.float64)
    if drop_nan:
        xyz = xyz[np.isfinite(xyz).all(axis=1)]
    return xyz


# -------------------------------------------------------------------------- laser


def scan_ranges(msg: LaserScan) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """(angles, ranges) of a scan; NaN or below range_min: NaN, above range_max: inf."""
    r = np.asarray(msg.ranges, dtype=np.float64)
    if r.size == 0:
        raise ValueError("scan has no ranges")
    inc = float(msg.angle_increment)
    if not math.isfinite(inc) or inc == 0.0 or not math.isfinite(float(msg.angle_min)):
        raise ValueError(f"scan angle_min/increment must be finite and increment != 0, "
                         f"got {msg.angle_min}/{inc}")
    angles = float(msg.angle_min) + inc * np.arange(r.size)
    r = np.where(np.isnan(r) | (r < msg.range_min), np.nan, np.where(r > msg.range_max, np.inf, r))
    return angles, r


def scan_to_points(msg: LaserScan, pose: tuple[float, float, float] | None = None,
                   mount_xy_yaw: tuple[float, float, float] = (0.0, 0.0, 0.0)
                   ) -> npt.NDArray[np.float64]:
    """(N, 2) points of the valid returns, in the scan frame or, given the robot ``pose``
    (x, y, yaw) and the scanner mount on the robot, in the pose's frame."""
    angles, r = scan_ranges(msg)
    ok = np.isfinite(r)
    a, rr = angles[ok], r[ok]
    pts = np.stack([rr * np.cos(a), rr * np.sin(a)], axis=1)
    mx, my, myaw = mount_xy_yaw
    if (mx, my, myaw) != (0.0, 0.0, 0.0):
        c, s = math.cos(myaw), math.sin(myaw)
        pts = pts @ np.array([[c, s], [-s, c]]) + np.array([mx, my])
    if pose is not None:
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        pts = pts @ np.array([[c, s], [-s, c]]) + np.array([x, y])
    return pts


def scan_to_msg(ranges: npt.ArrayLike, angle_min: float, angle_increment: float,
                range_min: float, range_max: float, header: Header | None = None,
                scan_time_s: float = 0.1) -> LaserScan:
    """LaserScan from ranges (inf = no return)."""
    r = np.asarray(ranges, dtype=np.float32)
    msg = LaserScan()
    msg.header = header if header is not None else Header()
    msg.angle_min = float(angle_min)
    msg.angle_increment = float(angle_increment)
    msg.angle_max = float(angle_min + angle_increment * (r.size - 1))
    msg.range_min, msg.range_max = float(range_min), float(range_max)
    msg.scan_time = float(scan_time_s)
    msg.time_increment = float(scan_time_s / max(1, r.size))
    msg.ranges = array.array("f", r.tobytes())
    return msg


# ------------------------------------------------------------------------- camera


def intrinsics_from_msg(msg: CameraInfo) -> CameraIntrinsics:
    """sensor_msgs/CameraInfo -> :class:`CameraIntrinsics` (from K)."""
    k = list(msg.k)
    if len(k) != 9:
        raise ValueError(f"CameraInfo.k must have 9 values, got {len(k)}")
    if not all(math.isfinite(v) for v in k):
        raise ValueError(f"CameraInfo.k must be finite, got {k}")
    return CameraIntrinsics(fx=float(k[0]), fy=float(k[4]), cx=float(k[2]), cy=float(k[5]),
                            width=int(msg.width), height=int(msg.height))


def intrinsics_to_msg(intr: CameraIntrinsics, header: Header | None = None) -> CameraInfo:
    """:class:`CameraIntrinsics` -> sensor_msgs/CameraInfo (plumb bob, no distortion)."""
    msg = CameraInfo()
    msg.header = header if header is not None else Header()
    msg.width, msg.height = int(intr.width), int(intr.height)
    msg.distortion_model = "plumb_bob"
    msg.d = [0.0] * 5
    msg.k = [intr.fx, 0.0, intr.cx, 0.0, intr.fy, intr.cy, 0.0, 0.0, 1.0]
    msg.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    msg.p = [intr.fx, 0.0, intr.cx, 0.0, 0.0, intr.fy, intr.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return msg
