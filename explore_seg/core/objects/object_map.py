"""The object map: boxes fused in the map frame over frames (matching, merging, misses
where the camera sees through an object, the robot's own disk and path) and its outputs
(the occupancy layer, the virtual point cloud, the boxes)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.camera import apply_transform, invert_transform, project_points
from explore_seg.core.grid import GridMap
from explore_seg.core.objects.boxes import Object3D
from explore_seg.core.objects.depth_obstacles import DepthObstacles
from explore_seg.core.objects.frame import DepthFrame
from explore_seg.core.objects.fusion import footprint_iou, fuse_boxes
from explore_seg.core.objects.geometry import points_in_rect
from explore_seg.core.objects.params import UNKNOWN_CLASS, ObjectParams
from explore_seg.core.objects.priors import SizePrior
from explore_seg.core.objects.walls import WallMask
from explore_seg.core.swept import SweptPath


@dataclass
class TrackedObject:
    """An object of the :class:`ObjectMap` with its bookkeeping."""

    id: int
    obj: Object3D
    hits: int = 1
    misses: int = 0
    last_seen_ns: int = 0
    #: Frames that saw a tentative object's place unoccluded without detecting it.
    unmatched: int = 0


def box_samples(obj: Object3D, spacing_m: float, surface_only: bool = True
                ) -> npt.NDArray[np.float64]:
    """Points on (or filling) a box on a grid of ``spacing_m`` (cell centres), shape (N, 3).

    ``surface_only`` keeps only the outer layer of the grid.
    """
    n = [max(int(math.ceil(s / spacing_m)), 1) for s in obj.size_xyz]
    axes = [((np.arange(k) + 0.5) / k - 0.5) * s for k, s in zip(n, obj.size_xyz)]
    gx, gy, gz = np.meshgrid(*axes, indexing="ij")
    if surface_only:
        ix, iy, iz = np.meshgrid(*(np.arange(k) for k in n), indexing="ij")
        outer = ((ix == 0) | (ix == n[0] - 1) | (iy == 0) | (iy == n[1] - 1)
                 | (iz == 0) | (iz == n[2] - 1))
        gx, gy, gz = gx[outer], gy[outer], gz[outer]
    local = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1)
    c, s = math.cos(obj.yaw), math.sin(obj.yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return local @ rot.T + np.asarray(obj.center_xyz)


class ObjectMap:
    """Objects fused in the map frame.

    Parameters
    ----------
    params : ObjectParams
    priors : dict of str to SizePrior
        Merged sizes are capped by the class's ``max_xy_m`` / ``max_z_m``.
    """

    def __init__(self, params: ObjectParams, priors: dict[str, SizePrior]) -> None:
        self.params = params
        self.priors = dict(priors)
        self._objects: list[TrackedObject] = []
        self._next_id = 0
        self._swept = SweptPath()
        #: Generic obstacles from depth (None when ``params.depth_obstacles`` is off).
        self.depth: DepthObstacles | None = (DepthObstacles(params) if params.depth_obstacles
                                             else None)

    def __len__(self) -> int:
        return len(self._objects)

    def note_robot_position(self, x_m: float, y_m: float) -> None:
        """Record where the robot is (map frame; call at the pose rate): the layer and
        the cloud are cleared along this path (``swept_clear_radius_m``)."""
        self._swept.add(float(x_m), float(y_m))

    @property
    def swept(self) -> SweptPath:
        """The robot's recorded path."""
        return self._swept

    @property
    def tracked(self) -> list[TrackedObject]:
        """Current objects with bookkeeping (copy of the list)."""
        return list(self._objects)

    def objects(self) -> list[Object3D]:
        """Current objects."""
        return [t.obj for t in self._objects]

    def clear(self) -> None:
        """Forget every object (and the depth obstacles)."""
        self._objects.clear()
        if self.depth is not None:
            self.depth.clear()

    def forget_since(self, stamp_ns: int | None,
                     jump: tuple[float, float, float] | None = None,
                     now_ns: int | None = None) -> bool:
        """After a SLAM correction: forget what was placed at poses it corrected.

        The tracked boxes last seen at or after ``stamp_ns`` (the previous correction;
        None: every box) are dropped when ``boxes_forget_on_correction``, the depth voxels
        last marked then when ``depth_forget_on_correction``. Their evidence came at
        uncorrected poses, and a pose-graph correction spreads over the poses since the
        previous one, so no single transform moves them all right; a dropped box in view
        is found again, where the corrected map has it, by the next frame. Older boxes
        stay: their evidence predates the poses the correction moved.

        Given the correction's ``jump`` (the rigid map-frame transform that took the
        robot's pose from before to after it) and its time ``now_ns``, those last seen
        within ``correction_move_recent_s`` before ``now_ns`` are moved by it instead
        (:meth:`Object3D.moved`, :meth:`DepthObstacles.forget_since`): they were placed
        at the pose error the robot had just before, which the jump corrects near the
        robot, and an obstacle beside the robot, outside the camera's view, would not be
        found again before the robot meets it.

        Returns
        -------
        bool
            True when a box was dropped or moved or the depth obstacle columns changed.
        """
        p = self.params
        recent_ns = (now_ns - int(round(p.correction_move_recent_s * 1e9))
                     if jump is not None and now_ns is not None
                     and p.correction_move_recent_s > 0 else None)
        changed = False
        if p.boxes_forget_on_correction:
            kept = []
            for t in self._objects:
                if stamp_ns is not None and t.last_seen_ns < stamp_ns:
                    kept.append(t)
                elif recent_ns is not None and t.last_seen_ns >= recent_ns:
                    assert jump is not None
                    t.obj = t.obj.moved(jump)
                    kept.append(t)
                    changed = True
            changed |= len(kept) != len(self._objects)
            self._objects = kept
        if p.depth_forget_on_correction and self.depth is not None:
            changed |= self.depth.forget_since(
                -math.inf if stamp_ns is None else stamp_ns * 1e-9,
                jump if recent_ns is not None else None,
                math.inf if recent_ns is None else recent_ns * 1e-9)
        return changed

    def time_went_back(self, stamp_ns: int) -> None:
        """The clock jumped back to ``stamp_ns``: the boxes last seen and the depth voxels
        last marked later (on the old time line) are kept, restamped to ``stamp_ns``, so
        that a correction's :meth:`forget_since` and the voxels' decay judge them on the
        new time line."""
        for t in self._objects:
            t.last_seen_ns = min(t.last_seen_ns, int(stamp_ns))
        if self.depth is not None:
            self.depth.time_went_back(stamp_ns * 1e-9)

    # ------------------------------------------------------------------ update
    def update(self, observations: Sequence[Object3D], frame: DepthFrame | None = None,
               stamp_ns: int = 0, robot_xy: Sequence[float] | None = None,
               walls: WallMask | None = None) -> None:
        """Fuse one frame's observations; count misses of unseen objects.

        Parameters
        ----------
        observations : sequence of Object3D
            Boxes found in this frame (detections and unclassified).
        frame : DepthFrame, optional
            The frame they came from; needed to count misses (objects in view that the
            camera sees through). Without it nothing is missed.
        stamp_ns : int
            Frame time.
        robot_xy : sequence of 2 float, optional
            Robot position (map frame). The robot's own body proves that no object stands
            there: observations and tracked objects whose footprint reaches at least
            ``robot_clear_fraction`` of ``robot_radius_m`` into the robot's disk are
            dropped (else a misplaced box can enclose the robot and end exploration).
        walls : WallMask, optional
            The 2D map's walls: their depth points do not mark depth obstacles.
        """
        if frame is not None and self.depth is not None:
            self.depth.update(frame, stamp_ns * 1e-9, walls)
        if robot_xy is not None:
            self.note_robot_position(robot_xy[0], robot_xy[1])
        if robot_xy is not None and self.params.robot_clear_fraction > 0:
            observations = [o for o in observations if not self._on_robot(o, robot_xy)]
            self._objects = [t for t in self._objects if not self._on_robot(t.obj, robot_xy)]
        matched: set[int] = set()
        for obs in observations:
            t = self._best_match(obs)
            if t is None and self._explained_by_other(obs):
                continue
            if t is None:
                t = TrackedObject(self._next_id, obs, last_seen_ns=stamp_ns)
                self._next_id += 1
                self._objects.append(t)
            else:
                t.obj = self._merge(t.obj, obs)
                t.hits += 1
                t.misses = 0
                t.last_seen_ns = stamp_ns
            matched.add(t.id)
        self._merge_overlapping()
        if frame is not None:
            p = self.params
            for t, visible in zip(self._objects, self._in_view(frame)):
                if not visible or t.id in matched:
                    continue
                if self._seen_through(t.obj, frame):
                    t.misses += 1
                if t.hits < p.confirm_hits and self._centre_unoccluded(t.obj, frame):
                    t.unmatched += 1
            self._objects = [t for t in self._objects
                             if t.misses < p.clear_after_misses
                             and (t.hits >= p.confirm_hits
                                  or t.unmatched < p.tentative_max_unmatched)]
        if len(self._objects) > self.params.max_objects:
            self._objects.sort(key=lambda t: (t.misses, -t.hits, -t.last_seen_ns, t.id))
            del self._objects[self.params.max_objects:]
            self._objects.sort(key=lambda t: t.id)

    def _on_robot(self, obj: Object3D, robot_xy: Sequence[float]) -> bool:
        """True when ``obj``'s footprint reaches ``robot_clear_fraction`` of the radius
        into the robot's disk (see :meth:`update`)."""
        # Reaching depth f * R into the disk = the centre within (1 - f) * R of the box
        # (Euclidean distance to the rectangle, 0 inside it).
        margin = self.params.robot_radius_m * (1.0 - self.params.robot_clear_fraction)
        c, s = math.cos(obj.yaw), math.sin(obj.yaw)
        dx, dy = robot_xy[0] - obj.center_xyz[0], robot_xy[1] - obj.center_xyz[1]
        out_u = max(abs(dx * c + dy * s) - 0.5 * obj.size_xyz[0], 0.0)
        out_v = max(abs(-dx * s + dy * c) - 0.5 * obj.size_xyz[1], 0.0)
        return math.hypot(out_u, out_v) <= margin

    def _explained_by_other(self, obs: Object3D) -> bool:
        """True when at least ``explained_fraction`` of ``obs``'s measured surface points
        lie inside the footprint (grown by ``miss_sample_spacing_m``) of one confirmed
        object of another known class: the detection's depth crop held that object."""
        p = self.params
        pts = obs.surface
        if (p.explained_fraction <= 0 or pts is None or len(pts) < p.miss_min_samples
                or obs.cls == UNKNOWN_CLASS):
            return False
        xy = np.asarray(pts[:, :2], dtype=np.float64)
        for t in self._objects:
            o = t.obj
            if t.hits < p.confirm_hits or o.cls == obs.cls or o.cls == UNKNOWN_CLASS:
                continue
            inside = points_in_rect(xy, o.center_xyz[:2], o.size_xyz[:2], o.yaw,
                                    p.miss_sample_spacing_m)
            if float(np.mean(inside)) >= p.explained_fraction:
                return True
        return False

    @staticmethod
    def _compatible(a: str, b: str) -> bool:
        return a == b or a == UNKNOWN_CLASS or b == UNKNOWN_CLASS

    def _centres_radii(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Footprint centres (N, 2) and circumradii (N,) of the tracked objects."""
        if not self._objects:
            return np.zeros((0, 2)), np.zeros(0)
        c = np.array([t.obj.center_xyz[:2] for t in self._objects], dtype=np.float64)
        r = 0.5 * np.array([math.hypot(t.obj.size_xyz[0], t.obj.size_xyz[1])
                            for t in self._objects], dtype=np.float64)
        return c, r

    def _best_match(self, obs: Object3D) -> TrackedObject | None:
        if not self._objects:
            return None
        centres, radii = self._centres_radii()
        dist = np.hypot(centres[:, 0] - obs.center_xyz[0], centres[:, 1] - obs.center_xyz[1])
        r_obs = 0.5 * math.hypot(obs.size_xyz[0], obs.size_xyz[1])
        # Only footprints whose circumcircles meet can overlap (vectorised pre-filter).
        near = np.flatnonzero((dist <= self.params.merge_distance_m) | (dist < radii + r_obs))
        best, best_key = None, None
        for i in near:
            t = self._objects[int(i)]
            if not self._compatible(t.obj.cls, obs.cls):
                continue
            iou = footprint_iou(t.obj, obs)
            if dist[i] <= self.params.merge_distance_m or iou > self.params.merge_iou:
                key = (iou, -float(dist[i]))
                if best_key is None or key > best_key:
                    best, best_key = t, key
        return best

    def _merge(self, old: Object3D, new: Object3D) -> Object3D:
        """Fuse a re-detection ``new`` into ``old`` (see :func:`fuse_boxes`)."""
        return fuse_boxes(old, new, self.params, self.priors.get(
            old.cls if old.cls != UNKNOWN_CLASS else new.cls))

    def _merge_overlapping(self) -> None:
        """Merge tracked objects that came to overlap (same class, IoU > merge_iou).

        Only pairs whose footprint circumcircles meet are tested (vectorised pre-filter).
        """
        while True:
            centres, radii = self._centres_radii()
            n = len(self._objects)
            if n < 2:
                return
            d = np.hypot(centres[:, None, 0] - centres[None, :, 0],
                         centres[:, None, 1] - centres[None, :, 1])
            ii, jj = np.nonzero(np.triu(d < radii[:, None] + radii[None, :], k=1))
            pair = next(((int(i), int(j)) for i, j in zip(ii, jj)
                         if self._compatible(self._objects[i].obj.cls, self._objects[j].obj.cls)
                         and footprint_iou(self._objects[i].obj, self._objects[j].obj)
                         > self.params.merge_iou), None)
            if pair is None:
                return
            a, b = self._objects[pair[0]], self._objects[pair[1]]
            a.obj = self._merge(a.obj, b.obj)
            a.hits += b.hits
            a.misses = min(a.misses, b.misses)
            a.last_seen_ns = max(a.last_seen_ns, b.last_seen_ns)
            del self._objects[pair[1]]

    def _in_view(self, frame: DepthFrame) -> npt.NDArray[np.bool_]:
        """Objects whose bounding sphere meets the camera's view frustum (up to
        ``max_depth_m``), shape (N,) bool (vectorised pre-filter of :meth:`_seen_through`)."""
        if not self._objects:
            return np.zeros(0, dtype=bool)
        c = np.array([t.obj.center_xyz for t in self._objects], dtype=np.float64)
        r = 0.5 * np.linalg.norm(np.array([t.obj.size_xyz for t in self._objects]), axis=1)
        opt = apply_transform(invert_transform(frame.map_from_optical), c)
        x, y, z = opt[:, 0], opt[:, 1], opt[:, 2]
        k = frame.intrinsics
        ok = (z > -r) & (z < self.params.max_depth_m + r)
        # Side planes through the optical centre (u = -0.5, u = W - 0.5, same for v).
        for f, cc, n, coord in ((k.fx, k.cx, k.width, x), (k.fy, k.cy, k.height, y)):
            lo, hi = -0.5 - cc, n - 0.5 - cc
            ok &= (f * coord - lo * z) / math.hypot(f, lo) >= -r
            ok &= (hi * z - f * coord) / math.hypot(f, hi) >= -r
        return ok

    def _depths_at(self, points_map: npt.NDArray[np.float64], frame: DepthFrame
                   ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """For the map points in front of the camera (up to ``max_depth_m``) whose pixel
        lies in the image with a valid depth (finite, > 0): their depth along the optical
        axis and the frame's measured depth at their pixel, both shape (M,)."""
        opt = apply_transform(invert_transform(frame.map_from_optical), points_map)
        z = opt[:, 2]
        front = (z > 1e-6) & (z <= self.params.max_depth_m)
        opt, z = opt[front], z[front]
        k = frame.intrinsics
        fu, fv, _ = project_points(opt, k)
        u, v = np.round(fu).astype(np.int64), np.round(fv).astype(np.int64)
        inside = (u >= 0) & (u < k.width) & (v >= 0) & (v < k.height)
        measured = frame.depth_m[v[inside], u[inside]]
        ok = np.isfinite(measured) & (measured > 0)
        return z[inside][ok], measured[ok]

    def _centre_unoccluded(self, obj: Object3D, frame: DepthFrame) -> bool:
        """True when the box's centre is in the image, within ``max_depth_m``, and nothing
        stands in front of the box there (the depth at its pixel reaches the box: at least
        its centre's depth - half its footprint diagonal - ``miss_depth_margin_m``)."""
        z, measured = self._depths_at(np.asarray([obj.center_xyz], dtype=np.float64), frame)
        if len(z) == 0:
            return False
        front = (float(z[0]) - 0.5 * math.hypot(obj.size_xyz[0], obj.size_xyz[1])
                 - self.params.miss_depth_margin_m)
        return float(measured[0]) >= front

    def _seen_through(self, obj: Object3D, frame: DepthFrame) -> bool:
        """True when the camera sees beyond most of the object's visible measured surface
        points (:attr:`Object3D.surface`; the box's faces when it has none)."""
        p = self.params
        samples = (obj.surface.astype(np.float64) if obj.surface is not None
                   and len(obj.surface) >= p.miss_min_samples
                   else box_samples(obj, p.miss_sample_spacing_m, surface_only=True))
        z, measured = self._depths_at(samples, frame)
        if len(z) < p.miss_min_samples:
            return False
        through = measured > z + p.miss_depth_margin_m
        return float(np.mean(through)) >= p.miss_free_fraction

    # ----------------------------------------------------------------- outputs
    def rasterize(self, grid: GridMap) -> GridMap:
        """The object layer on ``grid``'s geometry.

        Parameters
        ----------
        grid : GridMap
            Geometry (size, resolution, origin, frame, stamp) to align with; its data is
            not read.

        Returns
        -------
        GridMap
            ``object_value`` inside every footprint (cells whose centre is inside, plus
            the outline so thin objects keep at least one cell) and on every depth
            obstacle column, ``background_value`` elsewhere; the robot's swept path is
            cleared.
        """
        p = self.params
        img = np.full(grid.shape, p.background_value, dtype=np.int8)
        shift = 4
        polys = []
        for t in self._objects:
            corners = t.obj.footprint()
            rows, cols = grid.world_to_cell_float(corners[:, 0], corners[:, 1])
            # Cell (r, c) spans [c, c + 1): its centre is at c + 0.5 -> pixel c in cv2.
            pts = np.stack([cols - 0.5, rows - 0.5], axis=1) * (1 << shift)
            polys.append(np.round(pts).astype(np.int32))
        # One fill per box: a single fillPoly over all boxes fills even-odd, so the
        # overlap of two boxes (a chair pushed under a desk) would be left out.
        for poly in polys:
            cv2.fillConvexPoly(img, poly, int(p.object_value), lineType=cv2.LINE_8,
                               shift=shift)
        if polys:
            cv2.polylines(img, polys, True, int(p.object_value), lineType=cv2.LINE_8,
                          shift=shift)
        depth = self.depth is not None and self.depth.version > 0 and len(self.depth) > 0
        if depth:
            img[self.depth.mask(grid)] = p.object_value  # type: ignore[union-attr]
        if polys or depth:
            if p.swept_clear_radius_m > 0 and len(self._swept):
                img[self._swept.mask(grid, p.swept_clear_radius_m)] = p.background_value
        return grid.with_data(img)

    def virtual_cloud(self, spacing_m: float | None = None) -> npt.NDArray[np.float32]:
        """Points filling every box, and the centres of the depth obstacles' voxels (for
        a Nav2 voxel/obstacle layer), shape (N, 3).

        The boxes' spacing grows (doubling) until at most ``max_cloud_points`` points remain.

        Raises
        ------
        ValueError
            If ``spacing_m`` is not > 0.
        """
        spacing = self.params.cloud_spacing_m if spacing_m is None else float(spacing_m)
        if not spacing > 0:
            raise ValueError(f"spacing_m must be > 0, got {spacing_m}")
        depth = (self.depth.centres() if self.depth is not None and len(self.depth)
                 else np.zeros((0, 3)))
        if not self._objects and not len(depth):
            return np.zeros((0, 3), dtype=np.float32)
        while self._objects:
            total = sum(int(np.prod([max(math.ceil(s / spacing), 1) for s in t.obj.size_xyz]))
                        for t in self._objects)
            if total <= self.params.max_cloud_points:
                break
            spacing *= 2.0
        clouds = [box_samples(t.obj, spacing, surface_only=False) for t in self._objects]
        cloud = np.vstack(clouds + [depth])
        r = self.params.swept_clear_radius_m
        if r > 0 and len(self._swept) and len(cloud):
            # Rasterise the swept corridor over the cloud's extent (cells of half the
            # spacing) and drop the points on it, as rasterize() drops the cells.
            res = 0.5 * spacing
            lo = cloud[:, :2].min(axis=0) - res
            shape = tuple(int(v) for v in np.ceil((cloud[:, :2].max(axis=0) - lo) / res) + 2)
            geo = GridMap(np.zeros((shape[1], shape[0]), np.int8), res,
                          (float(lo[0]), float(lo[1])))
            rows, cols = geo.world_to_cells(cloud[:, 0], cloud[:, 1])
            cloud = cloud[~self._swept.mask(geo, r)[rows, cols]]
        return cloud.astype(np.float32)

    def boxes(self) -> list[tuple[int, Object3D]]:
        """``(id, Object3D)`` of every object (for markers)."""
        return [(t.id, t.obj) for t in self._objects]


# ---------------------------------------------------------------------- pipeline
