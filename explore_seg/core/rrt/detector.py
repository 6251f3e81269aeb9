"""Frontier points from RRTs, filtered into goal candidates: rrt_exploration's detectors
and filter (Umari & Mukhopadhyay, IROS 2017) in one stateful, seeded object.

Per :meth:`RrtFrontierDetector.update` (one decision):

1. **Detectors**: a *global* tree rooted at the first robot position (never reset,
   ``global_eta_m``) and a *local* tree (``local_eta_m``, re-rooted at the robot after each
   frontier point it finds) are extended ``iterations_per_step`` times each, toward
   uniform samples over the current map (:mod:`.tree`). An edge that reaches unknown space
   before any obstacle yields a frontier point: where it entered unknown space.
2. **Filter**: the kept points of the previous decision plus the new ones are clustered
   by mean shift (``cluster_bandwidth_m``, :mod:`.mean_shift`); the cluster centres
   replace the points. A centre is dropped when it lies on a known cell that is not
   passable (an obstacle or within the robot radius of one: the original tests the
   navigation costmap) or when the unknown area within ``info_radius_m / 2`` is below
   ``min_info_gain_m2`` (explored).
3. **Candidates**: one :class:`~explore_seg.core.frontiers.Frontier` per centre that still
   has unknown cells within ``info_radius_m``: its ``cells`` are those unknown cells,
   ``info_gain_m2`` their area (the assigner's information gain), ``centroid`` the
   centre and the cPoint the nearest passable cell in line of sight within
   ``FrontierParams.cpoint_search_radius_m`` (the goal is sent there, not into unknown
   space; without one it is no goal).

Differences from the ROS package: samples cover the whole current map (the original
samples a rectangle the user clicks); dropped centres are forgotten (the original keeps
them among the points it clusters, and drops them again after each clustering); the
trees grow per decision instead of at their own 100 Hz.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams, passable_in_sight
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.rrt.info_gain import unknown_within
from explore_seg.core.rrt.mean_shift import mean_shift
from explore_seg.core.rrt.params import RrtParams
from explore_seg.core.rrt.tree import UNKNOWN, CellClasses, RrtTree

#: Second word of the random generator's seed (keeps it apart from other seeded streams).
_STREAM = 0x525254


class RrtFrontierDetector:
    """Global + local RRT frontier detection and filtering (see the module docstring).

    Parameters
    ----------
    params : RrtParams
    frontier : FrontierParams
        Thresholds and the cPoint search radius.
    """

    def __init__(self, params: RrtParams = RrtParams(),
                 frontier: FrontierParams = FrontierParams()) -> None:
        self.params = params
        self._frontier_params = frontier
        self._rng = np.random.default_rng([params.seed, _STREAM])
        self._global: RrtTree | None = None
        self._local: RrtTree | None = None
        self._points = np.zeros((0, 2))
        self._cells: CellClasses | None = None
        self._cells_key: tuple[object, object] | None = None
        #: Frontier points the trees found so far.
        self.points_found = 0

    @property
    def points(self) -> npt.NDArray[np.float64]:
        """The filtered cluster centres (world m), shape (N, 2)."""
        return self._points.copy()

    @property
    def trees(self) -> tuple[RrtTree | None, RrtTree | None]:
        """(global, local) trees (None before the first update)."""
        return self._global, self._local

    def _classes(self, grid: GridMap, extra: npt.NDArray[np.bool_] | None) -> CellClasses:
        if self._cells is None or self._cells_key is None or self._cells_key[0] is not grid \
                or self._cells_key[1] is not extra:
            self._cells = CellClasses.from_grid(grid, self._frontier_params.occupied_threshold,
                                                extra)
            self._cells_key = (grid, extra)
        return self._cells

    def grow(self, grid: GridMap, robot_xy_m: tuple[float, float],
             extra_obstacles: npt.NDArray[np.bool_] | None = None
             ) -> npt.NDArray[np.float64]:
        """Extend both trees ``iterations_per_step`` times; the new frontier points (N, 2)."""
        p = self.params
        robot = (float(robot_xy_m[0]), float(robot_xy_m[1]))
        if self._global is None or self._local is None:
            self._global = RrtTree(robot, p.global_eta_m)
            self._local = RrtTree(robot, p.local_eta_m)
        cells = self._classes(grid, extra_obstacles)
        u = self._rng.random((p.iterations_per_step, 2, 2))
        sx, sy = grid.cells_to_world(u[..., 0] * grid.height - 0.5,
                                     u[..., 1] * grid.width - 0.5)
        found: list[tuple[float, float]] = []
        for k in range(p.iterations_per_step):
            for j, tree in enumerate((self._global, self._local)):
                status, point = tree.extend((float(sx[k, j]), float(sy[k, j])), cells)
                if status == UNKNOWN:
                    found.append(point)
                    if j == 1:
                        tree.reset(robot)
        self.points_found += len(found)
        return np.asarray(found, dtype=np.float64).reshape(-1, 2)

    def filter(self, grid: GridMap, new_points: npt.ArrayLike,
               passable: npt.NDArray[np.bool_]) -> npt.NDArray[np.float64]:
        """Cluster the kept and the new points, drop blocked and explored centres; the
        kept centres (N, 2)."""
        p = self.params
        pts = np.concatenate([self._points, np.asarray(new_points, np.float64).reshape(-1, 2)])
        if len(pts) > 1:
            pts, _ = mean_shift(pts, p.cluster_bandwidth_m)
        if len(pts):
            r, c = grid.world_to_cells(pts[:, 0], pts[:, 1])
            inside = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
            keep = inside.copy()
            ri, ci = r[inside], c[inside]
            blocked = (grid.data[ri, ci] >= 0) & ~passable[ri, ci]
            keep[np.flatnonzero(inside)[blocked]] = False
            counts, _ = unknown_within(grid, np.stack([r, c], axis=1), p.info_radius_m / 2)
            keep &= counts * grid.resolution_m ** 2 >= p.min_info_gain_m2
            pts = pts[keep]
        self._points = pts
        return pts.copy()

    def candidates(self, grid: GridMap, passable: npt.NDArray[np.bool_],
                   extra_obstacles: npt.NDArray[np.bool_] | None = None) -> list[Frontier]:
        """One Frontier per kept centre with unknown cells within ``info_radius_m``."""
        pts = self._points
        if len(pts) == 0:
            return []
        res = grid.resolution_m
        r, c = grid.world_to_cells(pts[:, 0], pts[:, 1])
        fr, fc = grid.world_to_cell_float(pts[:, 0], pts[:, 1])
        counts, cells = unknown_within(grid, np.stack([r, c], axis=1), self.params.info_radius_m)
        radius = metres_to_cells(self._frontier_params.cpoint_search_radius_m, res)
        out: list[Frontier] = []
        for i in np.flatnonzero(counts > 0):
            rc = (int(r[i]), int(c[i]))
            pt = passable_in_sight(rc, passable, grid, extra_obstacles,
                                   self._frontier_params.occupied_threshold, radius)
            ok = pt is not None
            if pt is None:
                pt = rc
            px, py = grid.cell_to_world(*pt)
            n = int(counts[i])
            out.append(Frontier(
                id=len(out), size_cells=n, length_m=n * res, point_rc=pt, point_xy_m=(px, py),
                point_passable=ok, centroid_rc=(float(fr[i]) - 0.5, float(fc[i]) - 0.5),
                centroid_xy_m=(float(pts[i, 0]), float(pts[i, 1])), cells=cells[i],
                info_gain_m2=n * res * res))
        return out

    def update(self, grid: GridMap, robot_xy_m: tuple[float, float],
               passable: npt.NDArray[np.bool_],
               extra_obstacles: npt.NDArray[np.bool_] | None = None) -> list[Frontier]:
        """:meth:`grow`, :meth:`filter`, :meth:`candidates` on one map.

        Parameters
        ----------
        grid : GridMap
            The current map (pass the same object while it is unchanged).
        robot_xy_m : (float, float)
            Robot position (root of the global tree on the first call; the local tree's
            new root after it finds a frontier point).
        passable : ndarray of bool, shape (H, W)
            Known-free cells outside the inflated obstacles (the path graph's mask).
        extra_obstacles : ndarray of bool, shape (H, W), optional
            Object-layer obstacles aligned with ``grid``.

        Returns
        -------
        list of Frontier
        """
        new = self.grow(grid, robot_xy_m, extra_obstacles)
        self.filter(grid, new, passable)
        return self.candidates(grid, passable, extra_obstacles)
