"""Grid path distances: obstacle inflation, one-sweep distance fields, path extraction.

All functions work on boolean masks in grid layout (row = y, col = x). Distances are in
metres along 8-connected moves (diagonal = sqrt(2) cells); unreachable cells are ``inf``.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

SQRT2 = math.sqrt(2.0)
# (drow, dcol, step length in cells)
_MOVES: tuple[tuple[int, int, float], ...] = (
    (0, 1, 1.0), (1, 0, 1.0), (1, 1, SQRT2), (1, -1, SQRT2),
)


def disk_kernel(radius_cells: int) -> npt.NDArray[np.uint8]:
    """Square uint8 kernel of side ``2r+1`` holding a filled disk of radius ``r`` cells."""
    r = int(radius_cells)
    if r < 0:
        raise ValueError(f"radius_cells must be >= 0, got {radius_cells}")
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    return ((xx * xx + yy * yy) <= r * r + 1e-9).astype(np.uint8)


def inflate(blocked: npt.NDArray[np.bool_], radius_m: float, resolution_m: float
            ) -> npt.NDArray[np.bool_]:
    """Grow ``blocked`` by a disk of ``radius_m`` (cells whose centre is within the radius).

    Parameters
    ----------
    blocked : ndarray of bool, shape (H, W)
    radius_m : float
        Inflation radius, >= 0.
    resolution_m : float
        Metres per cell, > 0.

    Returns
    -------
    ndarray of bool, shape (H, W)

    Examples
    --------
    >>> m = np.zeros((5, 5), bool); m[2, 2] = True
    >>> int(inflate(m, 0.1, 0.05).sum())
    13
    """
    if not resolution_m > 0:
        raise ValueError(f"resolution_m must be > 0, got {resolution_m}")
    if not radius_m >= 0:
        raise ValueError(f"radius_m must be >= 0, got {radius_m}")
    r = int(math.floor(radius_m / resolution_m + 1e-9))
    if r == 0 or not blocked.any():
        return blocked.copy()
    out = cv2.dilate(blocked.astype(np.uint8), disk_kernel(r), borderType=cv2.BORDER_CONSTANT,
                     borderValue=0)
    return out.astype(bool)


def _check_start(passable: np.ndarray, start_rc: tuple[int, int]) -> None:
    if passable.ndim != 2:
        raise ValueError(f"passable must be 2D, got shape {passable.shape}")
    r, c = start_rc
    if not (0 <= r < passable.shape[0] and 0 <= c < passable.shape[1]):
        raise ValueError(f"start cell {start_rc} outside grid of shape {passable.shape}")


def distance_field(passable: npt.NDArray[np.bool_], start_rc: tuple[int, int],
                   resolution_m: float = 1.0) -> npt.NDArray[np.float64]:
    """Shortest 8-connected path length from ``start_rc`` to every cell, in metres.

    A diagonal move is allowed only when both side cells are passable (no corner
    cutting). The start cell itself is treated as passable even when it is not, so a
    robot standing on an inflated margin still gets distances.

    Parameters
    ----------
    passable : ndarray of bool, shape (H, W)
    start_rc : (int, int)
        Start cell (row, col), inside the grid.
    resolution_m : float
        Scale of one cell step.

    Returns
    -------
    ndarray of float64, shape (H, W)
        ``inf`` for unreachable cells.

    Raises
    ------
    ValueError
        When the start cell lies outside the grid.
    """
    passable = np.asarray(passable, dtype=bool)
    _check_start(passable, start_rc)
    h, w = passable.shape
    pas = passable.copy()
    pas[start_rc] = True
    idx = np.full((h, w), -1, dtype=np.int64)
    n = int(pas.sum())
    idx[pas] = np.arange(n)
    src_list, dst_list, wt_list = [], [], []
    for dr, dc, step in _MOVES:
        r0, r1 = max(0, -dr), h - max(0, dr)
        c0, c1 = max(0, -dc), w - max(0, dc)
        a = pas[r0:r1, c0:c1]
        b = pas[r0 + dr:r1 + dr, c0 + dc:c1 + dc]
        ok = a & b
        if dr != 0 and dc != 0:
            ok &= pas[r0 + dr:r1 + dr, c0:c1] & pas[r0:r1, c0 + dc:c1 + dc]
        ia = idx[r0:r1, c0:c1][ok]
        ib = idx[r0 + dr:r1 + dr, c0 + dc:c1 + dc][ok]
        src_list.append(ia)
        dst_list.append(ib)
        wt_list.append(np.full(ia.shape, step * resolution_m))
    src = np.concatenate(src_list)
    dst = np.concatenate(dst_list)
    wts = np.concatenate(wt_list)
    graph = csr_matrix((wts, (src, dst)), shape=(n, n))
    d = dijkstra(graph, directed=False, indices=int(idx[start_rc]))
    out = np.full((h, w), np.inf)
    out[pas] = d
    return out


def extract_path(dist: npt.NDArray[np.float64], goal_rc: tuple[int, int]
                 ) -> npt.NDArray[np.int64]:
    """Cells from the field's start to ``goal_rc`` by steepest descent of ``dist``.

    Returns
    -------
    ndarray of int64, shape (N, 2)
        (row, col) cells, start first, goal last.

    Raises
    ------
    ValueError
        When the goal is outside the grid or unreachable (``dist`` is inf).
    """
    h, w = dist.shape
    r, c = int(goal_rc[0]), int(goal_rc[1])
    if not (0 <= r < h and 0 <= c < w):
        raise ValueError(f"goal cell {goal_rc} outside grid of shape {dist.shape}")
    if not np.isfinite(dist[r, c]):
        raise ValueError(f"goal cell {goal_rc} is unreachable")
    path = [(r, c)]
    limit = h * w
    while dist[r, c] > 0 and len(path) < limit:
        best = (dist[r, c], r, c)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rr, cc = r + dr, c + dc
                if (dr or dc) and 0 <= rr < h and 0 <= cc < w and dist[rr, cc] < best[0]:
                    best = (dist[rr, cc], rr, cc)
        if best[1] == r and best[2] == c:
            break
        r, c = best[1], best[2]
        path.append((r, c))
    return np.asarray(path[::-1], dtype=np.int64)


def path_length_m(cells: npt.NDArray[np.int64], resolution_m: float) -> float:
    """Length of a cell path (sum of step lengths) in metres."""
    if len(cells) < 2:
        return 0.0
    d = np.diff(np.asarray(cells, dtype=np.float64), axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum() * resolution_m)


def nearest_true(mask: npt.NDArray[np.bool_], rc: tuple[int, int], max_radius_cells: int
                 ) -> tuple[int, int] | None:
    """Closest cell (Euclidean) with ``mask`` true within a square window, or None."""
    h, w = mask.shape
    r, c = rc
    r0, r1 = max(0, r - max_radius_cells), min(h, r + max_radius_cells + 1)
    c0, c1 = max(0, c - max_radius_cells), min(w, c + max_radius_cells + 1)
    if r0 >= r1 or c0 >= c1:
        return None
    sub = mask[r0:r1, c0:c1]
    rr, cc = np.nonzero(sub)
    if rr.size == 0:
        return None
    d2 = (rr + r0 - r) ** 2 + (cc + c0 - c) ** 2
    k = int(np.argmin(d2))
    return int(rr[k] + r0), int(cc[k] + c0)
