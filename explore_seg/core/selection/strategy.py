"""What a target-selection strategy is, and the registry of strategies by name.

A :class:`Strategy` is a cost function over the frontier groups of one decision
(:class:`CostInputs` -> costs, lower is better) plus what it needs around it: where its
candidates come from, whether its cost reads region labels, an optional :class:`Planner`
that turns frontier groups into candidates before the path lengths and adds tour costs
after them, and its goal-handling options (:class:`GoalOptions`).

:func:`register` adds one under its name; :func:`get_strategy` is how the explorer, the goal
manager, the selection parameters, the ``target_selector`` node and the lock step find
it. The built-in strategies live in :mod:`explore_seg.core.selection.strategies`, one
module each, and register themselves when :mod:`explore_seg.core.selection` is imported.
This module imports nothing of the project, so the selection parameters can validate a
name against the registry without an import circle through a strategy's own modules.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Literal, Protocol, Sequence

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:  # imported for annotations only: the modules import this one
    from explore_seg.core.frontiers import Frontier, FrontierParams
    from explore_seg.core.grid import GridMap
    from explore_seg.core.selection.distances import PathGraphs
    from explore_seg.core.selection.params import SelectionParams


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
        Set by a strategy with a planner (``routed``): length of the tour over all
        viewpoints when this group is visited next; None for the others.
    """

    dist_m: npt.NDArray[np.float64]
    finite: npt.NDArray[np.bool_]
    size_cells: npt.NDArray[np.float64]
    length_m: npt.NDArray[np.float64]
    regions: npt.NDArray[np.int64] | None
    robot_region: int
    info_gain_m2: npt.NDArray[np.float64] | None = None
    tour_cost_m: npt.NDArray[np.float64] | None = None


#: ``cost(inputs, params) -> costs of the finite groups`` (shape ``(finite.sum(),)``, lower
#: is better); ``params`` is the :class:`~explore_seg.core.selection.SelectionParams`.
CostFunction = Callable[[CostInputs, Any], npt.NDArray[np.float64]]


class Planner(Protocol):
    """Per-decision work a routing strategy adds around the distances (``routed``'s
    :class:`~explore_seg.core.selection.router.Router` is one).

    :meth:`viewpoints` turns the frontier groups into the decision's candidates before the
    path lengths are computed; :meth:`tour_costs` returns, after them, an object whose
    ``tour_cost_m`` (one entry per candidate) the cost function reads.
    """

    viewpoint_s: float
    tour_s: float

    def viewpoints(self, grid: GridMap, frontiers: list[Frontier], graph: PathGraphs,
                   start: tuple[int, int] | None, passable: npt.NDArray[np.bool_]
                   ) -> list[Frontier]: ...

    def tour_costs(self, grid: GridMap, frontiers: Sequence[Frontier],
                   dist_m: npt.NDArray[np.float64], excluded: npt.NDArray[np.bool_] | None,
                   graph: PathGraphs, robot_rc: tuple[int, int],
                   labels: npt.NDArray[np.integer] | None, goal_index: int | None) -> Any: ...

    def reset(self) -> None: ...


#: ``make_planner(frontier_params, selection_params) -> Planner``.
PlannerFactory = Callable[["FrontierParams", "SelectionParams"], Planner]


@dataclass(frozen=True)
class GoalOptions:
    """How the goal manager treats a strategy's goals.

    Attributes
    ----------
    handover : bool
        A goal within ``SelectionParams.handover_m`` counts as reached (the next goal is
        sent while the robot still drives).
    reveal_on_arrival : bool
        A reached goal whose frontier remains is blacklisted only when less than
        ``reached_unknown_fraction`` of its cells were revealed on the way; otherwise the
        space goes on behind it and the goal is dropped without blacklisting (until
        ``revealed_arrivals_max`` such arrivals in one area).
    """

    handover: bool = False
    reveal_on_arrival: bool = False


@dataclass(frozen=True)
class Strategy:
    """One target-selection strategy.

    Attributes
    ----------
    name : str
        Its ``SelectionParams.strategy`` value (letters, digits and ``_``).
    cost : CostFunction
        Scores the frontier groups with a finite path length (lower is better).
    summary : str
        One line for parameter descriptions, the docs and the benchmark's tables.
    candidates : {"groups", "rrt"}
        Where the candidates come from: frontier cell groups, or the RRT frontier
        detector's cluster centres (:mod:`explore_seg.core.rrt`, run at every decision).
    region_term : bool
        The cost reads region labels (``CostInputs.regions``): the segmentation is worth
        running for it, and the node says once when the labels are missing.
    make_planner : PlannerFactory or None
        Builds the strategy's :class:`Planner`; with one, the frontier groups are split
        into parts of at most ``SelectionParams.frontier_split_m`` first.
    goals : GoalOptions
        How its goals are judged on arrival.
    nav_feedback : bool
        The lock step always feeds the navigator's outcome to the explorer in this
        strategy's runs (a ROS robot always reports it through the action status).
    params : type or None
        The dataclass of its own parameters. A built-in strategy's is a part of
        ``SelectionParams`` (its fields are flat ROS parameters of ``target_selector``);
        the cost function reads them from the ``SelectionParams`` it is given.
    """

    name: str
    cost: CostFunction
    summary: str
    candidates: Literal["groups", "rrt"] = "groups"
    region_term: bool = False
    make_planner: PlannerFactory | None = None
    goals: GoalOptions = GoalOptions()
    nav_feedback: bool = False
    params: type | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.isidentifier()):
            raise ValueError(f"strategy name must be an identifier (letters, digits, _), "
                             f"got {self.name!r}")
        if not callable(self.cost):
            raise TypeError(f"strategy {self.name!r}: cost must be callable, got "
                            f"{type(self.cost).__name__}")
        if self.candidates not in ("groups", "rrt"):
            raise ValueError(f"strategy {self.name!r}: candidates must be 'groups' or 'rrt', "
                             f"got {self.candidates!r}")
        if self.make_planner is not None and self.candidates != "groups":
            raise ValueError(f"strategy {self.name!r}: a planner works on frontier groups "
                             f"(candidates='groups'), got candidates={self.candidates!r}")


_REGISTRY: dict[str, Strategy] = {}


def register(strategy: Strategy, replace: bool = False) -> Strategy:
    """Add ``strategy`` under its name and return it.

    Raises
    ------
    TypeError
        When ``strategy`` is not a :class:`Strategy`.
    ValueError
        When the name is taken and ``replace`` is False.
    """
    if not isinstance(strategy, Strategy):
        raise TypeError(f"register expects a Strategy, got {type(strategy).__name__}")
    if strategy.name in _REGISTRY and not replace:
        raise ValueError(f"strategy {strategy.name!r} is already registered (pass "
                         "replace=True to replace it)")
    _REGISTRY[strategy.name] = strategy
    return strategy


def unregister(name: str) -> None:
    """Remove a registered strategy (a built-in one too).

    Raises
    ------
    ValueError
        When no strategy has that name.
    """
    if name not in _REGISTRY:
        raise ValueError(f"no strategy {name!r} is registered (have {strategy_names()})")
    del _REGISTRY[name]


def get_strategy(name: str) -> Strategy:
    """The registered strategy called ``name``.

    Raises
    ------
    ValueError
        When no strategy has that name (the message lists the registered ones).
    """
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ValueError(f"strategy must be one of {strategy_names()}, got {name!r}") from None


def strategy_names() -> tuple[str, ...]:
    """The registered names, in registration order."""
    return tuple(_REGISTRY)
