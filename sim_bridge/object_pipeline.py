"""The object costmap node's work on a lock-step engine: oracle detections, depth, scan.

:class:`ObjectPipeline` runs the ``object_costmap`` node's core code
(:func:`~explore_seg.core.objects.process_frame` + :class:`~explore_seg.core.objects.ObjectMap`)
on a :class:`~sim_bridge.engine.SimEngine`'s camera frames and latest scan, and tells the
lock step when the boxes changed enough to give navigation a new object layer.
Everything is in the map's frame: with a mapping error model (:mod:`sim_bridge.slam_error`)
frames, scans and the robot are placed by their SLAM poses, as the node places them.
"""

from __future__ import annotations

import math
import time
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from explore_seg.core.camera import CameraIntrinsics
from explore_seg.core.detector import Detector, DetectorParams
from explore_seg.core.objects import WALL_OCCUPIED_THRESHOLD, DepthFrame, ObjectMap, ObjectParams, \
    WallMask, load_priors, process_frame, wall_mask
from explore_seg.core.pose_fusion import Pose2D, compose, inverse
from sim_bridge.engine import SimEngine
from sim_bridge.sensors import CLASS_IDS

if TYPE_CHECKING:
    from sim_bridge.lockstep import LockstepParams

#: One black pixel, broadcast to the image passed to the oracle detector (which reads
#: only the semantic and instance images).
_BLACK = np.zeros(3, dtype=np.uint8)


def scan_points_map(engine: SimEngine) -> npt.NDArray[np.float64]:
    """Latest scan's returns in the map frame, shape (N, 2) (empty before the first)."""
    scan = engine.latest_scan
    if scan is None:
        return np.zeros((0, 2))
    g = engine.scan_geometry
    r = np.asarray(scan.ranges, dtype=np.float64)
    ang = g.angle_min_rad + g.angle_increment_rad * np.arange(r.shape[0])
    ok = np.isfinite(r) & (r >= g.range_min_m) & (r < g.range_max_m)
    x, y, yaw = scan.map_pose or scan.pose
    mx = engine.params.lidar_mount_x_m
    ox, oy = x + mx * math.cos(yaw), y + mx * math.sin(yaw)
    a = yaw + ang[ok]
    return np.column_stack([ox + r[ok] * np.cos(a), oy + r[ok] * np.sin(a)])


class ClosureWatch:
    """The simulator's loop closures as the lock step's nodes see them: :meth:`rerendered`
    says whether a closure since the previous call re-rendered the map (the exact signal:
    no closure missed, none invented; the nodes detect corrections from their inputs)."""

    def __init__(self, engine: SimEngine) -> None:
        self.engine = engine
        self._seen = 0

    def rerendered(self) -> bool:
        """True when a closure since the last call re-rendered the map."""
        return self.correction() is not None

    def correction(self) -> Pose2D | None:
        """The closures since the last call when one of them re-rendered the map: the
        rigid map-frame transform their pose jumps make together (the first applied
        first); None otherwise."""
        slam = self.engine.slam_error
        if slam is None or len(slam.closures) == self._seen:
            return None
        new = slam.closures[self._seen:]
        self._seen = len(slam.closures)
        if not any(c.rerendered for c in new):
            return None
        jump: Pose2D = (0.0, 0.0, 0.0)
        for c in new:
            jump = compose(c.jump, jump)
        return jump


class ObjectPipeline:
    """The object costmap node's work on one engine: oracle detections + depth + scan."""

    def __init__(self, engine: SimEngine, params: ObjectParams, seed: int,
                 lockstep: LockstepParams) -> None:
        self.engine = engine
        self.params = params
        self.priors = load_priors(params.priors_path or None)
        self.detector = Detector(DetectorParams(
            backend="oracle", oracle_miss_prob=lockstep.oracle_miss_prob,
            oracle_jitter_px=lockstep.oracle_jitter_px, oracle_seed=int(seed)),
            sim_class_ids=CLASS_IDS)
        self.map = ObjectMap(params, self.priors)
        cp = engine.params.camera_params()
        self.intrinsics: CameraIntrinsics = cp.intrinsics()
        self.tolerance_m = lockstep.object_update_tolerance_m
        self._last_stamp = -1.0
        self._published: list[tuple[float, ...]] = []
        self._published_depth = 0
        self._walls: tuple[int, WallMask] | None = None   # (map version, its wall mask)
        self._walls_occ: npt.NDArray[np.bool_] | None = None   # its occupied cells
        self._closures = ClosureWatch(engine)   # SLAM corrections seen
        self._correction_s = -math.inf   # sim time of the last one

    def _after_correction(self) -> None:
        """A loop closure that re-rendered the map since the last call: forget the boxes
        and depth voxels placed since the previous one, but move those of the last
        ``correction_move_recent_s`` with the SLAM pose's jump
        (:meth:`ObjectMap.forget_since`).

        The simulator's own record of its closures is the signal (exact: no closure
        missed, none invented); the object_costmap node, which has no such record,
        detects corrections from its inputs (:mod:`explore_seg.core.corrections`).
        """
        jump = self._closures.correction()
        if jump is None:
            return
        self.map.forget_since(None if self._correction_s == -math.inf
                              else int(round(self._correction_s * 1e9)),
                              jump, int(round(self.engine.time_s * 1e9)))
        self._correction_s = self.engine.time_s

    def _wall_mask(self) -> WallMask:
        """The wall mask of the engine's map, computed once per map version (as the node
        computes it once per map message); a new version whose occupied cells are those
        of the last computed one reuses its walls (they depend on nothing else)."""
        version = self.engine.map_version
        if self._walls is None or self._walls[0] != version:
            grid = self.engine.map
            occ = grid.data >= WALL_OCCUPIED_THRESHOLD
            last = self._walls_occ
            if (self._walls is not None and last is not None and last.shape == occ.shape
                    and np.array_equal(last, occ)):
                walls = self._walls[1].with_grid(grid)
            else:
                walls = wall_mask(grid, self.params, WALL_OCCUPIED_THRESHOLD)
            self._walls, self._walls_occ = (version, walls), occ
        return self._walls[1]

    def update(self, timings: dict[str, list[float]]) -> bool:
        """Process the newest camera frame if unseen; True when one was processed.

        Appends the oracle detection time to ``timings["detection"]`` and the rest
        (3D boxes, fusion; the layer is timed by the caller) to ``timings["objects"]``.
        """
        self.map.note_robot_position(*self.engine.slam_pose[:2])
        self._after_correction()
        cam = self.engine.latest_camera
        if cam is None or cam.stamp_s <= self._last_stamp:
            return False
        self._last_stamp = cam.stamp_s
        fr = cam.frame
        tf = np.eye(4)
        tf[:3, :3] = fr.rotation
        tf[:3, 3] = fr.translation
        if cam.map_pose is not None and cam.map_pose != cam.pose:
            tf = _map_from_world(compose(cam.map_pose, inverse(cam.pose))) @ tf
        t0 = time.perf_counter()
        # The oracle reads the semantic and instance images only: it gets a blank view of
        # the image's shape, and the frame's colour image is never shaded.
        rgb = (fr.rgb if self.detector.network is not None
               else np.broadcast_to(_BLACK, fr.semantic.shape + (3,)))
        dets = self.detector.detect(rgb, semantic=fr.semantic, instance=fr.instance)
        t1 = time.perf_counter()
        depth = DepthFrame(fr.depth_m, self.intrinsics, tf)
        walls = self._wall_mask()
        res = process_frame(depth, dets, self.priors, self.params, scan_points_map(self.engine),
                            walls)
        self.map.update(res.objects + res.unknown, depth, int(round(cam.stamp_s * 1e9)),
                        robot_xy=self.engine.slam_pose[:2], walls=walls)
        timings["detection"].append((t1 - t0) * 1e3)
        timings["objects"].append((time.perf_counter() - t1) * 1e3)
        return True

    def changed(self) -> bool:
        """True when the depth obstacles changed or the boxes differ from the last
        :meth:`mark_published` ones by more
        than the tolerance (or their number changed)."""
        cur = self._signature()
        if self._depth_version() != self._published_depth:
            return True
        if len(cur) != len(self._published):
            return True
        if not cur:
            return False
        a, b = np.asarray(cur), np.asarray(self._published)
        return bool(np.abs(a - b).max() > self.tolerance_m)

    def mark_published(self) -> None:
        self._published = self._signature()
        self._published_depth = self._depth_version()

    def _depth_version(self) -> int:
        return self.map.depth.version if self.map.depth is not None else 0

    def _signature(self) -> list[tuple[float, ...]]:
        return [(o.center_xyz[0], o.center_xyz[1], o.size_xyz[0], o.size_xyz[1],
                 math.sin(2 * o.yaw), math.cos(2 * o.yaw)) for _, o in self.map.boxes()]


def _map_from_world(drift: tuple[float, float, float]) -> npt.NDArray[np.float64]:
    """The 4x4 homogeneous transform of a map <- world drift (x, y, yaw)."""
    c, s = math.cos(drift[2]), math.sin(drift[2])
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    out[:2, 3] = drift[:2]
    return out
