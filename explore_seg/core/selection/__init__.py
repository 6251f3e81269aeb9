"""Target selection (Kim, Kim & Lee, RA-L 2022, Alg. 2 and eq. 1-3) and goal handling.

One concern per module:

* :mod:`.strategies`: the cost functions, one table entry per strategy;
* :mod:`.params`: :class:`SelectionParams` (algorithm) and :class:`SelectorNodeParams`;
* :mod:`.regions`: region ids of cells and cPoints from DuDe labels;
* :mod:`.costs`: costs of all frontiers and the cheapest (:func:`select_goal`);
* :mod:`.distances`: path lengths robot -> cPoints (:class:`PathGraphs`);
* :mod:`.goals`: :class:`GoalManager` (keep, switch, blacklist, done);
* :mod:`.lookout`: lookout goals, when no frontier has a path (look at an unreachable one
  from a reachable spot in line of sight before exploration ends);
* the ``routed`` strategy: :mod:`.viewpoints` (ray-cast view gain, one viewpoint per
  group), :mod:`.tour` (open tour: greedy, 2-opt, Or-opt), :mod:`.router` (viewpoints +
  tour costs per decision, :class:`~.router.Router`).

The decision loop that wires them is :class:`explore_seg.core.explorer.Explorer`.

Where ``paper`` loses time (decision traces, ``bench/trace_decisions.py``, lock step;
``--worlds eb/room_2,shared/house_cluttered_plus --strategies paper --seeds 0,1,2`` and
``--worlds house --seeds 0``):

* The region term decides often: of the NEW_GOAL decisions it changed the choice in 40 of
  252 on eb/room_2 (16 %), 12 of 72 on shared/house_cluttered_plus (17 %) and 24 of 106
  on house (23 %). gamma = 1 against a median spread of the distance terms of 0.12-0.15
  (eb/room_2), 0.15-0.21 (house_cluttered_plus) and 0.08 (house, more frontiers share
  the normalisation): whenever another region's frontier is in play, it loses. The
  frontiers the region term picked were small (median 50-75 cells on eb/room_2, 16-21 on
  house_cluttered_plus, 43 on house) at a median 4.3-5.6 m.
* The size term decides where the distance spread is small: 25 of 252 NEW_GOAL decisions
  on eb/room_2, 4 of 72 on house_cluttered_plus, but 36 of 106 (34 %) on house.
* Region ids change while the map grows: the robot's region changed 13-17 times per run
  on eb/room_2 (3 straight back to the previous id), 8-12 times on house_cluttered_plus
  (3-5 back) and 47 times on house (14 back; 24 different ids, each re-entered after
  leaving it): "finish the room first" is applied to rooms that do not yet exist as such.
* Path without coverage gain: 28-33 % of ``paper``'s path on eb/room_2 (``nearest`` seed
  0: 19 %), 56-66 % on house_cluttered_plus, 56 % on house (183 m in all; 24 goal
  switches, 100 s from 95 % to 99 %). paper's eb/room_2 paths are 92-109 m against
  73-90 m for ``nearest`` on the same seeds (bench/results/runs.csv).
* Waiting: on house_cluttered_plus seed 2 the robot stood still 72 s (two goals ended
  only by the 30 s progress timeout), which alone makes its T95 311 s against 157-162 s
  on seeds 0-1; on house seed 0 it stood still 52 s. With navigation feedback
  (``LockstepParams.nav_feedback``; always on for ``routed``) the navigator's end of a
  goal is acted on at once.
* ``paper``'s rows of bench/results/runs.csv on worlds with objects no longer reproduce
  (house_cluttered_plus seed 0: 128 s there, 162 s with this code and with e43b08d, the
  commit before ``routed``; house seed 0: 633 s there, 662 s here); on eb/room_2 (where
  paper_noobj's rows equal paper's) they do (367, 364, 354 s).
"""

from explore_seg.core.selection.costs import Selection, compute_costs, select_goal
from explore_seg.core.selection.distances import PathGraphs, frontier_distances
from explore_seg.core.selection.goals import (Action, Goal, GoalManager, NavOutcome,
                                              StepResult, goal_yaw)
from explore_seg.core.selection.params import (POSE_TOPIC_TYPES, SelectionParams,
                                               SelectorNodeParams)
from explore_seg.core.selection.regions import frontier_regions, region_at
from explore_seg.core.selection.router import Router, TourPlan
from explore_seg.core.selection.strategies import (COST_FUNCTIONS, REGION_STRATEGIES,
                                                   RRT_STRATEGIES, STRATEGIES, CostInputs)

__all__ = [
    "Action", "COST_FUNCTIONS", "CostInputs", "Goal", "GoalManager", "NavOutcome", "POSE_TOPIC_TYPES",
    "PathGraphs", "REGION_STRATEGIES", "RRT_STRATEGIES", "Router", "TourPlan", "STRATEGIES",
    "Selection", "SelectionParams",
    "SelectorNodeParams", "StepResult", "compute_costs", "frontier_distances",
    "frontier_regions", "goal_yaw", "region_at", "select_goal",
]
