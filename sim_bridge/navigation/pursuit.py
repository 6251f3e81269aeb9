"""Path following of the navigation stand-in: pure pursuit along the current plan, with
the arc check and what the controller does when no arc keeps clear.

:class:`Pursuit` is the following half of :class:`~sim_bridge.navigation.navigator.Navigator`
(which derives from it): it reads the navigator's plan state (``params``, ``_plan_xy``,
``_plan_index``, ``_plan_cost``, ``_plan_grid``) and obstacle lookup (``_obstacles``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.angles import wrap_angle
from explore_seg.core.grid import GridMap
from sim_bridge.navigation.clearance import (arc_points, clearance_window, edge_distances,
                                             edge_safe_cost)

if TYPE_CHECKING:
    from sim_bridge.navigation.params import NavParams

#: Plan points measured at a time when looking for the lookahead point.
_LOOKAHEAD_CHUNK = 64

#: Plan points ahead of the progress index searched for the one closest to the robot.
_PROGRESS_WINDOW = 64

#: The pure-pursuit arc check skips this much of the arc next to the robot (m).
ARC_FREE_START_M = 0.1


def clip_magnitude(v: float, limit: float) -> float:
    """``v`` clipped to [-limit, limit]."""
    return max(-limit, min(limit, v))


class Pursuit:
    """Pure pursuit along the plan (see the module docstring)."""

    params: NavParams
    _plan_xy: npt.NDArray[np.float64]
    _plan_index: int
    _plan_cost: npt.NDArray[np.float64] | None
    _plan_grid: GridMap | None
    #: The navigator's ``_obstacles(grid, window)``: (blocked, unknown) cells of a window.
    _obstacles: Callable[..., tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]]

    def _pursue(self, pose: tuple[float, float, float], dist_goal: float
                ) -> tuple[float, float]:
        p = self.params
        x, y, yaw = pose
        path = self._plan_xy
        # Advance the progress index to the closest point in a window ahead.
        i0 = self._plan_index
        i1 = min(len(path), i0 + _PROGRESS_WINDOW)
        d = np.hypot(path[i0:i1, 0] - x, path[i0:i1, 1] - y)
        self._plan_index = i0 + int(np.argmin(d))
        rest = path[self._plan_index:]
        # The first point at least the lookahead away, searched in chunks (the rest of a
        # long plan is not measured at every step).
        k = len(rest) - 1
        for i0 in range(0, len(rest), _LOOKAHEAD_CHUNK):
            part = rest[i0:i0 + _LOOKAHEAD_CHUNK]
            beyond = np.flatnonzero(np.hypot(part[:, 0] - x, part[:, 1] - y) >= p.lookahead_m)
            if beyond.size:
                k = i0 + int(beyond[0])
                break
        # A lookahead point behind an obstacle corner would make the arc cut the corner:
        # step back along the plan to the farthest point whose arc stays clear.
        k_look = k
        clear = k < 1 or self._arc_clear(pose, rest[k])
        while not clear and k > 1:
            k -= 1
            clear = self._arc_clear(pose, rest[k])
        if not clear:
            # No arc from the heading keeps clear (the robot stands close to an obstacle,
            # heading past it). An unchecked arc is never driven: it can cut a wall corner
            # the map shows (docs/experiments.md#navigation-no-unchecked-arc). In order:
            # face the next plan point when the straight line to it is clear (turning in
            # place never moves the footprint, as Nav2's recovery turns); drive an arc that
            # keeps the robot radius itself; face a farther point whose line is clear;
            # face the next point and wait.
            turn = self._turn_to_clear_line(pose, rest, 1, 1)
            if turn is not None:
                return turn
            k = self._relaxed_target(pose, rest, k_look)
            if k is None:
                turn = self._turn_to_clear_line(pose, rest, 2, k_look)
                return turn if turn is not None else self._face_and_wait(pose, rest)
        tx, ty = rest[k]
        alpha = wrap_angle(math.atan2(ty - y, tx - x) - yaw)
        if abs(alpha) > p.rotate_in_place_angle_rad:
            return 0.0, clip_magnitude(p.heading_gain * alpha, p.max_angular_speed_radps)
        ld = max(math.hypot(tx - x, ty - y), 1e-3)
        curvature = 2.0 * math.sin(alpha) / ld
        v = min(p.max_linear_speed_mps,
                p.approach_gain * dist_goal + p.min_approach_speed_mps)
        if abs(curvature) > 1e-6:
            v = min(v, p.max_angular_speed_radps / abs(curvature))
        w = clip_magnitude(v * curvature, p.max_angular_speed_radps)
        return v, w

    def _relaxed_target(self, pose: tuple[float, float, float],
                        rest: npt.NDArray[np.float64], k_look: int) -> int | None:
        """The farthest plan point up to the lookahead whose arc keeps the robot radius
        itself (no ``arc_clearance_m``) from every obstacle cell's edge (or, starting
        closer, gets no closer), None when there is none: a passage whose free cells lie
        only a few millimetres beyond the radius is driven through, not waited at (the
        map's obstacle cells hold the true surfaces, so their edges are never farther)."""
        for k in range(k_look, 0, -1):
            if self._arc_clear(pose, rest[k], extra_m=0.0):
                return k
        return None

    def _turn_to_clear_line(self, pose: tuple[float, float, float],
                            rest: npt.NDArray[np.float64], first: int, last: int
                            ) -> tuple[float, float] | None:
        """The in-place turn toward the first plan point ``rest[first..last]`` whose
        straight line from the robot is clear, None when none is."""
        p = self.params
        x, y, yaw = pose
        for j in range(first, last + 1):
            bearing = math.atan2(rest[j, 1] - y, rest[j, 0] - x)
            if self._arc_clear((x, y, bearing), rest[j]):
                turn = wrap_angle(bearing - yaw)
                return 0.0, clip_magnitude(p.heading_gain * turn, p.max_angular_speed_radps)
        return None

    def _face_and_wait(self, pose: tuple[float, float, float],
                       rest: npt.NDArray[np.float64]) -> tuple[float, float]:
        """Turn to face the next plan point, then wait (zero command) for a plan or map
        that gives a clear motion, or for the progress checker to abort the goal."""
        p = self.params
        turn = wrap_angle(math.atan2(rest[1, 1] - pose[1], rest[1, 0] - pose[0]) - pose[2])
        if abs(turn) > p.goal_tolerance_yaw_rad:
            return 0.0, clip_magnitude(p.heading_gain * turn, p.max_angular_speed_radps)
        return 0.0, 0.0

    def _arc_clear(self, pose: tuple[float, float, float], target: npt.NDArray[np.float64],
                   extra_m: float | None = None) -> bool:
        """True when the pure-pursuit arc from ``pose`` to ``target`` keeps out of the
        lethal zone of the cost grid of the current plan (its first ``ARC_FREE_START_M``
        are not checked: the robot may stand in the margin after a back-up) and, with
        ``arc_check_edges``, keeps ``robot_radius_m + extra_m`` (default
        ``arc_clearance_m``) from the edges of the obstacle cells all along (or, starting
        closer, gets no closer)."""
        cost, grid = self._plan_cost, self._plan_grid
        if cost is None or grid is None:
            return True
        x, y, yaw = pose
        ld = math.hypot(target[0] - x, target[1] - y)
        if ld <= ARC_FREE_START_M and not self.params.arc_check_edges:
            return True
        alpha = wrap_angle(math.atan2(target[1] - y, target[0] - x) - yaw)
        if abs(alpha) > self.params.rotate_in_place_angle_rad:
            return True          # turned in place first, then driven almost straight
        kappa = 2.0 * math.sin(alpha) / ld
        length = ld if abs(alpha) < 1e-6 else ld * alpha / math.sin(alpha)
        step = 0.5 * grid.resolution_m
        s = np.arange(ARC_FREE_START_M, length + 1e-9, step)
        px, py = arc_points(x, y, yaw, kappa, s)
        r, c = grid.world_to_cells(px, py)
        ok = (r >= 0) & (r < cost.shape[0]) & (c >= 0) & (c < cost.shape[1])
        if not ok.all():
            return False
        if not np.isfinite(cost[r, c]).all():
            return False
        if not self.params.arc_check_edges:
            return True
        qx, qy = arc_points(x, y, yaw, kappa, np.arange(0.0, min(ARC_FREE_START_M, length),
                                                        step))
        if len(qx) + len(px) < 2:
            return True
        safe = edge_safe_cost(self.params, grid.resolution_m)
        if safe is not None and len(qx):
            rq, cq = grid.world_to_cells(qx, qy)
            inside = ((rq >= 0) & (rq < cost.shape[0]) & (cq >= 0) & (cq < cost.shape[1])).all()
            if inside and (cost[rq, cq] <= safe).all() and (cost[r, c] <= safe).all():
                return True    # every sample's cell is far enough by its inflation cost
        clear = self._edge_clearance(grid, np.concatenate([qx, px]), np.concatenate([qy, py]))
        extra = self.params.arc_clearance_m if extra_m is None else extra_m
        need = min(self.params.robot_radius_m + extra, float(clear[0]))
        return bool(clear[1:].min(initial=math.inf) >= need - 1e-9)

    def _edge_clearance(self, grid: GridMap, px: npt.NDArray[np.float64],
                        py: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """Distance from each point to the nearest edge of an obstacle cell of the map or
        the layers, up to ``robot_radius_m + arc_clearance_m`` + a cell."""
        res = grid.resolution_m
        reach = self.params.robot_radius_m + self.params.arc_clearance_m + res
        fr, fc = grid.world_to_cell_float(px, py)
        window = clearance_window(fr, fc, reach / res, grid.shape)
        if window is None:
            return np.full(len(px), reach)
        blocked, _ = self._obstacles(grid, window)
        return edge_distances(blocked, window[0], window[2], fr, fc, res, reach)
