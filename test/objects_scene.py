"""Scene helpers of the object costmap tests (and bench/bench_objects.py): a ray caster
of boxes and the floor (``render_depth``), so every expected size and position is known
exactly, 2D boxes of parts, laser legs, maps, and the real RGB-D frames."""

from __future__ import annotations

import math

import numpy as np

from explore_seg.core.camera import (CameraIntrinsics, apply_transform, base_from_optical,
                                     depth_to_points, invert_transform, map_from_base,
                                     project_points)
from explore_seg.core.grid import GridMap
from explore_seg.core.objects import DepthFrame, Object3D, fit_box, load_priors

K = CameraIntrinsics(fx=525.0, fy=525.0, cx=319.5, cy=239.5, width=640, height=480)
PRIORS = load_priors()
CAM_Z_M = 1.0
CAM_PITCH_RAD = 0.5


def box_parts(center_xy, size_xyz, yaw=0.0, z0=0.0):
    """(center_xyz, size_xyz, yaw) of one solid box standing at height z0."""
    return ((center_xy[0], center_xy[1], z0 + 0.5 * size_xyz[2]), tuple(size_xyz), yaw)


def table_parts(center_xy, length_m, width_m, height_m=0.75, yaw=0.0, top_m=0.04,
                leg_m=0.05):
    """A table: top slab + 4 legs at the corners (list of box_parts)."""
    parts = [box_parts(center_xy, (length_m, width_m, top_m), yaw, height_m - top_m)]
    c, s = math.cos(yaw), math.sin(yaw)
    for sx in (-1, 1):
        for sy in (-1, 1):
            lx, ly = sx * (0.5 * length_m - leg_m), sy * (0.5 * width_m - leg_m)
            xy = (center_xy[0] + c * lx - s * ly, center_xy[1] + s * lx + c * ly)
            parts.append(box_parts(xy, (leg_m, leg_m, height_m - top_m), yaw))
    return parts


def camera_pose(x=0.0, y=0.0, yaw=0.0, z=CAM_Z_M, pitch=CAM_PITCH_RAD):
    """map <- optical transform of a camera on a robot at (x, y, yaw)."""
    return map_from_base(x, y, yaw) @ base_from_optical(0.0, 0.0, z, 0.0, pitch, 0.0)


def render_depth(parts, map_from_optical, intr=K, floor=True, max_range_m=20.0):
    """Depth image (optical z, NaN for no hit) of boxes + the floor plane z = 0."""
    v, u = np.mgrid[0:intr.height, 0:intr.width]
    d_opt = np.stack([(u - intr.cx) / intr.fx, (v - intr.cy) / intr.fy,
                      np.ones(u.shape)], axis=-1).reshape(-1, 3)
    rot, org = map_from_optical[:3, :3], map_from_optical[:3, 3]
    d = d_opt @ rot.T          # ray direction in map; ray parameter t == optical z
    best = np.full(len(d), np.inf)
    if floor:
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -org[2] / d[:, 2]
        best = np.where((t > 0) & np.isfinite(t), t, best)
    for center, size, yaw in parts:
        c, s = math.cos(yaw), math.sin(yaw)
        r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])   # map -> box
        o = r @ (org - np.asarray(center))
        dl = d @ r.T
        half = 0.5 * np.asarray(size)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (-half - o) / dl, (half - o) / dl
        tmin = np.nanmax(np.minimum(t1, t2), axis=1)
        tmax = np.nanmin(np.maximum(t1, t2), axis=1)
        hit = (tmax >= np.maximum(tmin, 0.0)) & (tmin > 0)
        best = np.where(hit & (tmin < best), tmin, best)
    best[best > max_range_m] = np.inf
    out = best.reshape(intr.height, intr.width).astype(np.float32)
    out[~np.isfinite(out)] = np.nan
    return out


def project_box(parts, map_from_optical, intr=K):
    """Tight 2D box (x0, y0, x1, y1) of the corners of the given parts."""
    pts = []
    for center, size, yaw in parts:
        obj = Object3D("x", 1.0, center, size, yaw, 0)
        for z in (center[2] - 0.5 * size[2], center[2] + 0.5 * size[2]):
            pts += [(x, y, z) for x, y in obj.footprint()]
    opt = apply_transform(invert_transform(map_from_optical), np.array(pts))
    u, v, _ = project_points(opt, intr)
    return (max(u.min(), 0), max(v.min(), 0), min(u.max(), intr.width - 1),
            min(v.max(), intr.height - 1))


class Det:
    """Minimal detection (duck-typed like core.detector.Detection)."""

    def __init__(self, cls_name, box_xyxy, score=0.9):
        self.cls_name, self.box_xyxy, self.score = cls_name, tuple(box_xyxy), score


def leg_scan(centres, radius_m=0.025, n=5):
    """Scan points on the near half-circle of round legs (map frame)."""
    out = []
    for cx, cy in centres:
        a = np.linspace(math.pi * 0.6, math.pi * 1.4, n)
        out.append(np.stack([cx + radius_m * np.cos(a), cy + radius_m * np.sin(a)], axis=1))
    return np.vstack(out)


def desk_at_wall_map(desk, wall_x_m, wall_half_m=0.05):
    """2D map (0.05 m cells, x 0..4, y -2..2) of a wall (|x - wall_x_m| <= wall_half_m)
    and the legs of ``desk`` (table_parts), as the lidar maps them."""
    grid = GridMap(np.zeros((80, 80), np.int8), 0.05, (0.0, -2.0))
    x, y = grid.cells_to_world(*np.indices(grid.shape))
    occ = np.abs(x - wall_x_m) <= wall_half_m
    for (cx, cy, _), _, _ in desk[1:]:
        occ |= (np.abs(x - cx) <= 0.03) & (np.abs(y - cy) <= 0.03)
    return grid.with_data(np.where(occ, 100, 0).astype(np.int8))


def make_obj(x, y, cls="chair", size=(0.6, 0.6, 0.9), yaw=0.0, n=100):
    """An Object3D standing on the floor at (x, y) (a chair unless told)."""
    return Object3D(cls, 0.9, (x, y, 0.5 * size[2]), size, yaw, n)


def measured_table(height_m, params):
    """A 1.2 x 0.8 table at (2, 0) with its top at ``height_m``, fitted to points on its
    top face and legs (as a camera measures them)."""
    table = table_parts((2.0, 0.0), 1.2, 0.8, height_m=height_m)
    gx, gy = np.meshgrid(np.linspace(1.42, 2.58, 12), np.linspace(-0.38, 0.38, 8))
    top = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, height_m)])
    legs = np.array([(c[0], c[1], z) for c, _, _ in table[1:]
                     for z in np.linspace(0.05, height_m - 0.05, 6)])
    return table, fit_box(np.vstack([top, legs]), "dining table", 0.9,
                          PRIORS["dining table"], params)


def floor_transform(depth_m, intr, rng):
    """map <- optical for a frame with unknown pose: the floor is the large plane with
    (almost) nothing below it; the camera sits at its height above it (test helper)."""
    mask = np.zeros(depth_m.shape, bool)
    mask[::4, ::4] = True
    pts = depth_to_points(depth_m, intr, mask).astype(np.float64)
    best = None
    for _ in range(600):
        s = pts[rng.choice(len(pts), 3, replace=False)]
        n = np.cross(s[1] - s[0], s[2] - s[0])
        if np.linalg.norm(n) < 1e-9:
            continue
        n /= np.linalg.norm(n)
        n = -n if n[1] > 0 else n          # up = -y in the optical frame
        if n[1] > -0.7:
            continue
        d = -n @ s[0]
        signed = pts @ n + d
        if np.mean(signed < -0.05) > 0.01:
            continue
        support = int(np.count_nonzero(np.abs(signed) < 0.03))
        if best is None or support > best[0]:
            best = (support, n, d)
    assert best is not None, "no floor plane found"
    _, z, d = best
    x = np.array([0.0, 0.0, 1.0]) - z * z[2]
    x /= np.linalg.norm(x)
    t = np.eye(4)
    t[:3, :3] = np.stack([x, np.cross(z, x), z])
    t[2, 3] = d
    return t


def real_frames(names):
    """(frame entry, DepthFrame) of the named real frames (:mod:`rgbd_data`; skips the
    test, naming the missing file, when one is absent)."""
    import cv2

    from rgbd_data import annotations, frame_dir

    rng = np.random.default_rng(0)
    for f in annotations(names).values():
        intr = CameraIntrinsics(**{k: f["intrinsics"][k]
                                   for k in ("fx", "fy", "cx", "cy", "width", "height")})
        raw = cv2.imread(str(frame_dir(f["name"]) / f["depth_file"]), cv2.IMREAD_UNCHANGED)
        depth = raw.astype(np.float32) / float(f["depth_units_per_m"])
        depth[raw == 0] = np.nan
        yield f, DepthFrame(depth, intr, floor_transform(depth, intr, rng))
