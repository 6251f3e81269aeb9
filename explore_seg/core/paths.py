"""Grid path distances: obstacle inflation, one-sweep distance fields, path extraction.

All functions work on boolean masks in grid layout (row = y, col = x). Distances are in
metres along 8-connected moves (diagonal = sqrt(2) cells); unreachable cells are ``inf``.

Two one-sweep solvers share one graph model (8-connected moves, a diagonal only when
both side cells are passable, so reachability equals 4-connectivity):

* :func:`distance_field` is exact: Dijkstra on every passable cell of the start's
  connected component (cropped to its bounding box); :func:`cost_distance_field`, its
  weighted form, builds every cell's 8 move costs from slices of the padded grid.
* :func:`explore_seg.core.block_graph.block_distances` is the fast approximation used by
  target selection: Dijkstra on a graph whose nodes are the 4-connected pieces of
  passable cells inside ``k x k`` blocks. Reachability stays exact (a piece is internally connected and two pieces are
  joined only where two of their cells touch), only lengths are approximated, see its
  docstring for the error bound.
"""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np
import numpy.typing as npt
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from explore_seg.core.grid import metres_to_cells

SQRT2 = math.sqrt(2.0)
#: Largest inflation radius done with a disk kernel; larger radii use a distance transform
#: (bounded work and memory whatever the radius in cells).
_MAX_KERNEL_RADIUS_CELLS = 32
# (drow, dcol, step length in cells): the 8 moves of the grid graph.
_MOVES8: tuple[tuple[int, int, float], ...] = (
    (0, 1, 1.0), (1, 0, 1.0), (0, -1, 1.0), (-1, 0, 1.0),
    (1, 1, SQRT2), (1, -1, SQRT2), (-1, 1, SQRT2), (-1, -1, SQRT2),
)


def disk_kernel(radius_cells: float) -> npt.NDArray[np.uint8]:
    """Square uint8 kernel of side ``2 floor(r) + 1`` holding the offsets whose centre is
    within ``r`` cells of the middle one (``r`` may be fractional: 4.4 cells holds the
    offset (4, 1), 4.12 cells away, which 4 cells does not).

    Examples
    --------
    >>> int(disk_kernel(4).sum()), int(disk_kernel(4.4).sum())
    (49, 61)
    """
    rr = float(radius_cells)
    if not rr >= 0:
        raise ValueError(f"radius_cells must be >= 0, got {radius_cells}")
    r = int(math.floor(rr + 1e-9))
    yy, xx = np.mgrid[-r:r + 1, -r:r + 1]
    return ((xx * xx + yy * yy) <= rr * rr + 1e-9).astype(np.uint8)


def obstacle_distance_cells(blocked: npt.NDArray[np.bool_]) -> npt.NDArray[np.float32]:
    """Exact Euclidean distance (cells) from every cell to the nearest blocked cell: the
    float32 square root of the exact squared distance, as OpenCV's own
    ``DIST_MASK_PRECISE`` transform gives it. Intel IPP's version, which OpenCV 4.14 uses
    for images of fewer than 128 x 128 cells, rounds some roots differently, so it is
    switched off for the call: a cell's value must not depend on the size of the window
    it was computed in (the navigation stand-in's costmap is updated in windows)."""
    free = np.ascontiguousarray(~blocked, dtype=np.uint8)
    use_ipp = cv2.ipp.useIPP()
    cv2.ipp.setUseIPP(False)
    try:
        return cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    finally:
        cv2.ipp.setUseIPP(use_ipp)


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
    r = metres_to_cells(radius_m, resolution_m)
    if r == 0 or not blocked.any():
        return blocked.copy()
    rr = radius_m / resolution_m    # the disk is metric, not rounded down to whole cells
    if r > _MAX_KERNEL_RADIUS_CELLS:
        # A disk kernel of side 2r+1 costs O(r^2) memory and O(H*W*r) time (27 s and
        # 0.7 GB for r = 2200); the exact Euclidean distance to the nearest blocked cell
        # gives the same cells in O(H*W) for any radius.
        return obstacle_distance_cells(blocked) <= rr + 1e-3
    out = cv2.dilate(blocked.astype(np.uint8), disk_kernel(rr), borderType=cv2.BORDER_CONSTANT,
                     borderValue=0)
    return out.astype(bool)


def check_start(passable: np.ndarray, start_rc: tuple[int, int]) -> None:
    if passable.ndim != 2:
        raise ValueError(f"passable must be 2D, got shape {passable.shape}")
    r, c = start_rc
    if not (0 <= r < passable.shape[0] and 0 <= c < passable.shape[1]):
        raise ValueError(f"start cell {start_rc} outside grid of shape {passable.shape}")


def check_resolution(resolution_m: float) -> None:
    if not (math.isfinite(resolution_m) and resolution_m > 0):
        raise ValueError(f"resolution_m must be finite and > 0, got {resolution_m}")


def _component_box(pas: npt.NDArray[np.bool_], start_rc: tuple[int, int]
                   ) -> tuple[npt.NDArray[np.bool_], int, int]:
    """The start's 4-connected component of ``pas``, cropped to its bounding box.

    Returns (mask of the component inside the box, row offset, col offset).
    """
    _, lab, stats, _ = cv2.connectedComponentsWithStats(pas.view(np.uint8), connectivity=4,
                                                        ltype=cv2.CV_32S)
    k = int(lab[start_rc])
    x, y, w, h = (int(v) for v in stats[k, :4])
    return lab[y:y + h, x:x + w] == k, y, x


def grid_csr(pas: npt.NDArray[np.bool_], resolution_m: float
             ) -> tuple[csr_matrix, npt.NDArray[np.signedinteger]]:
    """Directed CSR graph (both directions stored) of the passable cells of ``pas``.

    Returns the graph and an (H, W) integer image of node ids (-1 where not passable).
    Edges are built row by row in node order, so no sorting is needed. A move costs its
    length (weighted fields use :func:`_cost_graph`).

    Neighbours are gathered through flat indices into a one-cell padded copy of the
    grid (one gather of N values per move instead of masking the whole box), in int32
    where the sizes allow (the index type scipy's graph routines use internally).
    """
    h, w = pas.shape
    w2 = w + 2
    size = (h + 2) * w2
    itype = np.int32 if 8 * size < np.iinfo(np.int32).max else np.int64
    padp = np.zeros((h + 2, w2), dtype=bool)
    padp[1:h + 1, 1:w + 1] = pas
    padp_flat = padp.ravel()
    flat = np.flatnonzero(padp_flat).astype(itype)    # padded flat index of each node
    n = int(flat.shape[0])
    idx_flat = np.full(size, -1, dtype=itype)
    idx_flat[flat] = np.arange(n, dtype=itype)
    nbr = np.empty((n, 8), dtype=itype)
    ok = np.empty((n, 8), dtype=bool)
    counts = np.zeros(n, dtype=itype)
    wts = np.empty(8, dtype=np.float64)
    for j, (dr, dc, step) in enumerate(_MOVES8):
        off = flat + itype(dr * w2 + dc)
        sub = idx_flat[off]
        good = sub >= 0
        if dr != 0 and dc != 0:
            good &= padp_flat[flat + itype(dr * w2)]
            good &= padp_flat[flat + itype(dc)]
        nbr[:, j] = sub
        ok[:, j] = good
        counts += good
        wts[j] = step * resolution_m
    indptr = np.zeros(n + 1, dtype=itype)
    np.cumsum(counts, out=indptr[1:])
    indices = nbr[ok]
    data = np.broadcast_to(wts, (n, 8))[ok]
    graph = csr_matrix((data, indices, indptr), shape=(n, n))
    return graph, idx_flat.reshape(h + 2, w2)[1:h + 1, 1:w + 1]


@functools.lru_cache(maxsize=4)
def _padded_topology(h: int, w: int) -> tuple[npt.NDArray[np.signedinteger],
                                              npt.NDArray[np.signedinteger]]:
    """CSR ``indices`` and ``indptr`` of the 8-neighbour graph of an (h, w) grid padded by
    one cell: node ``r * (w + 2) + c`` of the padded grid; each interior cell has its 8
    moves (in :data:`_MOVES8` order) as out-edges, the border cells none. Read-only,
    cached for the last 4 shapes (the planner's windows repeat; 31 MB of indices for a
    1200 x 800 grid)."""
    w2 = w + 2
    n = (h + 2) * w2
    itype = np.int32 if 8 * n < np.iinfo(np.int32).max else np.int64
    interior = np.zeros((h + 2, w2), dtype=itype)
    interior[1:h + 1, 1:w + 1] = 8
    indptr = np.zeros(n + 1, dtype=itype)
    np.cumsum(interior.ravel(), out=indptr[1:])
    base = (np.arange(1, h + 1, dtype=itype)[:, None] * itype(w2)
            + np.arange(1, w + 1, dtype=itype)[None, :]).ravel()
    offsets = np.array([dr * w2 + dc for dr, dc, _ in _MOVES8], dtype=itype)
    indices = (base[:, None] + offsets[None, :]).ravel()
    indices.flags.writeable = False
    indptr.flags.writeable = False
    return indices, indptr


def _cost_graph(cost: npt.NDArray[np.float64], resolution_m: float) -> csr_matrix:
    """:func:`cost_distance_field`'s graph of an (h, w) cost grid, on the padded grid of
    :func:`_padded_topology` (node of cell (r, c): ``(r + 1) * (w + 2) + c + 1``).

    A move costs ``0.5 * length * (cost of its two cells)``, ``inf`` (never relaxed by
    Dijkstra, as if absent) when a cell is impassable or, for a diagonal, a side cell
    is. Every cell gets its 8 edges with the same arithmetic, so the weights are
    built from slices instead of a compressed node set.
    """
    h, w = cost.shape
    pad = np.full((h + 2, w + 2), np.inf)
    pad[1:h + 1, 1:w + 1] = cost
    fin = np.isfinite(pad)
    own = pad[1:h + 1, 1:w + 1]
    data = np.empty((h, w, 8), dtype=np.float64)
    for j, (dr, dc, step) in enumerate(_MOVES8):
        out = data[:, :, j]
        np.add(own, pad[1 + dr:h + 1 + dr, 1 + dc:w + 1 + dc], out=out)
        out *= 0.5 * (step * resolution_m)
        if dr and dc:
            cut = ~(fin[1 + dr:h + 1 + dr, 1:w + 1] & fin[1:h + 1, 1 + dc:w + 1 + dc])
            out[cut] = np.inf
    indices, indptr = _padded_topology(h, w)
    n = indptr.shape[0] - 1
    return csr_matrix((data.ravel(), indices, indptr), shape=(n, n))


def distance_field(passable: npt.NDArray[np.bool_], start_rc: tuple[int, int],
                   resolution_m: float = 1.0) -> npt.NDArray[np.float64]:
    """Shortest 8-connected path length from ``start_rc`` to every cell, in metres.

    A diagonal move is allowed only when both side cells are passable (no corner
    cutting). The start cell itself is treated as passable even when it is not, so a
    robot standing on an inflated margin still gets distances. Exact (Dijkstra); only the
    start's connected component is searched.

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
        When the start cell lies outside the grid or the resolution is not > 0.
    """
    passable = np.asarray(passable, dtype=bool)
    check_start(passable, start_rc)
    return cost_distance_field(np.where(passable, 1.0, np.inf), start_rc, resolution_m)


def cost_distance_field(cost: npt.NDArray[np.float64], start_rc: tuple[int, int],
                        resolution_m: float = 1.0, limit: float = math.inf
                        ) -> npt.NDArray[np.float64]:
    """Cheapest 8-connected path cost from ``start_rc`` to every cell (weighted
    :func:`distance_field`).

    A move between neighbours costs ``step length * mean of the two cell costs``; cells
    with infinite cost are impassable; diagonal moves need both side cells passable (no
    corner cutting). The start is passable (cost 1 if it was not). Only the start's
    connected component is searched.

    Parameters
    ----------
    cost : ndarray of float64, shape (H, W)
        Per-metre cost, >= 1 (so costs bound lengths), ``inf`` = impassable.
    start_rc : (int, int)
        Start cell (row, col), inside the grid.
    resolution_m : float
        Step length of one cell.
    limit : float
        Cells costlier than this are not expanded (reported ``inf``).

    Returns
    -------
    ndarray of float64, shape (H, W)
        ``inf`` for unreachable cells.

    Raises
    ------
    ValueError
        When the start lies outside the grid or the resolution is not > 0.

    Examples
    --------
    >>> c = np.ones((1, 3)); c[0, 2] = 3.0
    >>> cost_distance_field(c, (0, 0)).tolist()
    [[0.0, 1.0, 3.0]]
    """
    cost = np.asarray(cost, dtype=np.float64)
    check_start(cost, start_rc)
    check_resolution(resolution_m)
    start = (int(start_rc[0]), int(start_rc[1]))
    if not np.isfinite(cost[start]):
        cost = cost.copy()
        cost[start] = 1.0
    pas = np.isfinite(cost)
    comp, r0, c0 = _component_box(pas, start)
    hb, wb = comp.shape
    box = np.where(comp, cost[r0:r0 + hb, c0:c0 + wb], np.inf)
    d = dijkstra(_cost_graph(box, resolution_m), directed=True,
                 indices=(start[0] - r0 + 1) * (wb + 2) + start[1] - c0 + 1, limit=limit)
    out = np.full(pas.shape, np.inf)
    out[r0:r0 + hb, c0:c0 + wb] = d.reshape(hb + 2, wb + 2)[1:hb + 1, 1:wb + 1]
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
