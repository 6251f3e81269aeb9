"""Revisit goals: drive back along the robot's own path so that the SLAM can close a loop.

A SLAM map drifts between loop closures. Where the robot mapped a place twice at poses
that drifted apart, the second copy of a wall can lie across a passage it drove through:
the map then shows the frontiers beyond without a path, although the way is open. Looks
and turns at the passage do not clear such a wall (many keyframes confirmed it); a loop
closure does, when the SLAM optimises its pose graph and re-renders the map from the
corrected poses. A SLAM closes loops where the robot comes back to a place it mapped
long enough ago: slam_toolbox searches for loop candidates within
``loop_search_maximum_distance`` (3 m) among scans outside its running buffer
(``scan_buffer_maximum_scan_distance``, 10 m of travel).

When exploration would end (the goal manager's DONE, after its waits, turn looks and
blacklist retries: :attr:`~explore_seg.core.selection.goals.GoalManager.before_done`)
while frontiers without a path remain, and the map has been corrected at least once (the
SLAM closes loops, so its map drifts), :class:`Revisits` starts a **revisit**: a place
on the robot's path recorded at least ``revisit_min_travel_m`` of travel ago that the
robot reaches on the map now. Among the places within ``revisit_max_path_m`` of path the
oldest wins (the older the place, the more the drift there differs from now, the more a
closure corrects); with none that close, the nearest. At the next decisions the frontiers
without a path are returned with their cPoint moved there (:meth:`Revisits.goals`), so the
goal manager sends, judges (arrival, then "frontier still there?") and blacklists the
revisit as any other goal. Once it is over (blacklisted, or the navigator aborted it) the
goal manager's sequence runs again from there (waits, turn looks at the revisited place),
and the next revisit lies at least ``revisit_spacing_m`` from the earlier ones. After
``revisit_goals`` revisits without a selectable frontier exploration ends as before; a
selectable frontier starts the count anew. A map from a SLAM that has not corrected it,
or from the true poses, gets no revisits: a closure could not move its walls, and runs on
such maps are the same with revisits on or off.

Examples
--------
>>> import numpy as np
>>> from explore_seg.core.block_graph import BlockGraph
>>> from explore_seg.core.frontiers import Frontier
>>> from explore_seg.core.grid import GridMap
>>> from explore_seg.core.selection.lookout import Reach
>>> from explore_seg.core.selection.params import SelectionParams
>>> data = np.full((40, 200), 100, dtype=np.int8)  # 10 x 2 m at 0.05 m
>>> data[5:35, 5:195] = 0                            # a long room
>>> g = GridMap(data, 0.05, (0.0, 0.0))
>>> passable = np.zeros(data.shape, bool); passable[10:30, 10:190] = True
>>> reach = Reach(BlockGraph(passable, 0.05, 1), (20, 180), passable)
>>> r = Revisits()
>>> for x in np.arange(1.0, 9.01, 0.5):             # drove there and back: 16 m
...     r.add(float(x), 1.0)
>>> for x in np.arange(8.5, 0.99, -0.5):
...     r.add(float(x), 1.0)
>>> f = Frontier(1, 3, 0.15, (38, 100), g.cell_to_world(38, 100), False, (38.0, 100.0),
...              g.cell_to_world(38, 100), np.array([[38, 99], [38, 100], [38, 101]]))
>>> p = SelectionParams(revisit_min_travel_m=10.0, revisit_max_path_m=20.0)
>>> r.goals(g, [f], np.array([np.inf]), reach, np.array([False]), (), p) is None
True
>>> r.arm()                                       # no correction yet: nothing to start
False
>>> r.corrected()                                 # a loop closure re-rendered the map
>>> r.goals(g, [f], np.array([np.inf]), reach, np.array([False]), (), p) is None
True
>>> r.arm()                                       # instead of DONE
True
>>> out, d = r.goals(g, [f], np.array([np.inf]), reach, np.array([False]), (), p)
>>> out[0].point_xy_m, round(float(d[0]), 2)     # the oldest place within 20 m of path
((1.0, 1.0), 8.0)
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Callable, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier
from explore_seg.core.grid import GridMap
from explore_seg.core.selection.blacklist import near_any
from explore_seg.core.selection.lookout import Reach
from explore_seg.core.selection.params import SelectionParams

#: Consecutive positions farther apart than this are a pose jump (a correction, a
#: relocalisation), not travel.
MAX_STEP_M = 2.0


class Revisits:
    """The robot's path with the travel at each place, and the revisits of one stuck spell.

    Parameters
    ----------
    spacing_m : float
        A place is kept when the robot moved at least this far from the last kept one.
    max_points : int
        When reached, every second place is dropped (and the spacing doubled), so memory
        stays bounded on long runs.

    Raises
    ------
    ValueError
        On a spacing that is not finite and > 0, or ``max_points < 2``.
    """

    def __init__(self, spacing_m: float = 0.5, max_points: int = 4000) -> None:
        if not (math.isfinite(spacing_m) and spacing_m > 0):
            raise ValueError(f"spacing_m must be finite and > 0, got {spacing_m}")
        if max_points < 2:
            raise ValueError(f"max_points must be >= 2, got {max_points}")
        self.spacing_m = self._spacing0_m = float(spacing_m)
        self.max_points = int(max_points)
        self._places: list[tuple[float, float, float]] = []   # x, y, travel at the place
        self._last: tuple[float, float] | None = None
        self._travel_m = 0.0
        self._corrections = 0
        self._targets: list[tuple[float, float]] = []   # the revisits of this spell
        self._armed = False     # the last target is the revisit under way
        # the next revisit found at this decision: (cell, place, path length)
        self._pending: tuple[tuple[int, int], tuple[float, float], float] | None = None

    def __len__(self) -> int:
        return len(self._places)

    @property
    def travel_m(self) -> float:
        """Distance travelled, summed over the positions given (pose jumps left out)."""
        return self._travel_m

    @property
    def under_way(self) -> bool:
        """A revisit was started (:meth:`arm`) and is not over yet."""
        return self._armed

    @property
    def targets(self) -> tuple[tuple[float, float], ...]:
        """The revisits of the current stuck spell, oldest first."""
        return tuple(self._targets)

    def add(self, x_m: float, y_m: float) -> None:
        """Record a robot position (map frame) at a new decision; non-finite positions are
        ignored."""
        self._pending = None
        if not (math.isfinite(x_m) and math.isfinite(y_m)):
            return
        if self._last is not None:
            step = math.hypot(x_m - self._last[0], y_m - self._last[1])
            if step <= MAX_STEP_M:
                self._travel_m += step
        self._last = (float(x_m), float(y_m))
        if self._places:
            lx, ly, _ = self._places[-1]
            if math.hypot(x_m - lx, y_m - ly) < self.spacing_m:
                return
        self._places.append((float(x_m), float(y_m), self._travel_m))
        if len(self._places) >= self.max_points:
            self._places = self._places[::2] + ([self._places[-1]]
                                                 if len(self._places) % 2 == 0 else [])
            self.spacing_m *= 2.0

    def corrected(self) -> None:
        """The SLAM corrected the map (a loop closure re-rendered it): revisits are on."""
        self._corrections += 1

    def active(self, params: SelectionParams) -> bool:
        """Revisits are on: ``revisit_goals`` > 0 and the map was corrected."""
        return params.revisit_goals > 0 and self._corrections > 0

    def arm(self) -> bool:
        """Exploration would end (the goal manager's ``before_done``): start the revisit
        that :meth:`goals` found at this decision; False when there is none."""
        if self._pending is None:
            return False
        self._targets.append(self._pending[1])
        self._armed, self._pending = True, None
        return True

    def progress(self) -> None:
        """A frontier is selectable: the next stuck spell counts its revisits anew."""
        self._targets.clear()
        self._armed, self._pending = False, None

    def reset(self) -> None:
        """Forget the path, the travel, the corrections and the revisits (a new session)."""
        self._places.clear()
        self.spacing_m = self._spacing0_m
        self._last = None
        self._travel_m = 0.0
        self._corrections = 0
        self.progress()

    def goals(self, grid: GridMap, frontiers: Sequence[Frontier],
              dist_m: npt.NDArray[np.float64], reach: Reach,
              excluded: npt.NDArray[np.bool_], blacklist: Sequence[tuple[float, float]],
              params: SelectionParams,
              aborted: Callable[[tuple[float, float]], bool] | None = None
              ) -> tuple[list[Frontier], npt.NDArray[np.float64]] | None:
        """The frontiers without a path (and not ``excluded``) with their cPoint at the
        revisit under way (module docstring), the others unchanged; None when none is
        under way (then the next revisit, if any, is found for :meth:`arm`).

        Parameters
        ----------
        grid : GridMap
        frontiers : sequence of Frontier
        dist_m : ndarray of float64, shape (N,)
            Path lengths robot -> cPoints (inf: no path).
        reach : Reach
            The graph, start cell and passable cells the distances were computed on.
        excluded : ndarray of bool, shape (N,)
            Blacklisted frontiers (left as they are).
        blacklist : sequence of (x_m, y_m)
            The blacklisted goals: a revisit within ``blacklist_radius_m`` of one is over.
        params : SelectionParams
            ``revisit_goals``, ``revisit_min_travel_m``, ``revisit_max_path_m``,
            ``revisit_spacing_m``, ``blacklist_radius_m``.
        aborted : callable, optional
            True for a place where the navigator aborted a goal the map had no path to
            either (:meth:`~explore_seg.core.selection.goals.GoalManager.aborted_near`):
            a revisit there is over too.

        Returns
        -------
        (list of Frontier, ndarray of float64) or None
            Same order; the moved frontiers have ``point_passable`` True and the path
            length to the revisit.
        """
        out = list(frontiers)
        d_out = np.asarray(dist_m, dtype=np.float64).copy()
        todo = [i for i in range(len(out)) if not np.isfinite(d_out[i]) and not excluded[i]]
        if not self.active(params) or not todo:
            return None
        target = self._current(grid, reach, blacklist, params, aborted)
        if target is None:
            self._armed = False
            if len(self._targets) < params.revisit_goals:
                self._pending = self._next(grid, reach, blacklist, params)
            return None
        rc, xy, d = target
        for i in todo:
            out[i] = replace(out[i], point_rc=rc, point_xy_m=xy, point_passable=True)
            d_out[i] = d
        return out, d_out

    def _current(self, grid: GridMap, reach: Reach, blacklist: Sequence[tuple[float, float]],
                 params: SelectionParams,
                 aborted: Callable[[tuple[float, float]], bool] | None
                 ) -> tuple[tuple[int, int], tuple[float, float], float] | None:
        """The revisit under way while it is not over (blacklisted, aborted, no path)."""
        if not self._armed or not self._targets:
            return None
        xy = self._targets[-1]
        if (near_any([xy], blacklist, params.blacklist_radius_m)[0]
                or (aborted is not None and aborted(xy))):
            return None
        found = self._reachable(grid, reach, np.asarray([xy]))
        return (None if found is None
                else ((int(found[0][0, 0]), int(found[0][0, 1])), xy, float(found[1][0])))

    def _next(self, grid: GridMap, reach: Reach, blacklist: Sequence[tuple[float, float]],
              params: SelectionParams
              ) -> tuple[tuple[int, int], tuple[float, float], float] | None:
        """The next revisit (module docstring; not near a blacklisted goal); None when no
        place qualifies."""
        places = np.asarray(self._places, dtype=np.float64).reshape(-1, 3)
        old = places[self._travel_m - places[:, 2] >= params.revisit_min_travel_m, :2]
        # at least revisit_spacing_m from every earlier revisit (closer ones are out)
        closer = float(np.nextafter(params.revisit_spacing_m, 0.0))
        old = old[~near_any(old, self._targets, closer)
                  & ~near_any(old, blacklist, params.blacklist_radius_m)]
        if not len(old):
            return None
        found = self._reachable(grid, reach, old)
        if found is None:
            return None
        cells, d, keep = found
        # ``old`` is oldest first: the oldest within the path budget, else the nearest
        near = np.flatnonzero(d <= params.revisit_max_path_m)
        k = int(near[0]) if len(near) else int(np.argmin(d))
        xy = old[int(keep[k])]
        return (int(cells[k, 0]), int(cells[k, 1])), (float(xy[0]), float(xy[1])), float(d[k])

    @staticmethod
    def _reachable(grid: GridMap, reach: Reach, xy: npt.NDArray[np.float64]
                   ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64],
                              npt.NDArray[np.int64]] | None:
        """The places of ``xy`` on passable cells with a path: their cells, path lengths
        and indices into ``xy``; None when there is none."""
        rc = np.column_stack(grid.world_to_cells(xy[:, 0], xy[:, 1]))
        h, w = reach.passable.shape
        inside = (rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < w)
        idx = np.flatnonzero(inside)
        idx = idx[reach.passable[rc[idx, 0], rc[idx, 1]]]
        if not len(idx):
            return None
        d = reach.graph.distances(reach.start_rc, rc[idx]) + reach.hop_m
        ok = np.isfinite(d)
        if not ok.any():
            return None
        return rc[idx[ok]], d[ok], idx[ok]


__all__ = ["MAX_STEP_M", "Revisits"]
