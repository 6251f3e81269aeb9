"""Frontier costs and the choice of the cheapest (Kim, Kim & Lee, RA-L 2022, Alg. 2 and
eq. 1-3).

The strategies (:mod:`explore_seg.core.selection.strategies`) score every frontier group
``i`` (lower is better; unreachable = inf):

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
* ``rrt_exploration``: ``cost_i = dist_i - info_multiplier * gain_i`` (minus the revenue
  of rrt_exploration's assigner; ``gain_i`` = the candidate's ``info_gain_m2``, times
  ``hysteresis_gain`` within ``hysteresis_radius_m``). Its candidates are not frontier
  cell groups but the RRT detector's cluster centres (:mod:`explore_seg.core.rrt`).

alpha, beta, gamma: the paper's numeric values could not be recovered from the material
available to us (the seed code hard-codes a different, unweighted objective). The
defaults (alpha = 1, beta = 0.001, gamma = 1) are our choice: both gains are fractions, so
alpha = 1 makes the whole distance spread worth 1; beta = 0.001 makes a group holding
0.1 % of all frontier cells cost 1 (a 10-cell group among 1000 costs 0.1, as much as a
tenth of the distance spread); gamma = 1 makes leaving the robot's region cost as much as
the largest distance difference, so a room is finished first unless what is left in it
is tiny or far. A larger beta lets the size term outweigh distance (the robot crosses rooms
for big groups and comes back for small ones). See docs/experiments.md#paper-beta-sweep.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import metres_to_cells
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.regions import frontier_regions, region_at
from explore_seg.core.selection.strategy import CostInputs, get_strategy


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
                  regions: npt.NDArray[np.int64] | None = None,
                  tour_cost_m: npt.NDArray[np.float64] | None = None
                  ) -> npt.NDArray[np.float64]:
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
    tour_cost_m : ndarray of float64, shape (N,), optional
        The ``routed`` strategy's tour costs (required by it, ignored by the others).

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
    reg = None
    if labels is not None and robot_region > 0:
        rad = metres_to_cells(params.region_search_radius_m, _resolution(frontiers))
        reg = regions if regions is not None else frontier_regions(frontiers, labels, rad)
    inputs = CostInputs(
        dist_m=d, finite=finite,
        size_cells=np.asarray([f.size_cells for f in frontiers], dtype=np.float64),
        length_m=np.asarray([f.length_m for f in frontiers], dtype=np.float64),
        regions=reg, robot_region=int(robot_region),
        info_gain_m2=np.asarray([f.info_gain_m2 for f in frontiers], dtype=np.float64),
        tour_cost_m=None if tour_cost_m is None else np.asarray(tour_cost_m, np.float64))
    costs[finite] = get_strategy(params.strategy).cost(inputs, params)
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
                excluded: npt.NDArray[np.bool_] | None = None,
                tour_cost_m: npt.NDArray[np.float64] | None = None) -> Selection:
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
    tour_cost_m : ndarray of float64, shape (N,), optional
        The ``routed`` strategy's tour costs (:class:`~.router.Router`). ``routed`` is the
        default strategy and raises ``ValueError`` without them: outside
        :class:`~explore_seg.core.explorer.Explorer` (which runs the Router) pass
        ``params`` with another strategy.

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
    rad = metres_to_cells(params.region_search_radius_m, resolution_m)
    robot_region = region_at(use_labels, robot_rc, rad) if use_labels is not None else 0
    regions = frontier_regions(frontiers, use_labels, rad)
    costs = compute_costs(frontiers, dist_m, use_labels, robot_region, params, regions,
                          tour_cost_m)
    active = (get_strategy(params.strategy).region_term and use_labels is not None
              and robot_region > 0)
    pick = costs.copy()
    if excluded is not None:
        ex = np.asarray(excluded, dtype=bool).reshape(-1)
        if ex.shape[0] != n:
            raise ValueError(f"excluded has {ex.shape[0]} entries, expected {n}")
        pick[ex] = np.inf
    index = int(np.argmin(pick)) if n and np.isfinite(pick).any() else None
    return Selection(index, costs, regions, robot_region, active)
