"""Merging of regions: too small or too thin ones into a neighbour, parts of one passage
(:mod:`.passages`), and optionally corridor parts whose union stays nearly convex (DuDe
spec shared/docs/dude.md §10, §15)."""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.labels import (apply_mapping, label_counts, pair_counts,
                                                  region_edges)
from explore_seg.core.segmentation.params import SegmentationParams
from explore_seg.core.segmentation.passages import BorderPairs, merge_passages


def max_concavity(mask: npt.NDArray[np.uint8]) -> float:
    """Deepest vertex of the outer ring of a mask below its convex hull (pixels)."""
    contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    if not contours:
        return 0.0
    c = max(contours, key=cv2.contourArea)
    if len(c) < 4:
        return 0.0
    hull = cv2.convexHull(c, returnPoints=False)
    try:
        defects = cv2.convexityDefects(c, hull)
    except cv2.error:
        return 0.0
    if defects is None:
        return 0.0
    return float(defects[:, 0, 3].max()) / 256.0


class _Merger:
    """Union-find over region ids with areas and shared border lengths."""

    def __init__(self, areas: dict[int, int], borders: dict[tuple[int, int], int]) -> None:
        self.parent = {k: k for k in areas}
        self.area = dict(areas)
        self.nb: dict[int, dict[int, int]] = {k: {} for k in areas}
        for (a, b), c in borders.items():
            if a in self.nb and b in self.nb:
                self.nb[a][b] = self.nb[a].get(b, 0) + c
                self.nb[b][a] = self.nb[b].get(a, 0) + c

    def merge(self, small: int, into: int) -> None:
        self.parent[small] = into
        self.area[into] += self.area.pop(small)
        for o, c in self.nb.pop(small).items():
            self.nb[o].pop(small, None)
            if o != into:
                self.nb[into][o] = self.nb[into].get(o, 0) + c
                self.nb[o][into] = self.nb[o].get(into, 0) + c

    def root(self, k: int) -> int:
        guard = 0
        while self.parent[k] != k and guard < len(self.parent):
            k = self.parent[k]
            guard += 1
        return k


def merge_regions(labels: npt.NDArray[np.int32], out_mask: npt.NDArray[np.bool_],
                   candidates: set[int] | None, params: SegmentationParams,
                   res: float) -> None:
    """Merge too small or too thin regions, parts of one passage (and optionally corridor
    parts), in place.

    Parameters
    ----------
    labels : ndarray of int32, shape (H, W)
        Domain labels (modified in place).
    out_mask : ndarray of bool, shape (H, W)
        The cells whose labels are published (raw free cells); areas are counted there.
    candidates : set of int or None
        Only these ids may be merged away (None: all ids).
    """
    areas = {k: 0 for k in label_counts(labels)}
    areas.update(label_counts(np.multiply(labels, out_mask, dtype=labels.dtype)))
    if not areas:
        return
    cand = set(areas) if candidates is None else {c for c in candidates if c in areas}
    # the passage merge measures the borders' cell pairs: found once for both
    pairs = BorderPairs(labels) if params.passage_merge_ratio > 0 and cand else None
    borders = pair_counts(labels) if pairs is None else pairs.counts()
    mg = _Merger(areas, borders)
    min_area = params.min_region_area_m2 / (res * res)
    thin: set[int] = set()
    inner = None
    if params.min_region_width_m > 0 and cand:
        half_w = 0.5 * params.min_region_width_m / res
        # a region is thin when no cell is farther than half the width from its border;
        # borders between regions count as borders too (one distance transform to the
        # union of both: the chamfer distance to a union is the smaller of the two)
        inner = (labels > 0) & ~region_edges(labels)
        dd = cv2.distanceTransform(inner.view(np.uint8), cv2.DIST_L2, 3)
        wide = label_counts(labels[dd >= half_w])
        thin = {k for k in cand if k not in wide}
    dropped: set[int] = set()
    guard = 0
    while guard < 4 * len(areas) + 4:
        guard += 1
        live = [k for k in cand if mg.parent.get(k) == k and k not in dropped
                and (mg.area[k] < min_area or k in thin)]
        if not live:
            break
        k = min(live, key=lambda i: (mg.area[i], i))
        nbs = mg.nb.get(k, {})
        if not nbs:
            thin.discard(k)
            if mg.area[k] < min_area:
                dropped.add(k)
            continue
        into = max(nbs, key=lambda o: (nbs[o], -o))
        mg.merge(k, into)
        if mg.area[into] >= min_area:
            thin.discard(into)
    # in an update, only new pieces join: an old region stays as it was (§11.7)
    merge_passages(labels, mg, cand, params, res, both=candidates is not None, inner=inner,
                   pairs=pairs)
    if params.corridor_merge:
        _corridor_merge(labels, mg, cand, params, res)
    lut_keys = [k for k in mg.parent if mg.root(k) != k or k in dropped]
    if not lut_keys:
        return
    mapping = {k: (0 if mg.root(k) in dropped or k in dropped else mg.root(k))
               for k in lut_keys}
    apply_mapping(labels, mapping)


def _corridor_merge(labels: npt.NDArray[np.int32], mg: _Merger, cand: set[int],
                    params: SegmentationParams, res: float) -> None:
    """Merge neighbours joined by a wide border whose union is still nearly convex."""
    door_px = params.max_door_width_m / res
    limit = params.merge_concavity_factor * params.tau_m / res
    tried: set[tuple[int, int]] = set()
    guard = 0
    while guard < 4 * len(mg.parent) + 4:
        guard += 1
        best = None
        for a in list(mg.area):
            if mg.parent[a] != a or a not in cand:
                continue
            for b, c in mg.nb[a].items():
                key = (min(a, b), max(a, b))
                if c > door_px and key not in tried and (best is None or c > best[0]):
                    best = (c, a, b)
        if best is None:
            return
        _c, a, b = best
        tried.add((min(a, b), max(a, b)))
        roots = np.array([mg.root(k) for k in mg.parent], dtype=np.int64)
        keys = np.array(list(mg.parent), dtype=np.int64)
        members = keys[(roots == a) | (roots == b)]
        m = np.isin(labels, members)
        rows = np.flatnonzero(m.any(axis=1))
        cols = np.flatnonzero(m.any(axis=0))
        sub = m[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1].astype(np.uint8)
        sub = np.pad(sub, 1)
        if max_concavity(sub) < limit:
            small, into = (a, b) if mg.area[a] <= mg.area[b] else (b, a)
            mg.merge(small, into)
            cand.add(into)

