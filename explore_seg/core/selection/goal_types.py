"""What the goal manager takes and gives: navigation outcomes, actions, goals, step
inputs and results (ROS-free; :mod:`.goals` holds :class:`~.goals.GoalManager`)."""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import GridMap
from explore_seg.core.selection.costs import Selection


class NavOutcome(enum.Enum):
    """What the navigator did with a goal (Nav2's ``navigate_to_pose`` action status, or
    the simulator's stand-in), reported through :meth:`.goals.GoalManager.report_navigation`."""

    SUCCEEDED = "succeeded"          # reached: judge the goal's frontier now
    ABORTED = "aborted"              # gave up (no path, recoveries exhausted): judged
    REJECTED = "rejected"            # never accepted (or not within the timeout): blacklist
    CANCELED = "canceled"            # canceled by someone else: blacklist
    CANCELED_BY_US = "canceled_by_us"  # our own cancel (stop, done): forget, no blacklist


class Action(enum.Enum):
    """What :meth:`.goals.GoalManager.step` asks the caller to do."""

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
    #: A turn look (:func:`.areas.turn_goal`): turn in place at the robot's position.
    is_turn: bool = False


@dataclass(frozen=True)
class StepResult:
    """Outcome of one :meth:`GoalManager.step`."""

    action: Action
    goal: Goal | None
    reason: str
    selection: Selection | None = None


@dataclass(frozen=True, eq=False)
class StepInputs:
    """What the caller of :meth:`GoalManager.step` already has for a decision (each
    optional)."""

    #: Region labels aligned with the grid, shape (H, W).
    labels: npt.NDArray[np.integer] | None = None
    #: Robot cell (computed from the robot position when None).
    robot_rc: tuple[int, int] | None = None
    #: :meth:`GoalManager.excluded` of the frontiers computed by the caller before the
    #: call (for the path distances), shape (N,); recomputed when the blacklist changed.
    excluded: npt.NDArray[np.bool_] | None = None
    #: The ``routed`` strategy's tour costs (:class:`~.router.Router`), shape (N,).
    tour_cost_m: npt.NDArray[np.float64] | None = None
    #: The robot's heading (turn looks need it; none without it).
    robot_yaw_rad: float | None = None


def goal_yaw(frontier: Frontier, robot_xy_m: tuple[float, float]) -> float:
    """Heading at a frontier's cPoint toward the unknown side: cPoint -> group centroid
    (robot -> cPoint when the two coincide)."""
    px, py = frontier.point_xy_m
    gx, gy = frontier.centroid_xy_m
    if math.hypot(gx - px, gy - py) > 1e-9:
        return math.atan2(gy - py, gx - px)
    return math.atan2(py - robot_xy_m[1], px - robot_xy_m[0])


def goal_frontier_index(goal: Goal, grid: GridMap, frontiers: Sequence[Frontier],
                        match_radius_m: float) -> int | None:
    """Index of the frontier owning ``goal``: the one with the cell closest to the goal,
    when within ``match_radius_m`` + the goal's gap to its frontier; None otherwise."""
    gx, gy = goal.xy_m
    best, best_d = None, math.inf
    for i, f in enumerate(frontiers):
        x, y = grid.cells_to_world(f.cells[:, 0], f.cells[:, 1])
        d = float(np.min(np.hypot(x - gx, y - gy)))
        if d < best_d:
            best, best_d = i, d
    return best if best_d <= match_radius_m + goal.frontier_gap_m else None


def unknown_share(grid: GridMap, xy_m: npt.NDArray[np.float64] | None) -> float:
    """Share of the points ``xy_m`` (shape (N, 2), map frame) that lie on unknown cells of
    ``grid`` or outside it (0 without points)."""
    if xy_m is None or len(xy_m) == 0:
        return 0.0
    r, c = grid.world_to_cells(xy_m[:, 0], xy_m[:, 1])
    inside = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
    unknown = ~inside
    unknown[inside] = grid.data[r[inside], c[inside]] < 0
    return float(unknown.mean())


def frontiers_left(dist_m: npt.ArrayLike, excluded: npt.ArrayLike) -> str:
    """What is left when no frontier is selectable, for the decision's reason: how many
    frontiers have no path, are blacklisted, or have a path but the strategy rules them
    out (infinite cost: too small, outside the ``routed`` tour).

    >>> frontiers_left([], [])
    'no frontier left'
    >>> frontiers_left([np.inf, np.inf, 3.0, 2.0], [False, True, False, False])
    'no selectable frontier (4 left: 1 without a path, 1 blacklisted, 2 ruled out by the strategy)'
    """
    dist = np.asarray(dist_m, dtype=np.float64)
    ex = np.asarray(excluded, dtype=bool)
    if dist.size == 0:
        return "no frontier left"
    finite = np.isfinite(dist)
    parts = [(int(np.count_nonzero(~finite & ~ex)), "without a path"),
             (int(np.count_nonzero(ex)), "blacklisted"),
             (int(np.count_nonzero(finite & ~ex)), "ruled out by the strategy")]
    said = ", ".join(f"{n} {what}" for n, what in parts if n)
    return f"no selectable frontier ({dist.size} left: {said})"


__all__ = ["Action", "Goal", "NavOutcome", "StepInputs", "StepResult", "frontiers_left",
           "goal_frontier_index", "goal_yaw", "unknown_share"]
