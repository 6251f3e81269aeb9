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

The map every decision sees is the engine's published one, slam_toolbox's: keyframe scans,
republished every ``SimParams.map_update_interval_s``; regions are recomputed when its
content changed and the decision core reuses its frontiers and path graphs while it did not
(see :mod:`sim_bridge.engine` for the rates).

Differences from the ROS pipeline (intentional): everything is synchronous (every
decision sees the frontiers, regions and object layer of the latest published map, where
the nodes see their latest messages, possibly a cycle old); the navigation stand-in gets a
new object layer only when a box appeared, vanished or moved/grew by more than
``object_update_tolerance_m``; the camera is rendered only when the object costmap
processes a frame and, by default, at half the simulator's resolution (intrinsics
scaled) to keep runs cheap.
"""

from __future__ import annotations

import math
import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Iterator

import numpy as np
import numpy.typing as npt

from explore_seg.core.fields import param_meta
from explore_seg.core.explorer import Explorer, ExplorerStep
from explore_seg.core.frontiers import Frontier, FrontierParams, object_obstacles
from explore_seg.core.grid import GridMap
from explore_seg.core.objects import ObjectMap
from explore_seg.core.segmentation import IncrementalSegmenter
from explore_seg.core.selection import Action, NavOutcome, SelectionParams
from sim_bridge import worlds
from sim_bridge.contacts import classify_contact
from sim_bridge.early_stop import FrontiersLeft, explain_stop
from sim_bridge.engine import Collider, SimEngine, SimParams
from sim_bridge.navigation import OutcomeFollower
from sim_bridge.object_pipeline import ClosureWatch, ObjectPipeline
from sim_bridge.explorer_params import (ExplorerParams, default_explorer_params_file,  # noqa: F401
                                        load_explorer_params)
from sim_bridge.run_result import TIMING_KEYS, RunResult  # noqa: F401 (API)
from sim_bridge.strategy_specs import (STRATEGIES, STRATEGY_SPECS, StrategySpec,  # noqa: F401 (API)
                                      strategy_spec)
from sim_bridge.world import World

#: Layer name of the object costmap in the navigation stand-in.
OBJECT_LAYER = "object_costmap"


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
        "progress_timeout_s only, as with the target_selector's nav_action ''"))

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


def _sim_params(seed: int, spec: StrategySpec, lockstep: LockstepParams,
                base: SimParams | None) -> SimParams:
    """``base`` (default :class:`SimParams`) with the run's seed and the camera the object
    costmap gets: on with the strategy's objects, at its rate and ``camera_scale``."""
    sim = base if base is not None else SimParams()
    cam = sim.camera_params()
    s = lockstep.camera_scale
    w, h = max(16, int(round(cam.width * s))), max(16, int(round(cam.height * s)))
    fx = cam.fx * w / cam.width
    fy = cam.fy * h / cam.height
    return replace(sim, seed=int(seed), enable_camera=spec.use_objects,
                   camera_rate_hz=1.0 / lockstep.object_period_s,
                   camera_width_px=w, camera_height_px=h, camera_fx_px=fx, camera_fy_px=fy,
                   camera_cx_px=(w - 1) / 2.0, camera_cy_px=(h - 1) / 2.0)


@dataclass(frozen=True)
class _RunConfig:
    """Every parameter of one run, the strategy's settings applied."""

    spec: StrategySpec
    #: Periods resolved (0 replaced by the nodes' rates).
    lockstep: LockstepParams
    explorer: ExplorerParams
    #: ``explorer.selection`` / ``explorer.frontier`` with the strategy's fields set.
    selection: SelectionParams
    frontier: FrontierParams
    sim: SimParams


def _run_config(spec: StrategySpec, seed: int, params: LockstepParams | None,
                sim_params: SimParams | None,
                explorer_params: ExplorerParams | None) -> _RunConfig:
    """The run's parameters: the defaults where none are given, the strategy's fields set
    (see :func:`run_exploration`)."""
    lockstep = params if params is not None else LockstepParams()
    explorer = explorer_params if explorer_params is not None else load_explorer_params()
    selection = replace(explorer.selection, strategy=spec.selection,
                        use_regions=spec.use_regions)
    frontier = replace(explorer.frontier, use_object_costmap=spec.use_objects)
    lockstep = replace(
        lockstep, decision_period_s=lockstep.decision_period_s or 1.0 / selection.rate_hz,
        object_period_s=lockstep.object_period_s or 1.0 / explorer.objects.rate_hz)
    sim = _sim_params(seed, spec, lockstep, sim_params)
    return _RunConfig(spec, lockstep, explorer, selection, frontier, sim)


# ------------------------------------------------------------------------------ run


def run_exploration(world: World, strategy: str, seed: int, *,
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
    params : LockstepParams, optional
        Rates, time limit (``max_sim_time_s``), stop rule, seeded perturbations.
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
    config = _run_config(spec, seed, params, sim_params, explorer_params)
    run = _LockstepRun(world, strategy, seed, config, ground_truth, observer)
    run.start()
    while run.advance():
        pass
    return run.finish()


class _LockstepRun:
    """One run's state: the engine, the nodes' core objects, the schedule and the result.

    :meth:`start` gets the first scan; each :meth:`advance` is one tick (coverage and stop
    checks, the object costmap, a decision when one is due, then the engine's step);
    :meth:`finish` fills in the result.
    """

    def __init__(self, world: World, strategy: str, seed: int, config: _RunConfig,
                 ground_truth: Any,
                 observer: Callable[[LockstepState], None] | None) -> None:
        spec, lockstep, sim = config.spec, config.lockstep, config.sim
        self.config = config
        self.observer = observer
        start = perturbed_start(world, seed, lockstep, sim.robot_radius_m, sim.robot_height_m)
        run_world = replace(world, start_pose=start)
        if ground_truth is None and sim.compute_coverage:
            ground_truth = worlds.ground_truth(run_world, resolution_m=sim.map_resolution_m)
        self.engine = engine = SimEngine(run_world, sim, ground_truth=ground_truth)
        # the explorer knows where the simulated robot's lidar sits (as its launch file would)
        self.explorer = Explorer(config.frontier, config.selection,
                                 replace(config.explorer.rrt, seed=int(seed) & 0x7FFFFFFF),
                                 replace(config.explorer.overlay,
                                         lidar_x_m=sim.lidar_mount_x_m, lidar_y_m=0.0,
                                         lidar_yaw_rad=0.0))
        g = engine.scan_geometry
        self.scan_angles = g.angle_min_rad + g.angle_increment_rad * np.arange(g.num_beams)
        self.segmenter = (IncrementalSegmenter(config.explorer.segmentation)
                          if spec.use_regions else None)
        self.objects = (ObjectPipeline(engine, config.explorer.objects, seed, lockstep)
                        if spec.use_objects else None)
        self.result = res = RunResult(world=world.name, strategy=strategy, seed=int(seed),
                                      start_pose=start,
                                      timings_ms={k: [] for k in TIMING_KEYS})
        self.reference = engine.metrics.reference
        res.explorable_area_m2 = (self.reference.area_m2 if self.reference is not None
                                  else math.nan)
        self.milestones = sorted(lockstep.milestones_pct)
        res.time_to_s = {_key(m): math.nan for m in self.milestones}
        res.path_to_m = {_key(m): math.nan for m in self.milestones}
        self.tick_s = (min(lockstep.decision_period_s, lockstep.object_period_s)
                       if self.objects else lockstep.decision_period_s)
        self.next_decision_s = 0.0
        self.next_sample_s = 0.0
        self.labels: npt.NDArray[np.int32] | None = None
        self.labels_map_version = -1
        #: The object layer navigation has now (None before the first).
        self.layer: GridMap | None = None
        self.follower = (OutcomeFollower() if (lockstep.nav_feedback or spec.nav_feedback)
                         else None)
        self.last_step: ExplorerStep | None = None
        # the simulator's closures that re-rendered the map, and when the last one was seen
        self.closures = ClosureWatch(engine)
        self.corrected_s: float | None = None
        engine.on_collision(self._record_contact)
        self.wall_start_s = time.perf_counter()

    # ------------------------------------------------------------------ bookkeeping

    @contextmanager
    def _timed(self, key: str, add_to_last: bool = False) -> Iterator[None]:
        """Time the block into ``result.timings_ms[key]`` (ms), as a new entry or added to
        the last one."""
        t0 = time.perf_counter()
        yield
        ms = (time.perf_counter() - t0) * 1e3
        if add_to_last:
            self.result.timings_ms[key][-1] += ms
        else:
            self.result.timings_ms[key].append(ms)

    def _record_contact(self, event: Any) -> None:
        """Keep every contact, classified against the map and the layer navigation has."""
        self.result.contacts.append(
            classify_contact(event, self.engine.collider, self.engine.live_map, self.layer,
                             map_from_world=(self.engine.slam_error.drift
                                             if self.engine.slam_error is not None else None)))

    def _record_coverage(self) -> float:
        """The coverage now; the time and path length of each milestone it reaches first."""
        metrics = self.engine.metrics
        cov = metrics.coverage_pct
        if not math.isfinite(cov):
            return cov
        res = self.result
        for m in self.milestones:
            k = _key(m)
            if cov >= m and not math.isfinite(res.time_to_s[k]):
                res.time_to_s[k] = metrics.sim_time_s
                res.path_to_m[k] = metrics.path_length_m
        return cov

    def _sample_coverage(self, now: float, cov: float) -> None:
        if now >= self.next_sample_s - 1e-9:
            self.result.coverage_samples.append((now, cov, self.engine.metrics.path_length_m))
            self.next_sample_s += self.config.lockstep.sample_period_s

    def _stop_reason(self, now: float, cov: float) -> str | None:
        """"coverage" at the target coverage, "timeout" at the time limit, else None."""
        lockstep = self.config.lockstep
        if math.isfinite(cov) and cov >= lockstep.coverage_target_pct:
            return "coverage"
        if now >= lockstep.max_sim_time_s - 1e-9:
            return "timeout"
        return None

    # ------------------------------------------------------------------ the loop

    def start(self) -> None:
        """Step the engine once and run it until the first scan."""
        self.engine.step(0.0)
        self.engine.run_until(lambda e: e.latest_scan is not None, 1.0)

    def advance(self) -> bool:
        """One tick; False when the run stops (its ``stop_reason`` set)."""
        now = self.engine.time_s
        cov = self._record_coverage()
        self._sample_coverage(now, cov)
        reason = self._stop_reason(now, cov)
        if reason is not None:
            self.result.completed = reason == "coverage"
            self.result.stop_reason = reason
            return False
        if self.closures.rerendered():
            self.corrected_s = now
        self._update_object_layer()
        if now >= self.next_decision_s - 1e-9:
            self.next_decision_s += self.config.lockstep.decision_period_s
            if self._decide(now) is Action.DONE:
                self.result.stop_reason = "done"
                return False
        self.engine.step(self.tick_s)
        return True

    def _update_object_layer(self) -> None:
        """The object costmap node: process a new camera frame; when the boxes changed,
        rasterise them and give navigation the new layer."""
        objects = self.objects
        if objects is None or not (objects.update(self.result.timings_ms)
                                   and objects.changed()):
            return
        with self._timed("objects", add_to_last=True):
            self.layer = objects.map.rasterize(self.engine.map)
            self.engine.add_costmap_layer(OBJECT_LAYER, self.layer)
            objects.mark_published()

    def _decide(self, now: float) -> Action:
        """One decision: regions, the decision core's step, its goal sent; the observer
        told."""
        with self._timed("decision"):
            grid = self.engine.map
            self._update_regions(grid)
            labels = (self.labels if (self.labels is not None
                                      and self.labels.shape == grid.shape) else None)
            step = self._explorer_step(now, grid, labels)
            if step.action is Action.NEW_GOAL and step.goal is not None:
                self._send_goal(step.goal)
        if self.observer is not None:
            goal = self.explorer.goal
            self.observer(LockstepState(
                self.engine, grid, step.frontiers, labels, self.layer,
                self.objects.map if self.objects else None, goal.xy_m if goal else None,
                self.result.goals, step.action.value, step.reason, step))
        return step.action

    def _update_regions(self, grid: GridMap) -> None:
        """The segmentation node: new regions when the map changed."""
        if self.segmenter is None or self.engine.map_version == self.labels_map_version:
            return
        with self._timed("segmentation"):
            self.labels = self.segmenter.update(grid)
            self.labels_map_version = self.engine.map_version

    def _explorer_step(self, now: float, grid: GridMap,
                       labels: npt.NDArray[np.int32] | None) -> ExplorerStep:
        """The target_selector node: navigation's outcome reported, then frontiers,
        distances, costs and goal; its timings and counters recorded."""
        ended = self.follower.poll(self.engine.nav_status) if self.follower is not None else None
        if ended is not None:
            self.explorer.report_navigation(*ended)
        g = self.engine.scan_geometry
        for scan in self.engine.drain_scans():
            self.explorer.add_scan(scan.stamp_s, scan.map_pose or scan.pose, self.scan_angles,
                                   scan.ranges, g.range_max_m, g.range_min_m)
        if self.corrected_s is not None:
            # a closure re-rendered the map: the scans laid before it are off the new map
            self.explorer.map_corrected(self.corrected_s)
            self.corrected_s = None
        step = self.last_step = self.explorer.step(now, grid, self.engine.slam_pose, self.layer,
                                                   labels)
        timings, res = self.result.timings_ms, self.result
        if step.detected:
            timings["frontier"].append(step.detect_s * 1e3)
        timings["selection"].append(step.select_s * 1e3)
        # the decision core of the target_selector node: detection (when the map
        # changed) + viewpoints, path lengths, tour and goal; segmentation is a node
        # of its own, the lock step's "decision" adds it
        timings["core"].append((step.detect_s + step.select_s) * 1e3)
        res.goals_blacklisted += step.blacklisted
        res.goal_switches += int(step.switched)
        return step

    def _send_goal(self, goal: Any) -> None:
        """Give the goal to navigation (as a goal_pose message); a goal it rejects is
        reported rejected (with feedback) or abandoned and blacklisted (without)."""
        gx, gy = goal.xy_m
        try:
            self.engine.set_goal(gx, gy, goal.yaw_rad)
            self.result.goals_sent += 1
            self.result.goals.append((gx, gy))
            if self.follower is not None:
                self.follower.sent((gx, gy))
        except ValueError:
            if self.follower is not None:
                self.explorer.report_navigation(NavOutcome.REJECTED, goal)
            else:
                self.explorer.manager.abandon_goal(blacklist=True)

    # ------------------------------------------------------------------ the result

    def finish(self) -> RunResult:
        """The result: final coverage, path, collisions, objects, why an early stop
        stopped, the last coverage sample."""
        engine, res = self.engine, self.result
        metrics = engine.metrics
        res.sim_time_s = engine.time_s
        res.wall_time_s = time.perf_counter() - self.wall_start_s
        res.coverage_pct = float(metrics.coverage_pct)
        res.path_length_m = metrics.path_length_m
        res.collisions = metrics.n_collisions
        res.collision_places = [(e.x_m, e.y_m, e.object or e.cls) for e in metrics.collisions]
        res.nav_aborts = metrics.goals_aborted
        res.n_objects = len(self.objects.map) if self.objects is not None else 0
        if self.last_step is not None and self.reference is not None and not res.completed:
            res.early_stop = self._explain_stop(self.last_step)
        if not res.coverage_samples or res.coverage_samples[-1][0] < engine.time_s:
            res.coverage_samples.append((engine.time_s, res.coverage_pct, res.path_length_m))
        return res

    def _explain_stop(self, step: ExplorerStep) -> Any:
        """Why the run stopped short of the target, from the last decision's view."""
        frontier = self.config.frontier
        extra = (object_obstacles(self.layer, self.engine.map,
                                  frontier.object_occupied_threshold)
                 if frontier.use_object_costmap else None)
        left = FrontiersLeft(step.frontiers, step.dist_m,
                             self.explorer.manager.excluded(step.frontiers),
                             step.selection.costs if step.selection is not None else None)
        return explain_stop(self.engine.map, self.reference, left, frontier, extra)


def _key(m: float) -> str:
    return f"{m:g}"
