"""Room segmentation of an occupancy grid by (incremental) Dual-Space Decomposition.

Implements DuDe spec shared/docs/dude.md: cleaning of the grid into a free-space mask (§4), DuDe on every
free component (§5-§9, in :mod:`.dude`, raster shortcut), labelling back onto the true
free cells with gap filling and small-region merging (§10, §15), the incremental update
that redoes only the pieces touched by newly seen free space (§11) and region ids that
persist between updates (§12).

Label images follow :class:`~explore_seg.core.grid.GridMap`: int32 ``(H, W)``, row = y,
``0`` = no region (obstacle, unknown, undecided occupancy, or a free speck smaller than
``min_region_area_m2`` that touches no region), ``k > 0`` a region id.

Internally every cell of the *domain* (cleaned free space F united with the raw free
cells) carries a label; the published labels are the domain labels restricted to the raw
free cells. Keeping the F margin labelled (F reaches ``free_close_m`` into unknown space
at frontiers) is what lets the incremental update tell newly seen space from old.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.dude import DudeSettings, decompose_mask, find_cuts
from explore_seg.core.grid import GridMap
from explore_seg.core.fields import param_meta as _doc

#: Bounds on the DuDe checks of one incremental update: seams between new and clean
#: pieces, and clean pieces whose shape changed.
_MAX_SEAM_TESTS = 6
_MAX_SHAPE_TESTS = 4



@dataclass(frozen=True)
class SegmentationParams:
    """Parameters of the DuDe room segmentation (DuDe spec shared/docs/dude.md §13).

    Raises
    ------
    ValueError
        From ``__post_init__`` when a value is out of range.
    """

    tau_m: float = field(default=1.6, metadata=_doc(
        "DuDe max concavity tau: boundary vertices deeper than this in the dual space "
        "are cut (small: corridors over-segmented; large: rooms merged through doors). "
        "1.6 m is the best of a sweep on generated houses (bench/eval_segmentation.py); "
        "the draft's optimum is 2.5 m, the seed code uses 3.0 m", "m"))
    free_max_occupancy: int = field(default=10, metadata=_doc(
        "a cell is free when 0 <= occupancy < this", "%"))
    occupied_min_occupancy: int = field(default=90, metadata=_doc(
        "a cell is an obstacle when occupancy > this", "%"))
    obstacle_inflation_m: float = field(default=0.20, metadata=_doc(
        "obstacles are grown by this before decomposing (closes gaps in walls)", "m"))
    free_close_m: float = field(default=0.25, metadata=_doc(
        "free space is grown by this into unknown cells (fills unobserved specks)", "m"))
    obstacle_speck_area_m2: float = field(default=0.0075, metadata=_doc(
        "occupied components of at most this area are ignored (scan salt noise)", "m^2"))
    min_component_area_m2: float = field(default=1.0, metadata=_doc(
        "cleaned free components smaller than this are not decomposed", "m^2"))
    min_hole_area_m2: float = field(default=0.0125, metadata=_doc(
        "obstacle islands of at most this area are ignored by the decomposition", "m^2"))
    simplify_epsilon_m: float = field(default=0.075, metadata=_doc(
        "Douglas-Peucker tolerance applied to traced contours", "m"))
    min_region_area_m2: float = field(default=1.0, metadata=_doc(
        "regions smaller than this are merged into the neighbour sharing the longest "
        "border; isolated free specks smaller than this get no region", "m^2"))
    min_region_width_m: float = field(default=0.4, metadata=_doc(
        "regions thinner than this (twice the largest distance to their border) are "
        "merged into a neighbour", "m"))
    corridor_merge: bool = field(default=False, metadata=_doc(
        "merge two adjacent regions whose shared border is longer than "
        "max_door_width_m and whose union stays convex enough (DuDe spec shared/docs/dude.md §15)"))
    max_door_width_m: float = field(default=1.2, metadata=_doc(
        "corridor merge: borders at most this long are doors and never merged", "m"))
    merge_concavity_factor: float = field(default=2.0, metadata=_doc(
        "corridor merge: the union's deepest concavity must stay below this times tau"))
    max_rounds: int = field(default=16, metadata=_doc(
        "bound on decomposition rounds per piece"))
    max_cut_candidates: int = field(default=24, metadata=_doc(
        "per notch, how many nearest boundary points are tested as cut ends"))
    inc_min_blob_m2: float = field(default=0.25, metadata=_doc(
        "incremental: newly seen free blobs of at most this area are only gap-filled",
        "m^2"))
    inc_touch_cells: int = field(default=2, metadata=_doc(
        "incremental: a piece within this many cells of a new blob is redone", "cells"))
    inc_lost_frac: float = field(default=0.05, metadata=_doc(
        "incremental: a piece that lost more than this fraction of its cells is redone"))
    inc_full_frac: float = field(default=0.5, metadata=_doc(
        "incremental: when the work areas exceed this fraction of the free space, a full "
        "batch run is done instead"))
    id_keep_frac: float = field(default=0.5, metadata=_doc(
        "an old id passes to the new piece holding at least this share of its cells"))

    def __post_init__(self) -> None:
        pos = ("tau_m", "max_door_width_m", "merge_concavity_factor")
        nonneg = ("obstacle_inflation_m", "free_close_m", "obstacle_speck_area_m2",
                  "min_component_area_m2", "min_hole_area_m2", "simplify_epsilon_m",
                  "min_region_area_m2", "min_region_width_m", "inc_min_blob_m2")
        for name in pos:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        for name in nonneg:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        if not 0 < self.free_max_occupancy <= 100:
            raise ValueError(
                f"free_max_occupancy must be in 1..100, got {self.free_max_occupancy}")
        if not self.free_max_occupancy - 1 <= self.occupied_min_occupancy < 100:
            raise ValueError(
                f"occupied_min_occupancy must be in [free_max_occupancy - 1, 99], got "
                f"{self.occupied_min_occupancy} (free_max_occupancy "
                f"{self.free_max_occupancy})")
        for name in ("max_rounds", "max_cut_candidates"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.inc_touch_cells < 0:
            raise ValueError(f"inc_touch_cells must be >= 0, got {self.inc_touch_cells}")
        for name in ("inc_lost_frac", "inc_full_frac", "id_keep_frac"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v <= 1):
                raise ValueError(f"{name} must be in [0, 1], got {v}")


@dataclass(frozen=True)
class SegmentationNodeParams(SegmentationParams):
    """Parameters of the ``segmentation`` node: the algorithm's plus the node's own."""

    map_transient_local: bool = field(default=True, metadata=_doc(
        "subscribe to the map with transient-local durability (false: volatile); read "
        "only", read_only=True))
    incremental: bool = field(default=True, metadata=_doc(
        "update the segmentation incrementally (false: full batch on every map)"))
    process_period_s: float = field(default=0.1, metadata=_doc(
        "period of the timer that processes the latest map", "s"))

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.process_period_s) and self.process_period_s > 0):
            raise ValueError(f"process_period_s must be > 0, got {self.process_period_s}")


@dataclass(frozen=True)
class UpdateInfo:
    """What the last :meth:`IncrementalSegmenter.update` did."""

    mode: str                  # "full", "incremental", "unchanged" or "empty"
    time_s: float              # wall time of the update
    work_areas: int            # number of work areas redone (0 for full/unchanged)
    work_cells: int            # cells in the work areas (all domain cells for full)
    regions: int               # number of regions in the result
    reason: str = ""           # why a full run was done


# ------------------------------------------------------------------------------ helpers


def _cells(length_m: float, res: float) -> int:
    return int(round(length_m / res))


def _settings(params: SegmentationParams, res: float) -> DudeSettings:
    area = res * res
    return DudeSettings(
        tau_px=params.tau_m / res,
        simplify_eps_px=params.simplify_epsilon_m / res,
        min_hole_area_px=params.min_hole_area_m2 / area,
        min_component_px=int(math.ceil(params.min_component_area_m2 / area)),
        max_rounds=params.max_rounds,
        max_tip_candidates=params.max_cut_candidates,
    )


def _square(r: int) -> npt.NDArray[np.uint8]:
    return np.ones((2 * r + 1, 2 * r + 1), dtype=np.uint8)


def clean_free_space(grid: GridMap, params: SegmentationParams
                     ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Raw free cells and the cleaned free-space mask F of a grid (DuDe spec shared/docs/dude.md §4).

    Parameters
    ----------
    grid : GridMap
    params : SegmentationParams

    Returns
    -------
    free_raw : ndarray of bool, shape (H, W)
        ``0 <= occupancy < free_max_occupancy``.
    free_clean : ndarray of bool, shape (H, W)
        Free cells grown by ``free_close_m`` into non-obstacle cells, minus the obstacles
        (occupancy > ``occupied_min_occupancy``, specks dropped) grown by
        ``obstacle_inflation_m``.
    """
    return _clean(grid.data, params, grid.resolution_m)


def _clean(data: npt.NDArray[np.int8], params: SegmentationParams, res: float
           ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    free_raw = (data >= 0) & (data < params.free_max_occupancy)
    if data.size == 0:
        return free_raw, free_raw.copy()
    occ = data > params.occupied_min_occupancy
    occ_u8 = occ.astype(np.uint8)
    speck_px = math.floor(params.obstacle_speck_area_m2 / (res * res) + 1e-6)
    if speck_px >= 1 and occ.any():
        n, lab, stats, _ = cv2.connectedComponentsWithStats(occ_u8, connectivity=8)
        small = stats[:, cv2.CC_STAT_AREA] <= speck_px
        small[0] = False
        if small.any():
            occ_u8 = np.where(small[lab], 0, occ_u8).astype(np.uint8)
    r_inf = _cells(params.obstacle_inflation_m, res)
    obst = cv2.dilate(occ_u8, _square(r_inf)) if r_inf > 0 else occ_u8
    r_close = _cells(params.free_close_m, res)
    grown = cv2.dilate(free_raw.astype(np.uint8), _square(r_close)) if r_close > 0 \
        else free_raw.astype(np.uint8)
    free_clean = (grown > 0) & (obst == 0)
    return free_raw, free_clean


def _clean_influence_cells(params: SegmentationParams, res: float) -> int:
    """How far (cells) a changed grid cell can change the cleaned mask."""
    speck = int(math.ceil(params.obstacle_speck_area_m2 / (res * res)))
    return max(_cells(params.obstacle_inflation_m, res),
               _cells(params.free_close_m, res)) + speck + 2


def _bbox(mask: npt.NDArray[np.bool_], margin: int
          ) -> tuple[slice, slice] | None:
    """Bounding box of the true cells grown by ``margin`` (clipped), or None."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (slice(max(0, rows[0] - margin), min(h, rows[-1] + 1 + margin)),
            slice(max(0, cols[0] - margin), min(w, cols[-1] + 1 + margin)))


def _fill_gaps(labels: npt.NDArray[np.int32], domain: npt.NDArray[np.bool_],
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
    # grey dilation on ranks (float32 is exact below 2**24; ids may be larger)
    uniq, inv = np.unique(lab, return_inverse=True)
    rank = inv.reshape(lab.shape).astype(np.float32)
    k = np.ones((3, 3), np.uint8)
    for _ in range(max_iter):
        grown = cv2.dilate(rank, k)
        put = tgt & (grown > 0)
        if not put.any():
            break
        rank[put] = grown[put]
        tgt &= ~put
        if not tgt.any():
            break
    filled = todo[r0:r1, c0:c1] & (rank > 0)
    lab[filled] = uniq[rank[filled].astype(np.int64)]


def _counts(values: npt.NDArray[np.integer]) -> dict[int, int]:
    """{id: count} of the ids > 0 in ``values`` (ids are bounded by the id counter)."""
    v = values.ravel()
    if v.size == 0:
        return {}
    c = np.bincount(v)          # labels are never negative
    c[0] = 0
    nz = np.flatnonzero(c)
    return dict(zip(nz.tolist(), c[nz].tolist()))


def _pair_counts(lab: npt.NDArray[np.int32]) -> dict[tuple[int, int], int]:
    """Number of 4-neighbour cell pairs between every two different non-zero labels."""
    out: dict[tuple[int, int], int] = {}
    for a, b in ((lab[:, :-1], lab[:, 1:]), (lab[:-1, :], lab[1:, :])):
        m = (a != b) & (a > 0) & (b > 0)
        if not m.any():
            continue
        x = np.minimum(a[m], b[m]).astype(np.int64)
        y = np.maximum(a[m], b[m]).astype(np.int64)
        keys, cnt = np.unique(x * (1 << 32) + y, return_counts=True)
        for key, c in zip(keys.tolist(), cnt.tolist()):
            pair = (key >> 32, key & 0xFFFFFFFF)
            out[pair] = out.get(pair, 0) + c
    return out


def _max_concavity(mask: npt.NDArray[np.uint8]) -> float:
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


def _merge_regions(labels: npt.NDArray[np.int32], out_mask: npt.NDArray[np.bool_],
                   candidates: set[int] | None, params: SegmentationParams,
                   res: float) -> None:
    """Merge too small or too thin regions (and optionally corridor parts), in place.

    Parameters
    ----------
    labels : ndarray of int32, shape (H, W)
        Domain labels (modified in place).
    out_mask : ndarray of bool, shape (H, W)
        The cells whose labels are published (raw free cells); areas are counted there.
    candidates : set of int or None
        Only these ids may be merged away (None: all ids).
    """
    areas = {k: 0 for k in _counts(labels)}
    areas.update(_counts(labels[out_mask]))
    if not areas:
        return
    cand = set(areas) if candidates is None else {c for c in candidates if c in areas}
    borders = _pair_counts(labels)
    mg = _Merger(areas, borders)
    min_area = params.min_region_area_m2 / (res * res)
    thin: set[int] = set()
    if params.min_region_width_m > 0 and cand:
        half_w = 0.5 * params.min_region_width_m / res
        dist = cv2.distanceTransform((labels > 0).astype(np.uint8), cv2.DIST_L2, 3)
        # a region is thin when no cell is farther than half the width from its border;
        # borders between regions count as borders too
        edge = np.zeros(labels.shape, dtype=bool)
        edge[:, :-1] |= labels[:, :-1] != labels[:, 1:]
        edge[:, 1:] |= labels[:, :-1] != labels[:, 1:]
        edge[:-1, :] |= labels[:-1, :] != labels[1:, :]
        edge[1:, :] |= labels[:-1, :] != labels[1:, :]
        dist2 = cv2.distanceTransform((~edge).astype(np.uint8), cv2.DIST_L2, 3)
        dd = np.minimum(dist, dist2)
        wide = _counts(labels[dd >= half_w])
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
    if params.corridor_merge:
        _corridor_merge(labels, mg, cand, params, res)
    lut_keys = [k for k in mg.parent if mg.root(k) != k or k in dropped]
    if not lut_keys:
        return
    mapping = {k: (0 if mg.root(k) in dropped or k in dropped else mg.root(k))
               for k in lut_keys}
    _apply_mapping(labels, mapping)


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
        if _max_concavity(sub) < limit:
            small, into = (a, b) if mg.area[a] <= mg.area[b] else (b, a)
            mg.merge(small, into)
            cand.add(into)


def _apply_mapping(labels: npt.NDArray[np.int32], mapping: dict[int, int]) -> None:
    """Replace ids in place, all at once (``mapping``: old id -> new id)."""
    if not mapping:
        return
    top = max(int(labels.max()), max(mapping)) + 1
    lut = np.arange(top, dtype=np.int64)
    lut[np.fromiter(mapping.keys(), np.int64)] = np.fromiter(mapping.values(), np.int64)
    labels[...] = lut[labels].astype(np.int32)


def _match_ids(new: npt.NDArray[np.int32], old: npt.NDArray[np.int32],
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
    keys, cnt = np.unique(a * (1 << 32) + b, return_counts=True)
    best: dict[int, tuple[int, int]] = {}
    for key, c in zip(keys.tolist(), cnt.tolist()):
        i, j = key >> 32, key & 0xFFFFFFFF
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


def _shift_into(old: npt.NDArray, shape: tuple[int, int], drow: int, dcol: int,
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


# ------------------------------------------------------------------------- segmenter


class IncrementalSegmenter:
    """DuDe room segmentation with state: incremental updates and persistent ids.

    Parameters
    ----------
    params : SegmentationParams, optional

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii("#####\\n#...#\\n#####", resolution_m=0.5)
    >>> seg = IncrementalSegmenter(SegmentationParams(
    ...     min_region_area_m2=0.1, obstacle_inflation_m=0.0, free_close_m=0.0))
    >>> seg.update(g).tolist()
    [[0, 0, 0, 0, 0], [0, 1, 1, 1, 0], [0, 0, 0, 0, 0]]
    >>> seg.last_update_info.mode
    'full'
    """

    def __init__(self, params: SegmentationParams | None = None) -> None:
        self.params = params if params is not None else SegmentationParams()
        self._labels: npt.NDArray[np.int32] | None = None   # domain labels
        self._geom: GridMap | None = None
        self._data: npt.NDArray[np.int8] | None = None
        self._free_raw: npt.NDArray[np.bool_] | None = None
        self._free_clean: npt.NDArray[np.bool_] | None = None
        self._next_id = 1
        self._force_full = False
        self.last_update_info: UpdateInfo | None = None

    # --------------------------------------------------------------- public API
    def reset(self) -> None:
        """Forget the state (the id counter keeps counting: ids are never reused)."""
        self._labels = None
        self._geom = None
        self._data = None
        self._free_raw = None
        self._free_clean = None

    def set_params(self, params: SegmentationParams) -> None:
        """Use new parameters; the next update is a full run whose ids are matched."""
        self.params = params
        self._data = None
        self._force_full = True

    @property
    def next_id(self) -> int:
        """The id the next new region will get (ids are never reused)."""
        return self._next_id

    def update(self, grid: GridMap) -> npt.NDArray[np.int32]:
        """Segment ``grid``, reusing the previous result where nothing changed.

        Parameters
        ----------
        grid : GridMap

        Returns
        -------
        ndarray of int32, shape (grid.height, grid.width)
            Region ids (0 = no region), stable between calls for regions that did not
            change (DuDe spec shared/docs/dude.md §11-§12).

        Raises
        ------
        TypeError
            When ``grid`` is not a GridMap.
        """
        if not isinstance(grid, GridMap):
            raise TypeError(f"grid must be a GridMap, got {type(grid).__name__}")
        t0 = time.perf_counter()
        res = grid.resolution_m
        if grid.data.size == 0:
            self.reset()
            self.last_update_info = UpdateInfo("empty", time.perf_counter() - t0, 0, 0, 0)
            return np.zeros(grid.shape, dtype=np.int32)
        shift = self._aligned_shift(grid)
        prev_known_f = None
        if shift is not None and self._free_raw is not None and self._free_clean is not None:
            # cells that were known free and in the cleaned free space before
            prev_known_f = _shift_into(self._free_raw & self._free_clean, grid.shape, *shift)
        free_raw, free_clean = self._clean_update(grid, shift)
        domain = free_raw | free_clean
        prev = None
        if shift is not None and self._labels is not None:
            prev = _shift_into(self._labels, grid.shape, *shift)
        reason = ""
        if prev is None:
            reason = "no compatible previous state"
        elif self._force_full:
            reason = "parameters changed"
        if reason:
            if prev is None and self._labels is not None and self._geom is not None:
                prev = _resample_labels(self._labels, self._geom, grid)
            labels = self._full(free_raw, free_clean, domain, res, prev)
            mode, n_areas, n_cells = "full", 0, int(domain.sum())
        else:
            assert prev is not None and prev_known_f is not None
            labels, mode, n_areas, n_cells, reason = self._incremental(
                free_raw, free_clean, domain, res, prev, prev_known_f)
        self._force_full = False
        self._labels = labels
        self._geom = grid
        self._data = grid.data.copy()
        self._free_raw, self._free_clean = free_raw, free_clean
        out = np.where(free_raw, labels, 0).astype(np.int32)
        self.last_update_info = UpdateInfo(mode, time.perf_counter() - t0, n_areas,
                                           n_cells, len(_counts(out)), reason)
        return out

    # ---------------------------------------------------------------- internals
    def _aligned_shift(self, grid: GridMap) -> tuple[int, int] | None:
        """Whole-cell shift (drow, dcol) from the previous grid to ``grid``, or None."""
        g0 = self._geom
        if self._labels is None or g0 is None:
            return None
        if (abs(g0.resolution_m - grid.resolution_m) > 1e-9 * grid.resolution_m
                or g0.frame_id != grid.frame_id
                or abs(g0.origin_yaw_rad - grid.origin_yaw_rad) > 1e-9):
            return None
        r, c = grid.world_to_cell_float(*g0.cells_to_world(np.array([0]), np.array([0])))
        fr, fc = float(r[0]) - 0.5, float(c[0]) - 0.5
        ir, ic = round(fr), round(fc)
        if abs(fr - ir) > 1e-3 or abs(fc - ic) > 1e-3:
            return None
        return int(ir), int(ic)

    def _clean_update(self, grid: GridMap, shift: tuple[int, int] | None
                      ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
        """Cleaned masks of ``grid``, recomputed only around changed cells when possible."""
        p = self.params
        res = grid.resolution_m
        if (shift is None or self._data is None or self._free_raw is None
                or self._free_clean is None):
            return _clean(grid.data, p, res)
        old = _shift_into(self._data, grid.shape, *shift, fill=-1, reuse=True)
        changed = old != grid.data
        infl = _clean_influence_cells(p, res)
        box = _bbox(changed, infl)
        # cells the old masks did not cover (grown area) are recomputed too
        # the old masks are replaced by the result, so they may be updated in place
        free_raw = _shift_into(self._free_raw, grid.shape, *shift, reuse=True)
        free_clean = _shift_into(self._free_clean, grid.shape, *shift, reuse=True)
        if shift != (0, 0) or self._data.shape != grid.shape:
            cover = _shift_into(np.ones(self._data.shape, dtype=bool), grid.shape, *shift)
            edge = _bbox(~cover, infl)
            if edge is not None:
                box = edge if box is None else (
                    slice(min(box[0].start, edge[0].start), max(box[0].stop, edge[0].stop)),
                    slice(min(box[1].start, edge[1].start), max(box[1].stop, edge[1].stop)))
        if box is None:
            return free_raw, free_clean
        h, w = grid.shape
        wr = slice(max(0, box[0].start - infl), min(h, box[0].stop + infl))
        wc = slice(max(0, box[1].start - infl), min(w, box[1].stop + infl))
        fr, fc = _clean(grid.data[wr, wc], p, res)
        ir = slice(box[0].start - wr.start, box[0].stop - wr.start)
        ic = slice(box[1].start - wc.start, box[1].stop - wc.start)
        free_raw[box] = fr[ir, ic]
        free_clean[box] = fc[ir, ic]
        return free_raw, free_clean

    def _fresh(self) -> int:
        k = self._next_id
        self._next_id += 1
        return k

    def _fill_iters(self, res: float) -> int:
        p = self.params
        return 2 * (_cells(p.obstacle_inflation_m, res) + _cells(p.free_close_m, res)) + 4

    def _decompose(self, free_clean: npt.NDArray[np.bool_], res: float,
                   labels: npt.NDArray[np.int32], area: npt.NDArray[np.bool_] | None,
                   temp_next: int) -> tuple[list[int], int]:
        """Decompose ``free_clean`` (inside ``area``), writing temporary ids into labels."""
        st = _settings(self.params, res)
        if area is None:
            pieces, n = decompose_mask(free_clean, st)
            sel = pieces > 0
            labels[sel] = pieces[sel] + (temp_next - 1)
            return list(range(temp_next, temp_next + n)), temp_next + n
        box = _bbox(area, 2)
        if box is None:
            return [], temp_next
        sub = free_clean[box] & area[box]
        pieces, n = decompose_mask(sub, st)
        sel = pieces > 0
        labels[box][sel] = pieces[sel] + (temp_next - 1)
        return list(range(temp_next, temp_next + n)), temp_next + n

    def _finish(self, labels: npt.NDArray[np.int32], free_raw: npt.NDArray[np.bool_],
                domain: npt.NDArray[np.bool_], res: float, temp_ids: list[int],
                old: npt.NDArray[np.int32] | None, old_area: dict[int, int],
                merge_all: bool) -> set[int]:
        """Gap filling, new free components, merging, id matching (in place).

        The arrays may be crops (views) of the full images; ``temp_ids`` are the ids of
        the new pieces, which get old ids by overlap with ``old`` or fresh ids. Returns
        the final ids of the new pieces.
        """
        p = self.params
        _fill_gaps(labels, domain, self._fill_iters(res))
        temp_next = (max(temp_ids) + 1) if temp_ids else self._next_id
        # free components still unlabelled (touching no region): new regions or specks
        rest = domain & (labels == 0)
        if rest.any():
            n, lab = cv2.connectedComponents(rest.astype(np.uint8), connectivity=8)
            labels[rest] = lab[rest] + (temp_next - 1)
            temp_ids = temp_ids + list(range(temp_next, temp_next + n - 1))
        _merge_regions(labels, free_raw, None if merge_all else set(temp_ids), p, res)
        present = _counts(labels)
        live = [t for t in temp_ids if t in present]
        mapping: dict[int, int] = {}
        if old is not None and live:
            mapping.update(_match_ids(labels, old, live, p.id_keep_frac, old_area))
        for t in live:
            if t not in mapping:
                mapping[t] = self._fresh()
        _apply_mapping(labels, mapping)
        return set(mapping.values())

    def _leftovers(self, labels: npt.NDArray[np.int32], free_raw: npt.NDArray[np.bool_],
                   domain: npt.NDArray[np.bool_], res: float) -> None:
        """Label domain cells no piece covers yet (small new blobs), in place."""
        if not (domain & (labels == 0)).any():
            return
        _fill_gaps(labels, domain, self._fill_iters(res))
        rest = domain & (labels == 0)
        if not rest.any():
            return
        box = _bbox(rest, 1)
        n, lab = cv2.connectedComponents(rest[box].astype(np.uint8), connectivity=8)
        if n <= 1:
            return
        area = np.bincount(lab[free_raw[box]].ravel(), minlength=n)
        min_px = self.params.min_region_area_m2 / (res * res)
        sub = labels[box]
        for k in np.flatnonzero(area >= min_px).tolist():
            if k > 0:
                sub[lab == k] = self._fresh()

    def _full(self, free_raw, free_clean, domain, res, prev) -> npt.NDArray[np.int32]:
        labels = np.zeros(domain.shape, dtype=np.int32)
        temp_ids, _ = self._decompose(free_clean, res, labels, None, self._next_id)
        old_area = _counts(prev) if prev is not None else {}
        self._finish(labels, free_raw, domain, res, temp_ids, prev, old_area, True)
        return labels

    def _incremental(self, free_raw, free_clean, domain, res, prev, prev_known_f):
        p = self.params
        cell_area = res * res
        labels = prev.copy()
        old_area = _counts(labels)
        dirty: set[int] = set()
        # known free cells that left the cleaned free space: new obstacles, map fixes
        blocked = (labels > 0) & prev_known_f & ~free_clean
        lost = (labels > 0) & ~domain
        labels[lost] = 0
        new_free = free_clean & (labels == 0)
        blobs = None
        box_new = _bbox(new_free, 0)
        if box_new is not None:
            nf = new_free[box_new].astype(np.uint8)
            n, lab, stats, _ = cv2.connectedComponentsWithStats(nf, connectivity=8)
            big = stats[:, cv2.CC_STAT_AREA] * cell_area > p.inc_min_blob_m2
            big[0] = False
            if big.any():
                blobs = np.zeros(domain.shape, dtype=bool)
                blobs[box_new] = big[lab]
                t = p.inc_touch_cells
                bb = _bbox(blobs, t + 1)
                near = cv2.dilate(blobs[bb].astype(np.uint8),
                                  np.ones((2 * t + 1, 2 * t + 1), np.uint8)) > 0
                dirty.update(_counts(labels[bb][near]))
        if blocked.any():
            bl_cnt = _counts(prev[blocked])
            for i, c in bl_cnt.items():
                if c > p.inc_lost_frac * old_area[i]:
                    dirty.add(i)
            check = sorted((i for i in bl_cnt if i not in dirty), key=lambda i: -bl_cnt[i])
            if check:
                from scipy import ndimage
                objs = ndimage.find_objects(labels, max_label=max(check))
                st = _settings(p, res)
                tau_cells = p.tau_m / res
                tests = 0
                for i in check:
                    sl = objs[i - 1]
                    if sl is None:
                        continue
                    piece = labels[sl] == i
                    # split by a new obstacle, or a new structure DuDe would now cut
                    if cv2.connectedComponents(piece.astype(np.uint8), connectivity=8)[0] > 2:
                        dirty.add(i)
                    elif bl_cnt[i] >= tau_cells and tests < _MAX_SHAPE_TESTS:
                        tests += 1
                        sub = np.pad((piece & free_clean[sl]).astype(np.uint8), 1)
                        n_sub = cv2.connectedComponents(sub, connectivity=4)[0]
                        if n_sub > 2 or (n_sub == 2 and find_cuts(sub, st)):
                            dirty.add(i)
        if not dirty and blobs is None:
            self._leftovers(labels, free_raw, domain, res)
            return labels, "unchanged", 0, 0, ""
        lut = np.zeros(max(max(old_area, default=0), max(dirty, default=0)) + 2, dtype=bool)
        lut[list(dirty)] = True
        work = lut[labels]
        if blobs is not None:
            work |= blobs
        n_work = int(work.sum())
        n_dom = max(1, int(domain.sum()))
        if n_work > p.inc_full_frac * n_dom:
            full = self._full(free_raw, free_clean, domain, res, prev)
            return full, "full", 0, n_dom, (
                f"work areas {n_work} cells > {p.inc_full_frac:.2f} of {n_dom}")
        box = _bbox(work, self._fill_iters(res) + p.inc_touch_cells + 2)
        if box is None:
            self._leftovers(labels, free_raw, domain, res)
            return labels, "unchanged", 0, 0, ""
        lab_c = labels[box]
        work_c = work[box]
        old_c = np.where(work_c, lab_c, 0)
        lab_c[work_c] = 0
        n_areas, alab = cv2.connectedComponents(work_c.astype(np.uint8), connectivity=8)
        temp_ids: list[int] = []
        temp_next = self._next_id
        fc = free_clean[box]
        for a in range(1, n_areas):
            ids, temp_next = self._decompose(fc, res, lab_c, alab == a, temp_next)
            temp_ids += ids
        redone = self._finish(lab_c, free_raw[box], domain[box], res, temp_ids, old_c,
                              old_area, False)
        self._heal_seams(labels, free_clean, box, redone, res)
        self._leftovers(labels, free_raw, domain, res)
        return labels, "incremental", n_areas - 1, n_work, ""

    def _heal_seams(self, labels: npt.NDArray[np.int32], free_clean: npt.NDArray[np.bool_],
                    box: tuple[slice, slice], redone: set[int], res: float) -> None:
        """Merge a new piece into a clean neighbour when their union is convex enough.

        Pieces outside the work areas are kept as they are (§11.7), so a cut made at an
        old frontier (across a corridor that was only half seen, say) would stay forever.
        For every pair (new piece, clean neighbour) sharing a border of at least half a
        door width, the deepest concavity of the union's outer ring (convexity defects,
        the top-level concavity of §6) is measured inside a window around the work area;
        below tau DuDe would not cut the union, and the new piece takes the neighbour's
        id. Longest borders first; at most one merge per piece and update.
        """
        p = self.params
        pairs = _pair_counts(labels[box])
        min_border = 0.5 * p.max_door_width_m / res
        cand = sorted(((c, a, b) for (a, b), c in pairs.items()
                       if c >= min_border and ((a in redone) != (b in redone))), reverse=True)
        if not cand:
            return
        tau_px = p.tau_m / res
        m = int(math.ceil(2 * tau_px))
        h, w = labels.shape
        win = (slice(max(0, box[0].start - m), min(h, box[0].stop + m)),
               slice(max(0, box[1].start - m), min(w, box[1].stop + m)))
        lab_w = labels[win]
        fc_w = free_clean[win]
        used: set[int] = set()
        for _c, a, b in cand[:_MAX_SEAM_TESTS]:
            new, old = (a, b) if a in redone else (b, a)
            if new in used or old in used:
                continue
            both = (lab_w == new) | (lab_w == old)
            bb = _bbox(both, 1)
            union = np.pad((both[bb] & fc_w[bb]).astype(np.uint8), 1)
            if cv2.connectedComponents(union, connectivity=4)[0] != 2:
                continue
            if _max_concavity(union) < tau_px:
                lab_w[both & (lab_w == new)] = old
                used |= {new, old}


def _resample_labels(old: npt.NDArray[np.int32], g0: GridMap, g1: GridMap
                     ) -> npt.NDArray[np.int32]:
    """Old labels at the cell centres of ``g1`` (nearest cell; 0 outside ``g0``)."""
    rows, cols = np.indices(g1.shape)
    x, y = g1.cells_to_world(rows.ravel(), cols.ravel())
    r, c = g0.world_to_cells(x, y)
    ok = (r >= 0) & (r < g0.height) & (c >= 0) & (c < g0.width)
    out = np.zeros(g1.shape[0] * g1.shape[1], dtype=np.int32)
    out[ok] = old[r[ok], c[ok]]
    return out.reshape(g1.shape)


def segment(grid: GridMap, params: SegmentationParams | None = None
            ) -> npt.NDArray[np.int32]:
    """Batch DuDe room segmentation of one grid.

    Parameters
    ----------
    grid : GridMap
    params : SegmentationParams, optional

    Returns
    -------
    ndarray of int32, shape (grid.height, grid.width)
        0 = no region; ids 1..n numbered in raster order of their first cell.

    Examples
    --------
    >>> from explore_seg.core.grid import grid_from_ascii
    >>> g, _ = grid_from_ascii("####\\n#..#\\n####", resolution_m=0.5)
    >>> segment(g, SegmentationParams(min_region_area_m2=0.1, obstacle_inflation_m=0.0,
    ...                               free_close_m=0.0)).max().item()
    1
    """
    seg = IncrementalSegmenter(params)
    labels = seg.update(grid)
    return _renumber(labels)


def _renumber(labels: npt.NDArray[np.int32]) -> npt.NDArray[np.int32]:
    """Ids 1..n in raster order of each region's first cell."""
    flat = labels.ravel()
    ids, first = np.unique(flat, return_index=True)
    keep = ids > 0
    ids, first = ids[keep], first[keep]
    order = ids[np.argsort(first)]
    lut = {int(i): k + 1 for k, i in enumerate(order.tolist())}
    out = labels.copy()
    _apply_mapping(out, lut)
    return out
