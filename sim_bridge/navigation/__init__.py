"""Navigation stand-in: what Nav2's bt_navigator + planner + controller do, in a few lines.

:class:`Navigator` takes a goal (x, y, yaw) like ``goal_pose``, plans on the current map
plus any extra occupancy layers (e.g. the object costmap) whose occupied cells are
obstacles, follows the plan with a pure-pursuit controller within the speed limits,
replans periodically and when the plan gets blocked, and reports ``ACTIVE`` /
``SUCCEEDED`` / ``ABORTED`` with a reason.

Planning mirrors Nav2's NavFn on an inflated costmap:

* cells closer than ``robot_radius_m + inflation_margin_m`` to an obstacle are lethal
  (obstacles inflated by the robot radius, :func:`explore_seg.core.paths.inflate`
  semantics);
* beyond that, out to ``inflation_radius_m``, a cell costs
  ``1 + inflation_cost_weight * exp(-inflation_cost_scale * (d - lethal))`` (Nav2's
  exponential inflation decay), which keeps plans off walls;
* unknown cells are traversable (``allow_unknown: true``) at ``1 + unknown_cost``
  (NavFn gives unknown cells a near-lethal cost, so known free space is preferred);
* a goal inside a lethal cell moves to the nearest free cell within
  ``planner_goal_tolerance_m``.

The cost-weighted 8-connected Dijkstra runs on a window around start and goal that grows
until it provably holds the cheapest path. A new plan replaces the current one only when
it is clearly cheaper (``switch_cost_ratio``) or the current one got blocked, which
avoids the back-and-forth a planner through unknown space otherwise shows as walls
appear piece by piece.

Following: pure pursuit towards the plan point ``lookahead_m`` ahead, pulled back along
the plan while the arc to it would enter the lethal zone or, with ``arc_check_edges``,
come closer than ``robot_radius_m + arc_clearance_m`` to an obstacle cell's edge (so the
robot does not cut obstacle corners). When no arc from the robot's heading keeps clear, it
turns in place (the footprint does not move) to face the next plan point if the straight
line to it is clear; else it drives the farthest arc that keeps the robot radius itself
from the cells' edges (a passage only millimetres wider than the robot); else it turns to
face the first plan point whose straight line is clear, or the next plan point, and waits for a plan or map that gives a
clear one (or for the progress checker); it never drives an unchecked arc. A robot standing
inside the lethal zone gets a plan through the zone's cells that are no closer to an
obstacle than it is, so it leaves the zone before it turns along a wall. After a collision (the engine backs the robot off)
the goal stays active and is replanned up to ``collision_retries`` times, like Nav2's recoveries, and is
then aborted.

Modules: :mod:`~sim_bridge.navigation.params` (:class:`NavParams`),
:mod:`~sim_bridge.navigation.goal_status` (goal ids and statuses as Nav2's action reports
them, :class:`GoalBook`; outcomes for the lock step, :class:`OutcomeFollower`),
:mod:`~sim_bridge.navigation.planner` (costmap and windowed Dijkstra),
:mod:`~sim_bridge.navigation.navigator` (goal state machine, planning calls),
:mod:`~sim_bridge.navigation.pursuit` (pure-pursuit following, the arc check and its
fallbacks),
:mod:`~sim_bridge.navigation.clearance` (the arc check's exact distances to obstacle cells'
edges).
This package re-exports their public names.
"""

from explore_seg.core.angles import wrap_angle
from explore_seg.core.paths import cost_distance_field
from sim_bridge.navigation.goal_status import (OUTCOME_OF_STATE, STATUS_OF_STATE, GoalBook,
                                              OutcomeFollower)
from sim_bridge.navigation.navigator import NavState, NavStatus, Navigator
from sim_bridge.navigation.pursuit import ARC_FREE_START_M
from sim_bridge.navigation.params import NavParams
from sim_bridge.navigation.planner import coarsen, cost_grid, path_cost, plan_path

__all__ = ["ARC_FREE_START_M", "GoalBook", "NavParams", "NavState", "NavStatus", "Navigator",
           "OUTCOME_OF_STATE", "OutcomeFollower", "STATUS_OF_STATE", "coarsen",
           "cost_distance_field", "cost_grid", "path_cost", "plan_path", "wrap_angle"]
