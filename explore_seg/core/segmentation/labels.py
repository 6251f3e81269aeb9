"""Label-image helpers of the segmentation: boxes, counts, gap filling, id mapping.

Label images are int32 ``(H, W)``, ``0`` = no region, ``k > 0`` a region id.
"""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap


def bbox(mask: npt.NDArray[np.bool_], margin: int
          ) -> tuple[slice, slice] | None:
    """Bounding box of the true cells grown by ``margin`` (clipped), or None."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (slice(max(0, rows[0] - margin), min(h, rows[-1] + 1 + margin)),
            slice(max(0, cols[0] - margin), min(w, cols[-1] + 1 + margin)))


def lookup_mask(table: npt.NDArray[np.bool_], lab: npt.NDArray[np.integer]
                ) -> npt.NDArray[np.bool_]:
    """``table[lab]``: the cells of a label image whose id the boolean ``table`` marks.

    The look-up runs on a uint8 copy of the table (NumPy's take is markedly faster on
    uint8 than on bool), viewed back as bool."""
    return np.take(table.astype(np.uint8), lab).view(np.bool_)


def region_edges(labels: npt.NDArray[np.integer]) -> npt.NDArray[np.bool_]:
    """Cells with a 4-neighbour of another label (region borders, on both sides)."""
    edge = np.zeros(labels.shape, dtype=bool)
    ne = labels[:, :-1] != labels[:, 1:]
    edge[:, :-1] |= ne
    edge[:, 1:] |= ne
    ne = labels[:-1, :] != labels[1:, :]
    edge[:-1, :] |= ne
    edge[1:, :] |= ne
    return edge


def fill_gaps(labels: npt.NDArray[np.int32], domain: npt.NDArray[np.bool_],
               max_iter: int) -> None:
    """Give unlabelled domain cells the label of a labelled neighbour, in place (§10.3).

    Geodesic label dilation restricted to the domain, limited to the bounding box of the
    cells to fill, at most ``max_iter`` rounds (each round grows labels by one cell).
    """
    todo = domain & (labels == 0)
    if not todo.any():
        return
    rows = np.flatnonzero(todo.any(axis=1))
    cols = np.flatnonzero(todo.any(axis=0))
    r0, r1 = max(0, rows[0] - 1), min(labels.shape[0], rows[-1] + 2)
    c0, c1 = max(0, cols[0] - 1), min(labels.shape[1], cols[-1] + 2)
    lab = labels[r0:r1, c0:c1]
    tgt = todo[r0:r1, c0:c1].copy()
    # grey dilation (the largest id around wins) on the ids themselves when they fit in
    # 16 bits, else on their ranks (float32 is exact below 2**24; ids may be larger)
    top = int(lab.max())
    uniq = None
    if top < 256:
        rank = lab.astype(np.uint8)
    elif top < 65536:
        rank = lab.astype(np.uint16)
    else:
        uniq, rank = _ranks(lab)
    k = np.ones((3, 3), np.uint8)
    for _ in range(max_iter):
        grown = cv2.dilate(rank, k)
        put = tgt & (grown > 0)
        if not put.any():
            break
        np.copyto(rank, grown, where=put)
        tgt &= ~put
        if not tgt.any():
            break
    filled = todo[r0:r1, c0:c1] & (rank > 0)
    lab[filled] = rank[filled] if uniq is None else uniq[rank[filled].astype(np.int64)]


def _ranks(lab: npt.NDArray[np.int32]
           ) -> tuple[npt.NDArray[np.int32], npt.NDArray[np.float32]]:
    """``np.unique(lab, return_inverse=True)`` with the inverse as float32 ranks, through a
    look-up table over the ids (labels are small non-negative ids; the sort of
    ``np.unique`` dominated the segmentation's time), ``np.unique`` for other ids."""
    top = int(lab.max()) if lab.size else 0
    if lab.size == 0 or int(lab.min()) < 0 or top > 4 * lab.size + 65536:
        uniq, inv = np.unique(lab, return_inverse=True)
        return uniq, inv.reshape(lab.shape).astype(np.float32)
    present = np.zeros(top + 1, dtype=bool)
    present[lab] = True
    uniq = np.flatnonzero(present).astype(lab.dtype)
    lut = (np.cumsum(present) - 1).astype(np.float32)
    return uniq, lut[lab]


#: From this many values on, :func:`label_counts` counts with OpenCV's histogram.
_HIST_MIN_SIZE = 1 << 15


def label_counts(values: npt.NDArray[np.integer]) -> dict[int, int]:
    """{id: count} of the ids > 0 in ``values`` (ids are bounded by the id counter)."""
    v = values.ravel()
    if v.size == 0:
        return {}
    top = int(v.max())
    if v.size >= _HIST_MIN_SIZE and top < 65536 and int(v.min()) >= 0:
        # OpenCV's histogram of the 16-bit ids: exact counts (float32, < 2**24 cells),
        # several times faster than bincount's cast to intp on large images
        c = cv2.calcHist([v.astype(np.uint16).reshape(1, -1)], [0], None, [top + 1],
                         [0, top + 1]).ravel().astype(np.int64)
    else:
        c = np.bincount(v)          # labels are never negative
    c[0] = 0
    nz = np.flatnonzero(c)
    return dict(zip(nz.tolist(), c[nz].tolist()))


def _key_counts(x: npt.NDArray[np.int64], y: npt.NDArray[np.int64]
                ) -> tuple[list[int], list[int], list[int]]:
    """Distinct pairs (x, y) in ascending order of (x, y), with their counts.

    ``np.unique`` on ``x * 2**32 + y`` does it; a bincount over ``x * K + (y - y0)`` does
    the same without the sort when that table is small.
    """
    y0 = int(y.min())
    k = int(y.max()) - y0 + 1
    top = (int(x.max()) + 1) * k
    if top <= _MAX_TABLE:
        cnt = np.bincount(x * k + (y - y0), minlength=top)
        keys = np.flatnonzero(cnt)
        return (keys // k).tolist(), (keys % k + y0).tolist(), cnt[keys].tolist()
    keys, cnt = np.unique(x * (1 << 32) + y, return_counts=True)
    return (keys >> 32).tolist(), (keys & 0xFFFFFFFF).tolist(), cnt.tolist()


#: Largest count table :func:`_key_counts` allocates instead of sorting.
_MAX_TABLE = 1 << 21


def border_pairs(lab: npt.NDArray[np.int32]) -> list[tuple[npt.NDArray[np.intp],
                                                             npt.NDArray[np.intp], int, int,
                                                             npt.NDArray[np.int64],
                                                             npt.NDArray[np.int64]]]:
    """The 4-neighbour cell pairs between two different non-zero labels, per direction
    that has any: (rows, cols, dr, dc, lower label, higher label); the pair is the cell
    (row, col) and the cell (row + dr, col + dc)."""
    out = []
    pos = lab > 0
    for a, b, pa, pb, dr, dc in ((lab[:, :-1], lab[:, 1:], pos[:, :-1], pos[:, 1:], 0, 1),
                                 (lab[:-1, :], lab[1:, :], pos[:-1, :], pos[1:, :], 1, 0)):
        m = a != b
        m &= pa
        m &= pb
        r, c = np.nonzero(m)
        if r.size == 0:
            continue
        av, bv = a[r, c], b[r, c]
        out.append((r, c, dr, dc, np.minimum(av, bv).astype(np.int64),
                    np.maximum(av, bv).astype(np.int64)))
    return out


def pair_counts(lab: npt.NDArray[np.int32]) -> dict[tuple[int, int], int]:
    """Number of 4-neighbour cell pairs between every two different non-zero labels."""
    out: dict[tuple[int, int], int] = {}
    for _, _, _, _, x, y in border_pairs(lab):
        for i, j, c in zip(*_key_counts(x, y)):
            out[(i, j)] = out.get((i, j), 0) + c
    return out



def apply_mapping(labels: npt.NDArray[np.int32], mapping: dict[int, int]) -> None:
    """Replace ids in place, all at once (``mapping``: old id -> new id)."""
    if not mapping:
        return
    top = max(int(labels.max()), max(mapping)) + 1
    lut = np.arange(top, dtype=np.int64)
    lut[np.fromiter(mapping.keys(), np.int64)] = np.fromiter(mapping.values(), np.int64)
    if int(lut.max()) <= np.iinfo(np.int32).max:
        labels[...] = lut.astype(np.int32)[labels]
    else:
        labels[...] = lut[labels].astype(np.int32)


def match_ids(new: npt.NDArray[np.int32], old: npt.NDArray[np.int32],
               new_ids: list[int], keep_frac: float,
               old_area: dict[int, int]) -> dict[int, int]:
    """Temporary new id -> old id it inherits (§12.3); missing keys get fresh ids.

    Old pieces are processed in order of decreasing overlap; old id ``i`` passes to the
    new piece ``j`` holding the largest share of i's cells when that share is at least
    ``keep_frac`` of i (cells counted in ``old_area``) and ``j`` has no id yet.
    """
    m = (new > 0) & (old > 0)
    if not m.any():
        return {}
    a = old[m].astype(np.int64)
    b = new[m].astype(np.int64)
    best: dict[int, tuple[int, int]] = {}
    for i, j, c in zip(*_key_counts(a, b)):
        if i not in best or c > best[i][1] or (c == best[i][1] and j < best[i][0]):
            best[i] = (j, c)
    out: dict[int, int] = {}
    taken: set[int] = set()
    valid = set(new_ids)
    for i, (j, c) in sorted(best.items(), key=lambda t: (-t[1][1], t[0])):
        if j in taken or j not in valid:
            continue
        if c >= keep_frac * max(1, old_area.get(i, c)):
            out[j] = i
            taken.add(j)
    return out


def shift_into(old: npt.NDArray, shape: tuple[int, int], drow: int, dcol: int,
                fill: int = 0, reuse: bool = False) -> npt.NDArray:
    """Old array placed into a new array of ``shape`` with old (r, c) -> (r+drow, c+dcol).

    With ``reuse`` and no shift nor resize, ``old`` itself is returned (no copy).
    """
    if reuse and drow == 0 and dcol == 0 and old.shape == tuple(shape):
        return old
    out = np.full(shape, fill, dtype=old.dtype)
    h, w = old.shape
    r0, c0 = max(0, drow), max(0, dcol)
    r1, c1 = min(shape[0], h + drow), min(shape[1], w + dcol)
    if r1 > r0 and c1 > c0:
        out[r0:r1, c0:c1] = old[r0 - drow:r1 - drow, c0 - dcol:c1 - dcol]
    return out



def resample_labels(old: npt.NDArray[np.int32], g0: GridMap, g1: GridMap
                     ) -> npt.NDArray[np.int32]:
    """Old labels at the cell centres of ``g1`` (nearest cell; 0 outside ``g0``)."""
    rows, cols = np.indices(g1.shape)
    x, y = g1.cells_to_world(rows.ravel(), cols.ravel())
    r, c = g0.world_to_cells(x, y)
    ok = (r >= 0) & (r < g0.height) & (c >= 0) & (c < g0.width)
    out = np.zeros(g1.shape[0] * g1.shape[1], dtype=np.int32)
    out[ok] = old[r[ok], c[ok]]
    return out.reshape(g1.shape)



def renumber(labels: npt.NDArray[np.int32]) -> npt.NDArray[np.int32]:
    """Ids 1..n in raster order of each region's first cell."""
    flat = labels.ravel()
    ids, first = np.unique(flat, return_index=True)
    keep = ids > 0
    ids, first = ids[keep], first[keep]
    order = ids[np.argsort(first)]
    lut = {int(i): k + 1 for k, i in enumerate(order.tolist())}
    out = labels.copy()
    apply_mapping(out, lut)
    return out
