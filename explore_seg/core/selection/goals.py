"""Goal bookkeeping around the strategy's choice: keep, switch, blacklist, finish.

:class:`GoalManager` is ROS-free and time-agnostic (the caller passes the clock); the
decision core (:mod:`explore_seg.core.explorer`) drives it once per decision.
"""

from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import GridMap
from explore_seg.core.selection.areas import TURN_DONE_RAD, AreaCounts, turn_goal, turned
from explore_seg.core.selection.blacklist import Blacklist, RevealWatch
from explore_seg.core.selection.costs import Selection, select_goal
from explore_seg.core.selection.goal_types import (Action, Goal, NavOutcome, StepInputs,
                                                   StepResult, frontiers_left,
                                                   goal_frontier_index, goal_yaw, unknown_share)
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.strategy import get_strategy


class GoalManager:
    """Goal keeping, blacklisting and termination around :func:`select_goal` (ROS-free).

    Per call of :meth:`step` (one decision tick):

    1. With a current goal: progress is a decrease of the robot-goal distance by at least
       ``progress_min_m``; none for ``progress_timeout_s`` blacklists the goal. Reaching
       it (``goal_reached_tolerance_m``) while its frontier (a frontier with a cell
       within ``frontier_match_radius_m`` + the goal's gap to its frontier) is still
       there on a newer map stamped at or after the arrival (or after ``arrival_wait_s``)
       blacklists it too (``routed`` with ``reached_unknown_fraction`` > 0: unless the
       visit revealed the frontier's cells, at most ``revealed_arrivals_max`` - 1 times
       per area); reaching a
       return-to-start goal ends exploration (DONE). A ``routed`` goal counts as reached
       within ``handover_m`` already (the robot drives on while it is judged).
    2. Frontiers whose cPoint lies within ``blacklist_radius_m`` of a blacklisted goal
       are excluded. When no reachable frontier is detected but the current goal's
       frontier cells are still unknown (a thin frontier seen at a grazing angle comes and
       goes), the goal is kept. When no reachable frontier remains for
       ``done_confirmations`` consecutive ticks: the blacklist is cleared and its frontiers
       retried (``blacklist_retries`` times, not counting a retry after which
       ``retry_reveal_m2`` more of the map became known), then DONE (or first a
       return-to-start goal, or what :attr:`before_done` starts). A goal the navigator
       aborted is judged at the next decision with distances (:meth:`judge_aborted`):
       blacklisted when the explorer still has a path to its frontier (the navigator
       disagrees: retrying would repeat the abort), otherwise left to wait for a path (a
       doorway that map noise closed opens when the robot looks at it), at most
       ``abort_retries`` times per area.
       Before the blacklist retry (and DONE), while frontiers without a path or
       blacklisted remain, the robot turns in place by half a turn (:func:`.areas.turn_goal`,
       ``turn_looks`` per area): a keyframe map gains a scan from where it stands. A goal
       is unblacklisted once the map near it changed (:meth:`retry_changed`).
    3. The current goal is kept unless its frontier vanished or another frontier is
       cheaper than the current goal's frontier by ``hysteresis_margin * |cost|``; a
       new goal within ``goal_change_min_m`` of the current one is not sent. Observed
       cells do not become unknown again, so a frontier that vanishes before the robot
       arrives with its cells still unknown (so not cleared by sensing: its free
       neighbours turned occupied or were covered by an object) and keeps coming back at
       the same place (within ``flicker_radius_m`` of where it first vanished) is map
       flicker: after ``flicker_vanish_count`` such vanishings its goals are blacklisted.

    DONE is final until :meth:`reset`. The blacklist keeps the newest ``blacklist_max``.
    """

    def __init__(self, params: SelectionParams = SelectionParams()) -> None:
        self.params = params
        self._bl = Blacklist(params.blacklist_max)
        # Areas of: frontiers vanished before arrival, reached goals whose frontier remained
        # revealed, aborts without a path on the map, turn looks, retries on a map change.
        self._vanished, self._revealed = AreaCounts(), AreaCounts()
        self._aborted_areas, self._turns, self._changed = AreaCounts(), AreaCounts(), AreaCounts()
        #: Asked instead of DONE: True when it started something that may open a way (the
        #: decision waits); the explorer's revisits (revisit.py).
        self.before_done: Callable[[], bool] | None = None
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
        self._nav_succeeded = False
        self._outcome_reason = ""
        self._yaw: float | None = None      # the robot's heading at this decision
        self._unreached = False             # frontiers left without a path or blacklisted
        self._aborted: Goal | None = None   # aborted by the navigator, judged next decision
        self._empty_ticks = 0
        self._goal_cells_xy: npt.NDArray[np.float64] | None = None
        self._retries_left = self.params.blacklist_retries
        self._reveal = RevealWatch(self.params.retry_reveal_radius_m)   # the last retry's
        self.start_xy_m: tuple[float, float] | None = None
        self._start_yaw = 0.0
        if clear_blacklist:
            self._bl.clear()
            for areas in (self._vanished, self._revealed, self._aborted_areas, self._turns,
                          self._changed):
                areas.clear()

    @property
    def blacklist_added(self) -> int:
        """Entries ever added to the blacklist (callers count new ones by difference)."""
        return self._bl.added

    def restart_timers(self, now_s: float) -> None:
        """Restart the progress and arrival timers at ``now_s`` (after a clock jump)."""
        self._last_progress_s, self._arrived_s = now_s, None

    def set_params(self, params: SelectionParams) -> None:
        """Apply new parameters (the blacklist keeps its newest entries)."""
        self.params = params
        self._bl.resize(params.blacklist_max)
        self._reveal.radius_m = params.retry_reveal_radius_m

    @property
    def blacklist(self) -> tuple[tuple[float, float], ...]:
        """Blacklisted goal positions (x, y) in metres, oldest first."""
        return tuple(self._bl)

    def add_to_blacklist(self, xy_m: tuple[float, float]) -> None:
        """Blacklist a position (e.g. after the navigator reported a failure)."""
        self._bl.add(xy_m)

    def retry_changed(self, grid: GridMap, occupied_threshold: int) -> int:
        """Unblacklist the goals near which the map changed by ``retry_change_m2``
        (:meth:`.blacklist.Blacklist.changed`), ``change_retries`` times per area at most:
        their frontiers are candidates again. Returns how many."""
        p = self.params
        if p.retry_change_m2 <= 0 or p.change_retries < 1 or not len(self._bl):
            return 0
        cells = max(1, round(p.retry_change_m2 / grid.resolution_m ** 2))
        return self._bl.drop_changed(grid, (p.flicker_radius_m, occupied_threshold, cells),
                                     self._changed, p.change_retries)

    def abandon_goal(self, blacklist: bool = True) -> None:
        """Drop the current goal (blacklisting it unless told not to)."""
        if self.goal is not None and blacklist and not self.goal.is_return:
            self.add_to_blacklist(self.goal.xy_m)
        self.goal = None

    def report_navigation(self, outcome: NavOutcome,
                          goal_xy_m: tuple[float, float] | None = None) -> bool:
        """Tell the manager what the navigator did with the current goal.

        SUCCEEDED counts as arrival whatever the distance (the goal's frontier is judged
        at a later :meth:`step`, on a map newer than the arrival's and stamped at or after
        it, or after ``arrival_wait_s``; a return-to-start goal ends exploration there);
        ABORTED drops the goal and leaves it to :meth:`judge_aborted` at the next
        decision; REJECTED and CANCELED (by someone else) blacklist it at once, so the next
        :meth:`step` picks another frontier instead of waiting ``progress_timeout_s``.
        CANCELED_BY_US, and any other end of a turn look, drop the goal unblacklisted.

        Parameters
        ----------
        outcome : NavOutcome
        goal_xy_m : (float, float), optional
            The goal the outcome belongs to; an outcome for another goal (an older one
            that the navigator finished late) is ignored. None: the current goal.

        Returns ``True`` when the outcome was applied to the current goal.
        """
        goal = self.goal
        if goal is None or not isinstance(outcome, NavOutcome):
            return False
        if goal_xy_m is not None and math.hypot(goal_xy_m[0] - goal.xy_m[0],
                                                goal_xy_m[1] - goal.xy_m[1]) > 1e-6:
            return False
        if outcome is NavOutcome.SUCCEEDED:
            self._nav_succeeded = True
            return True
        if outcome is NavOutcome.CANCELED_BY_US or goal.is_turn:
            # a turn the navigator could not make has no frontier to blacklist
            self.goal = None
            self._outcome_reason = ("goal canceled by us" if not goal.is_turn else
                                    f"navigation {outcome.value} turning in place")
            return True
        if goal.is_return:
            self.goal = None
            self.done = True
            self._outcome_reason = f"navigation {outcome.value} returning to start"
            return True
        if outcome is NavOutcome.ABORTED and self.params.abort_retries > 0:
            self._aborted, self.goal = goal, None
            self._outcome_reason = "navigation aborted: judged on this map"
            return True
        self.abandon_goal(blacklist=True)
        self._outcome_reason = f"navigation {outcome.value}: blacklisted"
        return True

    def judge_aborted(self, grid: GridMap, frontiers: Sequence[Frontier],
                      dist_m: npt.ArrayLike) -> str:
        """Judge the goal the navigator last aborted (no-op without one).

        Blacklisted when its frontier (as in :meth:`goal_frontier`) still has a path on
        the explorer's map; otherwise not (the frontier is no candidate while it has no
        path, and is one again once the map opens one), unless this is the
        ``abort_retries``-th such abort in its area (the area's goals are blacklisted
        then). Call it with the path lengths to the frontiers' own cPoints, before
        lookouts or approaches replace the unreachable ones.

        Parameters
        ----------
        grid : GridMap
        frontiers : sequence of Frontier
        dist_m : array_like of float, shape (N,)
            Path lengths robot -> cPoints (inf: no path).

        Returns
        -------
        str
            What was decided, in words ("" without an aborted goal); also the reason the
            next :meth:`step` gives.
        """
        goal, self._aborted = self._aborted, None
        if goal is None:
            return ""
        i = goal_frontier_index(goal, grid, frontiers, self.params.frontier_match_radius_m)
        d = np.asarray(dist_m, dtype=np.float64)
        if i is not None and i < len(d) and np.isfinite(d[i]):
            self.add_to_blacklist(goal.xy_m)
            reason = "navigation aborted, but the map has a path to its frontier: blacklisted"
        elif self._note_area(self._aborted_areas, goal.xy_m, self.params.abort_retries):
            reason = (f"navigation aborted {self.params.abort_retries} times here with no "
                      "path on the map either: area blacklisted")
        else:
            reason = "navigation aborted, and the map has no path to its frontier: it waits"
        self._outcome_reason = reason
        return reason

    def set_start(self, xy_m: tuple[float, float], yaw_rad: float) -> None:
        """Remember the pose to return to (first pose, unless set again)."""
        self.start_xy_m, self._start_yaw = (float(xy_m[0]), float(xy_m[1])), float(yaw_rad)

    def _note_area(self, areas: AreaCounts, xy_m: tuple[float, float], limit: int) -> bool:
        """Count an event at ``xy_m`` in its area (within ``flicker_radius_m`` of the
        area's first point): vanished frontiers (``flicker_vanish_count``), revealed
        arrivals (``revealed_arrivals_max``), aborts (``abort_retries``). True, with the
        area's points blacklisted, when its count reached ``limit`` (never when < 1)."""
        if limit < 1:
            return False
        count, pts = areas.note(xy_m, self.params.flicker_radius_m)
        if count < limit:
            return False
        for pt in pts:
            self.add_to_blacklist(pt)
        return True

    def aborted_near(self, xy_m: tuple[float, float]) -> bool:
        """True when the navigator aborted a goal the map had no path to either within
        ``flicker_radius_m`` of ``xy_m`` (see :meth:`judge_aborted`)."""
        return self._aborted_areas.count_near(xy_m, self.params.flicker_radius_m) > 0

    def excluded(self, frontiers: Sequence[Frontier]) -> npt.NDArray[np.bool_]:
        """Frontiers whose cPoint lies within ``blacklist_radius_m`` of a blacklisted
        goal (not candidates now)."""
        if not len(self._bl) or not frontiers:
            return np.zeros(len(frontiers), dtype=bool)
        return self._bl.excluded(np.asarray([f.point_xy_m for f in frontiers]),
                                 self.params.blacklist_radius_m)

    def goal_frontier(self, grid: GridMap, frontiers: Sequence[Frontier]) -> int | None:
        """Index of the frontier owning the current goal (a cell within
        ``frontier_match_radius_m`` + the goal's gap to its frontier), None if none."""
        if self.goal is None or self.goal.is_return or self.goal.is_turn:
            return None
        return self._matching(grid, frontiers)

    def _matching(self, grid: GridMap, frontiers: Sequence[Frontier]) -> int | None:
        """Index of the frontier owning the current goal (closest cell within radius)."""
        if self.goal is None:
            return None
        return goal_frontier_index(self.goal, grid, frontiers,
                                   self.params.frontier_match_radius_m)

    def _remember_cells(self, grid: GridMap, f: Frontier) -> None:
        """Keep the (world) positions of the current goal's frontier cells."""
        x, y = grid.cells_to_world(f.cells[:, 0], f.cells[:, 1])
        self._goal_cells_xy = np.column_stack([x, y])

    def _still_unknown(self, grid: GridMap) -> float:
        """Share of the goal frontier's last cells that are still unknown in ``grid``
        (a frontier that vanished with its cells unexplored was not cleared by sensing)."""
        return unknown_share(grid, self._goal_cells_xy)

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
        self._nav_succeeded = False

    def step(self, now_s: float, robot_xy_m: tuple[float, float], grid: GridMap,
             frontiers: Sequence[Frontier], dist_m: npt.ArrayLike | None,
             known: StepInputs | None = None) -> StepResult:
        """One decision: progress on the current goal, then candidates, then keep or switch.

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
        known : StepInputs, optional
            What the caller already has: region labels, robot cell, excluded frontiers,
            tour costs (see :class:`StepInputs`).

        Returns
        -------
        StepResult
        """
        known = known if known is not None else StepInputs()
        labels, robot_rc, excluded = known.labels, known.robot_rc, known.excluded
        self._yaw = known.robot_yaw_rad
        if self.done:
            reason, self._outcome_reason = self._outcome_reason or "exploration done", ""
            return StepResult(Action.DONE, None, reason)
        if self.start_xy_m is None:
            self.set_start(robot_xy_m, 0.0)
        if robot_rc is None:
            robot_rc = grid.world_to_cell(*robot_xy_m)
        version = self._bl.version
        if self._aborted is not None and dist_m is not None:
            self.judge_aborted(grid, frontiers, dist_m)
        # 1. progress and arrival on the current goal
        early, reason = self._check_progress(now_s, robot_xy_m, grid, frontiers, dist_m)
        reason, self._outcome_reason = self._outcome_reason or reason, ""
        if early is not None:
            return early
        if dist_m is None:
            action = Action.KEEP if self.goal is not None else Action.WAIT
            return StepResult(action, self.goal, reason or "no path distances")
        # 2. candidates
        if excluded is None or self._bl.version != version:
            excluded = self.excluded(frontiers)
        sel = select_goal(frontiers, dist_m, labels, robot_rc, self.params, grid.resolution_m,
                          excluded, known.tour_cost_m)
        if sel.index is None:
            # frontiers left without a path, or blacklisted: worth a turn look
            self._unreached = bool(np.any(~np.isfinite(np.asarray(dist_m, dtype=np.float64))
                                          | excluded))
            return self._no_candidate(now_s, robot_xy_m, grid, reason, sel,
                                      frontiers_left(dist_m, excluded))
        self._empty_ticks = 0
        # 3. keep or switch
        return self._keep_or_switch(now_s, robot_xy_m, grid, frontiers, sel, excluded, reason)

    def _check_progress(self, now_s: float, robot_xy_m: tuple[float, float], grid: GridMap,
                        frontiers: Sequence[Frontier], dist_m: npt.ArrayLike | None
                        ) -> tuple[StepResult | None, str]:
        """Progress and arrival on the current goal: (a final result or None, reason).

        In order: progress toward the goal (straight line, then along the path), arrival
        (within reach, or navigation succeeded), the progress timeout.
        """
        if self.goal is None:
            return None, ""
        if self.goal.is_turn:
            return self._on_turn(now_s, grid)
        d_goal = math.hypot(robot_xy_m[0] - self.goal.xy_m[0],
                            robot_xy_m[1] - self.goal.xy_m[1])
        self._note_straight_progress(now_s, d_goal)
        self._note_path_progress(now_s, grid, frontiers, dist_m)
        if self._within_reach(d_goal) or self._nav_succeeded:
            return self._on_arrival(now_s, grid, frontiers)
        if now_s - self._last_progress_s > self.params.progress_timeout_s:
            return self._on_no_progress()
        return None, ""

    def _note_straight_progress(self, now_s: float, d_goal: float) -> None:
        """Progress: the robot-goal distance fell by ``progress_min_m`` below its best."""
        if d_goal <= self._best_dist - self.params.progress_min_m:
            self._best_dist = d_goal
            self._last_progress_s = now_s

    def _note_path_progress(self, now_s: float, grid: GridMap, frontiers: Sequence[Frontier],
                            dist_m: npt.ArrayLike | None) -> None:
        """Progress along the path counts too: the way to a goal often leads away from it
        first (around a wall, through a corridor)."""
        assert self.goal is not None
        cur_goal = (self._matching(grid, frontiers)
                    if dist_m is not None and not self.goal.is_return else None)
        if cur_goal is not None and np.isfinite(dist_m[cur_goal]):
            d_path = float(dist_m[cur_goal])
            if d_path <= self._best_path_dist - self.params.progress_min_m:
                if math.isfinite(self._best_path_dist):
                    self._last_progress_s = now_s
                self._best_path_dist = d_path

    def _on_turn(self, now_s: float, grid: GridMap) -> tuple[StepResult | None, str]:
        """A turn look ends once the navigator reports it done (or the heading is
        there) and a map that shows it came (or ``arrival_wait_s`` passed); it is given
        up, not blacklisted, after ``progress_timeout_s``. The decisions without a
        frontier before DONE count again from its end."""
        assert self.goal is not None
        if self._nav_succeeded or turned(self.goal, self._yaw, TURN_DONE_RAD):
            self._nav_succeeded = True
            if self._waiting_for_map(now_s, grid):
                return StepResult(Action.KEEP, self.goal,
                                  "turned in place: waiting for the map to update"), ""
            self.goal, self._arrived_s, self._empty_ticks = None, None, 0
            return None, "turned in place"
        if now_s - self._last_progress_s > self.params.progress_timeout_s:
            self.goal, self._empty_ticks = None, 0
            return None, "turn in place not done in time: given up"
        return None, ""

    def _within_reach(self, d_goal: float) -> bool:
        """The goal counts as reached at ``goal_reached_tolerance_m`` (at ``handover_m``
        for a strategy that hands over, except a return to start)."""
        assert self.goal is not None
        p = self.params
        reached_m = p.goal_reached_tolerance_m
        if get_strategy(p.strategy).goals.handover and not self.goal.is_return:
            reached_m = max(reached_m, p.handover_m)
        return d_goal <= reached_m

    def _on_arrival(self, now_s: float, grid: GridMap, frontiers: Sequence[Frontier]
                    ) -> tuple[StepResult | None, str]:
        """The goal is reached: a return to start ends exploration; otherwise wait for a
        map that shows the arrival (or ``arrival_wait_s``), then judge the goal's
        frontier."""
        assert self.goal is not None
        if self.goal.is_return:
            self.goal = None
            self.done = True
            return StepResult(Action.DONE, None, "returned to start"), ""
        if self._waiting_for_map(now_s, grid):
            return StepResult(Action.KEEP, self.goal,
                              "goal reached: waiting for the map to update"), ""
        self._arrived_s = None
        return None, self._judge_reached_frontier(grid, frontiers)

    def _waiting_for_map(self, now_s: float, grid: GridMap) -> bool:
        """True until a map newer than the arrival's and stamped at or after the arrival
        comes, for at most ``arrival_wait_s``. A map renewed every few seconds
        (slam_toolbox's ``map_update_interval``), or a newer one built from older scans,
        does not show what the robot sees from the goal yet: judged on it, the frontier
        would remain. Maps of every scan are newer at the next decision already."""
        if self._arrived_s is None:
            self._arrived_s, self._arrived_stamp_ns = now_s, grid.stamp_ns
        shows_arrival = (grid.stamp_ns != self._arrived_stamp_ns
                         and grid.stamp_ns >= round(self._arrived_s * 1e9))
        return not shows_arrival and now_s - self._arrived_s < self.params.arrival_wait_s

    def _judge_reached_frontier(self, grid: GridMap, frontiers: Sequence[Frontier]) -> str:
        """Drop the reached goal; blacklist it when its frontier remains (unless the
        strategy reveals on arrival and the visit revealed the frontier's cells, at most
        ``revealed_arrivals_max`` - 1 times per area). Returns the reason."""
        assert self.goal is not None
        p = self.params
        if self._matching(grid, frontiers) is None:
            self.goal = None
            return "goal reached"
        if (not get_strategy(p.strategy).goals.reveal_on_arrival
                or self._still_unknown(grid) >= p.reached_unknown_fraction):
            self.abandon_goal(blacklist=True)
            return "goal reached but its frontier remains: blacklisted"
        if self._note_area(self._revealed, self.goal.xy_m, p.revealed_arrivals_max):
            self.goal = None
            return (f"goal reached, its frontier's cells revealed "
                    f"{p.revealed_arrivals_max} times here and it remains: area blacklisted")
        self.goal = None
        return "goal reached: its frontier's cells were revealed, the space goes on"

    def _on_no_progress(self) -> tuple[StepResult | None, str]:
        """No progress for ``progress_timeout_s``: give up a return to start (DONE),
        blacklist any other goal."""
        assert self.goal is not None
        if self.goal.is_return:
            self.goal = None
            self.done = True
            return StepResult(Action.DONE, None, "no progress returning to start"), ""
        self.abandon_goal(blacklist=True)
        return None, f"no progress for {self.params.progress_timeout_s:.0f} s: blacklisted"

    def _no_candidate(self, now_s: float, robot_xy_m: tuple[float, float], grid: GridMap,
                      reason: str, sel: Selection, left: str) -> StepResult:
        """No selectable frontier: keep a goal whose cells are still unknown, wait for
        ``done_confirmations`` ticks, return to start, retry the blacklist, then DONE.
        ``left`` (:func:`frontiers_left`) names what is left in the reasons."""
        p = self.params
        self._empty_ticks += 1
        if self.goal is not None and (self.goal.is_return or self.goal.is_turn):
            return StepResult(Action.KEEP, self.goal, "returning to start"
                              if self.goal.is_return else "turning in place", sel)
        if self.goal is not None and self._still_unknown(grid) >= 0.5:
            # A thin frontier seen at a grazing angle (a doorway from the side) comes
            # and goes: its cells are still unknown, so drive on and look.
            return StepResult(Action.KEEP, self.goal, reason or "no frontier detected now, "
                              "but the goal's cells are still unknown: keeping goal", sel)
        self.goal = None
        if self._empty_ticks < p.done_confirmations:
            return StepResult(Action.WAIT, None, reason or left, sel)
        if (self._yaw is not None and self._unreached
                and self._turns.count_near(robot_xy_m, p.flicker_radius_m) < p.turn_looks):
            self._turns.note(robot_xy_m, p.flicker_radius_m)
            self.goal = turn_goal(robot_xy_m, self._yaw, grid.world_to_cell(*robot_xy_m))
            self._start_progress(self.goal, robot_xy_m, now_s)
            return StepResult(Action.NEW_GOAL, self.goal, f"{left}: turning in place, so that "
                              "the map gains a scan from here", sel)
        if p.return_to_start and self.start_xy_m is not None:
            d0 = math.hypot(robot_xy_m[0] - self.start_xy_m[0],
                            robot_xy_m[1] - self.start_xy_m[1])
            if d0 > p.goal_reached_tolerance_m:
                srow, scol = grid.world_to_cell(*self.start_xy_m)
                self.goal = Goal(self.start_xy_m, self._start_yaw, (srow, scol), 0, 0.0,
                                 is_return=True)
                self._start_progress(self.goal, robot_xy_m, now_s)
                return StepResult(Action.NEW_GOAL, self.goal,
                                  f"{left}: returning to start", sel)
        # the last retry revealed space near its goals: this one does not count
        free = (p.retry_reveal_m2 > 0 and len(self._bl) > 0
                and self._reveal.revealed_m2(grid) >= p.retry_reveal_m2)
        if len(self._bl) and (free or self._retries_left > 0):
            # The map changed since those goals failed (a doorway seen, a false
            # obstacle cleared): give the blacklisted frontiers another chance.
            if not free:
                self._retries_left -= 1
            self._reveal.start(grid, tuple(self._bl))
            self._bl.clear()
            self._empty_ticks = 0
            return StepResult(Action.WAIT, None, f"{left}: blacklist cleared, retrying "
                              "its frontiers", sel)
        if self.before_done is not None and self.before_done():
            self._empty_ticks = 0
            return StepResult(Action.WAIT, None, f"{left}: driving back to an old place of "
                              "the robot's path for a loop closure", sel)
        self.done = True
        return StepResult(Action.DONE, None, left, sel)

    def _keep_or_switch(self, now_s: float, robot_xy_m: tuple[float, float], grid: GridMap,
                        frontiers: Sequence[Frontier], sel: Selection,
                        excluded: npt.NDArray[np.bool_], reason: str) -> StepResult:
        """Keep the current goal unless a cheaper frontier wins by the hysteresis margin
        or its frontier is gone; a switch to a goal next to the current one is not made."""
        p = self.params
        best = sel.index
        assert best is not None
        best_cost = float(sel.costs[best])
        if self.goal is not None and not (self.goal.is_return or self.goal.is_turn):
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
                  and self._note_area(self._vanished, self.goal.xy_m,
                                      p.flicker_vanish_count)):
                reason = (f"goal frontier vanished {p.flicker_vanish_count} times here before "
                          "arrival (flickering): area blacklisted")
            elif cur is None:
                reason = reason or "goal frontier gone"
            else:
                # Still mapped, but its cost is inf: no path any more, or (routed) left out
                # of the tour (a leftover while a bigger view remains, a gain too small).
                reason = reason or ("goal frontier blacklisted" if excluded[cur] else
                                    "goal frontier no longer selectable (no path, or left "
                                    "out of the tour)")
        goal = self._new_goal(frontiers[best], best_cost, robot_xy_m, now_s)
        self._remember_cells(grid, frontiers[best])
        return StepResult(Action.NEW_GOAL, goal, reason or "new goal", sel)


__all__ = ["Action", "Goal", "GoalManager", "NavOutcome", "StepInputs", "StepResult",
           "goal_yaw"]
