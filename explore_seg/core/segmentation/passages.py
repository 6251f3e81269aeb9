"""Passage merge: neighbouring regions that are two parts of one passage become one
region.

DuDe cuts a corridor that turns a corner or runs round a block (a ring corridor, the
free space round a table block) into several pieces, though each is one room. Such a
cut crosses the whole width of the passage on both sides: the border between the two
pieces is about as long as both pieces are wide (their inscribed diameter), and so is
the free space across it. A doorway is narrow against the space on at least one side;
a room open to a corridor is wider than the opening; a cut along a wall that ends at a
door runs along the door's narrow gap. Two regions are merged when their shared border
is longer than a door (``max_door_width_m``) and both the border and the free width
across it (twice the largest distance from a border cell to an obstacle) are at least
``passage_merge_ratio`` times the larger of their inscribed diameters.
"""

from __future__ import annotations

import heapq
from typing import TYPE_CHECKING

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.labels import border_pairs, region_edges
from explore_seg.core.segmentation.params import SegmentationParams

if TYPE_CHECKING:
    from explore_seg.core.segmentation.merging import _Merger


#: The free width across a border must be at least this share of the border length the
#: ratio asks for (a corridor's cut at a corner is longer than the corridor is wide).
_FREE_WIDTH_SHARE = 0.6


def border_spans(labels: npt.NDArray[np.int32],
                 clearance: npt.NDArray[np.float32] | None = None
                 ) -> dict[tuple[int, int], tuple[float, float]]:
    """Length (cells) of the border between every two neighbouring regions, the
    diagonal of the bounding box of the cell pairs (4-neighbours) where they meet, and
    the largest ``clearance`` (0 without) of those cells.

    >>> lab = np.array([[1, 1, 2, 2], [1, 1, 2, 2], [1, 1, 2, 2]], dtype=np.int32)
    >>> border_spans(lab)
    {(1, 2): (3.0, 0.0)}
    """
    return BorderPairs(labels).spans(clearance)


class BorderPairs:
    """The 4-neighbour cell pairs between two different regions of a label image,
    grouped by region pair: found once, measured with or without a clearance image."""

    def __init__(self, labels: npt.NDArray[np.int32]) -> None:
        cells: list[tuple[npt.NDArray[np.intp], npt.NDArray[np.intp], int, int]] = []
        keys: list[npt.NDArray[np.int64]] = []
        for r, c, dr, dc, lo, hi in border_pairs(labels):
            cells.append((r, c, dr, dc))
            keys.append(lo * (1 << 32) + hi)
        self.cells = cells
        self.sizes = [len(k) for k in keys]
        self.uk: npt.NDArray[np.int64] | None = None
        self.inv: npt.NDArray[np.intp] | None = None
        self.span: npt.NDArray[np.float64] | None = None
        if not keys:
            return
        self.uk, self.inv = np.unique(np.concatenate(keys), return_inverse=True)
        # the point between the two cells of a pair, in half-cell units
        r = np.concatenate([2 * r + dr for r, _c, dr, _dc in cells])
        c = np.concatenate([2 * c + dc for _r, c, _dr, dc in cells])
        n = len(self.uk)
        big = np.iinfo(np.int64).max
        rmin = np.full(n, big)
        rmax = np.full(n, -1)
        cmin = np.full(n, big)
        cmax = np.full(n, -1)
        np.minimum.at(rmin, self.inv, r)
        np.maximum.at(rmax, self.inv, r)
        np.minimum.at(cmin, self.inv, c)
        np.maximum.at(cmax, self.inv, c)
        # a border of n cells spans n - 1 steps plus one cell
        span = np.hypot((rmax - rmin) / 2 + 1, (cmax - cmin) / 2 + 1)
        self.span = np.where((rmax == rmin) | (cmax == cmin),
                             np.maximum(rmax - rmin, cmax - cmin) / 2 + 1, span)

    def counts(self) -> dict[tuple[int, int], int]:
        """Number of cell pairs between every two regions, as
        :func:`.labels.pair_counts` gives it (the same order of keys)."""
        out: dict[tuple[int, int], int] = {}
        if self.uk is None or self.inv is None:
            return out
        start = 0
        for size in self.sizes:
            c = np.bincount(self.inv[start:start + size], minlength=len(self.uk))
            start += size
            nz = np.flatnonzero(c)
            for x, n in zip(self.uk[nz].tolist(), c[nz].tolist()):
                key = (x >> 32, x & 0xFFFFFFFF)
                out[key] = out.get(key, 0) + n
        return out

    def spans(self, clearance: npt.NDArray[np.float32] | None = None
              ) -> dict[tuple[int, int], tuple[float, float]]:
        """{(a, b): (span, largest clearance)} as :func:`border_spans` gives it."""
        if self.uk is None or self.span is None or self.inv is None:
            return {}
        cl = np.zeros(len(self.uk), dtype=np.float64)
        if clearance is not None:
            clear = np.concatenate([np.maximum(clearance[r, c], clearance[r + dr, c + dc])
                                    for r, c, dr, dc in self.cells])
            np.maximum.at(cl, self.inv, clear)
        return {(int(x >> 32), int(x & 0xFFFFFFFF)): (float(s), float(q))
                for x, s, q in zip(self.uk.tolist(), self.span.tolist(), cl.tolist())}


def inscribed_diameters(labels: npt.NDArray[np.int32],
                        inner: npt.NDArray[np.bool_] | None = None) -> dict[int, float]:
    """Twice the largest distance (cells) from a cell of each region to its edge (other
    regions and non-region cells alike). ``inner``: the region cells off the edges,
    when the caller has them."""
    if inner is None:
        inner = (labels > 0) & ~region_edges(labels)
    inner = inner.view(np.uint8)
    dd = cv2.distanceTransform(np.pad(inner, 1), cv2.DIST_L2, 3)[1:-1, 1:-1]
    top = int(labels.max()) if labels.size else 0
    best = np.zeros(top + 1, dtype=np.float64)
    # a region's largest distance is at one of the local maxima (few cells)
    m = (dd > 0) & (dd >= cv2.dilate(dd, np.ones((3, 3), np.uint8)))
    np.maximum.at(best, labels[m], dd[m])
    return {int(k): 2.0 * float(best[k]) + 1.0 for k in np.flatnonzero(best > 0)}


def merge_passages(labels: npt.NDArray[np.int32], mg: _Merger, cand: set[int],
                   params: SegmentationParams, res: float, both: bool = False,
                   inner: npt.NDArray[np.bool_] | None = None,
                   pairs: BorderPairs | None = None) -> None:
    """Merge neighbouring parts of one passage in the union-find ``mg`` (see the module
    docstring); one of each pair is in ``cand`` (with ``both``: the two). The part
    outside ``cand`` (an old, kept region) keeps its id, else the larger one.
    ``pairs``: the border pairs of ``labels``, when the caller has them."""
    ratio = params.passage_merge_ratio
    if ratio <= 0 or not cand:
        return
    door = params.max_door_width_m / res
    # the widths and clearances cost two distance transforms: only when a border
    # between candidate regions is longer than a door
    if pairs is None:
        pairs = BorderPairs(labels)
    if not any(sp > door and ((a in cand and b in cand) if both else (a in cand or b in cand))
               for (a, b), (sp, _c) in pairs.spans().items()):
        return
    width = inscribed_diameters(labels, inner)
    # the free space's own width where two regions meet (region borders do not count):
    # twice the largest distance to an obstacle along the border
    clearance = cv2.distanceTransform(np.pad((labels > 0).view(np.uint8), 1), cv2.DIST_L2,
                                      3)[1:-1, 1:-1]
    # best ratio first; a popped pair is checked against the merges done since (widths
    # only grow, so a pair's ratio only falls)
    heap: list[tuple[float, int, int]] = []
    span: dict[tuple[int, int], float] = {}
    for (a, b), (s, cl) in pairs.spans(clearance).items():
        if s > door and ((a in cand and b in cand) if both else (a in cand or b in cand)):
            # the narrower of the cut's length and the free width across it
            span[(a, b)] = min(s, (2.0 * cl + 1.0) / _FREE_WIDTH_SHARE)
            q = span[(a, b)] / max(width.get(a, 0.0), width.get(b, 0.0), 1.0)
            if q >= ratio:
                heap.append((-q, a, b))
    heapq.heapify(heap)
    while heap:
        negq, a, b = heapq.heappop(heap)
        ra, rb = mg.root(a), mg.root(b)
        if ra == rb or not ((ra in cand and rb in cand) if both
                            else (ra in cand or rb in cand)):
            continue
        q = span[(a, b)] / max(width.get(ra, 0.0), width.get(rb, 0.0), 1.0)
        if q < ratio:
            continue
        if q < -negq - 1e-9:
            heapq.heappush(heap, (-q, a, b))
            continue
        if ra in cand and rb not in cand:
            small, into = ra, rb
        elif rb in cand and ra not in cand:
            small, into = rb, ra
        else:
            small, into = (ra, rb) if (mg.area[ra], -ra) < (mg.area[rb], -rb) else (rb, ra)
        width[into] = max(width.get(ra, 0.0), width.get(rb, 0.0))
        mg.merge(small, into)
        if small in cand:
            cand.add(into)
