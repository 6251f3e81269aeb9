"""Planning of the navigation stand-in, after Nav2's NavFn on an inflated costmap.

:func:`cost_grid` builds the per-metre cost of an inflated costmap (lethal within
``robot_radius_m + inflation_margin_m``, an exponentially decaying inflation band, a
surcharge through unknown cells); :func:`plan_path` runs the cost-weighted 8-connected
Dijkstra on a window around start and goal that grows until it provably holds the
cheapest path; :func:`coarsen` downsamples a cost grid for planning on coarser cells.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.paths import cost_distance_field, extract_path, inflate
from sim_bridge.navigation.params import NavParams


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
        free = np.ascontiguousarray(~blocked, dtype=np.uint8)
        d = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * resolution_m
        band = ~lethal & (d < params.inflation_radius_m)
        excess = np.maximum(d[band] - params.lethal_radius_m, 0.0)
        cost[band] += params.inflation_cost_weight * np.exp(-params.inflation_cost_scale * excess)
    if params.inflation_soft_margin_m > 0 and blocked.any():   # near-lethal band
        soft = inflate(blocked, params.lethal_radius_m + params.inflation_soft_margin_m,
                       resolution_m) & ~lethal
        cost[soft] += params.inflation_soft_margin_cost
    if unknown is not None and params.unknown_cost > 0:
        cost[unknown] += params.unknown_cost
    cost[lethal] = np.inf
    return cost


def plan_path(cost: npt.NDArray[np.float64], start_rc: tuple[int, int],
              goal_rc: tuple[int, int], resolution_m: float, window_margin_m: float
              ) -> tuple[npt.NDArray[np.int64], float] | None:
    """Cheapest path from start to goal over a cost grid, searched in a growing window.

    Costs are >= 1 per metre, so a path of cost <= L is at most L long and lies in the
    ellipse of points whose distances to start and goal sum to <= L. The search runs on
    that ellipse's bounding box for ``L = 1.5 * |goal - start| + window_margin_m``; a
    path found there with cost <= L is the global optimum. Otherwise L doubles, up to
    the whole grid.

    Returns
    -------
    (cells, cost) or None
        cells: ndarray of int64, shape (N, 2), (row, col), start first; cost: its total
        cost. None when the goal is unreachable.
    """
    h, w = cost.shape
    (sr, sc), (gr, gc) = start_rc, goal_rc
    budget = 1.5 * math.hypot(gr - sr, gc - sc) * resolution_m + window_margin_m
    while True:
        half = budget / resolution_m / 2.0 + 1.0
        cr, cc = (sr + gr) / 2.0, (sc + gc) / 2.0
        r0, r1 = max(0, int(cr - half)), min(h, int(math.ceil(cr + half)) + 1)
        c0, c1 = max(0, int(cc - half)), min(w, int(math.ceil(cc + half)) + 1)
        whole = r0 == 0 and c0 == 0 and r1 == h and c1 == w
        dist = cost_distance_field(cost[r0:r1, c0:c1], (sr - r0, sc - c0), resolution_m,
                                   math.inf if whole else budget)
        g = float(dist[gr - r0, gc - c0])
        if math.isfinite(g) and (g <= budget or whole):
            cells = extract_path(dist, (gr - r0, gc - c0))
            return cells + np.array([r0, c0], dtype=np.int64), g
        if whole:
            return None
        budget *= 2.0


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
