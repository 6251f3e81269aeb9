"""Target selection (Kim, Kim & Lee, RA-L 2022, Alg. 2 and eq. 1-3) and goal handling.

One concern per module:

* :mod:`.strategy`: what a strategy is and the registry by name; :mod:`.strategies`: the
  built-in strategies, one module each (how to add one: its docstring);
* :mod:`.params`: :class:`SelectionParams` (algorithm) and :class:`SelectorNodeParams`;
* :mod:`.regions`: region ids of cells and cPoints from DuDe labels;
* :mod:`.costs`: costs of all frontiers and the cheapest (:func:`select_goal`);
* :mod:`.distances`: path lengths robot -> cPoints (:class:`PathGraphs`);
* :mod:`.goals`: :class:`GoalManager` (keep, switch, blacklist, done);
* :mod:`.lookout`: lookout goals, when no frontier has a path (look at an unreachable one
  from a reachable spot in line of sight before exploration ends);
* :mod:`.fallbacks`: the goals when no frontier is selectable, in turn: lookouts
  (:mod:`.lookout`), approaches to a passage only speckle closes (:mod:`.blockage`),
  revisits of the robot's path for a loop closure (:mod:`.revisit`);
* the ``routed`` strategy: :mod:`.viewpoints` (ray-cast view gain, one viewpoint per
  group), :mod:`.tour` (open tour: greedy, 2-opt, Or-opt), :mod:`.router` (viewpoints +
  tour costs per decision, :class:`~.router.Router`).

The decision loop that wires them is :class:`explore_seg.core.explorer.Explorer`.

Traces of where each strategy loses time, and the rules measured against them, are in
docs/experiments.md (e.g. docs/experiments.md#paper-where-time-goes).
"""

# The built-in strategies register first: SelectionParams checks its strategy against the
# registry, and modules below build default SelectionParams when they are imported.
from explore_seg.core.selection import strategies  # noqa: I001
from explore_seg.core.selection.costs import Selection, compute_costs, select_goal
from explore_seg.core.selection.distances import PathGraphs, frontier_distances
from explore_seg.core.selection.goals import (Action, Goal, GoalManager, NavOutcome,
                                              StepInputs, StepResult, goal_yaw)
from explore_seg.core.selection.params import (POSE_TOPIC_TYPES, SelectionParams,
                                               SelectorNodeParams)
from explore_seg.core.selection.regions import frontier_regions, region_at
from explore_seg.core.selection.router import Router, TourPlan
from explore_seg.core.selection.strategies import (COST_FUNCTIONS, REGION_STRATEGIES,
                                                   RRT_STRATEGIES, STRATEGIES, CostInputs)
from explore_seg.core.selection.strategy import (GoalOptions, Strategy, get_strategy, register,
                                                 strategy_names, unregister)

__all__ = [
    "Action", "COST_FUNCTIONS", "CostInputs", "Goal", "GoalManager", "NavOutcome", "POSE_TOPIC_TYPES",
    "PathGraphs", "REGION_STRATEGIES", "RRT_STRATEGIES", "Router", "TourPlan", "STRATEGIES",
    "Selection", "SelectionParams",
    "SelectorNodeParams", "StepInputs", "StepResult", "compute_costs", "frontier_distances",
    "frontier_regions", "goal_yaw", "region_at", "select_goal",
    "GoalOptions", "Strategy", "get_strategy", "register", "strategy_names", "unregister",
]
