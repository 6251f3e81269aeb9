"""Lock-step exploration runs: the simulator and the explorer's core code in one loop.

:func:`run_exploration` drives a :class:`~sim_bridge.engine.SimEngine` without any
real-time waiting and, at the explorer's rates, runs the SAME core code the ROS nodes
run:

* the decision core :class:`explore_seg.core.explorer.Explorer` (frontier detection with
  the object layer as extra obstacles, path lengths, costs and goal keeping) - the
  ``target_selector`` node; a NEW_GOAL is sent to the engine's navigation stand-in like a
  ``goal_pose`` message;
* DuDe regions (:class:`~explore_seg.core.segmentation.IncrementalSegmenter`) - the
  ``segmentation`` node;
* the object costmap (:func:`~explore_seg.core.objects.process_frame` +
  :class:`~explore_seg.core.objects.ObjectMap`) fed by the oracle detector backend from
  the engine's camera frames and by the latest scan (unclassified objects from laser
  legs), rasterised onto the map and given both to target selection and, as an
  obstacle layer, to the navigation stand-in - the ``object_costmap`` node.

Strategies (:data:`STRATEGY_SPECS`, the benchmark's arms): ``paper`` (eq. 1-3, regions and
object costmap), ``paper_noseg`` (regions off, i.e. gamma = 0), ``paper_noobj`` (no object
costmap), ``nearest``, ``explore_lite``, ``rrt_exploration`` (its RRTs seeded with the
run's seed) and ``routed``. The three baselines run as their original packages would: no
object costmap anywhere (not in frontier detection, not in the planner) and no regions.
Any other registered strategy (:mod:`explore_seg.core.selection.strategies`) runs with its
default arm (:func:`strategy_spec`).

A run stops at completion (coverage >= ``coverage_target_pct`` of the ground-truth
explorable area, measured by the engine's metrics), when the goal manager reports
DONE (no reachable frontier left) or at ``max_sim_time_s``. Runs are deterministic for
a seed; the seed perturbs the start pose (position within ``start_jitter_m``, heading
within ``start_yaw_jitter_rad``), the lidar noise and the oracle's misses and jitter,
so seeded runs differ from one another.

Parameters: the nodes' parameters come from ``config/explorer.yaml`` when it exists
(:func:`load_explorer_params`), else from the dataclass defaults, so a lock-step run and
the ROS explorer use the same values; decisions run at ``SelectorNodeParams.rate_hz`` and
the object costmap at ``ObjectCostmapNodeParams.rate_hz`` unless :class:`LockstepParams` says
otherwise.

Differences from the ROS pipeline (intentional): everything is synchronous (every
decision sees the frontiers, regions and object layer of the current map, where the
nodes see their latest messages, possibly a cycle old); the navigation stand-in gets a
new object layer only when a box appeared, vanished or moved/grew by more than
``object_update_tolerance_m``; the camera is rendered only when the object costmap
processes a frame and, by default, at half the simulator's resolution (intrinsics
scaled) to keep runs cheap.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.fields import param_meta
from explore_seg.core.camera import CameraIntrinsics
from explore_seg.core.detector import Detector, DetectorParams
from explore_seg.core.explorer import Explorer, ExplorerStep
from explore_seg.core.frontiers import Frontier, object_obstacles
from explore_seg.core.grid import GridMap
from explore_seg.core.objects import WALL_OCCUPIED_THRESHOLD, DepthFrame, ObjectMap, ObjectParams, \
    WallMask, load_priors, process_frame, wall_mask
from explore_seg.core.segmentation import IncrementalSegmenter
from explore_seg.core.selection import Action, NavOutcome
from sim_bridge import worlds
from sim_bridge.contacts import classify_contact
from sim_bridge.early_stop import explain_stop
from sim_bridge.engine import Collider, SimEngine, SimParams
from sim_bridge.navigation import OutcomeFollower
from sim_bridge.explorer_params import (ExplorerParams, default_explorer_params_file,  # noqa: F401
                                        load_explorer_params)
from sim_bridge.run_result import TIMING_KEYS, RunResult  # noqa: F401 (API)
from sim_bridge.strategy_specs import (STRATEGIES, STRATEGY_SPECS, StrategySpec,  # noqa: F401 (API)
                                      strategy_spec)
from sim_bridge.sensors import CLASS_IDS
from sim_bridge.world import World

#: Layer name of the object costmap in the navigation stand-in.
OBJECT_LAYER = "object_costmap"
#: One black pixel, broadcast to the image passed to the oracle detector (which reads
#: only the semantic and instance images).
_BLACK = np.zeros(3, dtype=np.uint8)


@dataclass(frozen=True)
class LockstepParams:
    """Parameters of a lock-step run (rates, stop rule, seeded perturbations)."""

    max_sim_time_s: float = field(default=1800.0, metadata=param_meta(
        "stop after this much sim time", "s"))
    decision_period_s: float = field(default=0.0, metadata=param_meta(
        "frontier detection + segmentation + goal decision period; 0 = "
        "1 / SelectorNodeParams.rate_hz (the target_selector's rate)", "s"))
    object_period_s: float = field(default=0.0, metadata=param_meta(
        "object costmap update period (one camera frame processed); 0 = "
        "1 / ObjectCostmapNodeParams.rate_hz (the object_costmap node's rate)", "s"))
    coverage_target_pct: float = field(default=99.0, metadata=param_meta(
        "run completed at this coverage of the explorable area", "%"))
    milestones_pct: tuple[float, ...] = field(
        default=(50.0, 90.0, 95.0, 99.0), metadata=param_meta(
        "coverages at which time and path length are recorded", "%"))
    sample_period_s: float = field(default=5.0, metadata=param_meta(
        "coverage-vs-time sampling period", "s"))
    start_jitter_m: float = field(default=0.2, metadata=param_meta(
        "seeded start position perturbation (uniform per axis)", "m"))
    start_yaw_jitter_rad: float = field(default=math.pi, metadata=param_meta(
        "seeded start heading perturbation (uniform)", "rad"))
    start_min_clearance_m: float = field(default=0.35, metadata=param_meta(
        "a perturbed start keeps at least this distance to every solid", "m"))
    oracle_miss_prob: float = field(default=0.1, metadata=param_meta(
        "probability that the oracle detector misses an object in a frame"))
    oracle_jitter_px: float = field(default=2.0, metadata=param_meta(
        "std of the oracle's box corner noise", "px"))
    camera_scale: float = field(default=0.5, metadata=param_meta(
        "camera resolution relative to the simulator default (intrinsics scaled)"))
    object_update_tolerance_m: float = field(default=0.05, metadata=param_meta(
        "the planner's object layer is replaced only when a box moved or grew "
        "by more than this (or appeared/vanished)", "m"))
    nav_feedback: bool = field(default=True, metadata=param_meta(
        "tell the decision core how the navigation stand-in ended each goal (succeeded: "
        "judge its frontier now; aborted/rejected: blacklist it now), as the "
        "target_selector does with Nav2's action status; false: goals end by distance and "
        "progress_timeout_s only (how benchmark rows without feedback were made)"))

    def __post_init__(self) -> None:
        for name in ("max_sim_time_s", "sample_period_s", "camera_scale"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        for name in ("decision_period_s", "object_period_s",
                     "start_jitter_m", "start_yaw_jitter_rad", "start_min_clearance_m",
                     "oracle_jitter_px", "object_update_tolerance_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        if not 0.0 < self.coverage_target_pct <= 100.0:
            raise ValueError(f"coverage_target_pct must be in (0, 100], got "
                             f"{self.coverage_target_pct}")
        if not 0.0 <= self.oracle_miss_prob <= 1.0:
            raise ValueError(f"oracle_miss_prob must be in [0, 1], got {self.oracle_miss_prob}")
        if not all(0.0 < m <= 100.0 for m in self.milestones_pct):
            raise ValueError(f"milestones_pct must be in (0, 100], got {self.milestones_pct}")
        if self.camera_scale > 1.0:
            raise ValueError(f"camera_scale must be <= 1, got {self.camera_scale}")


@dataclass
class LockstepState:
    """What an observer sees after every decision (for pictures and checks).

    The objects are live: copy what must outlive the call.
    """

    engine: SimEngine
    grid: GridMap
    frontiers: list[Frontier]
    labels: npt.NDArray[np.int32] | None
    object_layer: GridMap | None
    object_map: ObjectMap | None
    goal_xy: tuple[float, float] | None
    goals: list[tuple[float, float]]
    action: str = ""
    reason: str = ""
    #: The decision core's output of this decision (costs, distances, tour).
    step: ExplorerStep | None = None


# --------------------------------------------------------------------------- set-up


def perturbed_start(world: World, seed: int, params: LockstepParams,
                    radius_m: float = 0.22, height_m: float = 1.1
                    ) -> tuple[float, float, float]:
    """The world's start pose moved by the seed (see :class:`LockstepParams`).

    Positions are drawn until one keeps ``start_min_clearance_m`` to every solid that
    reaches below ``height_m`` (at most 50 draws; then the original position is kept).

    Parameters
    ----------
    world : World
    seed : int
    params : LockstepParams
    radius_m, height_m : float
        Robot disk radius and height of the collision test.

    Returns
    -------
    (x, y, yaw)
    """
    rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, 0x5EED])
    x0, y0, yaw0 = (float(v) for v in world.start_pose)
    yaw = yaw0 + float(rng.uniform(-params.start_yaw_jitter_rad, params.start_yaw_jitter_rad))
    yaw = (yaw + math.pi) % (2.0 * math.pi) - math.pi
    collider = Collider(world, radius_m, height_m)
    for _ in range(50):
        dx, dy = rng.uniform(-params.start_jitter_m, params.start_jitter_m, 2)
        x, y = x0 + float(dx), y0 + float(dy)
        if collider.clearance(x, y)[0] >= params.start_min_clearance_m:
            return (x, y, yaw)
    return (x0, y0, yaw)


def scan_points_map(engine: SimEngine) -> npt.NDArray[np.float64]:
    """Latest scan's returns in the map frame, shape (N, 2) (empty before the first)."""
    scan = engine.latest_scan
    if scan is None:
        return np.zeros((0, 2))
    g = engine.scan_geometry
    r = np.asarray(scan.ranges, dtype=np.float64)
    ang = g.angle_min_rad + g.angle_increment_rad * np.arange(r.shape[0])
    ok = np.isfinite(r) & (r >= g.range_min_m) & (r < g.range_max_m)
    x, y, yaw = scan.pose
    mx = engine.params.lidar_mount_x_m
    ox, oy = x + mx * math.cos(yaw), y + mx * math.sin(yaw)
    a = yaw + ang[ok]
    return np.column_stack([ox + r[ok] * np.cos(a), oy + r[ok] * np.sin(a)])


def _sim_params(seed: int, spec: StrategySpec, p: LockstepParams,
                base: SimParams | None) -> SimParams:
    sp = base if base is not None else SimParams()
    cam = sp.camera_params()
    s = p.camera_scale
    w, h = max(16, int(round(cam.width * s))), max(16, int(round(cam.height * s)))
    fx = cam.fx * w / cam.width
    fy = cam.fy * h / cam.height
    return replace(sp, seed=int(seed), enable_camera=spec.use_objects,
                   camera_rate_hz=1.0 / p.object_period_s,
                   camera_width_px=w, camera_height_px=h, camera_fx_px=fx, camera_fy_px=fy,
                   camera_cx_px=(w - 1) / 2.0, camera_cy_px=(h - 1) / 2.0)


class _ObjectPipeline:
    """The object costmap node's work on one engine: oracle detections + depth + scan."""

    def __init__(self, engine: SimEngine, params: ObjectParams, seed: int,
                 lp: LockstepParams) -> None:
        self.engine = engine
        self.params = params
        self.priors = load_priors(params.priors_path or None)
        self.detector = Detector(DetectorParams(
            backend="oracle", oracle_miss_prob=lp.oracle_miss_prob,
            oracle_jitter_px=lp.oracle_jitter_px, oracle_seed=int(seed)),
            sim_class_ids=CLASS_IDS)
        self.map = ObjectMap(params, self.priors)
        cp = engine.params.camera_params()
        self.intrinsics: CameraIntrinsics = cp.intrinsics()
        self.tolerance_m = lp.object_update_tolerance_m
        self._last_stamp = -1.0
        self._published: list[tuple[float, ...]] = []
        self._published_depth = 0
        self._walls: tuple[int, WallMask] | None = None   # (map version, its wall mask)
        self._walls_occ: npt.NDArray[np.bool_] | None = None   # its occupied cells

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
        self.map.note_robot_position(*self.engine.pose[:2])
        cam = self.engine.latest_camera
        if cam is None or cam.stamp_s <= self._last_stamp:
            return False
        self._last_stamp = cam.stamp_s
        fr = cam.frame
        tf = np.eye(4)
        tf[:3, :3] = fr.rotation
        tf[:3, 3] = fr.translation
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
                        robot_xy=self.engine.pose[:2], walls=walls)
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


# ------------------------------------------------------------------------------ run


def run_exploration(world: World, strategy: str, seed: int, *,
                    max_sim_time_s: float | None = None,
                    decision_period_s: float | None = None,
                    params: LockstepParams | None = None,
                    sim_params: SimParams | None = None,
                    explorer_params: ExplorerParams | None = None,
                    ground_truth: Any = None,
                    observer: Callable[[LockstepState], None] | None = None) -> RunResult:
    """Explore ``world`` with ``strategy`` in lock step and measure the run.

    Parameters
    ----------
    world : World
        Not modified (the perturbed start goes into a copy).
    strategy : str
        One of :data:`STRATEGIES`.
    seed : int
        Seeds the start perturbation, the simulator noise and the oracle.
    max_sim_time_s, decision_period_s : float, optional
        Override the fields of ``params``.
    params : LockstepParams, optional
    sim_params : SimParams, optional
        Base simulator parameters (seed, camera and world fields are set here).
    explorer_params : ExplorerParams, optional
        The nodes' parameters; default :func:`load_explorer_params` (``config/explorer.yaml``
        when present, else the dataclass defaults). The strategy fields (``strategy``,
        ``use_regions``, ``use_object_costmap``) are set from :data:`STRATEGY_SPECS`.
    ground_truth : worlds.GroundTruth, optional
        Precomputed ``worlds.ground_truth(world)`` (its ``inside`` must hold the start).
    observer : callable, optional
        Called with a :class:`LockstepState` after every decision.

    Returns
    -------
    RunResult

    Raises
    ------
    ValueError
        On an unknown strategy or invalid parameters.
    """
    spec = strategy_spec(strategy)
    p = params if params is not None else LockstepParams()
    if max_sim_time_s is not None:
        p = replace(p, max_sim_time_s=float(max_sim_time_s))
    if decision_period_s is not None:
        p = replace(p, decision_period_s=float(decision_period_s))
    ep = explorer_params if explorer_params is not None else load_explorer_params()
    sel_p = replace(ep.selection, strategy=spec.selection, use_regions=spec.use_regions)
    fr_p = replace(ep.frontier, use_object_costmap=spec.use_objects)
    obj_p = ep.objects
    p = replace(p, decision_period_s=p.decision_period_s or 1.0 / sel_p.rate_hz,
                object_period_s=p.object_period_s or 1.0 / obj_p.rate_hz)
    sp = _sim_params(seed, spec, p, sim_params)
    start = perturbed_start(world, seed, p, sp.robot_radius_m, sp.robot_height_m)
    run_world = replace(world, start_pose=start)
    if ground_truth is None and sp.compute_coverage:
        ground_truth = worlds.ground_truth(run_world, resolution_m=sp.map_resolution_m)
    engine = SimEngine(run_world, sp, ground_truth=ground_truth)
    explorer = Explorer(fr_p, sel_p, replace(ep.rrt, seed=int(seed) & 0x7FFFFFFF))
    segmenter = IncrementalSegmenter(ep.segmentation) if spec.use_regions else None
    objects = (_ObjectPipeline(engine, obj_p, seed, p)
               if spec.use_objects else None)

    res = RunResult(world=world.name, strategy=strategy, seed=int(seed), start_pose=start,
                    timings_ms={k: [] for k in TIMING_KEYS})
    ref = engine.metrics.reference
    res.explorable_area_m2 = ref.area_m2 if ref is not None else math.nan
    milestones = sorted(p.milestones_pct)
    res.time_to_s = {_key(m): math.nan for m in milestones}
    res.path_to_m = {_key(m): math.nan for m in milestones}
    tick = min(p.decision_period_s, p.object_period_s) if objects else p.decision_period_s
    next_decision = 0.0
    next_sample = 0.0
    labels: npt.NDArray[np.int32] | None = None
    seg_version = -1
    layer: GridMap | None = None
    follower = OutcomeFollower() if (p.nav_feedback or spec.nav_feedback) else None
    last_step = None
    # every contact classified against the map and the layer navigation had then
    engine.on_collision(lambda ev: res.contacts.append(
        classify_contact(ev, engine.collider, engine.map, layer)))
    wall0 = time.perf_counter()

    def record_coverage() -> float:
        cov = engine.metrics.coverage_pct
        if not math.isfinite(cov):
            return cov
        t = engine.metrics.sim_time_s
        for m in milestones:
            k = _key(m)
            if cov >= m and not math.isfinite(res.time_to_s[k]):
                res.time_to_s[k] = t
                res.path_to_m[k] = engine.metrics.path_length_m
        return cov

    engine.step(0.0)
    engine.run_until(lambda e: e.latest_scan is not None, 1.0)
    while True:
        now = engine.time_s
        cov = record_coverage()
        if now >= next_sample - 1e-9:
            res.coverage_samples.append((now, cov, engine.metrics.path_length_m))
            next_sample += p.sample_period_s
        if math.isfinite(cov) and cov >= p.coverage_target_pct:
            res.completed, res.stop_reason = True, "coverage"
            break
        if now >= p.max_sim_time_s - 1e-9:
            res.stop_reason = "timeout"
            break
        if objects is not None and objects.update(res.timings_ms) and objects.changed():
            t0 = time.perf_counter()
            layer = objects.map.rasterize(engine.map)
            engine.add_costmap_layer(OBJECT_LAYER, layer)
            objects.mark_published()
            res.timings_ms["objects"][-1] += (time.perf_counter() - t0) * 1e3
        if now >= next_decision - 1e-9:
            next_decision += p.decision_period_s
            t_dec = time.perf_counter()
            grid = engine.map
            # --- segmentation node
            if segmenter is not None and engine.map_version != seg_version:
                t0 = time.perf_counter()
                labels = segmenter.update(grid)
                seg_version = engine.map_version
                res.timings_ms["segmentation"].append((time.perf_counter() - t0) * 1e3)
            # --- target_selector node (frontiers, distances, costs, goal)
            use_labels = labels if (labels is not None and labels.shape == grid.shape) else None
            ended = follower.poll(engine.nav_status) if follower is not None else None
            if ended is not None:
                explorer.report_navigation(*ended)
            step = last_step = explorer.step(now, grid, engine.pose, layer, use_labels)
            if step.detected:
                res.timings_ms["frontier"].append(step.detect_s * 1e3)
            res.timings_ms["selection"].append(step.select_s * 1e3)
            # the decision core of the target_selector node: detection (when the map
            # changed) + viewpoints, path lengths, tour and goal; segmentation is a node
            # of its own, the lock step's "decision" adds it
            res.timings_ms["core"].append((step.detect_s + step.select_s) * 1e3)
            res.goals_blacklisted += step.blacklisted
            res.goal_switches += int(step.switched)
            if step.action is Action.NEW_GOAL and step.goal is not None:
                gx, gy = step.goal.xy_m
                try:
                    engine.set_goal(gx, gy, step.goal.yaw_rad)
                    res.goals_sent += 1
                    res.goals.append((gx, gy))
                    if follower is not None:
                        follower.sent((gx, gy))
                except ValueError:
                    if follower is not None:
                        explorer.report_navigation(NavOutcome.REJECTED, step.goal)
                    else:
                        explorer.manager.abandon_goal(blacklist=True)
            res.timings_ms["decision"].append((time.perf_counter() - t_dec) * 1e3)
            if observer is not None:
                goal = explorer.goal
                observer(LockstepState(engine, grid, step.frontiers, use_labels, layer,
                                       objects.map if objects else None,
                                       goal.xy_m if goal else None,
                                       res.goals, step.action.value, step.reason, step))
            if step.action is Action.DONE:
                res.stop_reason = "done"
                break
        engine.step(tick)

    res.sim_time_s = engine.time_s
    res.wall_time_s = time.perf_counter() - wall0
    res.coverage_pct = float(engine.metrics.coverage_pct)
    res.path_length_m = engine.metrics.path_length_m
    res.collisions = engine.metrics.n_collisions
    res.collision_places = [(e.x_m, e.y_m, e.object or e.cls) for e in engine.metrics.collisions]
    res.nav_aborts = engine.metrics.goals_aborted
    res.n_objects = len(objects.map) if objects is not None else 0
    if last_step is not None and ref is not None and not res.completed:
        extra = (object_obstacles(layer, engine.map, fr_p.object_occupied_threshold)
                 if fr_p.use_object_costmap else None)
        res.early_stop = explain_stop(
            engine.map, ref, last_step.frontiers, last_step.dist_m,
            explorer.manager.excluded(last_step.frontiers),
            last_step.selection.costs if last_step.selection is not None else None,
            fr_p, extra)
    if not res.coverage_samples or res.coverage_samples[-1][0] < engine.time_s:
        res.coverage_samples.append((engine.time_s, res.coverage_pct, res.path_length_m))
    return res


def _key(m: float) -> str:
    return f"{m:g}"
