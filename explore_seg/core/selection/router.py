"""The ``routed`` strategy's planning: viewpoints, then a global tour over them.

Per decision (:class:`Router`, driven by :class:`~explore_seg.core.explorer.Explorer`):

0. **Parts.** The explorer splits every frontier group longer than ``frontier_split_m``
   along its main axis into parts (:func:`~explore_seg.core.frontiers.split_frontiers`,
   FUEL's cluster split), once per map version. One viewpoint for a whole corridor side
   jumps between its ends as the map grows; each part is a tour stop instead.
   See docs/experiments.md#routed-frontier-split.
1. **Viewpoints** (:meth:`Router.viewpoints`). Every group gets a viewpoint
   (:mod:`.viewpoints`): among the reachable candidates (a lattice of ``viewpoint_step_m``
   within ``viewpoint_radius_m`` of its cells) whose 360-degree view of ``sensor_range_m``
   (``gain_rays`` rays) sees at least ``1 - viewpoint_gain_tolerance`` of the best unknown
   area, the one closest to the robot. The groups come back with their cPoint replaced by
   the viewpoint, so the goal manager sends, keeps, judges and blacklists viewpoints exactly
   as it does cPoints.
   Gains are kept per coarse cell across map versions (:class:`~.viewpoints.GainCache`).
   A group that only unreachable candidates see, and whose own cPoint has no path, keeps
   its cPoint (``blocked_views_unreachable``): it lies behind a blockage, and counts as
   unreachable rather than as a group with nothing to see.
2. **Selectable groups.** A group is in the tour when its viewpoint is reachable, not
   blacklisted and sees at least ``min_gain_m2`` (exploration ends rather than chasing
   frontier specks that reveal nothing).
3. **Leftovers.** A viewpoint that sees less than ``leftover_gain_m2`` is a leftover: it
   stays out of the tour while any viewpoint that sees more remains, and is toured once
   only leftovers are left (small corners often vanish as the robot passes them; they do
   not bend the tour). A group with ``leftover_max_length_m`` of frontier or more is never
   a leftover: at the map's edge, where max-range beams ended in the open, the view is cut
   short by the edge, not by walls. See docs/experiments.md#routed-leftover-gain and
   docs/experiments.md#routed-leftover-length.
4. **Tour** (:meth:`Router.tour_costs`, :mod:`.tour`). An open tour from the robot over
   the selectable viewpoints (greedy, 2-opt, Or-opt). Edge costs, in metres:

   * robot -> viewpoint: the path length the caller measured (``dist_m``);
   * viewpoint -> viewpoint: path lengths on the block graph the core already builds
     (:class:`~.pair_paths.PairPaths` keeps them across decisions and sweeps from new
     viewpoints and the ``tour_refresh_rows`` oldest); where only a path through unknown
     space exists, the straight line times ``unknown_path_factor``;
   * ``region_switch_m`` more for an edge between two different DuDe regions (or from the
     robot's region into another), so a tour finishes a region before it leaves unless
     what is left there is a longer detour.
     See docs/experiments.md#routed-region-switch.

5. **Costs.** A group's cost is the length of the tour when its viewpoint is visited next
   (the tour's first: the tour's length; the current goal's group: the best tour that
   starts with it; any other: the tour with it moved to the front) minus
   ``gain_weight_m_per_m2`` times its view's unknown area (big views first when the
   detour is small). See docs/experiments.md#routed-gain-weight.
6. **Goal.** The goal manager's hysteresis becomes a tour hysteresis: the goal changes only
   when a tour shorter by ``hysteresis_margin`` of the current goal's exists (or the goal's
   frontier is gone), so goals do not flip on small map changes. A goal within
   ``handover_m`` counts as reached, so the next one is sent while the robot still drives.
   See docs/experiments.md#routed-handover.

The measurements behind these rules, and the alternatives compared with them, are in
docs/experiments.md#selection-routed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Protocol, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.selection.distances import PathGraphs
from explore_seg.core.selection.pair_paths import PairPaths
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.regions import frontier_regions, region_at
from explore_seg.core.selection.tour import front_costs, solve_tour
from explore_seg.core.selection.viewpoints import GainCache, candidate_cells, pick_viewpoint


class GainSource(Protocol):
    """What rates viewpoint candidates: :class:`~.viewpoints.GainCache` is one."""

    def gains(self, grid: GridMap, cells_rc: npt.ArrayLike) -> npt.NDArray[np.float64]: ...

    def reset(self) -> None: ...


@dataclass(frozen=True)
class TourPlan:
    """The tour of one decision (for markers, traces and tests).

    Attributes
    ----------
    tour_cost_m : ndarray of float64, shape (N,)
        Per group: length of the tour when its viewpoint is visited next, minus
        ``gain_weight_m_per_m2`` times its gain (inf: not in the tour: unreachable,
        excluded, no passable viewpoint or a gain below ``min_gain_m2``).
    order : ndarray of int64
        Group indices in tour order.
    length_m : float
        Length of the best tour.
    regions : ndarray of int64, shape (N,)
        Region of each viewpoint (zeros without labels).
    robot_region : int
    gain_m2 : ndarray of float64, shape (N,)
        Unknown area seen from each viewpoint (zeros where none was computed).
    swept : int
        Viewpoints whose path lengths to the others were swept in this decision (the rest
        were kept: :class:`~.pair_paths.PairPaths`).
    """

    tour_cost_m: npt.NDArray[np.float64] = field(repr=False)
    order: npt.NDArray[np.int64]
    length_m: float
    regions: npt.NDArray[np.int64] = field(repr=False)
    robot_region: int
    gain_m2: npt.NDArray[np.float64] = field(repr=False, default_factory=lambda: np.zeros(0))
    swept: int = 0


class Router:
    """Viewpoints and tours of the ``routed`` strategy (see the module docstring).

    Parameters
    ----------
    frontier_params : FrontierParams
        ``occupied_threshold`` for the ray casting.
    params : SelectionParams
        The ``routed`` fields (sensor range, rays, viewpoint radius and step, region
        penalty) and ``region_search_radius_m``, ``unknown_path_factor``.
    gains : GainSource, optional
        Rates the viewpoint candidates (``gains(grid, cells_rc) -> m^2``, ``reset()``);
        default a :class:`~.viewpoints.GainCache` of the unknown area in view (another
        strategy's planner passes its own, as ``foresight`` does with the predicted plan).
    """

    def __init__(self, frontier_params: FrontierParams, params: SelectionParams,
                 gains: GainSource | None = None) -> None:
        self._frontier_params = frontier_params
        self._p = params
        self._gains_kept: GainSource = gains if gains is not None else GainCache(
            params.sensor_range_m, params.gain_rays, frontier_params.occupied_threshold)
        self._pairs = PairPaths(params.tour_refresh_rows)
        #: Gain (m^2) of each group's viewpoint in the last :meth:`viewpoints` call.
        self.gain_m2: npt.NDArray[np.float64] = np.zeros(0)
        #: Wall seconds of the last :meth:`viewpoints` and :meth:`tour_costs` calls.
        self.viewpoint_s = 0.0
        self.tour_s = 0.0

    def reset(self) -> None:
        """Forget the kept gains and path lengths (a new map)."""
        self._gains_kept.reset()
        self._pairs.reset()

    def viewpoints(self, grid: GridMap, frontiers: Sequence[Frontier],
                   graphs: PathGraphs, start_rc: tuple[int, int] | None,
                   passable: npt.NDArray[np.bool_]) -> list[Frontier]:
        """The groups with their cPoint moved to their viewpoint.

        Parameters
        ----------
        grid : GridMap
        frontiers : sequence of Frontier
        graphs : PathGraphs
            Path graphs of this map version (reachability and distances from the robot).
        start_rc : (int, int) or None
            The robot's passable start cell (None: distances unknown, cPoints kept).
        passable : ndarray of bool, shape (H, W)
            Passable cells (viewpoint candidates).

        Returns
        -------
        list of Frontier
            Same order and cells; ``point_rc``/``point_xy_m`` at the viewpoint,
            ``point_passable`` True where a reachable viewpoint was found (else the group
            is unchanged).
        """
        t0 = time.perf_counter()
        p = self._p
        res = grid.resolution_m
        n = len(frontiers)
        self.gain_m2 = np.zeros(n)
        if n == 0 or start_rc is None:
            self.viewpoint_s = time.perf_counter() - t0
            return list(frontiers)
        radius = metres_to_cells(p.viewpoint_radius_m, res)
        step = max(1, metres_to_cells(p.viewpoint_step_m, res))
        cands = [candidate_cells(f.cells, f.point_rc, passable, radius, step)
                 for f in frontiers]
        counts = np.asarray([len(c) for c in cands])
        allc = np.concatenate(cands)
        dist = graphs.graph.distances(start_rc, allc)
        gain = self._gains_kept.gains(grid, allc)
        out: list[Frontier] = []
        bounds = np.concatenate([[0], np.cumsum(counts)])
        for i, f in enumerate(frontiers):
            a, b = int(bounds[i]), int(bounds[i + 1])
            # The cPoint (first candidate) competes only when it is passable.
            d = dist[a:b].copy()
            if not f.point_passable:
                d[0] = np.inf
            k = pick_viewpoint(gain[a:b], d, p.viewpoint_gain_tolerance)
            if k is None or (p.blocked_views_unreachable
                             and _seen_only_from_beyond(gain[a:b], d, k, p.min_gain_m2)):
                # No reachable candidate (reachable through unknown space at most), or
                # none that sees anything where unreachable ones do: keep the cPoint,
                # rated by the best view near the group.
                self.gain_m2[i] = float(gain[a:b].max())
                out.append(f)
                continue
            self.gain_m2[i] = gain[a + k]
            r, c = int(allc[a + k, 0]), int(allc[a + k, 1])
            if (r, c) == tuple(f.point_rc) and f.point_passable:
                out.append(f)
                continue
            out.append(replace(f, point_rc=(r, c), point_xy_m=grid.cell_to_world(r, c),
                               point_passable=True))
        self.viewpoint_s = time.perf_counter() - t0
        return out

    def tour_costs(self, grid: GridMap, frontiers: Sequence[Frontier],
                   dist_m: npt.NDArray[np.float64], excluded: npt.NDArray[np.bool_] | None,
                   graphs: PathGraphs, robot_rc: tuple[int, int],
                   labels: npt.NDArray[np.integer] | None, goal_index: int | None
                   ) -> TourPlan:
        """Tour over the selectable viewpoints and each group's cost (module docstring).

        Parameters
        ----------
        grid : GridMap
        frontiers : sequence of Frontier
            Groups at their viewpoints (:meth:`viewpoints`).
        dist_m : ndarray of float64, shape (N,)
            Path length robot -> viewpoint (inf: unreachable).
        excluded : ndarray of bool, shape (N,) or None
            Blacklisted groups (left out of the tour).
        graphs : PathGraphs
        robot_rc : (int, int)
        labels : ndarray of int, shape (H, W), or None
            Region labels (None or ``use_regions`` False: no region penalty).
        goal_index : int or None
            The current goal's group (its tour is solved with it first).

        Returns
        -------
        TourPlan
        """
        t0 = time.perf_counter()
        p = self._p
        n = len(frontiers)
        cost_out = np.full(n, np.inf)
        use = labels if (p.use_regions and labels is not None) else None
        rad = metres_to_cells(p.region_search_radius_m, grid.resolution_m)
        regions = frontier_regions(frontiers, use, rad)
        robot_region = region_at(use, robot_rc, rad) if use is not None else 0
        # The last viewpoints' gains, when they belong to these groups.
        have_gains = len(self.gain_m2) == n
        gains = self.gain_m2.copy() if have_gains else np.zeros(n)
        sel = self._selectable(frontiers, dist_m, excluded, gains if have_gains else None)
        idx = np.flatnonzero(sel)
        if idx.size == 0:
            self.tour_s = time.perf_counter() - t0
            return TourPlan(cost_out, idx.astype(np.int64), 0.0, regions, robot_region, gains)
        node_regions = (np.concatenate([[robot_region], regions[idx]])
                        if p.region_switch_m > 0 and use is not None else None)
        cost = self._cost_matrix(grid, frontiers, dist_m, idx, graphs, node_regions)
        front, order, best_len = self._tour(cost, idx, sel, goal_index)
        cost_out[idx] = front[1:] - p.gain_weight_m_per_m2 * gains[idx]
        self.tour_s = time.perf_counter() - t0
        return TourPlan(cost_out, idx[order - 1].astype(np.int64), float(best_len), regions,
                        robot_region, gains, self._pairs.swept)

    def selectable(self, frontiers: Sequence[Frontier], dist_m: npt.NDArray[np.float64],
                   excluded: npt.NDArray[np.bool_] | None) -> npt.NDArray[np.bool_]:
        """The groups :meth:`tour_costs` would visit now (with the last viewpoints' gains
        when they belong to ``frontiers``), shape (N,)."""
        have_gains = len(self.gain_m2) == len(frontiers)
        return self._selectable(frontiers, dist_m, excluded,
                                self.gain_m2 if have_gains else None)

    def _selectable(self, frontiers: Sequence[Frontier], dist_m: npt.NDArray[np.float64],
                    excluded: npt.NDArray[np.bool_] | None,
                    gains: npt.NDArray[np.float64] | None) -> npt.NDArray[np.bool_]:
        """The groups the tour visits: reachable at a passable viewpoint, not excluded,
        with at least ``min_gain_m2`` of view; leftovers (small views) only while no
        bigger one remains. ``gains`` None: the viewpoints' gains are unknown (not used).
        """
        p = self._p
        sel = np.isfinite(np.asarray(dist_m, dtype=np.float64))
        sel &= np.asarray([f.point_passable for f in frontiers], dtype=bool)
        if gains is not None:
            sel &= gains >= p.min_gain_m2
        if excluded is not None:
            sel &= ~np.asarray(excluded, dtype=bool)
        if gains is not None:
            # Leftovers last: small views wait while a bigger one remains.
            big = gains >= p.leftover_gain_m2
            if p.leftover_max_length_m > 0:
                big |= np.asarray([f.length_m for f in frontiers]) >= p.leftover_max_length_m
            big &= sel
            if big.any():
                sel = big
        return sel

    def _cost_matrix(self, grid: GridMap, frontiers: Sequence[Frontier],
                     dist_m: npt.NDArray[np.float64], idx: npt.NDArray[np.int64],
                     graphs: PathGraphs, node_regions: npt.NDArray[np.int64] | None
                     ) -> npt.NDArray[np.float64]:
        """Open-tour cost matrix over node 0 (the robot) and the groups ``idx``: path
        lengths (straight line x ``unknown_path_factor`` where only unknown space links
        two viewpoints), plus ``region_switch_m`` between different regions
        (``node_regions``: per node, None = no penalty); returning to node 0 is free."""
        p = self._p
        pts = np.asarray([frontiers[i].point_rc for i in idx], dtype=np.int64)
        m = idx.size + 1
        cost = np.zeros((m, m))
        cost[0, 1:] = np.asarray(dist_m, dtype=np.float64)[idx]
        pair = self._pairs.matrix(graphs.graph, grid, pts)
        bad = ~np.isfinite(pair)
        if bad.any():
            # Reachable from the robot only through unknown space (fallback distances):
            # straight line times the unknown-space factor.
            xy = pts.astype(np.float64) * grid.resolution_m
            straight = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
            pair = np.where(bad, straight * p.unknown_path_factor, pair)
        cost[1:, 1:] = pair
        if node_regions is not None:
            reg = node_regions
            differ = (reg[:, None] > 0) & (reg[None, :] > 0) & (reg[:, None] != reg[None, :])
            cost += np.where(differ, p.region_switch_m, 0.0)
        cost[:, 0] = 0.0
        np.fill_diagonal(cost, 0.0)
        return cost

    @staticmethod
    def _tour(cost: npt.NDArray[np.float64], idx: npt.NDArray[np.int64],
              sel: npt.NDArray[np.bool_], goal_index: int | None
              ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], float]:
        """Solve the tour: (each node's cost of the best tour that visits it first, the
        tour's node order, its length); the current goal's group (``goal_index``, when
        selectable) gets its own tour solved with it first."""
        tour = solve_tour(cost)
        front = front_costs(cost, tour)
        best_len, order = tour.length_m, tour.order
        if goal_index is not None and sel[goal_index]:
            node = int(np.flatnonzero(idx == goal_index)[0]) + 1
            if node != int(tour.order[0]):
                own = solve_tour(cost, first=node)
                front[node] = min(front[node], own.length_m)
                if own.length_m < best_len:
                    best_len, order = own.length_m, own.order
        return front, order, best_len


def _seen_only_from_beyond(gain_m2: npt.NDArray[np.float64], dist_m: npt.NDArray[np.float64],
                           k: int, min_gain_m2: float) -> bool:
    """True when the picked reachable candidate ``k`` sees less than ``min_gain_m2`` while
    an unreachable one sees at least that, and the cPoint (candidate 0) is unreachable:
    the group lies behind a blockage (a doorway that drift shut in the map). A viewpoint
    on the near side would see nothing, so the group would quietly drop out of the tour;
    with its own unreachable cPoint it counts as unreachable, and the explorer looks for
    a way to it (lookouts, approach goals, turn looks) before exploration ends."""
    if gain_m2[k] >= min_gain_m2 or np.isfinite(dist_m[0]):
        return False
    return bool((~np.isfinite(dist_m) & (gain_m2 >= min_gain_m2)).any())


__all__ = ["GainSource", "Router", "TourPlan"]
