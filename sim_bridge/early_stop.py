"""Why a run ended below its coverage target: the frontiers left and the unseen gaps.

:func:`explain_stop` looks at the last decision of a run that stopped (``done`` or
``timeout``) below the target. It lists

* every frontier the explorer still had, with why it was not driven to (one of
  :data:`FRONTIER_REASONS`): ``blacklisted`` (within ``blacklist_radius_m`` of a failed
  goal), ``no passable cPoint`` (no cell clear of the robot radius near it), ``no path``
  (path length infinite), ``not selectable`` (finite path, infinite cost: the strategy
  ruled it out) or ``selectable`` (still a candidate: a timeout, or DONE raced a new one);
* every gap: a connected piece of the ground-truth explorable area the map does not know,
  with its area and cause (one of :data:`GAP_CAUSES`): the reason of a frontier on it,
  ``frontier too small`` (free cells border it but the frontier group was dropped by
  ``min_group_size_cells``), ``closed by object layer`` (the free cells that border it are
  obstacles in the object layer), ``behind mapped obstacles`` (bordered only by occupied
  or unknown cells: seen from nowhere the robot went, e.g. under furniture whose legs the
  lidar mapped) or ``outside the map``.

The run's ``cause`` is the cause of its largest gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams
from explore_seg.core.grid import GridMap
from sim_bridge.metrics import CoverageReference

FRONTIER_REASONS = ("blacklisted", "no passable cPoint", "no path", "not selectable",
                    "selectable")
GAP_CAUSES = FRONTIER_REASONS + ("frontier too small", "closed by object layer",
                                 "behind mapped obstacles", "outside the map")
_CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], np.uint8)


def frontier_reason(f: Frontier, dist_m: float, excluded: bool, cost: float) -> str:
    """Why a frontier left at the stop was not driven to (:data:`FRONTIER_REASONS`)."""
    if excluded:
        return "blacklisted"
    if not f.point_passable:
        return "no passable cPoint"
    if not math.isfinite(dist_m):
        return "no path"
    if not math.isfinite(cost):
        return "not selectable"
    return "selectable"


@dataclass(frozen=True, eq=False)
class FrontiersLeft:
    """The frontiers of a run's last decision (on the final map or the one just before)
    with their path lengths, blacklist mask and costs, each shape (N,) (None: unknown,
    taken as inf / False / inf)."""

    frontiers: Sequence[Frontier]
    dist_m: npt.ArrayLike | None = None
    excluded: npt.ArrayLike | None = None
    costs: npt.ArrayLike | None = None


def explain_stop(grid: GridMap, reference: CoverageReference, left: FrontiersLeft,
                 params: FrontierParams, extra_obstacles: npt.NDArray[np.bool_] | None = None,
                 max_items: int = 10) -> dict[str, Any]:
    """The frontiers and unseen gaps at the end of a run (see the module docstring).

    Parameters
    ----------
    grid : GridMap
        The final map.
    reference : CoverageReference
        The ground-truth explorable cells.
    left : FrontiersLeft
        The frontiers of the last decision, their path lengths, blacklist mask and costs.
    params : FrontierParams
        Thresholds and ``min_group_size_cells`` of the detection.
    extra_obstacles : ndarray of bool, shape of ``grid``, optional
        The object layer's obstacle cells on ``grid`` (None: no layer).
    max_items : int
        At most this many frontiers and gaps are listed (largest first).

    Returns
    -------
    dict
        ``missing_m2``, ``cause``, ``gaps`` (``xy_m``, ``area_m2``, ``cause``,
        ``frontier_xy_m`` of the frontier on it or None), ``n_gaps``, ``n_frontiers`` and
        ``frontiers`` (``xy_m``, ``size_cells``, ``dist_m``, ``reason``), JSON-able.
    """
    frontiers = left.frontiers
    n = len(frontiers)
    dist = _vec(left.dist_m, n, math.inf)
    excl = _vec(left.excluded, n, 0.0) > 0
    cost = _vec(left.costs, n, math.inf)
    reasons = [frontier_reason(f, dist[i], bool(excl[i]), cost[i]) for i, f in enumerate(frontiers)]
    # frontier id per map cell
    fid = np.full(grid.shape, -1, dtype=np.int32)
    for i, f in enumerate(frontiers):
        ok = ((f.cells[:, 0] >= 0) & (f.cells[:, 0] < grid.height)
              & (f.cells[:, 1] >= 0) & (f.cells[:, 1] < grid.width))
        fid[f.cells[ok, 0], f.cells[ok, 1]] = i
    vals = reference.values_at_inside(grid)
    missing = reference.inside & (vals < 0)
    res_ref = reference.geometry.resolution_m
    gaps: list[dict[str, Any]] = []
    if missing.any():
        k, lab, stats, _ = cv2.connectedComponentsWithStats(missing.astype(np.uint8), 8)
        order = sorted(range(1, k), key=lambda j: -stats[j, cv2.CC_STAT_AREA])
        for j in order:
            rr, cc = np.nonzero(lab == j)
            x, y = reference.geometry.cells_to_world(rr, cc)
            cause, fi = _gap_cause(grid, x, y, fid, reasons, params, extra_obstacles)
            gaps.append({"xy_m": [round(float(np.mean(x)), 2), round(float(np.mean(y)), 2)],
                         "area_m2": round(float(rr.size * res_ref ** 2), 3), "cause": cause,
                         "frontier_xy_m": (None if fi is None else
                                           [round(float(v), 2) for v in frontiers[fi].point_xy_m])})
    fr_out = [{"xy_m": [round(float(f.point_xy_m[0]), 2), round(float(f.point_xy_m[1]), 2)],
               "size_cells": int(f.size_cells),
               "dist_m": round(float(dist[i]), 2) if math.isfinite(dist[i]) else None,
               "reason": reasons[i]} for i, f in enumerate(frontiers)]
    fr_out.sort(key=lambda d: -d["size_cells"])
    return {"missing_m2": round(float(missing.sum() * res_ref ** 2), 3),
            "cause": gaps[0]["cause"] if gaps else ("no gap" if not fr_out else fr_out[0]["reason"]),
            "gaps": gaps[:max_items], "n_gaps": len(gaps), "frontiers": fr_out[:max_items],
            "n_frontiers": n}


def _vec(v: npt.ArrayLike | None, n: int, fill: float) -> npt.NDArray[np.float64]:
    if v is None:
        return np.full(n, fill)
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    return a if a.shape[0] == n else np.full(n, fill)


def _gap_cause(grid: GridMap, x: npt.NDArray[np.float64], y: npt.NDArray[np.float64],
               fid: npt.NDArray[np.int32], reasons: list[str], params: FrontierParams,
               extra: npt.NDArray[np.bool_] | None) -> tuple[str, int | None]:
    """Cause of one gap (world points of its cells) and the frontier index it rests on."""
    r, c = grid.world_to_cells(x, y)
    ok = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
    if not ok.any():
        return "outside the map", None
    r, c = r[ok], c[ok]
    r0, r1 = max(0, int(r.min()) - 2), min(grid.height, int(r.max()) + 3)
    c0, c1 = max(0, int(c.min()) - 2), min(grid.width, int(c.max()) + 3)
    gap = np.zeros((r1 - r0, c1 - c0), np.uint8)
    gap[r - r0, c - c0] = 1
    near = cv2.dilate(gap, np.ones((3, 3), np.uint8)).astype(bool)
    ids = fid[r0:r1, c0:c1][near]
    ids = ids[ids >= 0]
    if ids.size:
        # the frontier most of the gap's border rests on
        i = int(np.bincount(ids).argmax())
        return reasons[i], i
    data = grid.data[r0:r1, c0:c1]
    ring = cv2.dilate(gap, _CROSS).astype(bool) & ~gap.astype(bool)
    free = (data >= 0) & (data < params.free_threshold) & ring
    if extra is not None:
        blocked = extra[r0:r1, c0:c1]
        if (free & ~blocked).any():
            return "frontier too small", None
        if (free & blocked).any():
            return "closed by object layer", None
    elif free.any():
        return "frontier too small", None
    return "behind mapped obstacles", None
