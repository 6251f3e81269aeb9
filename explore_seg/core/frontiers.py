"""Frontier detection and grouping (Kim, Kim & Lee, RA-L 2022, Alg. 1; Yamauchi 1997).

Definition used here (the one of explore_lite's ``frontier_search``): a **frontier cell**
is an *unknown* cell with at least one *free* neighbour, in the 4-neighbourhood by default
(``free_neighbour_connectivity``). Cells marked occupied in an extra obstacle layer (the
object costmap) are neither free nor unknown, so objects close frontiers. Cells with an
occupancy between the free and occupied thresholds are neither free nor unknown either.

Frontier cells are grouped into 8-connected components (``group_connectivity``); groups
below ``min_group_size_cells`` are dropped. Each group gets a **cPoint**: the group cell
nearest to the group's centroid, moved to the nearest *passable* cell (free and outside
obstacles inflated by the robot radius) within ``cpoint_search_radius_m`` that is in
line of sight of it (the straight segment crosses no occupied cell), so the cPoint is
never in unknown space, in a wall or on the far side of one. Whether the robot can reach
it is decided later by the path search (selection).

Everything is vectorised (OpenCV morphology and connected components, numpy); only the
groups, never the cells, are visited in Python.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Sequence

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.fields import INT_MAX, param_meta
from explore_seg.core.grid import (FREE_THRESHOLD, OCCUPIED_THRESHOLD, GridMap,
                                    metres_to_cells)
from explore_seg.core.paths import inflate


@dataclass(frozen=True)
class FrontierParams:
    """Parameters of frontier detection (the explorer's ``frontier.*`` parameters)."""

    free_threshold: int = field(default=FREE_THRESHOLD, metadata=param_meta(
        "map cells with 0 <= value < this are free", "percent", range=(0, 101)))
    occupied_threshold: int = field(default=OCCUPIED_THRESHOLD, metadata=param_meta(
        "map cells with value >= this are obstacles", "percent", range=(0, 101)))
    object_occupied_threshold: int = field(default=OCCUPIED_THRESHOLD, metadata=param_meta(
        "object_costmap cells with value >= this are obstacles", "percent", range=(0, 101)))
    min_group_size_cells: int = field(default=10, metadata=param_meta(
        "frontier groups with fewer cells are ignored", "cells", range=(1, INT_MAX)))
    free_neighbour_connectivity: int = field(default=4, metadata=param_meta(
        "neighbourhood (4 or 8) in which an unknown cell needs a free cell to be "
        "a frontier cell", range=(4, 8, 4)))
    group_connectivity: int = field(default=8, metadata=param_meta(
        "connectivity (4 or 8) used to group frontier cells", range=(4, 8, 4)))
    robot_radius_m: float = field(default=0.22, metadata=param_meta(
        "obstacles are inflated by this radius to find passable cells and paths", "m",
        range=(0.0, math.inf)))
    cpoint_search_radius_m: float = field(default=1.0, metadata=param_meta(
        "how far a group's cPoint may be moved to reach a passable cell", "m",
        range=(0.0, math.inf)))
    use_object_costmap: bool = field(default=True, metadata=param_meta(
        "treat occupied object_costmap cells as obstacles"))

    def __post_init__(self) -> None:
        for name in ("free_threshold", "occupied_threshold", "object_occupied_threshold"):
            v = getattr(self, name)
            if not 0 <= v <= 101:
                raise ValueError(f"{name} must be in 0..101, got {v}")
        if self.free_threshold > self.occupied_threshold:
            raise ValueError(f"free_threshold ({self.free_threshold}) must be <= "
                             f"occupied_threshold ({self.occupied_threshold})")
        if self.min_group_size_cells < 1:
            raise ValueError(f"min_group_size_cells must be >= 1, got {self.min_group_size_cells}")
        for name in ("free_neighbour_connectivity", "group_connectivity"):
            if getattr(self, name) not in (4, 8):
                raise ValueError(f"{name} must be 4 or 8, got {getattr(self, name)}")
        if not (math.isfinite(self.robot_radius_m) and self.robot_radius_m >= 0):
            raise ValueError(f"robot_radius_m must be finite and >= 0, got {self.robot_radius_m}")
        if not (math.isfinite(self.cpoint_search_radius_m) and self.cpoint_search_radius_m >= 0):
            raise ValueError("cpoint_search_radius_m must be finite and >= 0, "
                             f"got {self.cpoint_search_radius_m}")


@dataclass(frozen=True)
class FrontierNodeParams:
    """Settings of the ``frontier_detector`` node (detection itself: :class:`FrontierParams`,
    bound under ``frontier.``)."""

    map_transient_local: bool = field(default=True, metadata=param_meta(
        "subscribe to map/object_costmap with transient-local durability (false for "
        "volatile publishers)"))
    rate_hz: float = field(default=2.0, metadata=param_meta(
        "rate of the node's tick (frontiers are recomputed only after a map or "
        "object_costmap update)", "Hz", range=(0.0, math.inf)))

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"rate_hz must be finite and > 0, got {self.rate_hz}")


@dataclass(frozen=True, eq=False)
class Frontier:
    """One frontier group.

    Attributes
    ----------
    id : int
        Index of the group in this detection (0..n-1, row-major order of its first cell;
        not stable across map updates).
    size_cells : int
        Number of frontier cells (the paper's cSize).
    length_m : float
        ``size_cells * resolution_m`` (explore_lite's frontier "size").
    point_rc, point_xy_m : (int, int), (float, float)
        The cPoint: cell and world position of the cell centre.
    point_passable : bool
        True when the cPoint is a passable cell; False when no passable cell was found
        near the group (it then is the group cell nearest the centroid, never a goal).
    centroid_rc, centroid_xy_m : (float, float), (float, float)
        Mean of the group's cells (cell units / world).
    cells : ndarray of int64, shape (K, 2)
        (row, col) of the group's frontier cells.
    info_gain_m2 : float
        Unknown area the frontier promises, when its detector measured it (the RRT
        detector of ``rrt_exploration``: unknown cells within ``info_radius_m``, which are
        then its ``cells``); NaN otherwise.
    """

    id: int
    size_cells: int
    length_m: float
    point_rc: tuple[int, int]
    point_xy_m: tuple[float, float]
    point_passable: bool
    centroid_rc: tuple[float, float]
    centroid_xy_m: tuple[float, float]
    cells: npt.NDArray[np.int64] = field(repr=False)
    info_gain_m2: float = math.nan


_KERNELS = {4: np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], np.uint8),
            8: np.ones((3, 3), np.uint8)}


def _check_layer(grid: GridMap, layer: npt.NDArray[np.bool_] | None, name: str
                 ) -> npt.NDArray[np.bool_] | None:
    if layer is None:
        return None
    arr = np.asarray(layer)
    if arr.shape != grid.shape:
        raise ValueError(f"{name} has shape {arr.shape}, expected the grid's {grid.shape}")
    return arr.astype(bool, copy=False)


def obstacle_mask(grid: GridMap, extra_obstacles: npt.NDArray[np.bool_] | None = None,
                  params: FrontierParams = FrontierParams()) -> npt.NDArray[np.bool_]:
    """Occupied cells of the map, plus those of ``extra_obstacles``.

    Parameters
    ----------
    grid : GridMap
    extra_obstacles : ndarray of bool, shape (H, W), optional
    params : FrontierParams

    Returns
    -------
    ndarray of bool, shape (H, W)

    Raises
    ------
    ValueError
        When ``extra_obstacles`` does not have the grid's shape.
    """
    extra = _check_layer(grid, extra_obstacles, "extra_obstacles")
    occ = grid.occupied_mask(params.occupied_threshold)
    return occ | extra if extra is not None else occ


def traversable_mask(grid: GridMap, extra_obstacles: npt.NDArray[np.bool_] | None = None,
                     params: FrontierParams = FrontierParams(), allow_unknown: bool = False
                     ) -> npt.NDArray[np.bool_]:
    """Passable cells: free, not an extra obstacle, farther than the robot radius from
    every obstacle (map or extra layer). With ``allow_unknown`` unknown cells count as
    free too (an optimistic mask, like Nav2's ``allow_unknown`` planner setting).

    Parameters
    ----------
    grid : GridMap
    extra_obstacles : ndarray of bool, shape (H, W), optional
    params : FrontierParams
        ``free_threshold``, ``occupied_threshold`` and ``robot_radius_m`` are used.

    Returns
    -------
    ndarray of bool, shape (H, W)

    Raises
    ------
    ValueError
        When ``extra_obstacles`` does not have the grid's shape.

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii('''
    ... #....
    ... .....
    ... ''', resolution_m=1.0)
    >>> traversable_mask(g, params=FrontierParams(robot_radius_m=1.0)).astype(int).tolist()
    [[0, 1, 1, 1, 1], [0, 0, 1, 1, 1]]
    """
    blocked = obstacle_mask(grid, extra_obstacles, params)
    free = grid.free_mask(params.free_threshold)
    if allow_unknown:
        free |= grid.unknown_mask()
    free &= ~blocked
    return free & ~inflate(blocked, params.robot_radius_m, grid.resolution_m)


def detect_frontier_cells(grid: GridMap, extra_obstacles: npt.NDArray[np.bool_] | None = None,
                          params: FrontierParams = FrontierParams()
                          ) -> npt.NDArray[np.bool_]:
    """Frontier cells: unknown cells with a free neighbour (see the module docstring).

    Parameters
    ----------
    grid : GridMap
    extra_obstacles : ndarray of bool, shape (H, W), optional
        Cells occupied in an extra layer (object costmap): never free, never frontier.
    params : FrontierParams

    Returns
    -------
    ndarray of bool, shape (H, W)

    Raises
    ------
    ValueError
        When ``extra_obstacles`` does not have the grid's shape.

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii('''
    ... ??#
    ... ..?
    ... ''')
    >>> detect_frontier_cells(g).astype(int).tolist()
    [[0, 0, 1], [1, 1, 0]]
    """
    extra = _check_layer(grid, extra_obstacles, "extra_obstacles")
    free = grid.free_mask(params.free_threshold)
    unknown = grid.unknown_mask()
    if extra is not None:
        free &= ~extra
        unknown &= ~extra
    if not free.any() or not unknown.any():
        return np.zeros(grid.shape, dtype=bool)
    near_free = cv2.dilate(free.view(np.uint8), _KERNELS[params.free_neighbour_connectivity],
                           borderType=cv2.BORDER_CONSTANT, borderValue=0)
    return unknown & near_free.view(bool)


def _line_clear(grid: GridMap, extra: npt.NDArray[np.bool_] | None, occupied_threshold: int,
                a_rc: tuple[int, int], b_rc: npt.NDArray[np.int64]) -> npt.NDArray[np.bool_]:
    """For each cell of ``b_rc`` (M, 2): does the segment a -> b avoid obstacle cells
    (map >= ``occupied_threshold`` or ``extra``)?

    The segment is sampled every half cell (end cells included).
    """
    diff = b_rc - np.asarray(a_rc)
    steps = int(2 * np.abs(diff).max()) + 1 if diff.size else 1
    t = np.linspace(0.0, 1.0, steps + 1)
    rr = np.rint(a_rc[0] + t[None, :] * diff[:, :1]).astype(np.int64)
    cc = np.rint(a_rc[1] + t[None, :] * diff[:, 1:]).astype(np.int64)
    hit = grid.data[rr, cc] >= occupied_threshold
    if extra is not None:
        hit |= extra[rr, cc]
    return ~hit.any(axis=1)


def _cpoint(rep_rc: tuple[int, int], passable: npt.NDArray[np.bool_], grid: GridMap,
            extra: npt.NDArray[np.bool_] | None, occupied_threshold: int, radius_cells: int
            ) -> tuple[int, int] | None:
    """Nearest passable cell to ``rep_rc`` within the radius and in line of sight."""
    h, w = passable.shape
    r, c = rep_rc
    r0, r1 = max(0, r - radius_cells), min(h, r + radius_cells + 1)
    c0, c1 = max(0, c - radius_cells), min(w, c + radius_cells + 1)
    rr, cc = np.nonzero(passable[r0:r1, c0:c1])
    if rr.size == 0:
        return None
    rr += r0
    cc += c0
    d2 = (rr - r) ** 2 + (cc - c) ** 2
    inside = d2 <= radius_cells * radius_cells
    rr, cc, d2 = rr[inside], cc[inside], d2[inside]
    if rr.size == 0:
        return None
    order = np.argsort(d2, kind="stable")
    cand = np.stack([rr[order], cc[order]], axis=1)
    batch = 16
    for s in range(0, cand.shape[0], batch):
        chunk = cand[s:s + batch]
        ok = np.flatnonzero(_line_clear(grid, extra, occupied_threshold, rep_rc, chunk))
        if ok.size:
            return int(chunk[ok[0], 0]), int(chunk[ok[0], 1])
    return None


class FrontierCache:
    """cPoints and splits of frontier groups kept across map versions (exact).

    A group's split (:func:`split_frontiers`) depends only on its cells: it is reused for
    a group of the same cells. A cPoint depends only on its representative cell, the
    search radius and, inside the ``(2 radius + 1)``-cell window around that cell, the
    passable mask, the occupied cells of the map and the extra obstacle layer (the
    line-of-sight segments stay in the window): it is reused while those windows are
    equal. A map that grew (another shape or origin) clears the cache. Only the entries
    asked for by the latest detection are kept (call :meth:`start` before each), so
    memory stays bounded by the number of groups.

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii('''
    ... ??????????
    ... ..........
    ... ..........
    ... ''', resolution_m=0.1)
    >>> cache = FrontierCache()
    >>> p = FrontierParams(robot_radius_m=0.0)
    >>> cache.start(g)
    >>> a = find_frontiers(g, params=p, cache=cache)
    >>> cache.start(g)
    >>> b = find_frontiers(g, params=p, cache=cache)
    >>> a[0].point_rc == b[0].point_rc, cache.hits, cache.misses
    (True, 1, 1)
    """

    def __init__(self) -> None:
        self._entries: dict[tuple, tuple] = {}
        self._next: dict[tuple, tuple] = {}
        self._geometry: tuple | None = None
        self.hits = 0
        self.misses = 0

    def reset(self) -> None:
        """Forget every entry (new parameters, a restart)."""
        self._entries, self._next, self._geometry = {}, {}, None

    def start(self, grid: GridMap) -> None:
        """Begin a detection on ``grid``: the entries the previous one used stay."""
        geometry = (grid.shape, grid.origin_xy_m, grid.origin_yaw_rad, grid.resolution_m)
        self._entries = self._next if geometry == self._geometry else {}
        self._next = {}
        self._geometry = geometry

    def split(self, cells: npt.NDArray[np.int64], max_extent_cells: float
              ) -> list[npt.NDArray[np.int64]]:
        """``_split_cells(cells, max_extent_cells)``, from the cache for the same cells."""
        key = ("split", cells.shape[0], cells.tobytes(), max_extent_cells)
        parts = self._entries.get(key)
        if parts is None:
            parts = _split_cells(cells, max_extent_cells)
        self._next[key] = parts
        return parts

    def cpoint(self, rep_rc: tuple[int, int], passable: npt.NDArray[np.bool_], grid: GridMap,
               extra: npt.NDArray[np.bool_] | None, occupied_threshold: int,
               radius_cells: int) -> tuple[int, int] | None:
        """:func:`passable_in_sight`, from the cache when its windows are unchanged."""
        h, w = passable.shape
        r, c = rep_rc
        win = (slice(max(0, r - radius_cells), min(h, r + radius_cells + 1)),
               slice(max(0, c - radius_cells), min(w, c + radius_cells + 1)))
        pas = passable[win]
        occ = grid.data[win] >= occupied_threshold
        ext = extra[win] if extra is not None else None
        key = (rep_rc, occupied_threshold, radius_cells)
        hit = self._entries.get(key)
        if (hit is not None and np.array_equal(hit[0], pas) and np.array_equal(hit[1], occ)
                and (hit[2] is None) == (ext is None)
                and (ext is None or np.array_equal(hit[2], ext))):
            self.hits += 1
            self._next[key] = hit
            return hit[3]
        self.misses += 1
        pt = _cpoint(rep_rc, passable, grid, extra, occupied_threshold, radius_cells)
        self._next[key] = (pas.copy(), occ, None if ext is None else ext.copy(), pt)
        return pt


def passable_in_sight(rep_rc: tuple[int, int], passable: npt.NDArray[np.bool_], grid: GridMap,
                      extra_obstacles: npt.NDArray[np.bool_] | None, occupied_threshold: int,
                      radius_cells: int) -> tuple[int, int] | None:
    """The passable cell nearest to ``rep_rc`` within ``radius_cells`` whose straight
    segment from ``rep_rc`` crosses no obstacle (how a cPoint is placed); None if none."""
    return _cpoint(rep_rc, passable, grid, extra_obstacles, occupied_threshold, radius_cells)


def group_frontiers(grid: GridMap, frontier_mask: npt.NDArray[np.bool_],
                    params: FrontierParams = FrontierParams(),
                    extra_obstacles: npt.NDArray[np.bool_] | None = None,
                    passable: npt.NDArray[np.bool_] | None = None,
                    cache: FrontierCache | None = None) -> list[Frontier]:
    """Group frontier cells into connected components and give each its cPoint.

    Parameters
    ----------
    grid : GridMap
    frontier_mask : ndarray of bool, shape (H, W)
        Output of :func:`detect_frontier_cells`.
    params : FrontierParams
    extra_obstacles : ndarray of bool, shape (H, W), optional
        Extra obstacle layer (also used for the cPoint's passability and line of sight).
    passable : ndarray of bool, shape (H, W), optional
        Precomputed :func:`traversable_mask` (saves one inflation).
    cache : FrontierCache, optional
        cPoints kept from the previous detection (same results, less work).

    Returns
    -------
    list of Frontier
        Groups of at least ``min_group_size_cells`` cells, ``id`` 0..n-1.

    Raises
    ------
    ValueError
        When a mask does not have the grid's shape.
    """
    mask = np.asarray(frontier_mask, dtype=bool)
    if mask.shape != grid.shape:
        raise ValueError(f"frontier_mask has shape {mask.shape}, expected the grid's {grid.shape}")
    extra = _check_layer(grid, extra_obstacles, "extra_obstacles")
    pas = _check_layer(grid, passable, "passable")
    flat = np.flatnonzero(mask)
    if flat.size == 0:
        return []
    n, lab = cv2.connectedComponents(np.ascontiguousarray(mask).view(np.uint8),
                                     connectivity=params.group_connectivity, ltype=cv2.CV_32S)
    ll = lab.ravel()[flat]
    sizes = np.bincount(ll, minlength=n)
    keep = np.flatnonzero(sizes[1:] >= params.min_group_size_cells) + 1
    if keep.size == 0:
        return []
    rr_all, cc_all = np.divmod(flat, grid.width)
    mean_r = np.bincount(ll, weights=rr_all, minlength=n) / np.maximum(sizes, 1)
    mean_c = np.bincount(ll, weights=cc_all, minlength=n) / np.maximum(sizes, 1)
    order = np.argsort(ll, kind="stable")
    rr, cc, ll = rr_all[order], cc_all[order], ll[order]
    starts = np.searchsorted(ll, np.arange(n + 1))

    if pas is None:
        pas = traversable_mask(grid, extra, params)
    search = _CpointSearch(grid, pas, extra, params, cache)
    out: list[Frontier] = []
    for gid, k in enumerate(keep):
        a, b = int(starts[k]), int(starts[k + 1])
        cells = np.stack([rr[a:b], cc[a:b]], axis=1).astype(np.int64)
        out.append(_group(gid, cells, (float(mean_r[k]), float(mean_c[k])), search))
    return out


@dataclass(frozen=True, eq=False)
class _CpointSearch:
    """A group's cPoint search on one map: :func:`_cpoint` (or the cache's) with these."""

    grid: GridMap
    passable: npt.NDArray[np.bool_]
    extra: npt.NDArray[np.bool_] | None
    params: FrontierParams
    cache: FrontierCache | None

    def near(self, rep_rc: tuple[int, int]) -> tuple[int, int] | None:
        find = _cpoint if self.cache is None else self.cache.cpoint
        radius = metres_to_cells(self.params.cpoint_search_radius_m, self.grid.resolution_m)
        return find(rep_rc, self.passable, self.grid, self.extra,
                    self.params.occupied_threshold, radius)


def _group(gid: int, cells: npt.NDArray[np.int64], centroid_rc: tuple[float, float],
           search: _CpointSearch) -> Frontier:
    """The group of ``cells``: its cPoint is the passable cell in sight nearest to the
    cell nearest to the centroid (that cell itself, not passable, when there is none)."""
    grid = search.grid
    cy, cx = centroid_rc
    d2 = (cells[:, 0] - cy) ** 2 + (cells[:, 1] - cx) ** 2
    j = int(np.argmin(d2))
    rep = (int(cells[j, 0]), int(cells[j, 1]))
    found = search.near(rep)
    ok = found is not None
    pt = found if found is not None else rep
    px, py = grid.cell_to_world(pt[0], pt[1])
    gx, gy = grid.cells_to_world(np.asarray([cy]), np.asarray([cx]))
    n = int(cells.shape[0])
    return Frontier(id=gid, size_cells=n, length_m=float(n * grid.resolution_m),
                    point_rc=pt, point_xy_m=(px, py), point_passable=ok,
                    centroid_rc=(cy, cx), centroid_xy_m=(float(gx[0]), float(gy[0])),
                    cells=cells)


def _split_cells(cells: npt.NDArray[np.int64], max_extent_cells: float
                 ) -> list[npt.NDArray[np.int64]]:
    """Split ``cells`` at their mean across their principal axis until no part extends
    more than ``max_extent_cells`` along its own principal axis (in input order within a
    part; parts ordered along the axes)."""
    if cells.shape[0] < 2:
        return [cells]
    centred = cells.astype(np.float64)
    centred -= centred.mean(axis=0)
    cov = centred.T @ centred
    axis = np.linalg.eigh(cov)[1][:, -1]
    proj = centred @ axis
    if float(proj.max() - proj.min()) <= max_extent_cells:
        return [cells]
    lo = proj < 0.0
    if lo.all() or not lo.any():
        return [cells]
    return (_split_cells(cells[lo], max_extent_cells)
            + _split_cells(cells[~lo], max_extent_cells))


def split_frontiers(grid: GridMap, frontiers: Sequence[Frontier], max_extent_m: float,
                    params: FrontierParams = FrontierParams(),
                    extra_obstacles: npt.NDArray[np.bool_] | None = None,
                    passable: npt.NDArray[np.bool_] | None = None,
                    cache: FrontierCache | None = None) -> list[Frontier]:
    """Frontier groups that extend more than ``max_extent_m`` along their principal axis,
    split (recursively, at the mean) into parts that do not, each a group with its own
    centroid and cPoint (FUEL's cluster split: a long frontier, e.g. along a corridor's
    side, is several places to look from, not one). Shorter groups are returned as they
    are; ids are renumbered 0..n-1 in the input order. ``max_extent_m`` <= 0: unchanged.
    ``cache``: as in :func:`group_frontiers`.

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii('''
    ... ????????????????????????????????????????
    ... ........................................
    ... ........................................
    ... ''', resolution_m=0.1)
    >>> fs = find_frontiers(g, params=FrontierParams(robot_radius_m=0.0))
    >>> [f.size_cells for f in fs], [f.size_cells for f in split_frontiers(g, fs, 1.5)]
    ([40], [10, 10, 10, 10])
    """
    if max_extent_m <= 0.0 or not frontiers:
        return list(frontiers)
    extra = _check_layer(grid, extra_obstacles, "extra_obstacles")
    pas = _check_layer(grid, passable, "passable")
    if pas is None:
        pas = traversable_mask(grid, extra, params)
    search = _CpointSearch(grid, pas, extra, params, cache)
    max_cells = max_extent_m / grid.resolution_m
    out: list[Frontier] = []
    for f in frontiers:
        parts = (_split_cells(f.cells, max_cells) if cache is None
                 else cache.split(f.cells, max_cells))
        if len(parts) == 1:
            out.append(replace(f, id=len(out)) if f.id != len(out) else f)
            continue
        for cells in parts:
            mean = cells.astype(np.float64).mean(axis=0)
            out.append(_group(len(out), cells, (float(mean[0]), float(mean[1])), search))
    return out


def find_frontiers(grid: GridMap, extra_obstacles: npt.NDArray[np.bool_] | None = None,
                   params: FrontierParams = FrontierParams(),
                   passable: npt.NDArray[np.bool_] | None = None,
                   cache: FrontierCache | None = None) -> list[Frontier]:
    """:func:`detect_frontier_cells` then :func:`group_frontiers`.

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii('''
    ... ??????
    ... ......
    ... ......
    ... ......
    ... ''', resolution_m=0.1)
    >>> [(f.size_cells, f.point_rc) for f in find_frontiers(g, params=FrontierParams(
    ...     min_group_size_cells=3, robot_radius_m=0.0))]
    [(6, (2, 2))]
    """
    mask = detect_frontier_cells(grid, extra_obstacles, params)
    return group_frontiers(grid, mask, params, extra_obstacles, passable, cache)


def object_obstacles(layer: GridMap | None, grid: GridMap, threshold: int
                     ) -> np.ndarray | None:
    """Cells of ``grid`` occupied (>= ``threshold``) in an extra layer (the object costmap).

    The layer is resampled onto the map's cells through world coordinates, so it may have
    another size or origin. Returns None without a layer.
    """
    if layer is None:
        return None
    return layer.resample_to(grid) >= threshold
