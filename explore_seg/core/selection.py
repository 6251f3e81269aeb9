"""Frontier target selection (Kim, Kim & Lee, RA-L 2022, Alg. 2 and eq. 1-3) and goal
bookkeeping.

Three strategies score every frontier group ``i`` (lower is better; unreachable = inf):

* ``paper`` (eq. 1-3)::

      cost_i = alpha * distGain_i + beta / sizeGain_i + regionGain_i
      distGain_i   = dist_i / sum_j dist_j        (j over groups with a finite dist)
      sizeGain_i   = cSize_i / sum_j cSize_j      (j over all candidate groups)
      regionGain_i = 0 if region(cPoint_i) == region(robot) else gamma

  ``dist`` is the path length robot -> cPoint over passable space (free, obstacles of the
  map and object costmap inflated by the robot radius), inf when unreachable or when the
  cPoint is not passable (e.g. inside an object obstacle). regionGain is 0 for every group
  when no labels are given or the robot's cell has no region (label <= 0); a cPoint with
  no region counts as in the robot's region (as the seed code does with its "no region"
  label).
* ``nearest``: ``cost_i = dist_i`` (greedy nearest frontier, Yamauchi).
* ``explore_lite``: ``cost_i = potential_scale * dist_i - gain_scale * length_i`` with
  ``length_i = cSize_i * resolution`` in metres (explore_lite's ``frontierCost`` with
  ``orientation_scale = 0``, its default). Deviations from explore_lite: ``dist_i`` is the
  path length to the cPoint in metres, where explore_lite uses the straight-line distance
  to the nearest frontier cell multiplied by the map resolution (metres * m/cell, a unit
  bug noted in STYLE.md).

alpha, beta, gamma: the paper's numeric values could not be recovered from the material
available to us (the seed code hard-codes a different, unweighted objective). The
defaults (alpha = 1, beta = 0.001, gamma = 1) are our choice: both gains are fractions, so
alpha = 1 makes the whole distance spread worth 1; beta = 0.001 makes a group holding
0.1 % of all frontier cells cost 1 (a 10-cell group among 1000 costs 0.1, as much as a
tenth of the distance spread); gamma = 1 makes leaving the robot's region cost as much as
the largest distance difference, so a room is finished first unless what is left in it
is tiny or far. beta was chosen by ``bench/sweep_selection.py`` (seeds 100..109, disjoint
from the benchmark's, generated cluttered house, ``paper_noobj``): with beta = 0.01 the
size term outweighed distance (the robot crossed rooms for big groups and came back for
small ones); beta = 0.001 reached 95 % coverage 10 % sooner on paired seeds with shorter
paths, beta = 0.0003 was no better, and gamma = 0 or 0.3 was slower than gamma = 1.
"""

from __future__ import annotations

import enum
import math
from collections import deque
from dataclasses import dataclass, field, fields
from typing import Callable, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams, traversable_mask
from explore_seg.core.grid import GridMap
from explore_seg.core.paths import MAX_BLOCK_CELLS, BlockGraph, nearest_true

STRATEGIES = ("paper", "nearest", "explore_lite")
POSE_TOPIC_TYPES = ("odom", "pose")
_FP = FrontierParams  # defaults of the detection fields are FrontierParams' own
#: Goal points kept per vanished-frontier area, and areas kept (oldest dropped).
_FLICKER_POINTS = 20
_FLICKER_AREAS = 100


@dataclass(frozen=True)
class SelectionParams:
    """Parameters of target selection (and of the ``target_selector`` node).

    The detection fields mirror :class:`FrontierParams` (same names and defaults); get
    them as a FrontierParams with :meth:`frontier_params`.
    """

    strategy: str = field(default="paper", metadata={
        "doc": "cost function: paper | nearest | explore_lite"})
    alpha: float = field(default=1.0, metadata={"doc": "paper: weight of distGain"})
    beta: float = field(default=0.001, metadata={"doc": "paper: weight of 1/sizeGain"})
    gamma: float = field(default=1.0, metadata={
        "doc": "paper: regionGain of a frontier outside the robot's region"})
    potential_scale: float = field(default=3.0, metadata={
        "doc": "explore_lite: weight of the path length", "unit": "1/m"})
    gain_scale: float = field(default=1.0, metadata={
        "doc": "explore_lite: weight of the frontier length", "unit": "1/m"})
    region_search_radius_m: float = field(default=0.3, metadata={
        "doc": "a cell without region takes the nearest labelled cell's within this radius",
        "unit": "m"})
    path_block_cells: int = field(default=4, metadata={
        "doc": f"path lengths on blocks of this many cells per side (1 = exact, "
               f"max {MAX_BLOCK_CELLS})", "unit": "cells"})
    start_search_radius_m: float = field(default=0.5, metadata={
        "doc": "a robot on a non-passable cell starts from the nearest passable cell "
               "within this radius", "unit": "m"})
    hysteresis_margin: float = field(default=0.1, metadata={
        "doc": "switch goals only when the new cost < current - margin * |current|"})
    progress_timeout_s: float = field(default=30.0, metadata={
        "doc": "blacklist a goal whose distance did not decrease for this long", "unit": "s"})
    progress_min_m: float = field(default=0.1, metadata={
        "doc": "decrease of the distance to the goal that counts as progress", "unit": "m"})
    goal_reached_tolerance_m: float = field(default=0.3, metadata={
        "doc": "robot closer than this to its goal has reached it", "unit": "m"})
    frontier_match_radius_m: float = field(default=0.5, metadata={
        "doc": "a frontier with a cell this close to the goal (plus the goal's distance to "
               "its frontier when set) is the goal's frontier", "unit": "m"})
    arrival_wait_s: float = field(default=2.0, metadata={
        "doc": "after reaching a goal, wait this long (or for a newer map) before judging "
               "whether its frontier was cleared", "unit": "s"})
    goal_change_min_m: float = field(default=0.3, metadata={
        "doc": "a new goal closer than this to the current one is not sent", "unit": "m"})
    blacklist_radius_m: float = field(default=0.5, metadata={
        "doc": "frontiers whose cPoint lies this close to a blacklisted goal are skipped",
        "unit": "m"})
    blacklist_max: int = field(default=50, metadata={
        "doc": "blacklist length (oldest entries dropped)"})
    unknown_path_factor: float = field(default=1.5, metadata={
        "doc": "when no cPoint is reachable through known free space, distances through "
               "unknown cells are used, multiplied by this factor (>= 1)"})
    blacklist_retries: int = field(default=1, metadata={
        "doc": "times the blacklist is cleared to retry its frontiers before DONE"})
    flicker_vanish_count: int = field(default=3, metadata={
        "doc": "blacklist a goal area once its frontier vanished this many times before the "
               "robot got there with its cells still unknown (it came back in between: a "
               "wall edge flickering between occupied and free next to unknown space pulls "
               "the robot back and forth otherwise); 0 = never"})
    flicker_radius_m: float = field(default=1.0, metadata={
        "doc": "goals within this distance of the first vanished goal of an area count as "
               "that area for flicker_vanish_count", "unit": "m"})
    done_confirmations: int = field(default=3, metadata={
        "doc": "consecutive decisions without a reachable frontier before DONE"})
    return_to_start: bool = field(default=False, metadata={
        "doc": "drive back to the start pose when exploration is done"})
    rate_hz: float = field(default=1.0, metadata={"doc": "decision rate", "unit": "Hz"})
    pose_topic_type: str = field(default="odom", metadata={
        "doc": "robot pose source: odom (Odometry on 'odom', pose in the map "
               "frame) | pose (PoseWithCovarianceStamped on 'pose')"})
    pose_timeout_s: float = field(default=5.0, metadata={
        "doc": "a pose older than this is not used", "unit": "s"})
    goal_republish_s: float = field(default=0.0, metadata={
        "doc": "re-publish the current goal this often (0 = only when it changes)",
        "unit": "s"})
    autostart: bool = field(default=True, metadata={
        "doc": "start exploring without a call to ~/start"})
    use_regions: bool = field(default=True, metadata={
        "doc": "use the regions labels for regionGain (paper strategy)"})
    # ---- detection (FrontierParams' fields and defaults)
    free_threshold: int = field(default=_FP.free_threshold, metadata={
        "doc": "map cells with 0 <= value < this are free", "unit": "percent"})
    occupied_threshold: int = field(default=_FP.occupied_threshold, metadata={
        "doc": "map cells with value >= this are obstacles", "unit": "percent"})
    object_occupied_threshold: int = field(default=_FP.object_occupied_threshold, metadata={
        "doc": "object_costmap cells with value >= this are obstacles", "unit": "percent"})
    min_group_size_cells: int = field(default=_FP.min_group_size_cells, metadata={
        "doc": "frontier groups with fewer cells are ignored", "unit": "cells"})
    free_neighbour_connectivity: int = field(default=_FP.free_neighbour_connectivity, metadata={
        "doc": "neighbourhood (4 or 8) in which an unknown cell needs a free cell"})
    group_connectivity: int = field(default=_FP.group_connectivity, metadata={
        "doc": "connectivity (4 or 8) used to group frontier cells"})
    robot_radius_m: float = field(default=_FP.robot_radius_m, metadata={
        "doc": "obstacles are inflated by this radius for paths and cPoints", "unit": "m"})
    cpoint_search_radius_m: float = field(default=_FP.cpoint_search_radius_m, metadata={
        "doc": "how far a group's cPoint may be moved to reach a passable cell", "unit": "m"})
    use_object_costmap: bool = field(default=_FP.use_object_costmap, metadata={
        "doc": "treat occupied object_costmap cells as obstacles"})
    map_transient_local: bool = field(default=_FP.map_transient_local, metadata={
        "doc": "transient-local map/object_costmap/regions subscriptions"})

    def __post_init__(self) -> None:
        if self.strategy not in STRATEGIES:
            raise ValueError(f"strategy must be one of {STRATEGIES}, got {self.strategy!r}")
        if self.pose_topic_type not in POSE_TOPIC_TYPES:
            raise ValueError(f"pose_topic_type must be one of {POSE_TOPIC_TYPES}, "
                             f"got {self.pose_topic_type!r}")
        for name in ("alpha", "beta", "gamma", "potential_scale", "gain_scale",
                     "region_search_radius_m", "start_search_radius_m", "hysteresis_margin",
                     "progress_min_m", "goal_reached_tolerance_m", "frontier_match_radius_m",
                     "blacklist_radius_m", "goal_republish_s", "arrival_wait_s",
                     "goal_change_min_m", "flicker_radius_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        for name in ("progress_timeout_s", "rate_hz", "pose_timeout_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not 1 <= self.path_block_cells <= MAX_BLOCK_CELLS:
            raise ValueError(f"path_block_cells must be in 1..{MAX_BLOCK_CELLS}, "
                             f"got {self.path_block_cells}")
        if self.blacklist_max < 1:
            raise ValueError(f"blacklist_max must be >= 1, got {self.blacklist_max}")
        if not self.unknown_path_factor >= 1.0:
            raise ValueError(f"unknown_path_factor must be >= 1, got {self.unknown_path_factor}")
        if self.blacklist_retries < 0:
            raise ValueError(f"blacklist_retries must be >= 0, got {self.blacklist_retries}")
        if self.flicker_vanish_count < 0:
            raise ValueError(f"flicker_vanish_count must be >= 0, got "
                             f"{self.flicker_vanish_count}")
        if self.done_confirmations < 1:
            raise ValueError(f"done_confirmations must be >= 1, got {self.done_confirmations}")
        self.frontier_params()  # validates the detection fields

    def frontier_params(self) -> FrontierParams:
        """The detection fields as a :class:`FrontierParams`."""
        names = {f.name for f in fields(FrontierParams)}
        return FrontierParams(**{n: getattr(self, n) for n in names})


# --------------------------------------------------------------------------- regions


def region_at(labels: npt.NDArray[np.integer], rc: tuple[int, int], radius_cells: int) -> int:
    """Region id at cell ``rc``: its label if > 0, else the nearest label > 0 within
    ``radius_cells`` (Euclidean), else 0 (no region). Cells outside the image give 0."""
    h, w = labels.shape
    r, c = int(rc[0]), int(rc[1])
    if not (0 <= r < h and 0 <= c < w):
        return 0
    v = int(labels[r, c])
    if v > 0:
        return v
    r0, c0 = max(0, r - radius_cells), max(0, c - radius_cells)
    win = labels[r0:r + radius_cells + 1, c0:c + radius_cells + 1]
    near = nearest_true(win > 0, (r - r0, c - c0), radius_cells)
    if near is None:
        return 0
    return int(win[near])


def frontier_regions(frontiers: Sequence[Frontier], labels: npt.NDArray[np.integer] | None,
                     radius_cells: int) -> npt.NDArray[np.int64]:
    """Region id of each frontier's cPoint (:func:`region_at`); zeros without labels."""
    if labels is None:
        return np.zeros(len(frontiers), dtype=np.int64)
    return np.asarray([region_at(labels, f.point_rc, radius_cells) for f in frontiers],
                      dtype=np.int64)


# ----------------------------------------------------------------------------- costs


def _resolution(frontiers: Sequence[Frontier]) -> float:
    """Map resolution the frontiers were detected at (length_m / size_cells)."""
    f = frontiers[0]
    return f.length_m / f.size_cells


def _check_dist(frontiers: Sequence[Frontier], dist_m: npt.ArrayLike) -> np.ndarray:
    d = np.asarray(dist_m, dtype=np.float64).reshape(-1)
    if d.shape[0] != len(frontiers):
        raise ValueError(f"dist_m has {d.shape[0]} entries, expected one per frontier "
                         f"({len(frontiers)})")
    if np.any(np.isnan(d)) or np.any(d < 0):
        raise ValueError("dist_m must be >= 0 or inf, got NaN or negative values")
    return d


def compute_costs(frontiers: Sequence[Frontier], dist_m: npt.ArrayLike,
                  labels: npt.NDArray[np.integer] | None, robot_region: int,
                  params: SelectionParams = SelectionParams(),
                  regions: npt.NDArray[np.int64] | None = None) -> npt.NDArray[np.float64]:
    """Cost of every frontier under ``params.strategy`` (formulas in the module docstring).

    Parameters
    ----------
    frontiers : sequence of Frontier
    dist_m : array_like of float, shape (N,)
        Path length robot -> cPoint, ``inf`` when unreachable.
    labels : ndarray of int, shape (H, W), or None
        Region labels aligned with the map (0 = no region); None disables regionGain.
    robot_region : int
        Region id of the robot (<= 0: unknown, regionGain disabled).
    params : SelectionParams
    regions : ndarray of int, shape (N,), optional
        Precomputed :func:`frontier_regions` (else computed from ``labels``).

    Returns
    -------
    ndarray of float64, shape (N,)
        ``inf`` where ``dist_m`` is inf or the cPoint is not passable.

    Raises
    ------
    ValueError
        When ``dist_m`` does not hold one value >= 0 per frontier.
    """
    d = _check_dist(frontiers, dist_m).copy()
    n = len(frontiers)
    if n == 0:
        return np.zeros(0, dtype=np.float64)
    d[[not f.point_passable for f in frontiers]] = np.inf
    finite = np.isfinite(d)
    costs = np.full(n, np.inf)
    if not finite.any():
        return costs
    size = np.asarray([f.size_cells for f in frontiers], dtype=np.float64)
    if params.strategy == "nearest":
        costs[finite] = d[finite]
    elif params.strategy == "explore_lite":
        length = np.asarray([f.length_m for f in frontiers], dtype=np.float64)
        costs[finite] = params.potential_scale * d[finite] - params.gain_scale * length[finite]
    else:
        total_d = float(d[finite].sum())
        dist_gain = d[finite] / total_d if total_d > 0 else np.zeros(int(finite.sum()))
        size_gain = size[finite] / float(size.sum())
        region_gain = np.zeros(int(finite.sum()))
        if labels is not None and robot_region > 0:
            rad = int(math.floor(params.region_search_radius_m / _resolution(frontiers) + 1e-9))
            reg = regions if regions is not None else frontier_regions(frontiers, labels, rad)
            reg = np.asarray(reg)[finite]
            region_gain = np.where((reg > 0) & (reg != robot_region), params.gamma, 0.0)
        costs[finite] = params.alpha * dist_gain + params.beta / size_gain + region_gain
    return costs


@dataclass(frozen=True)
class Selection:
    """Outcome of :func:`select_goal`.

    Attributes
    ----------
    index : int or None
        Index into the frontier list of the cheapest frontier, None when none is reachable.
    costs : ndarray of float64, shape (N,)
    regions : ndarray of int64, shape (N,)
        Region of each cPoint (zeros without labels).
    robot_region : int
        Region of the robot (0 = unknown / no labels).
    region_gain_active : bool
        False when regionGain was off (paper strategy without labels or without a robot
        region); the node logs it once.
    """

    index: int | None
    costs: npt.NDArray[np.float64] = field(repr=False)
    regions: npt.NDArray[np.int64] = field(repr=False)
    robot_region: int
    region_gain_active: bool


def select_goal(frontiers: Sequence[Frontier], dist_m: npt.ArrayLike,
                labels: npt.NDArray[np.integer] | None, robot_rc: tuple[int, int],
                params: SelectionParams = SelectionParams(),
                resolution_m: float | None = None,
                excluded: npt.NDArray[np.bool_] | None = None) -> Selection:
    """The min-cost frontier (paper Alg. 2), with the costs and regions used.

    Parameters
    ----------
    frontiers : sequence of Frontier
    dist_m : array_like of float, shape (N,)
    labels : ndarray of int, shape (H, W), or None
        Region labels aligned with the map; ignored when ``params.use_regions`` is False.
    robot_rc : (int, int)
        Robot cell (for its region).
    params : SelectionParams
    resolution_m : float, optional
        Map resolution for the region search radius (taken from the frontiers if None).
    excluded : ndarray of bool, shape (N,), optional
        Frontiers not to choose (blacklisted); they still count in the normalisations.

    Returns
    -------
    Selection

    Raises
    ------
    ValueError
        When ``dist_m`` or ``excluded`` do not have one entry per frontier.
    """
    n = len(frontiers)
    use_labels = labels if params.use_regions else None
    if resolution_m is None:
        resolution_m = _resolution(frontiers) if n else 1.0
    rad = int(math.floor(params.region_search_radius_m / resolution_m + 1e-9))
    robot_region = region_at(use_labels, robot_rc, rad) if use_labels is not None else 0
    regions = frontier_regions(frontiers, use_labels, rad)
    costs = compute_costs(frontiers, dist_m, use_labels, robot_region, params, regions)
    active = params.strategy == "paper" and use_labels is not None and robot_region > 0
    pick = costs.copy()
    if excluded is not None:
        ex = np.asarray(excluded, dtype=bool).reshape(-1)
        if ex.shape[0] != n:
            raise ValueError(f"excluded has {ex.shape[0]} entries, expected {n}")
        pick[ex] = np.inf
    index = int(np.argmin(pick)) if n and np.isfinite(pick).any() else None
    return Selection(index, costs, regions, robot_region, active)


def frontier_distances(graph: BlockGraph, robot_rc: tuple[int, int],
                       frontiers: Sequence[Frontier],
                       params: SelectionParams = SelectionParams(),
                       fallback: Callable[[], BlockGraph] | None = None,
                       excluded: npt.NDArray[np.bool_] | None = None
                       ) -> npt.NDArray[np.float64]:
    """Path length (m) robot -> each cPoint, all from one sweep; inf when unreachable.

    A robot on a non-passable cell (inflated margin, map noise) starts from the nearest
    passable cell within ``start_search_radius_m`` (the straight hop is added); without
    one every distance is inf. cPoints that are not passable get inf.

    ``fallback`` builds a graph over an optimistic mask (free or unknown, see
    ``traversable_mask(..., allow_unknown=True)``). It is used only when no cPoint is
    reachable through known free space, leaving out the frontiers marked in ``excluded``
    (the goal manager's blacklist: a reachable but blacklisted frontier must not hide
    the others). A frontier seen through a doorway whose known free strip is narrower
    than the robot is then still a goal (the planner may cross unknown cells, as Nav2
    does with ``allow_unknown``) instead of ending exploration early. Those distances
    are multiplied by ``unknown_path_factor``.

    Returns
    -------
    ndarray of float64, shape (N,)
    """
    d = _frontier_distances(graph, robot_rc, frontiers, params)
    usable = np.isfinite(d)
    if excluded is not None:
        usable &= ~np.asarray(excluded, dtype=bool)
    if fallback is not None and len(d) and not usable.any():
        d = _frontier_distances(fallback(), robot_rc, frontiers, params) \
            * params.unknown_path_factor
    return d


def _frontier_distances(graph: BlockGraph, robot_rc: tuple[int, int],
                        frontiers: Sequence[Frontier], params: SelectionParams
                        ) -> npt.NDArray[np.float64]:
    n = len(frontiers)
    if n == 0:
        return np.zeros(0, dtype=np.float64)
    res = graph.resolution_m
    rad = int(math.floor(params.start_search_radius_m / res + 1e-9))
    start = graph.nearest_passable(robot_rc, rad)
    if start is None:
        return np.full(n, np.inf)
    hop = math.hypot(start[0] - robot_rc[0], start[1] - robot_rc[1]) * res
    pts = np.asarray([f.point_rc for f in frontiers], dtype=np.int64)
    d = graph.distances(start, pts) + hop
    d[[not f.point_passable for f in frontiers]] = np.inf
    return d


class PathGraphs:
    """Path graphs of one map (and object layer) version, for :func:`frontier_distances`.

    The graph over known free space is built at once; the optimistic graph (free or
    unknown) only when a decision needs it, and then kept for this map version.

    Parameters
    ----------
    grid : GridMap
    extra_obstacles : ndarray of bool, shape (H, W), optional
        Object-layer obstacles aligned with ``grid``.
    params : SelectionParams
    passable : ndarray of bool, optional
        The known-free passable mask when the caller already has it.
    """

    def __init__(self, grid: GridMap, extra_obstacles: npt.NDArray[np.bool_] | None,
                 params: SelectionParams, passable: npt.NDArray[np.bool_] | None = None
                 ) -> None:
        self._grid, self._extra, self._params = grid, extra_obstacles, params
        if passable is None:
            passable = traversable_mask(grid, extra_obstacles, params.frontier_params())
        self.graph = BlockGraph(passable, grid.resolution_m, params.path_block_cells)
        self._fallback: BlockGraph | None = None

    def fallback(self) -> BlockGraph:
        """The graph over free-or-unknown cells (built on first use)."""
        if self._fallback is None:
            mask = traversable_mask(self._grid, self._extra, self._params.frontier_params(),
                                    allow_unknown=True)
            self._fallback = BlockGraph(mask, self._grid.resolution_m,
                                        self._params.path_block_cells)
        return self._fallback

    def distances(self, robot_rc: tuple[int, int], frontiers: Sequence[Frontier],
                  excluded: npt.NDArray[np.bool_] | None = None
                  ) -> npt.NDArray[np.float64]:
        """:func:`frontier_distances` with the fallback through unknown space
        (``excluded``: e.g. :meth:`GoalManager.excluded`)."""
        return frontier_distances(self.graph, robot_rc, frontiers, self._params,
                                  self.fallback, excluded)


# ------------------------------------------------------------------------ goal manager


class Action(enum.Enum):
    """What :meth:`GoalManager.step` asks the caller to do."""

    NEW_GOAL = "new_goal"    # send ``goal``
    KEEP = "keep"            # keep driving to the current goal
    WAIT = "wait"            # nothing to do now (no reachable frontier yet, bad input)
    DONE = "done"            # exploration finished


@dataclass(frozen=True)
class Goal:
    """A navigation goal in the map frame."""

    xy_m: tuple[float, float]
    yaw_rad: float
    rc: tuple[int, int]
    frontier_size_cells: int
    cost: float
    is_return: bool = False
    frontier_gap_m: float = 0.0


@dataclass(frozen=True)
class StepResult:
    """Outcome of one :meth:`GoalManager.step`."""

    action: Action
    goal: Goal | None
    reason: str
    selection: Selection | None = None


def goal_yaw(frontier: Frontier, robot_xy_m: tuple[float, float]) -> float:
    """Heading at a frontier's cPoint toward the unknown side: cPoint -> group centroid
    (robot -> cPoint when the two coincide)."""
    px, py = frontier.point_xy_m
    gx, gy = frontier.centroid_xy_m
    if math.hypot(gx - px, gy - py) > 1e-9:
        return math.atan2(gy - py, gx - px)
    return math.atan2(py - robot_xy_m[1], px - robot_xy_m[0])


class GoalManager:
    """Goal keeping, blacklisting and termination around :func:`select_goal` (ROS-free).

    Per call of :meth:`step` (one decision tick):

    1. With a current goal: progress is a decrease of the robot-goal distance by at least
       ``progress_min_m``; none for ``progress_timeout_s`` blacklists the goal. Reaching
       it (``goal_reached_tolerance_m``) while its frontier (a frontier with a cell
       within ``frontier_match_radius_m`` + the goal's gap to its frontier) is still
       there after a newer map (or ``arrival_wait_s``) blacklists it too; reaching a
       return-to-start goal ends exploration (DONE).
    2. Frontiers whose cPoint lies within ``blacklist_radius_m`` of a blacklisted goal
       are excluded. When no reachable frontier is detected but the current goal's
       frontier cells are still unknown (a thin frontier seen at a grazing angle comes and
       goes), the goal is kept. When no reachable frontier remains for
       ``done_confirmations`` consecutive ticks: the blacklist is cleared and its
       frontiers retried (``blacklist_retries`` times), then DONE (or first a
       return-to-start goal).
    3. The current goal is kept unless its frontier vanished or another frontier is
       cheaper than the current goal's frontier by ``hysteresis_margin * |cost|``; a
       new goal within ``goal_change_min_m`` of the current one is not sent. Observed
       cells do not become unknown again, so a frontier that vanishes before the robot
       arrives with its cells still unknown (so not cleared by sensing: its free
       neighbours turned occupied or were covered by an object) and keeps coming back at
       the same place (within ``flicker_radius_m`` of where it first vanished) is map
       flicker: after ``flicker_vanish_count`` such vanishings its goals are blacklisted.

    DONE is final until :meth:`reset`. The blacklist keeps the newest ``blacklist_max``
    goals.
    """

    def __init__(self, params: SelectionParams = SelectionParams()) -> None:
        self.params = params
        self._blacklist: deque[tuple[float, float]] = deque(maxlen=params.blacklist_max)
        # Areas where a goal's frontier vanished before arrival: [count, goal points].
        self._vanished: list[tuple[list[int], list[tuple[float, float]]]] = []
        self.reset()

    def reset(self, clear_blacklist: bool = False) -> None:
        """Forget the goal and the DONE state (and the blacklist when asked)."""
        self.goal: Goal | None = None
        self.done = False
        self._best_dist = math.inf
        self._best_path_dist = math.inf
        self._last_progress_s = 0.0
        self._arrived_s: float | None = None
        self._arrived_stamp_ns = 0
        self._empty_ticks = 0
        self._goal_cells_xy: npt.NDArray[np.float64] | None = None
        self._retries_left = self.params.blacklist_retries
        self.start_xy_m: tuple[float, float] | None = None
        self._start_yaw = 0.0
        if clear_blacklist:
            self._blacklist.clear()
            self._vanished.clear()

    def set_params(self, params: SelectionParams) -> None:
        """Apply new parameters (the blacklist keeps its newest entries)."""
        self.params = params
        self._blacklist = deque(self._blacklist, maxlen=params.blacklist_max)

    @property
    def blacklist(self) -> tuple[tuple[float, float], ...]:
        """Blacklisted goal positions (x, y) in metres, oldest first."""
        return tuple(self._blacklist)

    def add_to_blacklist(self, xy_m: tuple[float, float]) -> None:
        """Blacklist a position (e.g. after the navigator reported a failure)."""
        self._blacklist.append((float(xy_m[0]), float(xy_m[1])))

    def abandon_goal(self, blacklist: bool = True) -> None:
        """Drop the current goal (blacklisting it unless told not to)."""
        if self.goal is not None and blacklist and not self.goal.is_return:
            self.add_to_blacklist(self.goal.xy_m)
        self.goal = None

    def set_start(self, xy_m: tuple[float, float], yaw_rad: float) -> None:
        """Remember the pose to return to (first pose, unless set again)."""
        self.start_xy_m = (float(xy_m[0]), float(xy_m[1]))
        self._start_yaw = float(yaw_rad)

    def _note_vanished(self, xy_m: tuple[float, float]) -> bool:
        """Count a goal whose frontier vanished before arrival; True when its area reached
        ``flicker_vanish_count`` (its goal points are then blacklisted)."""
        p = self.params
        if p.flicker_vanish_count < 1:
            return False
        x, y = float(xy_m[0]), float(xy_m[1])
        for count, pts in self._vanished:
            if math.hypot(x - pts[0][0], y - pts[0][1]) <= p.flicker_radius_m:
                count[0] += 1
                pts.append((x, y))
                del pts[1:-_FLICKER_POINTS]
                break
        else:
            count, pts = [1], [(x, y)]
            self._vanished.append((count, pts))
            del self._vanished[:-_FLICKER_AREAS]
        if count[0] < p.flicker_vanish_count:
            return False
        for pt in pts:
            self.add_to_blacklist(pt)
        return True

    def excluded(self, frontiers: Sequence[Frontier]) -> npt.NDArray[np.bool_]:
        """Frontiers whose cPoint lies within ``blacklist_radius_m`` of a blacklisted
        goal (not candidates now); pass it to :meth:`PathGraphs.distances`."""
        if not self._blacklist or not frontiers:
            return np.zeros(len(frontiers), dtype=bool)
        pts = np.asarray([f.point_xy_m for f in frontiers])
        bl = np.asarray(self._blacklist)
        d2 = ((pts[:, None, :] - bl[None, :, :]) ** 2).sum(axis=2)
        return (d2 <= self.params.blacklist_radius_m ** 2).any(axis=1)

    def _matching(self, grid: GridMap, frontiers: Sequence[Frontier]) -> int | None:
        """Index of the frontier owning the current goal (closest cell within radius)."""
        if self.goal is None or not frontiers:
            return None
        gx, gy = self.goal.xy_m
        best, best_d = None, math.inf
        for i, f in enumerate(frontiers):
            x, y = grid.cells_to_world(f.cells[:, 0], f.cells[:, 1])
            d = float(np.min(np.hypot(x - gx, y - gy)))
            if d < best_d:
                best, best_d = i, d
        radius = self.params.frontier_match_radius_m + self.goal.frontier_gap_m
        return best if best_d <= radius else None

    def _remember_cells(self, grid: GridMap, f: Frontier) -> None:
        """Keep the (world) positions of the current goal's frontier cells."""
        x, y = grid.cells_to_world(f.cells[:, 0], f.cells[:, 1])
        self._goal_cells_xy = np.column_stack([x, y])

    def _still_unknown(self, grid: GridMap) -> float:
        """Share of the goal frontier's last cells that are still unknown in ``grid``
        (a frontier that vanished with its cells unexplored was not cleared by sensing)."""
        xy = self._goal_cells_xy
        if xy is None or len(xy) == 0:
            return 0.0
        r, c = grid.world_to_cells(xy[:, 0], xy[:, 1])
        inside = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
        unknown = ~inside
        unknown[inside] = grid.data[r[inside], c[inside]] < 0
        return float(unknown.mean())

    def _new_goal(self, f: Frontier, cost: float, robot_xy_m: tuple[float, float],
                  now_s: float) -> Goal:
        gap = float(np.min(np.hypot(f.cells[:, 0] - f.point_rc[0],
                                    f.cells[:, 1] - f.point_rc[1]))) * f.length_m / f.size_cells
        self.goal = Goal(f.point_xy_m, goal_yaw(f, robot_xy_m), f.point_rc, f.size_cells,
                         float(cost), frontier_gap_m=gap)
        self._start_progress(self.goal, robot_xy_m, now_s)
        return self.goal

    def _start_progress(self, goal: Goal, robot_xy_m: tuple[float, float], now_s: float
                        ) -> None:
        """Progress is measured from the robot-goal distance when the goal was set."""
        self._best_dist = math.hypot(robot_xy_m[0] - goal.xy_m[0],
                                     robot_xy_m[1] - goal.xy_m[1])
        self._best_path_dist = math.inf
        self._last_progress_s = now_s
        self._arrived_s = None

    def step(self, now_s: float, robot_xy_m: tuple[float, float], grid: GridMap,
             frontiers: Sequence[Frontier], dist_m: npt.ArrayLike | None,
             labels: npt.NDArray[np.integer] | None = None,
             robot_rc: tuple[int, int] | None = None) -> StepResult:
        """One decision.

        Parameters
        ----------
        now_s : float
            Current time in seconds (monotonic, e.g. the node clock).
        robot_xy_m : (float, float)
            Robot position in the map frame.
        grid : GridMap
            The map the frontiers were detected on.
        frontiers : sequence of Frontier
        dist_m : array_like of float, shape (N,), or None
            Path lengths robot -> cPoints; None when they could not be computed (robot
            outside the map or enclosed): only progress is checked, no selection.
        labels : ndarray of int, shape (H, W), optional
            Region labels aligned with ``grid``.
        robot_rc : (int, int), optional
            Robot cell (computed from ``robot_xy_m`` when None).

        Returns
        -------
        StepResult
        """
        p = self.params
        if self.done:
            return StepResult(Action.DONE, None, "exploration done")
        if self.start_xy_m is None:
            self.set_start(robot_xy_m, 0.0)
        if robot_rc is None:
            robot_rc = grid.world_to_cell(*robot_xy_m)
        reason = ""
        # 1. progress and arrival on the current goal
        if self.goal is not None:
            d_goal = math.hypot(robot_xy_m[0] - self.goal.xy_m[0],
                                robot_xy_m[1] - self.goal.xy_m[1])
            if d_goal <= self._best_dist - p.progress_min_m:
                self._best_dist = d_goal
                self._last_progress_s = now_s
            # Progress along the path counts too: the way to a goal often leads away
            # from it first (around a wall, through a corridor).
            cur_goal = (self._matching(grid, frontiers)
                        if dist_m is not None and not self.goal.is_return else None)
            if cur_goal is not None and np.isfinite(dist_m[cur_goal]):
                d_path = float(dist_m[cur_goal])
                if d_path <= self._best_path_dist - p.progress_min_m:
                    if math.isfinite(self._best_path_dist):
                        self._last_progress_s = now_s
                    self._best_path_dist = d_path
            if d_goal <= p.goal_reached_tolerance_m:
                if self.goal.is_return:
                    self.goal = None
                    self.done = True
                    return StepResult(Action.DONE, None, "returned to start")
                if self._arrived_s is None:
                    self._arrived_s, self._arrived_stamp_ns = now_s, grid.stamp_ns
                if (grid.stamp_ns == self._arrived_stamp_ns
                        and now_s - self._arrived_s < p.arrival_wait_s):
                    return StepResult(Action.KEEP, self.goal,
                                      "goal reached: waiting for the map to update")
                self._arrived_s = None
                if self._matching(grid, frontiers) is not None:
                    self.abandon_goal(blacklist=True)
                    reason = "goal reached but its frontier remains: blacklisted"
                else:
                    self.goal = None
                    reason = "goal reached"
            elif now_s - self._last_progress_s > p.progress_timeout_s:
                if self.goal.is_return:
                    self.goal = None
                    self.done = True
                    return StepResult(Action.DONE, None, "no progress returning to start")
                self.abandon_goal(blacklist=True)
                reason = f"no progress for {p.progress_timeout_s:.0f} s: blacklisted"
        if dist_m is None:
            action = Action.KEEP if self.goal is not None else Action.WAIT
            return StepResult(action, self.goal, reason or "no path distances")
        # 2. candidates
        excluded = self.excluded(frontiers)
        sel = select_goal(frontiers, dist_m, labels, robot_rc, p, grid.resolution_m,
                          excluded)
        if sel.index is None:
            self._empty_ticks += 1
            if self.goal is not None and self.goal.is_return:
                return StepResult(Action.KEEP, self.goal, "returning to start", sel)
            if self.goal is not None and self._still_unknown(grid) >= 0.5:
                # A thin frontier seen at a grazing angle (a doorway from the side) comes
                # and goes: its cells are still unknown, so drive on and look.
                return StepResult(Action.KEEP, self.goal, reason or "no frontier detected now, "
                                  "but the goal's cells are still unknown: keeping goal", sel)
            self.goal = None
            if self._empty_ticks < p.done_confirmations:
                return StepResult(Action.WAIT, None, reason or "no reachable frontier", sel)
            if p.return_to_start and self.start_xy_m is not None:
                d0 = math.hypot(robot_xy_m[0] - self.start_xy_m[0],
                                robot_xy_m[1] - self.start_xy_m[1])
                if d0 > p.goal_reached_tolerance_m:
                    srow, scol = grid.world_to_cell(*self.start_xy_m)
                    self.goal = Goal(self.start_xy_m, self._start_yaw, (srow, scol), 0, 0.0,
                                     is_return=True)
                    self._start_progress(self.goal, robot_xy_m, now_s)
                    return StepResult(Action.NEW_GOAL, self.goal,
                                      "no reachable frontier: returning to start", sel)
            if self._retries_left > 0 and self._blacklist:
                # The map changed since those goals failed (a doorway seen, a false
                # obstacle cleared): give the blacklisted frontiers another chance.
                self._retries_left -= 1
                self._blacklist.clear()
                self._empty_ticks = 0
                return StepResult(Action.WAIT, None, "no reachable frontier: blacklist "
                                  "cleared, retrying its frontiers", sel)
            self.done = True
            return StepResult(Action.DONE, None, "no reachable frontier", sel)
        self._empty_ticks = 0
        best = sel.index
        best_cost = float(sel.costs[best])
        # 3. keep or switch
        if self.goal is not None and not self.goal.is_return:
            cur = self._matching(grid, frontiers)
            if cur is not None:
                self._remember_cells(grid, frontiers[cur])
            if cur is not None and not excluded[cur] and np.isfinite(sel.costs[cur]):
                cur_cost = float(sel.costs[cur])
                if best == cur or best_cost >= cur_cost - p.hysteresis_margin * abs(cur_cost):
                    return StepResult(Action.KEEP, self.goal, reason or "keeping goal", sel)
            bx, by = frontiers[best].point_xy_m
            if math.hypot(bx - self.goal.xy_m[0], by - self.goal.xy_m[1]) < p.goal_change_min_m:
                return StepResult(Action.KEEP, self.goal, reason or "new goal next to the old",
                                  sel)
            if cur is not None and not excluded[cur] and np.isfinite(sel.costs[cur]):
                reason = reason or "a better frontier appeared"
            elif (cur is None and self._still_unknown(grid) >= 0.5
                  and self._note_vanished(self.goal.xy_m)):
                reason = (f"goal frontier vanished {p.flicker_vanish_count} times here before "
                          "arrival (flickering): area blacklisted")
            else:
                reason = reason or "goal frontier gone or unreachable"
        goal = self._new_goal(frontiers[best], best_cost, robot_xy_m, now_s)
        self._remember_cells(grid, frontiers[best])
        return StepResult(Action.NEW_GOAL, goal, reason or "new goal", sel)
