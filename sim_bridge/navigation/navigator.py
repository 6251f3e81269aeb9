"""The navigation stand-in's goal state machine and path follower.

:class:`Navigator` takes a goal (x, y, yaw) like ``goal_pose``, plans with
:mod:`sim_bridge.navigation.planner` on the current map plus extra occupancy layers,
follows the plan with a pure-pursuit controller within the speed limits, replans
periodically and when the plan gets blocked, and reports ``ACTIVE`` / ``SUCCEEDED`` /
``ABORTED`` / ``CANCELED`` like Nav2's ``navigate_to_pose`` action.
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass
from typing import Callable

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.angles import wrap_angle
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.paths import _MAX_KERNEL_RADIUS_CELLS, disk_kernel, inflate
from sim_bridge.navigation.params import NavParams
from sim_bridge.navigation.costmap import CostGridCache
from sim_bridge.navigation.planner import coarsen, path_cost, plan_path
from sim_bridge.navigation.pursuit import Pursuit, clip_magnitude

__all__ = ["NavState", "NavStatus", "Navigator"]


class NavState(enum.Enum):
    """Goal status, as Nav2's action reports it."""

    IDLE = "idle"
    ACTIVE = "active"
    SUCCEEDED = "succeeded"
    ABORTED = "aborted"
    CANCELED = "canceled"


@dataclass(frozen=True)
class NavStatus:
    """Current state, a human reason for ABORTED/CANCELED, and the goal (x, y, yaw)."""

    state: NavState
    reason: str = ""
    goal: tuple[float, float, float] | None = None


#: Largest lethal radius (cells) that :meth:`Navigator._plan_blocked` checks through disk
#: offsets: the radii :func:`inflate` grows with its disk kernel (beyond, it inflates the
#: window as before).
_DISK_LOOKUP_MAX_CELLS = _MAX_KERNEL_RADIUS_CELLS


@functools.lru_cache(maxsize=8)
def _disk_offsets(r: float) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """(rows, cols) offsets of the cells of :func:`disk_kernel` ``(r)`` (its centre at 0)."""
    kernel = disk_kernel(r)
    half = kernel.shape[0] // 2
    dr, dc = np.nonzero(kernel)
    return dr.astype(np.int64) - half, dc.astype(np.int64) - half


class Navigator(Pursuit):
    """Goal handling, planning and path following for one robot.

    The engine calls :meth:`control` every physics step with the pose and the sim time;
    it returns the (v, w) command, :meth:`update`'s at the controller's rate. Planning uses
    the latest map given through :meth:`set_map` and the layers given through
    :meth:`set_layer`.
    """

    def __init__(self, params: NavParams | None = None) -> None:
        self.params = params if params is not None else NavParams()
        self._map_src: GridMap | Callable[[], GridMap] | None = None
        self._map_cache: GridMap | None = None
        self._map_cache_version = -1
        self._map_version = 0
        self._layer_version = 0
        self._layers: dict[str, GridMap] = {}
        self._status = NavStatus(NavState.IDLE)
        self._plan_xy = np.zeros((0, 2), dtype=np.float64)
        self._plan_index = 0
        self._planned_key: tuple[int, int] = (-1, -1)
        self._last_plan_s = -math.inf
        self._last_check_s = -math.inf
        self._goal_start_s = 0.0
        self._progress_xy = (0.0, 0.0)
        self._progress_s = 0.0
        self._plan_count = 0
        self._need_plan = False
        self._final_turn = False
        self._target_xy: tuple[float, float] | None = None
        self._plan_version = 0
        self._retries_left = 0
        self._plan_cost: npt.NDArray[np.float64] | None = None
        self._plan_grid: GridMap | None = None
        # Cost of the last plan per (goal cell, downsampling): only a hint that saves
        # planning work (plan_path's result does not depend on it).
        self._goal_cost: dict[tuple[tuple[int, int], int], float] = {}
        # (key, mask, lattice-aligned) of :meth:`_layer_blocked`.
        self._layer_mask: tuple[tuple, npt.NDArray[np.bool_], bool] | None = None
        self._costmap = CostGridCache()
        # The controller's held command and the time of its next computation.
        self._held = (0.0, 0.0)
        self._next_control_s = 0.0

    # ---------------------------------------------------------------- inputs
    @property
    def status(self) -> NavStatus:
        """Current goal status."""
        return self._status

    @property
    def plan_xy(self) -> npt.NDArray[np.float64]:
        """Current plan as world points, shape (N, 2) (empty without a plan)."""
        return self._plan_xy

    @property
    def plan_version(self) -> int:
        """Changes whenever :attr:`plan_xy` is replaced."""
        return self._plan_version

    @property
    def plan_count(self) -> int:
        """Number of plans computed so far (kept or not; for diagnostics)."""
        return self._plan_count

    def set_params(self, params: NavParams) -> None:
        """Swap parameters (takes effect at the next plan / control step)."""
        self.params = params
        self._need_plan = self._status.state is NavState.ACTIVE

    def set_map(self, grid: GridMap | Callable[[], GridMap], version: int) -> None:
        """Latest map, or a function returning it (called only when a plan needs it);
        ``version`` must change whenever the map content changes."""
        self._map_src = grid
        self._map_version = int(version)

    def _content_key(self) -> tuple[int, int]:
        return (self._map_version, self._layer_version)

    @property
    def _map(self) -> GridMap | None:
        if self._map_src is None or isinstance(self._map_src, GridMap):
            return self._map_src
        if self._map_cache is None or self._map_cache_version != self._map_version:
            self._map_cache = self._map_src()
            self._map_cache_version = self._map_version
        return self._map_cache

    def set_layer(self, name: str, grid: GridMap | None) -> None:
        """Add/replace (or with None remove) an obstacle layer; forces a replan."""
        if grid is None:
            self._layers.pop(name, None)
        else:
            self._layers[name] = grid
        self._layer_version += 1
        self._need_plan = self._status.state is NavState.ACTIVE

    def set_goal(self, x: float, y: float, yaw: float, now_s: float,
                 pose: tuple[float, float, float]) -> None:
        """Accept a new goal (replacing any active one) or raise ValueError.

        Raises
        ------
        ValueError
            When a coordinate is not finite, no map exists yet, or the goal lies outside
            the current map.
        """
        vals = (float(x), float(y), float(yaw))
        if not all(math.isfinite(v) for v in vals):
            raise ValueError(f"goal must be finite, got (x, y, yaw) = {vals}")
        g = self._map
        if g is None:
            raise ValueError("no map yet: goals are accepted once the first scan is mapped")
        if not g.in_bounds(*g.world_to_cell(vals[0], vals[1])):
            xmax = g.origin_xy_m[0] + g.width * g.resolution_m
            ymax = g.origin_xy_m[1] + g.height * g.resolution_m
            raise ValueError(
                f"goal ({vals[0]:.2f}, {vals[1]:.2f}) outside the map "
                f"[{g.origin_xy_m[0]:.2f}, {xmax:.2f}] x [{g.origin_xy_m[1]:.2f}, {ymax:.2f}]")
        self._status = NavStatus(NavState.ACTIVE, "", vals)
        self._goal_start_s = now_s
        self._progress_xy = (pose[0], pose[1])
        self._progress_s = now_s
        self._plan_xy = np.zeros((0, 2))
        self._plan_version += 1
        self._plan_index = 0
        self._need_plan = True
        self._final_turn = False
        self._target_xy = None
        self._retries_left = self.params.collision_retries
        self._held = (0.0, 0.0)

    def cancel(self, reason: str = "canceled") -> None:
        """Cancel the active goal (no-op otherwise)."""
        if self._status.state is NavState.ACTIVE:
            self._finish(NavState.CANCELED, reason)

    def abort(self, reason: str) -> None:
        """Abort the active goal (e.g. after a collision)."""
        if self._status.state is NavState.ACTIVE:
            self._finish(NavState.ABORTED, reason)

    def recover(self, reason: str, now_s: float, pose: tuple[float, float, float]) -> bool:
        """After a collision: replan from ``pose`` at the next update and go on while
        ``collision_retries`` are left for this goal (True), else abort it (False).
        The progress checker restarts at ``pose``. No-op (False) without an active goal."""
        self._held = (0.0, 0.0)
        if self._status.state is not NavState.ACTIVE:
            return False
        if self._retries_left <= 0:
            self._finish(NavState.ABORTED, reason)
            return False
        self._retries_left -= 1
        self._plan_xy = np.zeros((0, 2))
        self._plan_version += 1
        self._plan_index = 0
        self._need_plan = True
        self._final_turn = False
        self._progress_xy, self._progress_s = (pose[0], pose[1]), now_s
        return True

    def _finish(self, state: NavState, reason: str) -> None:
        self._status = NavStatus(state, reason, self._status.goal)
        self._plan_xy = np.zeros((0, 2))
        self._plan_version += 1
        self._plan_index = 0

    # -------------------------------------------------------------- planning
    def _obstacles(self, grid: GridMap, window: tuple[int, int, int, int] | None = None
                   ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
        """(blocked, unknown) masks of the map (or a window r0, r1, c0, c1 of it)."""
        p = self.params
        r0, r1, c0, c1 = window if window is not None else (0, grid.height, 0, grid.width)
        data = grid.data[r0:r1, c0:c1]
        blocked = data >= p.occupied_threshold
        unknown = data < 0
        if self._layers:
            whole, aligned = self._layer_blocked(grid)
            if window is None or aligned:
                blocked |= whole[r0:r1, c0:c1]
            else:
                blocked |= self._resampled_layers(grid, window)
        if not p.allow_unknown:
            blocked |= unknown
        return blocked, unknown

    def _resampled_layers(self, grid: GridMap, window: tuple[int, int, int, int]
                          ) -> npt.NDArray[np.bool_]:
        """Cells of a window (r0, r1, c0, c1) of the map that a layer blocks."""
        r0, r1, c0, c1 = window
        corner = grid.cells_to_world(r0 - 0.5, c0 - 0.5)
        geom = GridMap(np.zeros((r1 - r0, c1 - c0), dtype=np.int8),
                       grid.resolution_m, corner, grid.origin_yaw_rad, grid.frame_id)
        out = np.zeros(geom.shape, dtype=bool)
        for layer in self._layers.values():
            out |= layer.resample_to(geom, fill=0) >= self.params.occupied_threshold
        return out

    def _layer_blocked(self, grid: GridMap) -> tuple[npt.NDArray[np.bool_], bool]:
        """Cells of the whole map that a layer blocks, computed once per layer set and map
        geometry (the map changes every scan, its geometry and the layers rarely), and
        whether every layer lies on the map's cell lattice (same resolution and
        orientation, origin a whole number of cells away): a window of the map then
        samples each layer at cell centres whose layer cell is the whole map's, so the
        window's mask is a slice of this one."""
        key = (self._layer_version, grid.shape, grid.origin_xy_m, grid.resolution_m,
               grid.origin_yaw_rad, grid.frame_id, self.params.occupied_threshold)
        if self._layer_mask is None or self._layer_mask[0] != key:
            mask = self._resampled_layers(grid, (0, grid.height, 0, grid.width))
            res = grid.resolution_m
            aligned = all(
                layer.resolution_m == res and layer.origin_yaw_rad == grid.origin_yaw_rad
                and grid.origin_yaw_rad == 0.0
                and all(abs(d - round(d)) < 1e-6 for d in (
                    (layer.origin_xy_m[0] - grid.origin_xy_m[0]) / res,
                    (layer.origin_xy_m[1] - grid.origin_xy_m[1]) / res))
                for layer in self._layers.values())
            self._layer_mask = (key, mask, aligned)
        return self._layer_mask[1], self._layer_mask[2]

    def _cost(self, grid: GridMap) -> npt.NDArray[np.float64]:
        blocked, unknown = self._obstacles(grid)
        return self._costmap.cost(blocked, unknown if self.params.allow_unknown else None,
                                  grid.resolution_m, self.params,
                                  (grid.origin_xy_m, grid.origin_yaw_rad))

    def _plan(self, pose: tuple[float, float, float], now_s: float) -> bool:
        """Plan from the pose to the goal; False (and ABORTED) when impossible."""
        p = self.params
        grid = self._map
        assert grid is not None and self._status.goal is not None
        gx, gy, _ = self._status.goal
        res = grid.resolution_m
        start = grid.world_to_cell(pose[0], pose[1])
        goal = grid.world_to_cell(gx, gy)
        self._last_plan_s = now_s
        self._planned_key = self._content_key()
        self._plan_count += 1
        if not grid.in_bounds(*start):
            self._finish(NavState.ABORTED, f"robot at ({pose[0]:.2f}, {pose[1]:.2f}) is "
                                           "outside the map")
            return False
        if not grid.in_bounds(*goal):
            self._finish(NavState.ABORTED, "goal outside the map")
            return False
        cost = self._cost(grid)
        self._escape_start(cost, start, res)
        self._plan_cost, self._plan_grid = cost, grid
        k = p.plan_downsample
        coarse, s_rc, g_rc = coarsen(cost, start, goal, k)
        known = grid.data >= 0
        if k > 1:  # a coarse cell is known when all its fine cells are
            known = np.isfinite(coarsen(np.where(known, 0.0, np.inf), start, goal, k)[0])
        g_rc = self._reachable_goal(coarse, g_rc, res * k, known)
        found = (plan_path(coarse, s_rc, g_rc, res * k, p.plan_window_margin_m,
                           cost_hint=self._goal_cost.get((g_rc, k)))
                 if g_rc is not None else None)
        if found is None:
            self._finish(NavState.ABORTED, f"no path to ({gx:.2f}, {gy:.2f}): goal "
                                           "unreachable or blocked")
            return False
        cells, new_cost = found
        self._goal_cost = {(g_rc, k): new_cost}     # the next plan's first guess
        rows = (cells[:, 0].astype(np.float64) + 0.5) * k - 0.5
        cols = (cells[:, 1].astype(np.float64) + 0.5) * k - 0.5
        x, y = grid.cells_to_world(rows, cols)
        xy = np.column_stack([x, y])
        xy[0] = pose[0], pose[1]
        if math.hypot(xy[-1, 0] - gx, xy[-1, 1] - gy) <= res * k:
            xy[-1] = gx, gy
        # Hysteresis: keep a still-valid current plan unless the new one is clearly cheaper.
        if len(self._plan_xy) >= 2:
            rest = np.vstack([[pose[0], pose[1]], self._plan_xy[self._plan_index + 1:]])
            old_cost = path_cost(rest, cost, grid)
            if math.isfinite(old_cost) and not new_cost < p.switch_cost_ratio * old_cost:
                return True
        self._plan_xy = xy
        self._plan_version += 1
        self._target_xy = (float(xy[-1, 0]), float(xy[-1, 1]))
        self._plan_index = 0
        return True

    def _escape_start(self, cost: npt.NDArray[np.float64], start: tuple[int, int],
                      res: float) -> None:
        """Let a robot standing in the lethal margin drive out of it: lethal cells near
        the start that keep half a robot radius from true obstacles, and are no closer to
        an obstacle than the start (so the plan leads out of the margin, not along or
        into it), get a high finite cost (Nav2 likewise lets a robot leave the inscribed
        zone)."""
        if np.isfinite(cost[start]):
            return
        p = self.params
        rad = int(math.ceil(p.lethal_radius_m / res))
        r, c = start
        h, w = cost.shape
        # Obstacles up to 2 rad from the start can be a disk cell's nearest one.
        wr0, wr1 = max(0, r - 2 * rad), min(h, r + 2 * rad + 1)
        wc0, wc1 = max(0, c - 2 * rad), min(w, c + 2 * rad + 1)
        grid = self._map
        assert grid is not None
        blocked, _ = self._obstacles(grid, (wr0, wr1, wc0, wc1))
        hard = inflate(blocked, 0.5 * p.robot_radius_m, res)
        near = cv2.distanceTransform(np.ascontiguousarray(~blocked, dtype=np.uint8),
                                     cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        outward = near >= near[r - wr0, c - wc0]
        rr, cc = np.ogrid[wr0:wr1, wc0:wc1]
        disk = (rr - r) ** 2 + (cc - c) ** 2 <= rad * rad
        sub = cost[wr0:wr1, wc0:wc1]
        sub[disk & ~hard & outward & ~np.isfinite(sub)] = 1.0 + p.inflation_cost_weight

    def _reachable_goal(self, cost: npt.NDArray[np.float64], goal_rc: tuple[int, int],
                        res: float, known: npt.NDArray[np.bool_]) -> tuple[int, int] | None:
        """The goal cell, or the nearest passable cell within the planner tolerance.

        Known cells are preferred over unknown ones, so a goal next to a wall is moved
        into the room, not behind the wall (where unknown space is also "passable").
        """
        if np.isfinite(cost[goal_rc]):
            return goal_rc
        rad = int(math.floor(self.params.planner_goal_tolerance_m / res))
        if rad <= 0:
            return None
        h, w = cost.shape
        r, c = goal_rc
        r0, r1 = max(0, r - rad), min(h, r + rad + 1)
        c0, c1 = max(0, c - rad), min(w, c + rad + 1)
        ok = np.isfinite(cost[r0:r1, c0:c1])
        rr, cc = np.nonzero(ok)
        if rr.size == 0:
            return None
        d2 = ((rr + r0 - r) ** 2 + (cc + c0 - c) ** 2).astype(np.float64)
        d2[d2 > rad * rad] = np.inf
        d2[~known[r0:r1, c0:c1][rr, cc]] += 4.0 * rad * rad  # unknown only as a fallback
        i = int(np.argmin(d2))
        if not np.isfinite(d2[i]):
            return None
        return int(rr[i] + r0), int(cc[i] + c0)

    def _plan_blocked(self) -> bool:
        """True when a remaining plan point lies in the lethal zone of an obstacle."""
        grid = self._map
        if grid is None or len(self._plan_xy) < 2:
            return False
        pts = self._plan_xy[self._plan_index + 1:]
        if len(pts) == 0:
            return False
        rows, cols = grid.world_to_cells(pts[:, 0], pts[:, 1])
        ok = (rows >= 0) & (rows < grid.height) & (cols >= 0) & (cols < grid.width)
        if not ok.all():
            return True  # the map moved under the plan: replan
        rad = int(math.ceil(self.params.lethal_radius_m / grid.resolution_m))
        r0, r1 = max(0, int(rows.min()) - rad), min(grid.height, int(rows.max()) + rad + 1)
        c0, c1 = max(0, int(cols.min()) - rad), min(grid.width, int(cols.max()) + rad + 1)
        blocked, _ = self._obstacles(grid, (r0, r1, c0, c1))
        if not blocked.any():
            return False
        k = metres_to_cells(self.params.lethal_radius_m, grid.resolution_m)
        if k > _DISK_LOOKUP_MAX_CELLS:
            lethal = inflate(blocked, self.params.lethal_radius_m, grid.resolution_m)
            return bool(lethal[rows - r0, cols - c0].any())
        # inflate(blocked)[plan cells] without inflating the window: a plan cell is lethal
        # when a blocked cell of the window lies in the disk of inflate's radius around it.
        h, w = blocked.shape
        flat = np.unique((rows - r0) * w + (cols - c0))
        dr, dc = _disk_offsets(self.params.lethal_radius_m / grid.resolution_m)
        rr = (flat // w)[:, None] + dr[None, :]
        cc = (flat % w)[:, None] + dc[None, :]
        ok = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
        return bool(blocked[rr[ok], cc[ok]].any())

    # ------------------------------------------------------------- following
    def control(self, pose: tuple[float, float, float], now_s: float) -> tuple[float, float]:
        """The command at ``now_s`` (called every physics step): :meth:`update`'s at
        ``controller_rate_hz`` (at every call with 0), the last one held in between, as
        Nav2's controller server runs at its ``controller_frequency`` under a faster
        physics step. A new goal or a collision drops the held command."""
        rate = self.params.controller_rate_hz
        if rate <= 0:
            return self.update(pose, now_s)
        if now_s >= self._next_control_s - 1e-9:
            period = 1.0 / rate
            self._next_control_s += period
            if self._next_control_s <= now_s:     # after an idle spell: no burst of calls
                self._next_control_s = now_s + period
            self._held = self.update(pose, now_s)
        return self._held

    def update(self, pose: tuple[float, float, float], now_s: float
               ) -> tuple[float, float]:
        """Advance the state machine; returns the command (v m/s, w rad/s)."""
        st = self._status
        if st.state is not NavState.ACTIVE or st.goal is None:
            return 0.0, 0.0
        p = self.params
        gx, gy, gyaw = st.goal
        x, y, yaw = pose
        if p.goal_timeout_s and now_s - self._goal_start_s > p.goal_timeout_s:
            self._finish(NavState.ABORTED, f"timeout after {p.goal_timeout_s:.0f} s")
            return 0.0, 0.0
        # Like Nav2's controller, success is judged at the end of the plan, which differs
        # from the goal when the planner moved a blocked goal within its tolerance.
        tx, ty = self._target_xy if self._target_xy is not None else (gx, gy)
        if math.hypot(tx - x, ty - y) <= p.goal_tolerance_xy_m or self._final_turn:
            self._final_turn = True
            err = wrap_angle(gyaw - yaw)
            if abs(err) <= p.goal_tolerance_yaw_rad:
                self._finish(NavState.SUCCEEDED, "")
                return 0.0, 0.0
            return 0.0, clip_magnitude(p.heading_gain * err, p.max_angular_speed_radps)
        # Progress checker.
        if math.hypot(x - self._progress_xy[0], y - self._progress_xy[1]) >= p.progress_radius_m:
            self._progress_xy, self._progress_s = (x, y), now_s
        elif p.progress_timeout_s and now_s - self._progress_s > p.progress_timeout_s:
            self._finish(NavState.ABORTED, f"no progress for {p.progress_timeout_s:.0f} s")
            return 0.0, 0.0
        # Replanning: when the plan got blocked, else periodically while the map changes.
        if (not self._need_plan and len(self._plan_xy)
                and now_s - self._last_check_s >= p.blocked_check_period_s):
            self._last_check_s = now_s
            if self._planned_key != self._content_key() and self._plan_blocked():
                self._plan_xy = np.zeros((0, 2))
                self._plan_version += 1
                self._need_plan = True
        if (self._need_plan or len(self._plan_xy) == 0
                or (self._planned_key != self._content_key()
                    and now_s - self._last_plan_s >= p.replan_period_s)):
            self._need_plan = False
            if not self._plan(pose, now_s):
                return 0.0, 0.0
        assert self._target_xy is not None
        return self._pursue(pose, math.hypot(self._target_xy[0] - x, self._target_xy[1] - y))
