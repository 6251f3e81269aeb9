"""Open tours over viewpoints: greedy construction, then 2-opt and Or-opt improvement.

The tour starts at node 0 (the robot) and visits every other node once; it does not
return (an open path, the asymmetric TSP with free return to node 0). Costs are a dense
``(n, n)`` matrix in metres: ``cost[i, j]`` is the cost of driving from node ``i`` to node
``j`` (row 0: from the robot; column 0 is never used). Between viewpoints the matrix may be
asymmetric (a region-change penalty, a one-way path estimate): 2-opt evaluates reversed
segments with the reversed edges' own costs, so every accepted move shortens the tour.

Everything is vectorised over the candidate moves of one pass (numpy), so one pass costs
``O(n^2)`` array work; with the tens of viewpoints of a house a tour takes about a
millisecond.

Examples
--------
>>> import numpy as np
>>> xy = np.array([[0.0, 0.0], [3.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
>>> cost = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
>>> t = solve_tour(cost)
>>> t.order.tolist(), float(t.length_m)
([2, 3, 1], 3.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

#: Improvement passes at most (each applies the best move of its kind).
MAX_PASSES = 200
#: Longest segment Or-opt moves.
OR_OPT_MAX_SEGMENT = 3
_EPS = 1e-9


@dataclass(frozen=True)
class Tour:
    """An open tour from node 0.

    Attributes
    ----------
    order : ndarray of int64, shape (n - 1,)
        The nodes 1..n-1 in visiting order.
    length_m : float
        Sum of ``cost`` along 0 -> order[0] -> ... -> order[-1].
    """

    order: npt.NDArray[np.int64]
    length_m: float


def tour_length(cost: npt.NDArray[np.float64], order: npt.ArrayLike) -> float:
    """Length of the open tour 0 -> ``order`` under ``cost``."""
    path = np.concatenate([[0], np.asarray(order, dtype=np.int64)])
    return float(cost[path[:-1], path[1:]].sum()) if len(path) > 1 else 0.0


def greedy_order(cost: npt.NDArray[np.float64], first: int | None = None
                 ) -> npt.NDArray[np.int64]:
    """Nearest-neighbour order from node 0 (``first``: the node visited first)."""
    n = cost.shape[0]
    left = np.ones(n, dtype=bool)
    left[0] = False
    order: list[int] = []
    cur = 0
    if first is not None:
        order.append(int(first))
        left[first] = False
        cur = int(first)
    while left.any():
        row = np.where(left, cost[cur], np.inf)
        nxt = int(np.argmin(row))
        order.append(nxt)
        left[nxt] = False
        cur = nxt
    return np.asarray(order, dtype=np.int64)


def _pairs(m: int, lo: int) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """All index pairs ``lo <= i < j < m`` (row-major), the 2-opt moves of a path of
    ``m`` nodes."""
    ii, jj = np.triu_indices(m - lo, k=1)
    return ii.astype(np.int64) + lo, jj.astype(np.int64) + lo


def _two_opt_pass(cost: npt.NDArray[np.float64], path: npt.NDArray[np.int64], lo: int,
                  pairs: tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]] | None = None
                  ) -> bool:
    """Apply the best segment reversal of ``path[i..j]`` (``lo <= i < j``); True if any.
    ``pairs``: :func:`_pairs` of ``(len(path), lo)`` when the caller keeps them."""
    m = len(path)
    if m - lo < 2:
        return False
    # Prefix sums of forward and backward edge costs along the path.
    fwd = cost[path[:-1], path[1:]]
    bwd = cost[path[1:], path[:-1]]
    cf = np.concatenate([[0.0], np.cumsum(fwd)])
    cb = np.concatenate([[0.0], np.cumsum(bwd)])
    ii, jj = pairs if pairs is not None else _pairs(m, lo)
    inner_old = cf[jj] - cf[ii]                    # edges i..j forward
    inner_new = cb[jj] - cb[ii]                    # the same edges driven backwards
    pi, pj = path[ii], path[jj]
    before = path[ii - 1]
    before_old = cost[before, pi]
    before_new = cost[before, pj]
    has_after = jj < m - 1
    after = path[np.minimum(jj + 1, m - 1)]
    after_old = np.where(has_after, cost[pj, after], 0.0)
    after_new = np.where(has_after, cost[pi, after], 0.0)
    delta = (before_new + inner_new + after_new) - (before_old + inner_old + after_old)
    k = int(np.argmin(delta))
    if not delta[k] < -_EPS:
        return False
    a, b = int(ii[k]), int(jj[k])
    path[a:b + 1] = path[a:b + 1][::-1].copy()
    return True


def _or_opt_pass(cost: npt.NDArray[np.float64], path: npt.NDArray[np.int64], lo: int
                 ) -> npt.NDArray[np.int64] | None:
    """Apply the best move of a segment of 1..OR_OPT_MAX_SEGMENT nodes (``path[i..i+s-1]``,
    ``i >= lo``) to another place, kept or reversed; the new path, or None."""
    m = len(path)
    best = (-_EPS, None)
    for s in range(1, OR_OPT_MAX_SEGMENT + 1):
        if m - lo < s + 1:
            break
        starts = np.arange(lo, m - s + 1)
        ends = starts + s - 1
        prev = path[starts - 1]
        first, last = path[starts], path[ends]
        has_next = ends < m - 1
        nxt = path[np.minimum(ends + 1, m - 1)]
        removed = (cost[prev, first] + np.where(has_next, cost[last, nxt], 0.0)
                   - np.where(has_next, cost[prev, nxt], 0.0))
        # Cost along each segment, forwards and backwards (edges summed in path order).
        inner_f = np.zeros(len(starts))
        inner_b = np.zeros(len(starts))
        for t in range(s - 1):
            inner_f = inner_f + cost[path[starts + t], path[starts + t + 1]]
        for t in range(s - 1, 0, -1):
            inner_b = inner_b + cost[path[starts + t], path[starts + t - 1]]
        # Insert between path[p] and path[p+1] (p == m - 1: at the end), p outside the
        # segment and not its old place.
        p = np.arange(lo - 1, m)[None, :]
        ok = (p < starts[:, None] - 1) | (p > ends[:, None])
        u = path[p]                                               # (1, P)
        at_end = p == m - 1
        w = path[np.minimum(p + 1, m - 1)]
        base = np.where(at_end, 0.0, cost[u, w])
        add_f = (cost[u, first[:, None]] + np.where(at_end, 0.0, cost[last[:, None], w])
                 - base)
        add_b = (cost[u, last[:, None]] + np.where(at_end, 0.0, cost[first[:, None], w])
                 - base + (inner_b - inner_f)[:, None])
        for add, rev in ((add_f, False), (add_b, True)):
            delta = np.where(ok, add - removed[:, None], np.inf)
            k = int(np.argmin(delta))
            if delta.flat[k] < best[0]:
                r, c = divmod(k, delta.shape[1])
                best = (float(delta.flat[k]), (int(starts[r]), s, int(p[0, c]), rev))
    if best[1] is None:
        return None
    a, s, p, rev = best[1]
    seg = path[a:a + s]
    if rev:
        seg = seg[::-1]
    rest = np.concatenate([path[:a], path[a + s:]])
    q = p + 1 if p < a else p + 1 - s                 # insertion index in ``rest``
    return np.concatenate([rest[:q], seg, rest[q:]]).astype(np.int64)


def improve(cost: npt.NDArray[np.float64], order: npt.ArrayLike, fixed_first: bool = False
            ) -> npt.NDArray[np.int64]:
    """2-opt and Or-opt on an open tour from node 0 until no move shortens it.

    Parameters
    ----------
    cost : ndarray of float64, shape (n, n)
    order : array_like of int, shape (n - 1,)
    fixed_first : bool
        Keep ``order[0]`` first (the tour of a given next goal).

    Returns
    -------
    ndarray of int64, shape (n - 1,)
        Never longer than ``order``.
    """
    path = np.concatenate([[0], np.asarray(order, dtype=np.int64)])
    lo = 2 if fixed_first else 1
    pairs = _pairs(len(path), lo) if len(path) - lo >= 2 else None
    for _ in range(MAX_PASSES):
        if _two_opt_pass(cost, path, lo, pairs):
            continue
        moved = _or_opt_pass(cost, path, lo)
        if moved is None:
            break
        path = moved
    return path[1:].copy()


def solve_tour(cost: npt.ArrayLike, first: int | None = None) -> Tour:
    """Short open tour from node 0 over all nodes: greedy, then :func:`improve`.

    Parameters
    ----------
    cost : array_like of float, shape (n, n)
        Finite, >= 0 travel costs (row 0 from the start).
    first : int, optional
        Node to visit first (kept first by the improvement).

    Returns
    -------
    Tour

    Raises
    ------
    ValueError
        On a non-square matrix, negative or non-finite costs, or a bad ``first``.
    """
    c = np.asarray(cost, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] != c.shape[1] or c.shape[0] < 1:
        raise ValueError(f"cost must be a square (n, n) matrix with n >= 1, got {c.shape}")
    if not np.all(np.isfinite(c)) or np.any(c < 0):
        raise ValueError("cost must be finite and >= 0")
    n = c.shape[0]
    if first is not None and not 1 <= first < n:
        raise ValueError(f"first must be in 1..{n - 1}, got {first}")
    if n == 1:
        return Tour(np.zeros(0, dtype=np.int64), 0.0)
    order = improve(c, greedy_order(c, first), fixed_first=first is not None)
    return Tour(order, tour_length(c, order))


def front_costs(cost: npt.NDArray[np.float64], tour: Tour) -> npt.NDArray[np.float64]:
    """Length of the tour when each node is moved to the front (visited next), the rest
    in the tour's order: ``out[tour.order[0]] == tour.length_m``; ``out[0]`` is 0.

    Returns
    -------
    ndarray of float64, shape (n,)
    """
    n = cost.shape[0]
    out = np.zeros(n)
    order = tour.order
    if len(order) == 0:
        return out
    path = np.concatenate([[0], order])
    pos = np.arange(1, len(path))
    node = path[pos]
    prev = path[pos - 1]
    has_next = pos < len(path) - 1
    nxt = path[np.minimum(pos + 1, len(path) - 1)]
    removed = (cost[prev, node] + np.where(has_next, cost[node, nxt], 0.0)
               - np.where(has_next, cost[prev, nxt], 0.0))
    head = path[1]
    # Moved to the front: 0 -> node -> head ... (node's old place bridged).
    moved = tour.length_m - removed - cost[0, head] + cost[0, node] + cost[node, head]
    out[node] = np.where(node == head, tour.length_m, moved)
    # A node that was second: 0 -> node -> head -> rest (formula holds; head == prev).
    return out


__all__ = ["MAX_PASSES", "OR_OPT_MAX_SEGMENT", "Tour", "front_costs", "greedy_order",
           "improve", "solve_tour", "tour_length"]
