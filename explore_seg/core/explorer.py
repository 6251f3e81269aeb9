"""The explorer's decision loop, ROS-free: one call per decision.

:class:`Explorer` wires frontier detection, path distances, the strategy's costs and the
goal manager once, for every caller: the ``target_selector`` node, the lock-step benchmark
(``sim_bridge.lockstep``) and the tests. Per :meth:`Explorer.step` it

1. detects frontiers and builds the path graphs when the map or the object layer changed;
   while both are unchanged - the same objects, or equal ones (a map republished without
   change, as slam_toolbox does every ``map_update_interval``) - it reuses the frontiers,
   their masks and the path graphs' distance fields, which depend on nothing else;
2. finds the robot's cell and checks it is inside the map with a passable cell nearby;
3. computes the path lengths robot -> cPoints (fallback through unknown space left to
   :class:`~explore_seg.core.selection.PathGraphs`), with the blacklisted frontiers excluded;
4. lets the :class:`~explore_seg.core.selection.GoalManager` keep, switch, blacklist or
   finish, under the strategy of :class:`~explore_seg.core.selection.SelectionParams`.

Under an RRT strategy (``rrt_exploration``) step 1 is the RRT frontier detector instead
(:class:`~explore_seg.core.rrt.RrtFrontierDetector`, run at every step: its trees grow
per decision); the path graphs are still built once per map.

It returns an :class:`ExplorerStep`: the action (new goal / keep / wait / done), the goal,
the frontiers with their distances and costs (for markers and metrics), what was
blacklisted or switched, warnings for the caller to log, and the time spent.

Examples
--------
>>> from explore_seg.core.grid import grid_from_ascii
>>> grid, marks = grid_from_ascii('''
... ##########
... #R.......?
... #........?
... ##########''', resolution_m=0.1)
>>> ex = Explorer(FrontierParams(min_group_size_cells=1, robot_radius_m=0.0),
...               SelectionParams(strategy="nearest"))
>>> x, y = grid.cell_to_world(*marks["R"][0])
>>> out = ex.step(0.0, grid, (x, y, 0.0))
>>> out.action.value, len(out.frontiers)
('new_goal', 1)
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import (Frontier, FrontierCache, FrontierParams, find_frontiers,
                                        object_obstacles, split_frontiers,
                                        traversable_mask)
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.rrt import RrtFrontierDetector, RrtParams
from explore_seg.core.scan_overlay import ScanOverlay, ScanOverlayParams
from explore_seg.core.selection import (Action, Goal, GoalManager, NavOutcome, PathGraphs,
                                        Selection, SelectionParams, StepInputs)
from explore_seg.core.selection.fallbacks import Fallbacks
from explore_seg.core.selection.lookout import Reach
from explore_seg.core.selection.router import TourPlan
from explore_seg.core.selection.strategies import Planner, Strategy, get_strategy

#: Keys of :attr:`ExplorerStep.warnings` (the caller throttles its log per key).
WARN_LAYER_FRAME = "layer_frame"
WARN_LABELS_SHAPE = "labels_shape"
WARN_ROBOT_OUTSIDE = "robot_outside"
WARN_ROBOT_BLOCKED = "robot_blocked"


@dataclass(frozen=True)
class Detection:
    """Frontiers of one map (and object layer) and the masks they were found with."""

    frontiers: list[Frontier]
    extra_obstacles: npt.NDArray[np.bool_] | None = field(repr=False)
    passable: npt.NDArray[np.bool_] = field(repr=False)
    layer_warning: str = ""


def detect_frontiers(grid: GridMap, layer: GridMap | None, params: FrontierParams,
                     groups: bool = True, cache: FrontierCache | None = None) -> Detection:
    """Frontiers of ``grid`` with the object layer's occupied cells as obstacles.

    The layer is used when ``params.use_object_costmap`` and it is in the map's frame
    (else ignored, with ``layer_warning`` saying why); it may have any size or origin.
    ``groups=False``: only the masks (no frontier groups; the RRT strategies find their
    candidates themselves). ``cache``: cPoints and splits kept from the previous detection
    (see :class:`~explore_seg.core.frontiers.FrontierCache`; same frontiers, less work).
    """
    extra = None
    warning = ""
    if params.use_object_costmap and layer is not None:
        if layer.frame_id != grid.frame_id:
            warning = (f"object_costmap frame {layer.frame_id!r} differs from map frame "
                       f"{grid.frame_id!r}: ignored")
        else:
            extra = object_obstacles(layer, grid, params.object_occupied_threshold)
    passable = traversable_mask(grid, extra, params)
    frontiers = (find_frontiers(grid, extra, params, passable=passable, cache=cache)
                 if groups else [])
    return Detection(frontiers, extra, passable, warning)


@dataclass(frozen=True)
class ExplorerStep:
    """Outcome of one :meth:`Explorer.step`.

    Attributes
    ----------
    action : Action
        NEW_GOAL (send ``goal``), KEEP (drive on to ``goal``), WAIT, DONE.
    goal : Goal or None
        The goal to drive to (NEW_GOAL, KEEP).
    reason : str
        Why, in words (for the log).
    selection : Selection or None
        Costs, regions and the chosen index (None when no selection ran).
    frontiers : list of Frontier
        The frontiers of this map version.
    dist_m : ndarray of float64, shape (N,), or None
        Path lengths robot -> cPoints (None: robot outside the map or walled in).
    robot_rc : (int, int)
        The robot's cell.
    detected : bool
        True when frontiers and path graphs were recomputed in this step (the candidates:
        at every step under an RRT strategy).
    blacklisted : int
        Goals added to the blacklist in this step.
    switched : bool
        A new goal replaced one that was neither reached nor given up while its frontier
        was still there and reachable (a cheaper one won).
    warnings : tuple of (key, message)
        Problems with the input (layer frame, robot outside the map or walled in).
    detect_s, select_s : float
        Wall seconds of detection (0 when cached) and of distances + selection
        (viewpoints and tour included).
    tour : TourPlan or None
        The ``routed`` strategy's tour (None for the other strategies); ``frontiers``
        then hold the viewpoints as their cPoints.
    route_s : float
        Wall seconds of viewpoints + tour (part of ``select_s``; 0 without a tour).
    """

    action: Action
    goal: Goal | None
    reason: str
    selection: Selection | None
    frontiers: list[Frontier] = field(repr=False)
    dist_m: npt.NDArray[np.float64] | None = field(repr=False)
    robot_rc: tuple[int, int]
    detected: bool
    blacklisted: int
    switched: bool
    warnings: tuple[tuple[str, str], ...]
    detect_s: float
    select_s: float
    tour: TourPlan | None = None
    route_s: float = 0.0


class Explorer:
    """Frontier exploration decisions (see the module docstring).

    Parameters
    ----------
    frontier : FrontierParams
        Detection (thresholds, robot radius, object layer use).
    selection : SelectionParams
        Strategy and goal handling.
    rrt : RrtParams
        The RRT frontier detector's (used by the RRT strategies only).
    overlay : ScanOverlayParams, optional
        The scans laid over the map's unknown cells (:meth:`add_scan`); None: decisions
        on the map alone.
    """

    def __init__(self, frontier: FrontierParams = FrontierParams(),
                 selection: SelectionParams = SelectionParams(),
                 rrt: RrtParams = RrtParams(),
                 overlay: ScanOverlayParams | None = None) -> None:
        self._overlay = (ScanOverlay(overlay) if overlay is not None and overlay.enabled
                         else None)
        self._frontier_params = frontier
        self._selection_params = selection
        self._rrt_params = rrt
        self._rrt: RrtFrontierDetector | None = None
        self._det: Detection | None = None
        self.manager = GoalManager(selection)
        self._key: tuple[GridMap, GridMap | None] | None = None
        self._frontiers: list[Frontier] = []
        self._graph: PathGraphs | None = None
        self._strategy: Strategy = get_strategy(selection.strategy)
        self._planner = self._make_planner()
        self._fcache = FrontierCache()
        self._layer_warning = ""
        self._reported_blacklisted = 0
        # goals when no frontier is selectable
        self._fallbacks = Fallbacks(self.manager, self._any_selectable)
        self.manager.before_done = self._fallbacks.revisits.arm

    # ------------------------------------------------------------------ state
    @property
    def frontier_params(self) -> FrontierParams:
        """Current detection parameters."""
        return self._frontier_params

    @property
    def selection_params(self) -> SelectionParams:
        """Current selection parameters."""
        return self._selection_params

    @property
    def rrt_params(self) -> RrtParams:
        """Current RRT detector parameters."""
        return self._rrt_params

    @property
    def rrt_detector(self) -> RrtFrontierDetector | None:
        """The RRT frontier detector (None unless an RRT strategy ran a step)."""
        return self._rrt

    @property
    def frontiers(self) -> list[Frontier]:
        """Frontiers of the last map seen by :meth:`step`."""
        return self._frontiers

    @property
    def goal(self) -> Goal | None:
        """The current goal."""
        return self.manager.goal

    @property
    def done(self) -> bool:
        """True once exploration is finished (until :meth:`reset`)."""
        return self.manager.done

    def set_params(self, frontier: FrontierParams | None = None,
                   selection: SelectionParams | None = None,
                   rrt: RrtParams | None = None,
                   overlay: ScanOverlayParams | None = None) -> None:
        """Apply new parameters; frontiers and paths are recomputed at the next step (new
        RRT or detection parameters restart the RRT detector: new trees, no points; new
        overlay parameters start an empty overlay)."""
        if overlay is not None:
            self._overlay = ScanOverlay(overlay) if overlay.enabled else None
        if frontier is not None:
            self._frontier_params = frontier
            self._rrt = None
        if selection is not None:
            self._selection_params = selection
            self.manager.set_params(selection)
        if rrt is not None:
            self._rrt_params = rrt
            self._rrt = None
        self._strategy = get_strategy(self._selection_params.strategy)
        self._planner = self._make_planner()
        self._fcache.reset()
        self._key = None

    def _make_planner(self) -> Planner | None:
        make = self._strategy.make_planner
        return make(self._frontier_params, self._selection_params) if make is not None else None

    @property
    def strategy(self) -> Strategy:
        """The registered strategy of the current selection parameters."""
        return self._strategy

    def reset(self, clear_blacklist: bool = False) -> None:
        """Forget the goal and DONE (and the blacklist and the robot's path when asked),
        as on a (re)start; the ``routed`` tour forgets its kept gains and path
        lengths."""
        self.manager.reset(clear_blacklist=clear_blacklist)
        self._fcache.reset()
        if self._overlay is not None:
            self._overlay.reset()
        if self._planner is not None:
            self._planner.reset()
        if clear_blacklist:
            self._fallbacks.reset()

    def report_navigation(self, outcome: NavOutcome,
                          goal: Goal | tuple[float, float] | None = None) -> bool:
        """What the navigator did with a goal (Nav2's action status, the simulator's
        stand-in): see :meth:`GoalManager.report_navigation`. A blacklisting here is
        counted in the next step's :attr:`ExplorerStep.blacklisted`.

        Parameters
        ----------
        outcome : NavOutcome
        goal : Goal or (x_m, y_m), optional
            The goal the outcome belongs to (ignored when it is not the current goal);
            None: the current goal.

        Returns
        -------
        bool
            True when applied to the current goal.
        """
        xy = goal.xy_m if isinstance(goal, Goal) else goal
        added = self.manager.blacklist_added
        applied = self.manager.report_navigation(outcome, xy)
        self._reported_blacklisted += self.manager.blacklist_added - added
        return applied

    def clock_jumped(self, now_s: float) -> None:
        """The clock jumped (sim reset, ``/clock`` leap): the current goal's progress and
        arrival timers restart at ``now_s`` instead of timing out (or never) on a stale
        reference; the ``routed`` tour forgets its kept path lengths and gains (a sim
        reset comes with a new map), and so does the robot's path of approach goals."""
        self.manager.restart_timers(now_s)
        self._fallbacks.reset()
        if self._overlay is not None:
            self._overlay.reset()
        if self._planner is not None:
            self._planner.reset()

    # ------------------------------------------------------------------- step
    def _detect(self, grid: GridMap, layer: GridMap | None) -> None:
        self._fcache.start(grid)
        det = detect_frontiers(grid, layer, self._frontier_params,
                               groups=self._strategy.candidates == "groups",
                               cache=self._fcache)
        self._det = det
        self._layer_warning = det.layer_warning
        self._frontiers = (det.frontiers if self._planner is None else split_frontiers(
            grid, det.frontiers, self._selection_params.frontier_split_m,
            self._frontier_params, det.extra_obstacles, det.passable, self._fcache))
        self._graph = PathGraphs(grid, det.extra_obstacles, self._frontier_params,
                                 self._selection_params, det.passable)
        self._key = (grid, layer)

    def _detect_rrt(self, grid: GridMap, xy: tuple[float, float]) -> None:
        """Grow the RRTs and filter their points into this step's candidates."""
        det = self._det
        assert det is not None
        if self._rrt is None:
            self._rrt = RrtFrontierDetector(self._rrt_params, self._frontier_params)
        self._frontiers = self._rrt.update(grid, xy, det.passable, det.extra_obstacles)

    def step(self, now_s: float, grid: GridMap, pose: tuple[float, float, float],
             layer: GridMap | None = None,
             labels: npt.NDArray[np.integer] | None = None) -> ExplorerStep:
        """One decision.

        Parameters
        ----------
        now_s : float
            Current time in seconds (sim or ROS clock; monotonic between resets).
        grid : GridMap
            The occupancy map. While it is the same object as the last step's or an equal
            one (geometry, frame and cells; a republished map), frontiers and path graphs
            are reused; the goal manager still gets this map (its stamp).
        pose : (x_m, y_m, yaw_rad)
            The robot's pose in the map frame.
        layer : GridMap, optional
            The object costmap (any geometry; resampled onto ``grid``); used when
            ``FrontierParams.use_object_costmap``. Same object while unchanged.
        labels : ndarray of int, shape (H, W), optional
            Region labels aligned with ``grid`` (0 = no region); others are ignored with a
            warning.

        Returns
        -------
        ExplorerStep
        """
        warnings: list[tuple[str, str]] = []
        t0 = time.perf_counter()
        # the map near blacklisted goals changed: their frontiers are candidates again
        self.manager.retry_changed(grid, self._frontier_params.occupied_threshold)
        key = self._key
        grid = self._seen_map(grid, layer, pose)
        # The goal manager gets the map as given (its stamp tells a newer map); everything
        # map-derived gets the map the products were made from (identity caches hit).
        stamped = grid
        detected, grid = self._detected(grid, layer)
        detected = detected or self._key is not key     # or on the overlaid map, above
        x, y, yaw = (float(v) for v in pose)
        self._fallbacks.add(x, y)
        if self._strategy.candidates == "rrt":
            self._detect_rrt(grid, (x, y))
            detected = True
        if self._layer_warning:
            warnings.append((WARN_LAYER_FRAME, self._layer_warning))
        t1 = time.perf_counter()
        manager = self.manager
        if manager.start_xy_m is None:
            manager.set_start((x, y), yaw)
        if labels is not None and labels.shape != grid.shape:
            warnings.append((WARN_LABELS_SHAPE, f"region labels of shape {labels.shape} do "
                                                f"not match the map's {grid.shape}: ignored"))
            labels = None
        frontiers = self._frontiers
        robot_rc = grid.world_to_cell(x, y)
        start = self._start_cell(grid, robot_rc, (x, y), warnings)
        planner, tour = self._planner, None
        if planner is not None:
            assert self._det is not None
            frontiers = planner.viewpoints(grid, frontiers, self._graph, start,
                                          self._det.passable)
        dist, excluded = self._distances(start, robot_rc, frontiers)
        added = manager.blacklist_added
        if dist is not None and manager.judge_aborted(grid, frontiers, dist):
            excluded = manager.excluded(frontiers)
        if dist is not None and len(dist) and not self._any_selectable(frontiers, dist, excluded):
            assert start is not None
            frontiers, dist, excluded = self._unreachable_goals(grid, frontiers, dist, excluded,
                                                                start, robot_rc)
        elif dist is not None and len(dist):
            self._fallbacks.revisits.progress()
        if planner is not None and dist is not None:
            tour = planner.tour_costs(grid, frontiers, dist, excluded, self._graph, robot_rc,
                                     labels, manager.goal_frontier(grid, frontiers))
        old_goal = manager.goal
        res = manager.step(now_s, (x, y), stamped, frontiers, dist, StepInputs(
            labels, robot_rc, excluded, tour.tour_cost_m if tour is not None else None, yaw))
        blacklisted = manager.blacklist_added - added + self._reported_blacklisted
        self._reported_blacklisted = 0
        switched = (res.action is Action.NEW_GOAL and res.goal is not None
                    and old_goal is not None and not (old_goal.is_return or old_goal.is_turn)
                    and not blacklisted
                    and res.selection is not None
                    and _frontier_alive(grid, frontiers, res.selection.costs, old_goal.xy_m,
                                        self._selection_params.frontier_match_radius_m))
        reason = (f"{res.reason}: a revisit of the robot's path, for a loop closure"
                  if res.action is Action.NEW_GOAL and self._fallbacks.revisits.under_way
                  else res.reason)
        return ExplorerStep(res.action, res.goal, reason, res.selection, frontiers, dist,
                            robot_rc, detected, blacklisted, switched, tuple(warnings),
                            t1 - t0, time.perf_counter() - t1, tour,
                            planner.viewpoint_s + planner.tour_s if planner is not None else 0.0)

    def add_scan(self, stamp_s: float, robot_pose: tuple[float, float, float],
                 angles: npt.ArrayLike, ranges: npt.ArrayLike, range_max_m: float,
                 range_min_m: float = 0.0) -> None:
        """A lidar scan and the robot's map-frame pose when it was taken, for the next
        steps' map (see :class:`~explore_seg.core.scan_overlay.ScanOverlay`; ignored
        without an overlay). Raises ValueError on a malformed scan, changing nothing."""
        if self._overlay is not None:
            self._overlay.add_scan(stamp_s, robot_pose, angles, ranges, range_max_m,
                                   range_min_m)

    def map_corrected(self, stamp_s: float | None = None) -> None:
        """A SLAM correction (a loop closure that re-rendered the map) at ``stamp_s`` (None:
        unknown): the overlay forgets the scans taken before it, laid at uncorrected poses
        (:meth:`ScanOverlay.forget_before`), the robot's path of approach goals starts
        anew (its positions were uncorrected too), and revisits may start (revisit.py)."""
        if self._overlay is not None:
            self._overlay.forget_before(stamp_s)
        self._fallbacks.corrected()

    def _detected(self, grid: GridMap, layer: GridMap | None) -> tuple[bool, GridMap]:
        """Detect on ``grid`` unless the products are of an equal map and layer; returns
        whether it detected and the map the products belong to."""
        key = self._key
        if key is None or not (_same_map(key[0], grid) and _same_map(key[1], layer)):
            self._detect(grid, layer)
            return True, grid
        return False, key[0]

    def _seen_map(self, grid: GridMap, layer: GridMap | None,
                  pose: tuple[float, float, float]) -> GridMap:
        """The map with the overlay's scans when they leave a selectable frontier, else
        the map alone: the SLAM map, not the recent scans, decides that nothing is left
        (a view that never became a keyframe is not in the map the user keeps)."""
        if self._overlay is None:
            return grid
        seen = self._overlay.apply(grid)
        if seen is grid:
            return grid
        self._detected(seen, layer)
        xy = (float(pose[0]), float(pose[1]))
        robot_rc = seen.world_to_cell(*xy)
        start = self._start_cell(seen, robot_rc, xy, [])   # its warnings come from step
        frontiers = self._frontiers
        if self._strategy.candidates == "rrt" and self._det is not None:
            # the RRT detection has no frontier groups: judge the map by its groups
            frontiers = find_frontiers(seen, self._det.extra_obstacles, self._frontier_params,
                                       passable=self._det.passable)
        dist, excluded = self._distances(start, robot_rc, frontiers)
        if dist is None or excluded is None or not (np.isfinite(dist) & ~excluded).any():
            return grid
        return seen

    def _any_selectable(self, frontiers: list[Frontier], dist: npt.NDArray[np.float64],
                        excluded: npt.NDArray[np.bool_]) -> bool:
        """True when a frontier has a path and is not blacklisted (``routed``: and the
        tour would visit it; a reachable view too small to visit must not hide an
        unreachable big one from the lookouts and approaches)."""
        ok = np.isfinite(dist) & ~excluded
        if self._planner is not None and ok.any():
            ok &= self._planner.selectable(frontiers, dist, excluded)
        return bool(ok.any())

    def _unreachable_goals(self, grid: GridMap, frontiers: list[Frontier],
                           dist: npt.NDArray[np.float64], excluded: npt.NDArray[np.bool_],
                           start: tuple[int, int], robot_rc: tuple[int, int]
                           ) -> tuple[list[Frontier], npt.NDArray[np.float64],
                                      npt.NDArray[np.bool_]]:
        """No selectable frontier: the fallback goals (lookouts, approaches, the revisit
        under way: :class:`~explore_seg.core.selection.fallbacks.Fallbacks`) from the
        robot's start cell. Returns the frontiers, their path lengths and blacklist
        mask."""
        assert self._det is not None and self._graph is not None
        hop = math.hypot(start[0] - robot_rc[0], start[1] - robot_rc[1]) * grid.resolution_m
        reach = Reach(self._graph.graph, start, self._det.passable, hop)
        return self._fallbacks.goals(grid, frontiers, dist, excluded, reach,
                                     self._selection_params, self._frontier_params,
                                     self._det.extra_obstacles)

    def _start_cell(self, grid: GridMap, robot_rc: tuple[int, int], xy: tuple[float, float],
                    warnings: list[tuple[str, str]]) -> tuple[int, int] | None:
        """The robot's passable start cell; None (with a warning) when the robot is outside
        the map or has no passable cell within ``start_search_radius_m``."""
        graph = self._graph
        assert graph is not None
        if not grid.in_bounds(*robot_rc):
            warnings.append((WARN_ROBOT_OUTSIDE,
                             f"robot at ({xy[0]:.2f}, {xy[1]:.2f}) lies outside the map"))
            return None
        radius = metres_to_cells(self._selection_params.start_search_radius_m, grid.resolution_m)
        start = graph.graph.nearest_passable(robot_rc, radius)
        if start is None:
            warnings.append((WARN_ROBOT_BLOCKED, f"robot cell {robot_rc} is not passable and "
                                                 "has no passable cell nearby: no new goals"))
        return start

    def _distances(self, start: tuple[int, int] | None, robot_rc: tuple[int, int],
                   frontiers: list[Frontier]
                   ) -> tuple[npt.NDArray[np.float64] | None, npt.NDArray[np.bool_] | None]:
        """Path lengths robot -> cPoints and the blacklist mask; (None, None) without a
        start cell (:meth:`_start_cell`)."""
        graph = self._graph
        assert graph is not None
        if start is None:
            return None, None
        excluded = self.manager.excluded(frontiers)
        return graph.distances(robot_rc, frontiers, excluded), excluded


def _same_map(a: GridMap | None, b: GridMap | None) -> bool:
    """True when ``a`` and ``b`` are the same map or equal ones (geometry, frame and cells;
    the stamp aside), so that every product derived from one holds for the other."""
    if a is b:
        return True
    if a is None or b is None:
        return False
    return (a.shape == b.shape and a.resolution_m == b.resolution_m
            and a.origin_xy_m == b.origin_xy_m and a.origin_yaw_rad == b.origin_yaw_rad
            and a.frame_id == b.frame_id and np.array_equal(a.data, b.data))


def _frontier_alive(grid: GridMap, frontiers: Sequence[Frontier],
                    costs: npt.NDArray[np.float64], xy: tuple[float, float],
                    radius_m: float) -> bool:
    """True when a frontier with finite cost has a cell within ``radius_m`` of ``xy``."""
    for f, cost in zip(frontiers, costs):
        if not np.isfinite(cost):
            continue
        fx, fy = grid.cells_to_world(f.cells[:, 0], f.cells[:, 1])
        if float(np.min(np.hypot(fx - xy[0], fy - xy[1]))) <= radius_m:
            return True
    return False


__all__ = ["Detection", "Explorer", "ExplorerStep", "detect_frontiers", "WARN_LABELS_SHAPE", "WARN_LAYER_FRAME",
           "WARN_ROBOT_BLOCKED", "WARN_ROBOT_OUTSIDE"]
