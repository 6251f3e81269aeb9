"""The strategies' cost functions: one table entry per strategy.

Each function scores the frontier groups with a finite path distance (lower is better)
from a :class:`CostInputs`; :func:`~explore_seg.core.selection.costs.compute_costs`
handles the unreachable ones. Adding a strategy is one function and one entry in
:data:`COST_FUNCTIONS`; ``SelectionParams.strategy`` accepts the table's keys.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import numpy.typing as npt


@dataclass(frozen=True)
class CostInputs:
    """What a cost function sees of the N frontier groups of one decision.

    Attributes
    ----------
    dist_m : ndarray of float64, shape (N,)
        Path length robot -> cPoint (inf: unreachable or cPoint not passable).
    finite : ndarray of bool, shape (N,)
        ``isfinite(dist_m)``: the groups to score.
    size_cells : ndarray of float64, shape (N,)
        Group sizes (all groups: the paper normalises over every candidate).
    length_m : ndarray of float64, shape (N,)
        Group lengths in metres (``size_cells * resolution``).
    regions : ndarray of int64, shape (N,) or None
        Region of each cPoint; None when regionGain is off (no labels or no robot region).
    robot_region : int
        Region of the robot (0 = unknown).
    info_gain_m2 : ndarray of float64, shape (N,), or None
        Unknown area each frontier promises (``Frontier.info_gain_m2``; NaN where its
        detector did not measure it); None when not given.
    tour_cost_m : ndarray of float64, shape (N,), or None
        ``routed``: length of the tour over all viewpoints when this group is visited
        next (:class:`~explore_seg.core.selection.router.Router`); None for the others.
    """

    dist_m: npt.NDArray[np.float64]
    finite: npt.NDArray[np.bool_]
    size_cells: npt.NDArray[np.float64]
    length_m: npt.NDArray[np.float64]
    regions: npt.NDArray[np.int64] | None
    robot_region: int
    info_gain_m2: npt.NDArray[np.float64] | None = None
    tour_cost_m: npt.NDArray[np.float64] | None = None


#: ``cost(inputs, params) -> costs of the finite groups`` (shape ``(finite.sum(),)``).
CostFunction = Callable[[CostInputs, Any], npt.NDArray[np.float64]]


def paper_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """The paper's eq. 1-3: ``alpha * distGain + beta / sizeGain + regionGain``."""
    d = inp.dist_m[inp.finite]
    total_d = float(d.sum())
    dist_gain = d / total_d if total_d > 0 else np.zeros(len(d))
    size_gain = inp.size_cells[inp.finite] / float(inp.size_cells.sum())
    region_gain = np.zeros(len(d))
    if inp.regions is not None:
        reg = np.asarray(inp.regions)[inp.finite]
        region_gain = np.where((reg > 0) & (reg != inp.robot_region), params.gamma, 0.0)
    return params.alpha * dist_gain + params.beta / size_gain + region_gain


def nearest_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """Greedy nearest frontier (Yamauchi): the path length."""
    return inp.dist_m[inp.finite]


def explore_lite_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """explore_lite's ``frontierCost`` (orientation_scale 0):
    ``potential_scale * dist - gain_scale * length``."""
    f = inp.finite
    return params.potential_scale * inp.dist_m[f] - params.gain_scale * inp.length_m[f]


def rrt_exploration_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """rrt_exploration's assigner (Umari & Mukhopadhyay 2017), as a cost (-revenue)::

        revenue = info_multiplier * gain - dist
        gain    = info_gain_m2 * (hysteresis_gain if dist <= hysteresis_radius_m else 1)

    ``info_gain_m2``: unknown area within ``rrt.info_radius_m`` of the cluster centre
    (NaN counts as 0). Deviations: ``dist`` is the path length to the cPoint, where the
    assigner uses the straight-line distance robot -> centre for both terms; the assigner's
    second bonus (centres near the robot's current goal while it is busy) is left to the
    goal manager's ``hysteresis_margin``, as for every strategy.
    """
    f = inp.finite
    d = inp.dist_m[f]
    gain = np.zeros(len(d)) if inp.info_gain_m2 is None else \
        np.nan_to_num(np.asarray(inp.info_gain_m2, dtype=np.float64)[f], nan=0.0)
    gain = np.where(d <= params.hysteresis_radius_m, gain * params.hysteresis_gain, gain)
    return d - params.info_multiplier * gain


def routed_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """The tour length (m) when the group is visited next (region changes included)."""
    if inp.tour_cost_m is None:
        raise ValueError("the routed strategy needs tour costs (explore_seg.core.selection."
                         "router.Router, run by explore_seg.core.explorer.Explorer)")
    return np.asarray(inp.tour_cost_m, dtype=np.float64)[inp.finite]


#: Strategy name -> cost function. The first entry is listed first in the docs.
COST_FUNCTIONS: dict[str, CostFunction] = {
    "paper": paper_cost,
    "nearest": nearest_cost,
    "explore_lite": explore_lite_cost,
    "rrt_exploration": rrt_exploration_cost,
    "routed": routed_cost,
}
#: Strategies ``SelectionParams.strategy`` accepts.
STRATEGIES: tuple[str, ...] = tuple(COST_FUNCTIONS)
#: Strategies whose candidates come from the RRT frontier detector
#: (:mod:`explore_seg.core.rrt`) instead of frontier cell groups.
RRT_STRATEGIES: frozenset[str] = frozenset({"rrt_exploration"})
#: Strategies whose cost has a region term (the node logs once when it is inactive).
REGION_STRATEGIES: frozenset[str] = frozenset({"paper", "routed"})
