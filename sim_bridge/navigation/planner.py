"""Planning of the navigation stand-in, after Nav2's NavFn on an inflated costmap.

:func:`cost_grid` builds the per-metre cost of an inflated costmap (lethal within
``robot_radius_m + inflation_margin_m``, an exponentially decaying inflation band, a
near-lethal soft margin, a surcharge through the cells whose distance to an obstacle cell's
edge is inside the lethal radius though their centre distance is not
(:func:`edge_overlap_kernel`), a surcharge through unknown cells); :func:`plan_path` runs
the cost-weighted 8-connected Dijkstra on a window around start and goal that grows until
it provably holds the cheapest path; :func:`coarsen` downsamples a cost grid for planning
on coarser cells.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.paths import (SQRT2, cost_distance_field, extract_path, inflate,
                                    obstacle_distance_cells)
from sim_bridge.navigation.params import NavParams


def edge_overlap_kernel(radius_m: float, resolution_m: float) -> npt.NDArray[np.uint8]:
    """Offsets (as a dilation kernel) of the obstacle cells whose square lies closer than
    ``radius_m`` to a cell's centre: ``hypot(max(|dc| - 1/2, 0), max(|dr| - 1/2, 0)) *
    resolution_m < radius_m``.

    Examples
    --------
    >>> k = edge_overlap_kernel(0.22, 0.05)
    >>> k.shape, int(k[5, 5 + 4]), int(k[5 + 4, 5 + 3]), int(k[5 + 4, 5 + 4])
    ((11, 11), 1, 1, 0)
    """
    r = int(math.ceil(radius_m / resolution_m + 0.5))
    d = np.maximum(np.abs(np.arange(-r, r + 1, dtype=np.float64)) - 0.5, 0.0)
    return (np.hypot(d[:, None], d[None, :]) * resolution_m < radius_m).astype(np.uint8)


def cost_grid(blocked: npt.NDArray[np.bool_], unknown: npt.NDArray[np.bool_] | None,
              resolution_m: float, params: NavParams) -> npt.NDArray[np.float64]:
    """Per-cell traversal cost (per metre) of an inflated costmap; ``inf`` = lethal.

    Parameters
    ----------
    blocked : ndarray of bool, shape (H, W)
        Obstacle cells.
    unknown : ndarray of bool, shape (H, W), or None
        Unknown cells (extra ``unknown_cost``); None when unknown cells are not allowed
        (the caller then marks them blocked).
    resolution_m : float
    params : NavParams

    Returns
    -------
    ndarray of float64, shape (H, W)
        ``>= 1`` for traversable cells, ``inf`` within the lethal radius of an obstacle.
    """
    lethal = inflate(blocked, params.lethal_radius_m, resolution_m)
    cost = np.ones(blocked.shape, dtype=np.float64)
    if blocked.any() and params.inflation_cost_weight > 0:
        d = obstacle_distance_cells(blocked) * resolution_m
        band = ~lethal & (d < params.inflation_radius_m)
        excess = np.maximum(d[band] - params.lethal_radius_m, 0.0)
        cost[band] += params.inflation_cost_weight * np.exp(-params.inflation_cost_scale * excess)
    if params.inflation_soft_margin_m > 0 and blocked.any():   # near-lethal band
        soft = inflate(blocked, params.lethal_radius_m + params.inflation_soft_margin_m,
                       resolution_m) & ~lethal
        cost[soft] += params.inflation_soft_margin_cost
    if params.inflation_edge_cost > 0 and blocked.any():   # disk overlaps a cell's square
        kernel = edge_overlap_kernel(params.lethal_radius_m, resolution_m)
        edge = cv2.dilate(blocked.astype(np.uint8), kernel).astype(bool) & ~lethal
        cost[edge] += params.inflation_edge_cost
    if unknown is not None and params.unknown_cost > 0:
        cost[unknown] += params.unknown_cost
    cost[lethal] = np.inf
    return cost


def plan_path(cost: npt.NDArray[np.float64], start_rc: tuple[int, int],
              goal_rc: tuple[int, int], resolution_m: float, window_margin_m: float,
              cost_hint: float | None = None, prune: bool = True
              ) -> tuple[npt.NDArray[np.int64], float] | None:
    """Cheapest path from start to goal over a cost grid, searched in a growing window.

    Costs are >= 1 per metre, so a path of cost <= L is at most L long and lies in the
    ellipse of points whose distances to start and goal sum to <= L. The search runs on
    that ellipse's bounding box for ``L = 1.5 * |goal - start| + window_margin_m``; a
    path found there with cost <= L is the global optimum. Otherwise L doubles, up to
    the whole grid. The path is the steepest descent of the window's cost-distance field
    from the goal (:func:`~explore_seg.core.paths.extract_path`).

    With ``prune`` (default) the grid is first searched only where a path of cost
    ``<= U`` can pass, for growing guesses ``U`` (A*'s pruning with the admissible
    octile-distance heuristic, see :func:`_pruned_plan`); a result is used only when it
    is certified to equal the windows' (same cost, same cells, bit for bit), else the
    windows are searched as described. Results never depend on ``prune`` or
    ``cost_hint``; only the work does (on long winding paths, as in a maze, the
    windows' search also skips the windows too small to hold the path).

    Parameters
    ----------
    cost : ndarray of float64, shape (H, W)
        Per-metre cost, >= 1, ``inf`` = lethal (see :func:`cost_grid`).
    start_rc, goal_rc : (int, int)
    resolution_m : float
    window_margin_m : float
    cost_hint : float, optional
        Expected cost of the path (e.g. the last plan's to the same goal): the first
        guess of ``U``.
    prune : bool
        False searches every window whole (the reference the tests compare with).

    Returns
    -------
    (cells, cost) or None
        cells: ndarray of int64, shape (N, 2), (row, col), start first; cost: its total
        cost. None when the goal is unreachable.
    """
    h, w = cost.shape
    (sr, sc), (gr, gc) = start_rc, goal_rc
    budget = 1.5 * math.hypot(gr - sr, gc - sc) * resolution_m + window_margin_m
    lower = 0.0
    if prune:
        found, lower = _pruned_plan(cost, start_rc, goal_rc, resolution_m, budget, cost_hint)
        if found is not None:
            return found
    while True:
        r0, r1, c0, c1 = _window(start_rc, goal_rc, budget, resolution_m, (h, w))
        whole = r0 == 0 and c0 == 0 and r1 == h and c1 == w
        if not whole and budget < lower * (1.0 - _SKIP_MARGIN):
            # The pruned searches proved every path costlier than this budget: this
            # window's search would find none within it and go on to the next.
            budget *= 2.0
            continue
        dist = cost_distance_field(cost[r0:r1, c0:c1], (sr - r0, sc - c0), resolution_m,
                                   math.inf if whole else budget)
        g = float(dist[gr - r0, gc - c0])
        if math.isfinite(g) and (g <= budget or whole):
            cells = extract_path(dist, (gr - r0, gc - c0))
            return cells + np.array([r0, c0], dtype=np.int64), g
        if whole:
            return None
        budget *= 2.0


def _window(start_rc: tuple[int, int], goal_rc: tuple[int, int], budget: float,
            resolution_m: float, shape: tuple[int, int]) -> tuple[int, int, int, int]:
    """Rows r0:r1 and columns c0:c1 of :func:`plan_path`'s search window for a budget."""
    (sr, sc), (gr, gc) = start_rc, goal_rc
    half = budget / resolution_m / 2.0 + 1.0
    cr, cc = (sr + gr) / 2.0, (sc + gc) / 2.0
    return (max(0, int(cr - half)), min(shape[0], int(math.ceil(cr + half)) + 1),
            max(0, int(cc - half)), min(shape[1], int(math.ceil(cc + half)) + 1))


def _pruned_plan(cost: npt.NDArray[np.float64], start_rc: tuple[int, int],
                 goal_rc: tuple[int, int], resolution_m: float, budget: float,
                 cost_hint: float | None
                 ) -> tuple[tuple[npt.NDArray[np.int64], float] | None, float]:
    """:func:`plan_path`'s result from pruned searches (:func:`_pruned_search`) for
    growing bounds, or None when none could be certified (the caller then searches the
    windows whole); and a lower bound of the cheapest path's cost that the searches
    proved (0 when none did): the cost itself once certified, else the certification
    limit of a search that did not reach the goal within it (no path costs less).

    A certified cost ``g`` is the cheapest over the whole grid. The windows' search
    stops at the first window whose budget is ``>= g`` (a path of cost ``<= budget``
    lies in the window; earlier windows only have costlier ones), and the descent there
    equals the certified one when the pruned region lies inside that window.
    """
    h, w = cost.shape
    res = resolution_m
    guess = 1.6 * _octile(start_rc, goal_rc) * res + 4.0 * res
    if cost_hint is not None and math.isfinite(cost_hint):
        guess = max(guess, 1.1 * cost_hint + 4.0 * res)
    # A bound whose region's box (about bound / resolution cells square) covers most of
    # the grid saves little over the windows' search.
    lower = 0.0
    while (guess / res) ** 2 < 0.5 * h * w:
        cells, g, box = _pruned_search(cost, start_rc, goal_rc, res, guess)
        cert_lim = guess - guess * _PRUNE_SLACK
        # A goal value within the certification limit is the cheapest cost; beyond it,
        # every path costs more than the limit.
        lower = max(lower, g if g <= cert_lim else cert_lim)
        if cells is not None:
            b = budget
            while True:
                win = _window(start_rc, goal_rc, b, res, (h, w))
                if win == (0, h, 0, w) or g <= b:
                    break
                b *= 2.0
            r0, r1, c0, c1 = win
            if r0 <= box[0] and box[1] <= r1 and c0 <= box[2] and box[3] <= c1:
                return (cells, g), lower
            return None, lower
        # g (a path's cost) bounds the cheapest cost from above.
        guess = max(1.1 * g + 4.0 * res, 1.3 * guess) if math.isfinite(g) else 2.0 * guess
    return None, lower


def _octile(a: tuple[int, int], b: tuple[int, int]) -> float:
    """Octile distance between two cells, in cells (the shortest 8-connected length)."""
    dr, dc = abs(a[0] - b[0]), abs(a[1] - b[1])
    return max(dr, dc) + (SQRT2 - 1.0) * min(dr, dc)


def _octile_field(rows: npt.NDArray[np.int64], cols: npt.NDArray[np.int64],
                  rc: tuple[int, int]) -> npt.NDArray[np.float64]:
    """Octile distance (cells) of every (row, col) of an open grid to ``rc``."""
    dr = np.abs(rows - rc[0]).astype(np.float64)
    dc = np.abs(cols - rc[1]).astype(np.float64)
    return np.maximum(dr, dc) + (SQRT2 - 1.0) * np.minimum(dr, dc)


#: Relative slack of the pruning bounds (covers the rounding of summed edge costs).
_PRUNE_SLACK = 1e-9

#: :func:`plan_path` skips a window only when its budget lies this far (relative) below
#: the proven lower bound: far more than the rounding that ``_PRUNE_SLACK`` covers.
_SKIP_MARGIN = 1e-6


def _pruned_search(cost: npt.NDArray[np.float64], start: tuple[int, int],
                   goal: tuple[int, int], resolution_m: float, bound: float
                   ) -> tuple[npt.NDArray[np.int64] | None, float, tuple[int, int, int, int]]:
    """The window's cheapest path found with the cells where a path of cost <= ``bound``
    can pass, its cost and the box (r0, r1, c0, c1) of the region searched; no cells
    when that cannot be certified to equal the whole grid's (or a window's holding the
    box) result; the cost is then that of a path found in the region (an upper bound of
    the cheapest) or ``inf``.

    Let ``o_s(p)``, ``o_g(p)`` be the octile distances (m) of ``p`` to start and goal.
    A move costs at least its length, so every cell ``p`` on a cheapest path to ``n``
    has ``o_s(p) + o_g(p) <= d(n) + o_g(n)``: searching only the region ``R`` where
    ``o_s + o_g <= bound`` (with the Dijkstra limit ``bound``) gives the exact field
    value ``v(n) = d(n)`` for every ``n`` with ``d(n) + o_g(n) <= bound`` (certified
    when ``v(n) + o_g(n) <= bound``), and for every other cell ``d(n) > bound - o_g(n)``
    (``R`` keeps a margin of 2 cells for the side cells of diagonal moves).
    The descent from the goal (:func:`~explore_seg.core.paths.extract_path`, same
    neighbour order and strict comparison) is replayed on ``v``; it equals the whole
    window's when at every step each neighbour is either certified or provably no
    better than the best so far. Edge costs are computed by the same code
    (:func:`~explore_seg.core.paths.cost_distance_field`) from the same cell costs, so
    certified values are bit-identical.
    """
    h, w = cost.shape
    res = float(resolution_m)
    slack = bound * _PRUNE_SLACK
    lim_cells = (bound + slack) / res
    (sr, sc), (gr, gc) = start, goal
    if _octile(start, goal) > lim_cells:
        return None, math.inf, (0, 0, 0, 0)
    # The region keeps 2 cells more, so that the side cells of every diagonal move of
    # such a path are in it too (a diagonal needs both passable). Its bounding box:
    # o_s + o_g >= |r - sr| + |r - gr| (and so for columns).
    span = lim_cells + 2.0
    r_lo = int(math.floor((sr + gr - span) / 2.0))
    r_hi = int(math.ceil((sr + gr + span) / 2.0)) + 1
    c_lo = int(math.floor((sc + gc - span) / 2.0))
    c_hi = int(math.ceil((sc + gc + span) / 2.0)) + 1
    r0, r1, c0, c1 = max(0, r_lo), min(h, r_hi), max(0, c_lo), min(w, c_hi)
    rows = np.arange(r0, r1, dtype=np.int64)[:, None]
    cols = np.arange(c0, c1, dtype=np.int64)[None, :]
    o_g = _octile_field(rows, cols, goal)
    region = _octile_field(rows, cols, start) + o_g <= span
    sub = np.where(region, cost[r0:r1, c0:c1], np.inf)
    s_loc, g_loc = (sr - r0, sc - c0), (gr - r0, gc - c0)
    dist = cost_distance_field(sub, s_loc, res, bound + slack)
    g = float(dist[g_loc])
    cert_lim = bound - slack
    box = (r0, r1, c0, c1)
    if not g <= cert_lim:
        return None, g, box
    return _certified_descent(dist, g_loc, o_g * res, cert_lim, (r0, c0), (h, w), res), g, box


def _certified_descent(dist: npt.NDArray[np.float64], goal: tuple[int, int],
                       o_g_m: npt.NDArray[np.float64], cert_lim: float,
                       offset: tuple[int, int], full_shape: tuple[int, int],
                       resolution_m: float) -> npt.NDArray[np.int64] | None:
    """:func:`~explore_seg.core.paths.extract_path` on a field ``dist`` that is exact
    only where ``dist + o_g_m <= cert_lim`` (see :func:`_pruned_search`); ``dist`` covers
    the box at ``offset`` of a window of ``full_shape``, whose other cells count as
    uncertified. Returns the cells in window coordinates, or None when an uncertified
    neighbour could have been chosen."""
    hb, wb = dist.shape
    h, w = full_shape
    r0, c0 = offset
    gr, gc = goal[0] + r0, goal[1] + c0          # goal in window coordinates
    r, c = goal
    path = [(r, c)]
    limit = h * w
    while dist[r, c] > 0 and len(path) < limit:
        best = (dist[r, c], r, c)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                if not (dr or dc):
                    continue
                rr, cc = r + dr, c + dc
                ar, ac = rr + r0, cc + c0
                if not (0 <= ar < h and 0 <= ac < w):
                    continue                    # outside the window: never a neighbour
                if 0 <= rr < hb and 0 <= cc < wb:
                    v, og = dist[rr, cc], o_g_m[rr, cc]
                    if v + og <= cert_lim:      # exact value
                        if v < best[0]:
                            best = (v, rr, cc)
                        continue
                else:
                    og = _octile((ar, ac), (gr, gc)) * resolution_m
                # Uncertified: its true value exceeds cert_lim - og (see _pruned_search);
                # it cannot be chosen when that is no better than the best so far.
                if not cert_lim - og >= best[0]:
                    return None
        if best[1] == r and best[2] == c:
            break
        r, c = best[1], best[2]
        path.append((r, c))
    return np.asarray(path[::-1], dtype=np.int64) + np.array([r0, c0], dtype=np.int64)


def path_cost(xy: npt.NDArray[np.float64], cost: npt.NDArray[np.float64], grid: GridMap
              ) -> float:
    """Cost of a world polyline on a cost grid (``inf`` if it crosses a lethal cell or
    leaves the grid); each segment is charged its length times its end cell's cost."""
    if len(xy) < 2:
        return 0.0
    rows, cols = grid.world_to_cells(xy[:, 0], xy[:, 1])
    if (rows.min() < 0 or cols.min() < 0 or rows.max() >= cost.shape[0]
            or cols.max() >= cost.shape[1]):
        return math.inf
    seg = np.hypot(np.diff(xy[:, 0]), np.diff(xy[:, 1]))
    return float((seg * cost[rows[1:], cols[1:]]).sum())


def coarsen(cost: npt.NDArray[np.float64], start: tuple[int, int], goal: tuple[int, int],
            k: int) -> tuple[npt.NDArray[np.float64], tuple[int, int], tuple[int, int]]:
    """Block-max downsampling by ``k`` (a coarse cell costs its worst fine cell; cells
    past the border count as lethal)."""
    if k == 1:
        return cost, start, goal
    h, w = cost.shape
    hp, wp = -(-h // k) * k, -(-w // k) * k
    pad = np.full((hp, wp), np.inf)
    pad[:h, :w] = cost
    coarse = pad[0::k, 0::k].copy()
    for dr in range(k):
        for dc in range(k):
            if dr or dc:
                np.maximum(coarse, pad[dr::k, dc::k], out=coarse)
    return coarse, (start[0] // k, start[1] // k), (goal[0] // k, goal[1] // k)
