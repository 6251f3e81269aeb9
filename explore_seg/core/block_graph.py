"""Block graph: fast one-sweep approximate path lengths on a passability mask.

Dijkstra on a graph whose nodes are the 4-connected pieces of passable cells inside
``k x k`` blocks (:class:`BlockGraph`, :func:`block_distances`). Reachability stays exact
(a piece is internally connected and two pieces are joined only where two of their cells
touch); only lengths are approximated (see :class:`BlockGraph` for the error bound).
``k = 1`` is the exact 8-connected grid graph of :mod:`explore_seg.core.paths`.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import numpy.typing as npt
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from explore_seg.core.paths import check_resolution, check_start, grid_csr, nearest_true

#: Largest block side supported by :func:`block_distances` (its lookup table has
#: 2**(k*k) entries).
MAX_BLOCK_CELLS = 4



@functools.lru_cache(maxsize=MAX_BLOCK_CELLS)
def _block_tables(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lookup tables over all 2**(k*k) passability patterns of a ``k x k`` block.

    Bit ``i*k + j`` of a pattern is cell (i, j) of the block. Returns
    ``labels`` (P, k*k) uint8: 4-connected piece of each cell, 1.. in order of the piece's
    first cell, 0 for blocked cells; ``count`` (P,) int64: pieces per pattern;
    ``centre`` (P, m, 2) float64: mean (row, col) of each piece inside the block (m =
    maximal number of pieces).
    """
    nc = k * k
    pats = np.arange(1 << nc, dtype=np.int64)
    bits = ((pats[:, None] >> np.arange(nc)) & 1).astype(bool)          # (P, nc)
    lab = np.where(bits, np.arange(1, nc + 1), 0).reshape(-1, k, k)
    big = nc + 1
    for _ in range(nc):
        cur = np.where(lab > 0, lab, big)
        best = cur.copy()
        best[:, 1:, :] = np.minimum(best[:, 1:, :], cur[:, :-1, :])
        best[:, :-1, :] = np.minimum(best[:, :-1, :], cur[:, 1:, :])
        best[:, :, 1:] = np.minimum(best[:, :, 1:], cur[:, :, :-1])
        best[:, :, :-1] = np.minimum(best[:, :, :-1], cur[:, :, 1:])
        new = np.where(lab > 0, best, 0)
        if np.array_equal(new, lab):
            break
        lab = new
    lab = lab.reshape(-1, nc)
    is_root = lab == np.arange(1, nc + 1)                                # piece's first cell
    rank = np.cumsum(is_root, axis=1)                                    # 1.. per root
    safe = np.maximum(lab - 1, 0)
    labels = np.where(lab > 0, np.take_along_axis(rank, safe, axis=1), 0).astype(np.uint8)
    count = is_root.sum(axis=1).astype(np.int64)
    m = max(1, int(count.max()))
    rows = np.repeat(np.arange(k), k).astype(np.float64)
    cols = np.tile(np.arange(k), k).astype(np.float64)
    onehot = labels[:, :, None] == np.arange(1, m + 1)                   # (P, nc, m)
    n_in = np.maximum(onehot.sum(axis=1), 1)
    centre = np.stack([(onehot * rows[None, :, None]).sum(axis=1) / n_in,
                       (onehot * cols[None, :, None]).sum(axis=1) / n_in], axis=-1)
    return labels, count, centre


def _block_edges(nid: npt.NDArray[np.int32], k: int) -> tuple[np.ndarray, np.ndarray]:
    """Edges (u, v) between the nodes of neighbouring blocks, each node pair once.

    ``nid`` is (hb, wb, k*k): the node id of every block-local cell, -1 where blocked.
    Horizontal and vertical neighbours link through their touching boundary cells;
    diagonal neighbours through their touching corner cells when both side cells are
    passable.
    """
    hb, wb = nid.shape[0], nid.shape[1]

    def node_of(cell_idx: int, sl_r: slice, sl_c: slice) -> np.ndarray:
        """Node id of block-local cell ``cell_idx`` for the blocks in (sl_r, sl_c)."""
        return nid[sl_r, sl_c, cell_idx].ravel()

    src: list[np.ndarray] = []
    dst: list[np.ndarray] = []

    def add_unique(pairs: list[tuple[np.ndarray, np.ndarray]]) -> None:
        """Append the k boundary-cell pairs of each block pair, each node pair once."""
        for i, (a, b) in enumerate(pairs):
            ok = (a >= 0) & (b >= 0)
            for a_prev, b_prev in pairs[:i]:
                ok &= (a != a_prev) | (b != b_prev)
            src.append(a[ok])
            dst.append(b[ok])

    full = slice(None)
    r_lo, r_hi = slice(0, hb - 1), slice(1, hb)
    c_lo, c_hi = slice(0, wb - 1), slice(1, wb)
    last = k - 1
    # Horizontal: right column of block (i, j) with the left column of (i, j+1).
    add_unique([(node_of(i * k + last, full, c_lo), node_of(i * k, full, c_hi))
                for i in range(k)])
    # Vertical: top row of block (i, j) with the bottom row of (i+1, j).
    add_unique([(node_of(last * k + j, r_lo, full), node_of(j, r_hi, full))
                for j in range(k)])
    # Diagonal: corner of A = (i, j) with the corner of B = (i+1, j+dj); the side
    # cells lie in the blocks (i+1, j) and (i, j+dj). (A, B, side1, side2).
    diagonals = (
        ((r_lo, c_lo, last * k + last), (r_hi, c_hi, 0),
         (r_hi, c_lo, last), (r_lo, c_hi, last * k)),
        ((r_lo, c_hi, last * k), (r_hi, c_lo, last),
         (r_hi, c_hi, 0), (r_lo, c_lo, last * k + last)),
    )
    for (ar, ac, acell), (br, bc, bcell), (s1r, s1c, s1cell), (s2r, s2c, s2cell) \
            in diagonals:
        a = node_of(acell, ar, ac)
        b = node_of(bcell, br, bc)
        ok = (node_of(s1cell, s1r, s1c) >= 0) & (node_of(s2cell, s2r, s2c) >= 0)
        ok &= (a >= 0) & (b >= 0)
        src.append(a[ok])
        dst.append(b[ok])
    return np.concatenate(src), np.concatenate(dst)


class BlockGraph:
    """Coarse graph of a passability mask for fast one-sweep path lengths.

    The grid is cut into ``k x k`` blocks (``k = block_cells``); every 4-connected piece
    of passable cells inside a block is one node placed at the piece's mean cell. Two
    nodes are joined when a cell of one is 4-adjacent to a cell of the other, and nodes
    of diagonal blocks also when their touching corner cells and both side cells are
    passable (no corner cutting); an edge is as long as the straight line between the
    node positions. Build once per mask (map update), query per robot position.

    ``block_cells = 1`` keeps every passable cell as a node with the exact 8-connected
    moves of :func:`distance_field`, so :meth:`distances` is then exact.

    Guarantees (any ``k``): a target gets a finite distance iff it is reachable in
    :func:`distance_field` on the same mask (a piece is connected inside, pieces are
    joined only where their cells touch); every finite result is >= the straight-line
    distance start -> target (triangle inequality along the polyline). Error: the
    polyline through node positions equals the 8-connected length between block centres
    across open space (full blocks); the difference to the exact field comes from the two
    end segments and from detours through partial blocks near obstacles, at most
    ``(k - 1) * sqrt(2)`` cells per partial block passed. On seeded random clutter and
    mazes (test_paths.py) it stays within ``0.2 * exact + 2 * k * resolution_m``.

    Parameters
    ----------
    passable : ndarray of bool, shape (H, W)
    resolution_m : float
        Metres per cell, > 0.
    block_cells : int
        Block side ``k`` in 1..MAX_BLOCK_CELLS.

    Raises
    ------
    ValueError
        On a non-2D mask, a bad ``block_cells`` or resolution.
    """

    def __init__(self, passable: npt.NDArray[np.bool_], resolution_m: float = 1.0,
                 block_cells: int = 4) -> None:
        pas = np.asarray(passable, dtype=bool)
        if pas.ndim != 2:
            raise ValueError(f"passable must be 2D, got shape {pas.shape}")
        check_resolution(resolution_m)
        k = int(block_cells)
        if not 1 <= k <= MAX_BLOCK_CELLS:
            raise ValueError(f"block_cells must be in 1..{MAX_BLOCK_CELLS}, got {block_cells}")
        self.shape: tuple[int, int] = (int(pas.shape[0]), int(pas.shape[1]))
        self.resolution_m = float(resolution_m)
        self.block_cells = k
        self._pas = pas.copy()
        #: The last single-source sweep (start node, distances): a decision asks for the
        #: robot's distances more than once (viewpoints, then cPoints) on one graph.
        self._sweep: tuple[int, npt.NDArray[np.float64]] | None = None
        if not pas.any():
            self._n = 0
            return
        if k == 1:
            self._graph, idx = grid_csr(pas, self.resolution_m)
            self._r0 = self._c0 = 0
            self._n = int(self._graph.shape[0])
            self._nid = idx.reshape(pas.shape[0], pas.shape[1], 1)
            rr, cc = np.nonzero(pas)
            self._pos_r, self._pos_c = rr.astype(np.float64), cc.astype(np.float64)
            return
        self._build_blocks(pas, k)

    def _build_blocks(self, pas: npt.NDArray[np.bool_], k: int) -> None:
        # Crop to the bounding box of the passable cells, aligned to the blocks.
        rows_any = np.flatnonzero(pas.any(axis=1))
        cols_any = np.flatnonzero(pas.any(axis=0))
        r0, c0 = int(rows_any[0]), int(cols_any[0])
        r1, c1 = int(rows_any[-1]) + 1, int(cols_any[-1]) + 1
        r0a, c0a = r0 - r0 % k, c0 - c0 % k
        hb, wb = -(-(r1 - r0a) // k), -(-(c1 - c0a) // k)
        grid = np.zeros((hb * k, wb * k), dtype=bool)
        grid[r0 - r0a:r1 - r0a, c0 - c0a:c1 - c0a] = pas[r0:r1, c0:c1]

        labels_lut, count_lut, centre_lut = _block_tables(k)
        code = np.zeros((hb, wb), dtype=np.int64)
        for i in range(k):
            for j in range(k):
                code |= grid[i::k, j::k].astype(np.int64) << (i * k + j)
        count = count_lut[code]                                   # (hb, wb)
        base = np.zeros(hb * wb + 1, dtype=np.int64)
        np.cumsum(count.ravel(), out=base[1:])
        n = int(base[-1])
        base = base[:-1].reshape(hb, wb) - 1                      # node id = base + label

        # Node positions (row, col of the piece's mean cell, crop coordinates).
        blk = np.repeat(np.arange(hb * wb), count.ravel())
        rank = np.arange(n) - np.repeat(base.ravel() + 1, count.ravel())
        cen = centre_lut[code.ravel()[blk], rank]                 # (n, 2)
        pos_r = (blk // wb) * k + cen[:, 0]
        pos_c = (blk % wb) * k + cen[:, 1]

        lab = labels_lut[code]                                    # (hb, wb, k*k) labels
        nid = base.astype(np.int32)[:, :, None] + lab             # node ids ...
        nid[lab == 0] = -1                                        # ... -1 where blocked

        u, v = _block_edges(nid, k)
        wt = np.hypot(pos_r[u] - pos_r[v], pos_c[u] - pos_c[v]) * self.resolution_m
        self._graph = csr_matrix((np.concatenate([wt, wt]),
                                  (np.concatenate([u, v]), np.concatenate([v, u]))),
                                 shape=(n, n))
        self._n = n
        self._r0, self._c0 = r0a, c0a
        self._nid = nid
        self._pos_r, self._pos_c = pos_r, pos_c

    @property
    def num_nodes(self) -> int:
        """Number of graph nodes (passable pieces)."""
        return self._n

    def is_passable(self, rc: tuple[int, int]) -> bool:
        """True when cell ``rc`` lies inside the grid and is passable."""
        r, c = int(rc[0]), int(rc[1])
        return 0 <= r < self.shape[0] and 0 <= c < self.shape[1] and bool(self._pas[r, c])

    def nearest_passable(self, rc: tuple[int, int], radius_cells: int
                         ) -> tuple[int, int] | None:
        """``rc`` when passable, else the nearest passable cell (Euclidean) within
        ``radius_cells`` (square window, cells outside the grid ignored), else None."""
        r, c = int(rc[0]), int(rc[1])
        if self.is_passable((r, c)):
            return (r, c)
        return nearest_true(self._pas, (r, c), int(radius_cells))

    def _nodes(self, rc: np.ndarray) -> np.ndarray:
        """Node id of each (row, col) cell; -1 outside the grid or not passable."""
        k = self.block_cells
        res = np.full(rc.shape[0], -1, dtype=np.int64)
        if self._n == 0:
            return res
        h, w = self.shape
        inside = (rc[:, 0] >= 0) & (rc[:, 0] < h) & (rc[:, 1] >= 0) & (rc[:, 1] < w)
        if k == 1:
            res[inside] = self._nid[rc[inside, 0], rc[inside, 1], 0]
            return res
        rr, cc = rc[inside, 0] - self._r0, rc[inside, 1] - self._c0
        hb, wb = self._nid.shape[:2]
        ok = (rr >= 0) & (rr < hb * k) & (cc >= 0) & (cc < wb * k)
        sub = np.full(rr.shape[0], -1, dtype=np.int64)
        rr, cc = rr[ok], cc[ok]
        sub[ok] = self._nid[rr // k, cc // k, (rr % k) * k + (cc % k)]
        res[inside] = sub
        return res

    def distances(self, start_rc: tuple[int, int], targets_rc: npt.ArrayLike
                  ) -> npt.NDArray[np.float64]:
        """Path lengths (m) from ``start_rc`` to each target cell, one Dijkstra sweep.

        Parameters
        ----------
        start_rc : (int, int)
            Start cell; when it is not passable every result is ``inf``.
        targets_rc : array_like of int, shape (N, 2)
            Target cells (row, col); cells outside the grid or not passable get ``inf``.

        Returns
        -------
        ndarray of float64, shape (N,)
            A target's distance is its node's plus the straight line from the node's
            position to the target cell (start likewise); the straight line start ->
            target when both lie in the same node.

        Raises
        ------
        ValueError
            When ``targets_rc`` is not shaped (N, 2).
        """
        tg = np.asarray(targets_rc, dtype=np.int64)
        if tg.size == 0:
            return np.zeros(0, dtype=np.float64)
        if tg.ndim != 2 or tg.shape[1] != 2:
            raise ValueError(f"targets_rc must have shape (N, 2), got {tg.shape}")
        out = np.full(tg.shape[0], np.inf)
        start = np.asarray([[int(start_rc[0]), int(start_rc[1])]], dtype=np.int64)
        s_node = int(self._nodes(start)[0])
        if s_node < 0:
            return out
        t_node = self._nodes(tg)
        has = t_node >= 0
        if not has.any():
            return out
        d = self._sweep_from(s_node)
        tn = t_node[has]
        res_m = self.resolution_m
        if self.block_cells == 1:
            out[has] = d[tn]
            return out
        s_off = math.hypot(start[0, 0] - self._r0 - self._pos_r[s_node],
                           start[0, 1] - self._c0 - self._pos_c[s_node])
        t_off = np.hypot(tg[has, 0] - self._r0 - self._pos_r[tn],
                         tg[has, 1] - self._c0 - self._pos_c[tn])
        res = d[tn] + (s_off + t_off) * res_m
        same = tn == s_node
        res[same] = np.hypot(tg[has, 0][same] - start[0, 0],
                             tg[has, 1][same] - start[0, 1]) * res_m
        out[has] = res
        return out

    def _sweep_from(self, node: int) -> npt.NDArray[np.float64]:
        """Distances (m) from ``node`` to every node (kept for the next call from it)."""
        if self._sweep is None or self._sweep[0] != node:
            self._sweep = (node, dijkstra(self._graph, directed=True, indices=node))
        return self._sweep[1]

    def distance_matrix(self, cells_rc: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Path lengths (m) between all pairs of cells, one multi-source sweep: entry
        ``[i, j]`` is :meth:`distances` from cell ``i`` to cell ``j`` (inf when either is
        not passable or they are not connected; 0 on the diagonal).

        Parameters
        ----------
        cells_rc : array_like of int, shape (N, 2)

        Returns
        -------
        ndarray of float64, shape (N, N)
        """
        rc = np.asarray(cells_rc, dtype=np.int64).reshape(-1, 2)
        out = self.distance_rows(rc, rc)
        np.fill_diagonal(out, 0.0)
        return out

    def distance_rows(self, sources_rc: npt.ArrayLike, targets_rc: npt.ArrayLike
                      ) -> npt.NDArray[np.float64]:
        """Path lengths (m) from each source cell to each target cell, one Dijkstra sweep
        per distinct source node: entry ``[i, j]`` is :meth:`distances` from source ``i``
        to target ``j`` (inf when either is not passable or they are not connected).

        Parameters
        ----------
        sources_rc : array_like of int, shape (S, 2)
        targets_rc : array_like of int, shape (T, 2)

        Returns
        -------
        ndarray of float64, shape (S, T)
        """
        src = np.asarray(sources_rc, dtype=np.int64).reshape(-1, 2)
        tgt = np.asarray(targets_rc, dtype=np.int64).reshape(-1, 2)
        out = np.full((src.shape[0], tgt.shape[0]), np.inf)
        if src.shape[0] == 0 or tgt.shape[0] == 0:
            return out
        s_node, t_node = self._nodes(src), self._nodes(tgt)
        s_has, t_has = np.flatnonzero(s_node >= 0), np.flatnonzero(t_node >= 0)
        if s_has.size == 0 or t_has.size == 0:
            return out
        sn, tn = s_node[s_has], t_node[t_has]
        uniq, inv = np.unique(sn, return_inverse=True)
        sub = dijkstra(self._graph, directed=True, indices=uniq)[:, tn][inv]     # (S', T')
        if self.block_cells > 1:
            s_off = np.hypot(src[s_has, 0] - self._r0 - self._pos_r[sn],
                             src[s_has, 1] - self._c0 - self._pos_c[sn]) * self.resolution_m
            t_off = np.hypot(tgt[t_has, 0] - self._r0 - self._pos_r[tn],
                             tgt[t_has, 1] - self._c0 - self._pos_c[tn]) * self.resolution_m
            sub = sub + s_off[:, None] + t_off[None, :]
            same = sn[:, None] == tn[None, :]
            straight = np.hypot(src[s_has, 0][:, None] - tgt[t_has, 0][None, :],
                                src[s_has, 1][:, None] - tgt[t_has, 1][None, :]
                                ) * self.resolution_m
            sub = np.where(same, straight, sub)
        out[np.ix_(s_has, t_has)] = sub
        return out


def block_distances(passable: npt.NDArray[np.bool_], start_rc: tuple[int, int],
                    targets_rc: npt.ArrayLike, resolution_m: float = 1.0,
                    block_cells: int = 4) -> npt.NDArray[np.float64]:
    """Approximate path lengths from ``start_rc`` to many target cells, one sweep.

    :class:`BlockGraph` built and queried once, with the start cell treated as passable
    (the rule of :func:`distance_field`). See :class:`BlockGraph` for the model, the
    guarantees and the error bound; ``block_cells = 1`` is exact.

    Parameters
    ----------
    passable : ndarray of bool, shape (H, W)
    start_rc : (int, int)
        Start cell (row, col), inside the grid.
    targets_rc : array_like of int, shape (N, 2)
    resolution_m : float
    block_cells : int

    Returns
    -------
    ndarray of float64, shape (N,)
        Path length in metres, ``inf`` when unreachable.

    Raises
    ------
    ValueError
        On a start outside the grid, a bad ``block_cells`` or resolution, or targets not
        shaped (N, 2).
    """
    passable = np.asarray(passable, dtype=bool)
    check_start(passable, start_rc)
    start = (int(start_rc[0]), int(start_rc[1]))
    pas = passable.copy()
    pas[start] = True
    return BlockGraph(pas, resolution_m, block_cells).distances(start, targets_rc)
