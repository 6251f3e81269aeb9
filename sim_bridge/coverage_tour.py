"""Full-knowledge coverage tour: a reference path length for exploration benchmarks.

With the whole ground truth known and a 360 degree range sensor, how far must a robot
drive so that every explorable cell has been in view? :func:`coverage_tour` answers it
in five steps:

1. **candidates**: viewpoints on a regular lattice (``candidate_spacing_m``) over the
   inflated free space (``inside`` cells at least ``clearance_m`` from every obstacle of
   the footprint raster) that the start can reach;
2. **visibility**: from each candidate the simulator's lidar (ray cast against the
   world's primitives, ``sensor_range_m``, ``num_beams``) marks the cells its beams
   cross; the targets are the ``inside`` cells on a ``target_stride_cells`` sub-lattice;
3. **greedy set cover** (lazy evaluation) until every target that any candidate sees is
   covered (targets no candidate sees are reported, not required);
4. **tour**: nearest neighbour from the start over geodesic distances
   (:func:`explore_seg.core.paths.distance_field` on the inflated free space, exact
   8-connected lengths) then 2-opt with the start fixed and an open end;
5. **pruning**: the sensor also scans every ``sample_spacing_m`` along the tour, and the
   tour ends once ``coverage_fraction`` (99 %, the benchmark's completion rule) of the
   coverable targets was in view; viewpoints are dropped one by one (fewest targets
   first) while the re-ordered tour without them is no longer.

The result is a near-optimal informed tour, not a proven lower bound: set cover, 2-opt
and the pruning are heuristics. Exploration with an unknown map should still need
more: the benchmark reports each strategy's path length to 99 % divided by this tour
length.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.fields import param_meta
from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap
from explore_seg.core.paths import distance_field, extract_path, inflate
from sim_bridge import worlds
from sim_bridge.sensors import Lidar, LidarParams
from sim_bridge.world import World


@dataclass(frozen=True)
class TourParams:
    """Parameters of :func:`coverage_tour`."""

    sensor_range_m: float = field(default=5.0, metadata=param_meta(
        "range of the 360 degree sensor (the paper's lidar: 5 m)", "m", range=(0.0, math.inf)))
    num_beams: int = field(default=360, metadata=param_meta(
        "beams per viewpoint scan", range=(3, 2**31 - 1)))
    candidate_spacing_m: float = field(default=0.5, metadata=param_meta(
        "lattice spacing of candidate viewpoints", "m", range=(0.0, math.inf)))
    clearance_m: float = field(default=0.27, metadata=param_meta(
        "viewpoints and paths keep this distance to obstacles of the footprint raster (robot "
        "radius + planner margin)", "m", range=(0.0, math.inf)))
    target_stride_cells: int = field(default=2, metadata=param_meta(
        "targets: inside cells on every n-th row and column", range=(1, 2**31 - 1)))
    ray_step_cells: float = field(default=0.5, metadata=param_meta(
        "sampling step along a beam", "cells", range=(0.0, math.inf)))
    two_opt_max_sweeps: int = field(default=50, metadata=param_meta(
        "bound on the 2-opt improvement sweeps", range=(1, 2**31 - 1)))
    prune_passes: int = field(default=3, metadata=param_meta(
        "bound on the passes of the viewpoint pruning", range=(1, 2**31 - 1)))
    sample_spacing_m: float = field(default=0.25, metadata=param_meta(
        "the sensor also scans every this far along the tour", "m", range=(0.0, math.inf)))
    coverage_fraction: float = field(default=0.99, metadata=param_meta(
        "the tour ends once this share of the coverable targets was in view (the benchmark's "
        "completion rule)", range=(0.0, 1.0)))

    def __post_init__(self) -> None:
        if not 0.0 < self.coverage_fraction <= 1.0:
            raise ValueError(f"coverage_fraction must be in (0, 1], got {self.coverage_fraction}")
        for name in ("sensor_range_m", "candidate_spacing_m", "ray_step_cells",
                     "sample_spacing_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not (math.isfinite(self.clearance_m) and self.clearance_m >= 0):
            raise ValueError(f"clearance_m must be finite and >= 0, got {self.clearance_m}")
        for name in ("num_beams", "target_stride_cells", "two_opt_max_sweeps", "prune_passes"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v}")
        if self.num_beams < 3:
            raise ValueError(f"num_beams must be >= 3, got {self.num_beams}")


@dataclass(frozen=True)
class TourResult:
    """Outcome of :func:`coverage_tour`.

    Attributes
    ----------
    length_m : float
        Geodesic length start -> viewpoints in tour order (open tour).
    viewpoints_xy : ndarray of float64, shape (K, 2)
        Chosen viewpoints in tour order.
    path_xy : ndarray of float64, shape (N, 2)
        The tour as world points (cell centres of the geodesic paths).
    coverable_fraction : float
        Share of the targets that some candidate sees (the rest cannot be seen from the
        inflated free space).
    n_candidates, n_targets : int
    """

    length_m: float
    viewpoints_xy: npt.NDArray[np.float64]
    path_xy: npt.NDArray[np.float64]
    coverable_fraction: float
    n_candidates: int
    n_targets: int


def _visible_cells(lidar: Lidar, xy: tuple[float, float], geom: GridMap,
                   params: TourParams) -> npt.NDArray[np.int64]:
    """Flat indices (into ``geom``) of the cells the beams from ``xy`` cross."""
    ranges = np.asarray(lidar.scan((xy[0], xy[1], 0.0), None), dtype=np.float64)
    lp = lidar.params
    ang = lp.angle_min_rad + lp.angle_increment_rad * np.arange(ranges.shape[0])
    # +inf: nothing within range (the beam sees all of it); -inf: too close to see.
    reach = np.where(np.isfinite(ranges), ranges,
                     np.where(ranges > 0, params.sensor_range_m, 0.0))
    reach = np.minimum(reach, params.sensor_range_m)
    step = params.ray_step_cells * geom.resolution_m
    n = int(math.ceil(params.sensor_range_m / step)) + 1
    s = np.arange(n, dtype=np.float64) * step                      # (n,)
    ok = s[None, :] < reach[:, None]                               # (beams, n)
    px = xy[0] + np.cos(ang)[:, None] * s[None, :]
    py = xy[1] + np.sin(ang)[:, None] * s[None, :]
    r, c = geom.world_to_cells(px[ok], py[ok])
    inb = (r >= 0) & (r < geom.height) & (c >= 0) & (c < geom.width)
    return np.unique(r[inb] * geom.width + c[inb])


def greedy_cover(sets: list[npt.NDArray[np.int64]], n_targets: int) -> list[int]:
    """Lazy greedy set cover of every coverable target; returns chosen set indices."""
    covered = np.zeros(n_targets, dtype=bool)
    heap = [(-len(s), i) for i, s in enumerate(sets) if len(s)]
    heapq.heapify(heap)
    chosen: list[int] = []
    coverable = np.zeros(n_targets, dtype=bool)
    for s in sets:
        coverable[s] = True
    remaining = int(coverable.sum())
    while remaining > 0 and heap:
        neg, i = heapq.heappop(heap)
        gain = int((~covered[sets[i]]).sum())
        if gain == 0:
            continue
        if heap and gain < -heap[0][0]:
            heapq.heappush(heap, (-gain, i))
            continue
        chosen.append(i)
        covered[sets[i]] = True
        remaining -= gain
    return chosen


def tour_order(dist: npt.NDArray[np.float64], max_sweeps: int) -> list[int]:
    """Open tour from node 0 through all nodes: nearest neighbour, then 2-opt."""
    n = dist.shape[0]
    order = [0]
    left = set(range(1, n))
    while left:
        cur = order[-1]
        nxt = min(left, key=lambda j: (dist[cur, j], j))
        order.append(nxt)
        left.remove(nxt)
    for _ in range(max_sweeps):
        improved = False
        for i in range(1, n - 1):
            a, b = order[i - 1], order[i]
            for j in range(i + 1, n):
                c = order[j]
                d_after = order[j + 1] if j + 1 < n else None
                old = dist[a, b] + (dist[c, d_after] if d_after is not None else 0.0)
                new = dist[a, c] + (dist[b, d_after] if d_after is not None else 0.0)
                if new < old - 1e-9:
                    order[i:j + 1] = order[i:j + 1][::-1]
                    b = order[i]
                    improved = True
        if not improved:
            break
    return order


def coverage_tour(world: World, start_xy: tuple[float, float] | None = None,
                  params: TourParams | None = None,
                  ground_truth: worlds.GroundTruth | None = None) -> TourResult:
    """Shortest-tour estimate that brings every explorable cell into sensor view.

    Parameters
    ----------
    world : World
    start_xy : (float, float), optional
        Tour start; default the world's start pose.
    params : TourParams, optional
    ground_truth : worlds.GroundTruth, optional
        Precomputed ``worlds.ground_truth(world)``.

    Returns
    -------
    TourResult

    Raises
    ------
    ValueError
        When the start lies outside the world's rasters or no viewpoint is reachable.
    """
    p = params if params is not None else TourParams()
    return coverage_tours(world, (p.coverage_fraction,), start_xy, p, ground_truth)[0]


def coverage_tours(world: World, fractions: tuple[float, ...],
                   start_xy: tuple[float, float] | None = None,
                   params: TourParams | None = None,
                   ground_truth: worlds.GroundTruth | None = None) -> list[TourResult]:
    """:func:`coverage_tour` to each of several coverage fractions, in one go: steps 1-4
    (candidates, visibility, set cover, distances) and the scans along the tour legs are
    shared; only the pruning (step 5) runs per fraction. ``params.coverage_fraction`` is
    ignored; each result equals ``coverage_tour`` with that fraction.

    Raises
    ------
    ValueError
        When a fraction is not in (0, 1], the start lies outside the world's rasters or no
        viewpoint is reachable.
    """
    p = params if params is not None else TourParams()
    for f in fractions:
        if not 0.0 < f <= 1.0:
            raise ValueError(f"coverage fractions must be in (0, 1], got {f}")
    gt = ground_truth if ground_truth is not None else worlds.ground_truth(world)
    geom = gt.lidar
    res = geom.resolution_m
    sx, sy = start_xy if start_xy is not None else world.start_pose[:2]
    s_rc = geom.world_to_cell(float(sx), float(sy))
    if not geom.in_bounds(*s_rc):
        raise ValueError(f"start ({sx:.2f}, {sy:.2f}) outside the world raster "
                         f"{geom.shape}")
    blocked = (gt.footprint.data >= OCCUPIED_THRESHOLD) | ~gt.inside
    passable = ~inflate(blocked, p.clearance_m, res)
    reach = np.isfinite(distance_field(passable, s_rc, res))
    reach &= passable
    # 1. candidates on a lattice
    cand_rc = _candidates(reach, p.candidate_spacing_m / res)
    cx, cy = geom.cells_to_world(cand_rc[:, 0], cand_rc[:, 1])
    # 2. visibility of targets
    st = p.target_stride_cells
    tmask = np.zeros(geom.shape, dtype=bool)
    tmask[::st, ::st] = True
    tmask &= gt.explorable
    tid = np.full(geom.shape[0] * geom.shape[1], -1, dtype=np.int64)
    tflat = np.flatnonzero(tmask.ravel())
    tid[tflat] = np.arange(tflat.size)
    lidar = Lidar(world, LidarParams(num_beams=p.num_beams, range_max_m=p.sensor_range_m,
                                     noise_std_m=0.0, mount_xy_m=(0.0, 0.0)))
    sets = []
    for x, y in zip(cx.tolist(), cy.tolist()):
        ids = tid[_visible_cells(lidar, (x, y), geom, p)]
        sets.append(ids[ids >= 0])
    coverable = np.zeros(tflat.size, dtype=bool)
    for s in sets:
        coverable[s] = True
    # 3. set cover
    chosen = greedy_cover(sets, tflat.size)
    pts_rc = [s_rc] + [tuple(int(v) for v in cand_rc[i]) for i in chosen]
    # 4. geodesic distances and tour
    fields_, dist = _geodesics(passable, pts_rc, res)

    def target_ids(xy: tuple[float, float]) -> npt.NDArray[np.int64]:
        ids = tid[_visible_cells(lidar, xy, geom, p)]
        return ids[ids >= 0]

    walker = _PathWalker(fields_, pts_rc, geom, p, target_ids, passable)
    n_coverable = int(coverable.sum())
    set_sizes = [len(sets[i]) for i in chosen]
    results = []
    for fraction in fractions:
        need = int(math.ceil(fraction * n_coverable))
        best_len, best_order = _pruned_tour(walker, dist, set_sizes, need, p)
        verts = walker.vertices(best_order)
        px, py = geom.cells_to_world(verts[:, 0], verts[:, 1])
        vis = [pts_rc[i] for i in best_order[1:]]
        vx, vy = geom.cells_to_world(np.asarray([v[0] for v in vis]),
                                     np.asarray([v[1] for v in vis]))
        results.append(TourResult(
            length_m=float(best_len),
            viewpoints_xy=np.column_stack([vx, vy]).reshape(-1, 2),
            path_xy=np.column_stack([px, py]),
            coverable_fraction=float(coverable.mean()) if coverable.size else 1.0,
            n_candidates=int(cand_rc.shape[0]), n_targets=int(tflat.size)))
    return results


def _candidates(reach: npt.NDArray[np.bool_], spacing_cells: float) -> npt.NDArray[np.int64]:
    """Reachable cells of a lattice with ``spacing_cells`` (rounded), shape (N, 2) (row,
    col). Raises ValueError when there is none."""
    k = max(1, int(round(spacing_cells)))
    lattice = np.zeros(reach.shape, dtype=bool)
    lattice[k // 2::k, k // 2::k] = True
    cand_rc = np.argwhere(reach & lattice)
    if cand_rc.size == 0:
        raise ValueError("no reachable viewpoint: the start is enclosed at this clearance")
    return cand_rc


def _geodesics(passable: npt.NDArray[np.bool_], pts_rc: list[tuple[int, int]],
               res: float) -> tuple[list[npt.NDArray[np.float64]], npt.NDArray[np.float64]]:
    """The distance field of every point and the symmetric matrix of their geodesic
    distances (the start may sit in the inflated margin: the shorter direction wins)."""
    n = len(pts_rc)
    dist = np.zeros((n, n))
    fields_ = []
    for i, rc in enumerate(pts_rc):
        f = distance_field(passable, rc, res)
        fields_.append(f)
        dist[i] = [f[q] for q in pts_rc]
    return fields_, np.minimum(dist, dist.T)


def _pruned_tour(walker: _PathWalker, dist: npt.NDArray[np.float64], set_sizes: list[int],
                 need: int, p: TourParams) -> tuple[float, list[int]]:
    """Step 5: drop viewpoints (node i >= 1 of ``dist`` sees ``set_sizes[i - 1]`` targets;
    fewest first) that the path to the others already brings into view, while the
    re-ordered tour to ``need`` targets in view is no longer. Returns (length, order)."""
    keep = list(range(1, dist.shape[0]))
    order = tour_order(dist[np.ix_([0] + keep, [0] + keep)], p.two_opt_max_sweeps)
    best_len, best_order = walker.length([([0] + keep)[i] for i in order], need)
    for _ in range(p.prune_passes):
        removed = False
        for v in sorted(keep, key=lambda i: set_sizes[i - 1]):
            trial = [i for i in keep if i != v]
            sub = [0] + trial
            o = tour_order(dist[np.ix_(sub, sub)], p.two_opt_max_sweeps)
            length, ordered = walker.length([sub[i] for i in o], need)
            if math.isfinite(length) and length <= best_len + 1e-9:
                keep, best_len, best_order = trial, length, ordered
                removed = True
        if not removed:
            break
    return best_len, best_order


def _shortcut(cells: npt.NDArray[np.int64], passable: npt.NDArray[np.bool_],
              window: int = 256) -> npt.NDArray[np.float64]:
    """Any-angle version of a cell path: from each kept vertex jump to the farthest path
    cell (within ``window`` cells ahead) reachable in a straight line over passable cells
    (segment sampled every half cell), as a path follower smooths a grid plan.

    Returns
    -------
    ndarray of float64, shape (K, 2)
        Kept (row, col) vertices, first and last cell included.
    """
    pts = np.asarray(cells, dtype=np.float64)
    n = len(pts)
    keep = [0]
    i = 0
    h, w = passable.shape
    while i < n - 1:
        cand = np.arange(min(n - 1, i + window), i, -1)            # far to near
        diff = pts[cand] - pts[i]
        steps = int(2 * np.abs(diff).max()) + 1
        t = np.linspace(0.0, 1.0, steps + 1)
        rr = np.clip(np.rint(pts[i, 0] + t[None, :] * diff[:, :1]), 0, h - 1).astype(np.int64)
        cc = np.clip(np.rint(pts[i, 1] + t[None, :] * diff[:, 1:]), 0, w - 1).astype(np.int64)
        clear = passable[rr, cc].all(axis=1)
        i = int(cand[int(np.argmax(clear))]) if clear.any() else i + 1
        keep.append(i)
    return pts[keep]


class _PathWalker:
    """Coverage gathered while driving a tour: the geodesic legs are smoothed
    (:func:`_shortcut`), the sensor scans every ``sample_spacing_m`` along them (cached per
    cell, shared by every coverage goal), and the tour length counts until the goal's
    number of targets was in view."""

    def __init__(self, fields_: list[npt.NDArray[np.float64]], pts_rc: list[tuple[int, int]],
                 geom: GridMap, params: TourParams, visible,
                 passable: npt.NDArray[np.bool_]) -> None:
        self._fields = fields_
        self._pts = pts_rc
        self._geom = geom
        self._p = params
        self._visible = visible
        self._passable = passable
        self._legs: dict[tuple[int, int], npt.NDArray[np.float64]] = {}
        self._seen: dict[tuple[int, int], npt.NDArray[np.int64]] = {}

    def _leg(self, a: int, b: int) -> npt.NDArray[np.float64]:
        key = (a, b)
        if key not in self._legs:
            pas = self._passable.copy()
            pas[self._pts[a]] = True       # the start may sit in the inflated margin
            self._legs[key] = _shortcut(extract_path(self._fields[a], self._pts[b]), pas)
        return self._legs[key]

    def vertices(self, order: list[int]) -> npt.NDArray[np.float64]:
        """The tour as (row, col) polyline vertices (float cells)."""
        parts = [np.asarray([self._pts[order[0]]], dtype=np.float64)]
        parts += [self._leg(order[i], order[i + 1])[1:] for i in range(len(order) - 1)]
        return np.vstack(parts)

    def _scan(self, rc: tuple[int, int]) -> npt.NDArray[np.int64]:
        if rc not in self._seen:
            self._seen[rc] = self._visible(self._geom.cell_to_world(rc[0], rc[1]))
        return self._seen[rc]

    def length(self, order: list[int], need: int) -> tuple[float, list[int]]:
        """(length until ``need`` targets were in view or inf, the order)."""
        v = self.vertices(order)
        res = self._geom.resolution_m
        d = np.hypot(*np.diff(v, axis=0).T) * res
        cum = np.concatenate([[0.0], np.cumsum(d)])
        spacing = self._p.sample_spacing_m
        s = np.append(np.arange(0.0, cum[-1], spacing), cum[-1])
        rows = np.interp(s, cum, v[:, 0])
        cols = np.interp(s, cum, v[:, 1])
        seen: set[int] = set()
        for k in range(len(s)):
            seen.update(self._scan((int(round(rows[k])), int(round(cols[k])))).tolist())
            if len(seen) >= need:
                return float(s[k]), order
        return math.inf, order
