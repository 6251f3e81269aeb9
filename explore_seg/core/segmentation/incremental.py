"""The stateful segmenter: incremental DuDe updates and persistent region ids
(DuDe spec shared/docs/dude.md §11-§12), and the one-shot :func:`segment`.

Every update works on the bounding box of the grid's known cells, grown by a margin
that no cleaning or labelling step reaches across (:func:`known_crop`) and snapped
outward to :data:`CROP_CHUNK_CELLS`: its memory and time scale with the explored area,
not with the grid (a 5000 x 5000 map that is mostly unknown costs what its known part
costs). The labels are the ones the whole grid would get; the state is kept in the
crop's geometry, so a crop that moves or grows is an ordinary map shift.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.segmentation.clean_update import union, update_clean_state
from explore_seg.core.segmentation.cleaning import CleanState, clean_state, length_to_cells
from explore_seg.core.segmentation.crop import (CROP_CHUNK_CELLS, crop_grid,  # noqa: F401
                                                crop_margin_cells, known_crop)
from explore_seg.core.segmentation.dude import decompose_mask, find_cuts
from explore_seg.core.segmentation.furniture import FillCache
from explore_seg.core.segmentation.labels import (apply_mapping, bbox, fill_gaps,
                                                  label_counts, lookup_mask, match_ids,
                                                  pair_counts, renumber, resample_labels,
                                                  shift_into)
from explore_seg.core.segmentation.merging import max_concavity, merge_regions
from explore_seg.core.segmentation.params import SegmentationParams, dude_settings

#: Bounds on the DuDe checks of one incremental update: seams between new and clean
#: pieces, and clean pieces whose shape changed.
_MAX_SEAM_TESTS = 6
_MAX_SHAPE_TESTS = 4
@dataclass(frozen=True)
class UpdateInfo:
    """What the last :meth:`IncrementalSegmenter.update` did.

    ``regions`` (the number of regions in the result) is counted when first read: the
    count costs a pass over the labels that most callers never need.
    """

    mode: str                  # "full", "incremental", "unchanged" or "empty"
    time_s: float              # wall time of the update
    work_areas: int            # number of work areas redone (0 for full/unchanged)
    work_cells: int            # cells in the work areas (all domain cells for full)
    reason: str = ""           # why a full run was done
    # the segmenter's labels and the published cells (never written after the update)
    _labels: npt.NDArray[np.int32] | None = field(default=None, repr=False, compare=False)
    _shown: npt.NDArray[np.bool_] | None = field(default=None, repr=False, compare=False)
    _count: list[int] = field(default_factory=list, repr=False, compare=False)

    @property
    def regions(self) -> int:
        """Number of regions in the result."""
        if self._labels is None or self._shown is None:
            return 0
        if not self._count:
            out = np.multiply(self._labels, self._shown, dtype=np.int32)
            self._count.append(len(label_counts(out)))
        return self._count[0]



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
        # the obstacles as inflated and their furniture bulges (None: rule off)
        self._occ: npt.NDArray[np.uint8] | None = None
        self._bulge: npt.NDArray[np.bool_] | None = None
        self._shown: npt.NDArray[np.bool_] | None = None
        # the cleaned free space before the fills and after the clutter fill
        self._base: npt.NDArray[np.bool_] | None = None
        self._clutter: npt.NDArray[np.bool_] | None = None
        # the bulges' fills, keyed in cells of the first grid of this state; that grid's
        # cell (0, 0) is cell _ref_rc of the current one
        self._fill_cache = FillCache()
        self._ref_rc = (0, 0)
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
        self._occ = None
        self._bulge = None
        self._shown = None
        self._base = None
        self._clutter = None
        self._fill_cache = FillCache()

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
            change (DuDe spec shared/docs/dude.md §11-§12). Only the known cells' crop
            (:func:`known_crop`) is segmented; the labels equal the whole grid's.

        Raises
        ------
        TypeError
            When ``grid`` is not a GridMap.
        """
        if not isinstance(grid, GridMap):
            raise TypeError(f"grid must be a GridMap, got {type(grid).__name__}")
        t0 = time.perf_counter()
        box = (known_crop(grid.data, crop_margin_cells(self.params, grid.resolution_m))
               if grid.data.size else None)
        if box is None:
            # nothing known: no region (and no state worth keeping)
            self.reset()
            self.last_update_info = UpdateInfo("empty", time.perf_counter() - t0, 0, 0)
            return np.zeros(grid.shape, dtype=np.int32)
        if (box[0].stop - box[0].start, box[1].stop - box[1].start) == grid.shape:
            return self._update_grid(grid, t0)             # the crop is the whole grid
        out = np.zeros(grid.shape, dtype=np.int32)
        out[box] = self._update_grid(crop_grid(grid, box), t0)
        return out

    def _update_grid(self, grid: GridMap, t0: float) -> npt.NDArray[np.int32]:
        """:meth:`update` on the whole of ``grid`` (a crop of the caller's grid)."""
        res = grid.resolution_m
        if grid.data.size == 0:
            self.reset()
            self.last_update_info = UpdateInfo("empty", time.perf_counter() - t0, 0, 0)
            return np.zeros(grid.shape, dtype=np.int32)
        shift = self._aligned_shift(grid)
        prev_known_f = None
        if shift is not None and self._free_raw is not None and self._free_clean is not None:
            # cells that were known free and in the cleaned free space before
            prev_known_f = shift_into(self._free_raw & self._free_clean, grid.shape, *shift)
        cs = self._clean_update(grid, shift)
        free_raw, free_clean = cs.free_raw, cs.free_clean
        domain = free_raw | free_clean
        prev = None
        if shift is not None and self._labels is not None:
            prev = shift_into(self._labels, grid.shape, *shift, reuse=True)  # read only
        reason = ""
        if prev is None:
            reason = "no compatible previous state"
        elif self._force_full:
            reason = "parameters changed"
        if reason:
            if prev is None and self._labels is not None and self._geom is not None:
                prev = resample_labels(self._labels, self._geom, grid)
            labels = self._full(free_raw, free_clean, domain, res, prev)
            mode, n_areas, n_cells = "full", 0, int(np.count_nonzero(domain))
        else:
            assert prev is not None and prev_known_f is not None
            labels, mode, n_areas, n_cells, reason = self._incremental(
                free_raw, free_clean, domain, res, prev, prev_known_f)
        self._force_full = False
        self._labels = labels
        self._data = grid.data.copy()
        # the geometry over the copy: a crop's data is a view that would keep the
        # caller's whole grid alive
        self._geom = grid.with_data(self._data)
        self._free_raw, self._free_clean = free_raw, free_clean
        self._occ, self._bulge, self._shown = cs.occ, cs.bulge, cs.shown
        self._base, self._clutter = cs.base, cs.clutter
        # free cells, and free-standing furniture the cleaning counts as room: a table in
        # an office is part of it
        shown = cs.shown
        out = np.multiply(labels, shown, dtype=np.int32)
        self.last_update_info = UpdateInfo(mode, time.perf_counter() - t0, n_areas,
                                           n_cells, reason, labels, shown.copy())
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
                      ) -> CleanState:
        """:func:`.cleaning.clean_state` of ``grid``, recomputed only around changed
        cells when possible (:func:`.clean_update.update_clean_state`)."""
        p = self.params
        res = grid.resolution_m
        if (shift is None or self._data is None or self._free_raw is None
                or self._free_clean is None or self._occ is None or self._shown is None
                or self._base is None or self._clutter is None
                or (p.furniture_min_thickness_m > 0) != (self._bulge is not None)):
            self._fill_cache = FillCache()
            self._ref_rc = (0, 0)
            return clean_state(grid.data, p, res, fill_cache=self._fill_cache)
        self._ref_rc = (self._ref_rc[0] + shift[0], self._ref_rc[1] + shift[1])
        old = shift_into(self._data, grid.shape, *shift, fill=-1, reuse=True)
        box = bbox(old != grid.data, 0)
        if shift != (0, 0) or self._data.shape != grid.shape:
            # cells the old masks did not cover (grown area) are recomputed too
            cover = shift_into(np.ones(self._data.shape, dtype=bool), grid.shape, *shift)
            box = union(box, bbox(~cover, 0))
        # the old masks are replaced by the result, so they may be updated in place;
        # cells the old state did not cover count as changed obstacles (value 2)
        st = CleanState(*(None if a is None else shift_into(a, grid.shape, *shift, reuse=True,
                                                            fill=f)
                          for a, f in ((self._free_raw, 0), (self._free_clean, 0),
                                       (self._occ, 2), (self._bulge, 0), (self._shown, 0),
                                       (self._base, 0), (self._clutter, 0))))
        if box is None:
            return st
        return update_clean_state(st, grid.data, box, p, res, self._fill_cache,
                                  (-self._ref_rc[0], -self._ref_rc[1]))

    def _fresh(self) -> int:
        k = self._next_id
        self._next_id += 1
        return k

    def _fill_iters(self, res: float) -> int:
        p = self.params
        return 2 * (length_to_cells(p.obstacle_inflation_m, res)
                    + length_to_cells(p.free_close_m, res)) + 4

    def _decompose(self, free_clean: npt.NDArray[np.bool_], res: float,
                   labels: npt.NDArray[np.int32], area: npt.NDArray[np.bool_] | None,
                   temp_next: int) -> tuple[list[int], int]:
        """Decompose ``free_clean`` (inside ``area``), writing temporary ids into labels."""
        st = dude_settings(self.params, res)
        if area is None:
            pieces, n = decompose_mask(free_clean, st)
            sel = pieces > 0
            labels[sel] = pieces[sel] + (temp_next - 1)
            return list(range(temp_next, temp_next + n)), temp_next + n
        box = bbox(area, 2)
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
        fill_gaps(labels, domain, self._fill_iters(res))
        temp_next = (max(temp_ids) + 1) if temp_ids else self._next_id
        # free components still unlabelled (touching no region): new regions or specks
        rest = domain & (labels == 0)
        if rest.any():
            n, lab = cv2.connectedComponents(rest.astype(np.uint8), connectivity=8)
            labels[rest] = lab[rest] + (temp_next - 1)
            temp_ids = temp_ids + list(range(temp_next, temp_next + n - 1))
        merge_regions(labels, free_raw, None if merge_all else set(temp_ids), p, res)
        present = label_counts(labels)
        live = [t for t in temp_ids if t in present]
        mapping: dict[int, int] = {}
        if old is not None and live:
            mapping.update(match_ids(labels, old, live, p.id_keep_frac, old_area))
        for t in live:
            if t not in mapping:
                mapping[t] = self._fresh()
        apply_mapping(labels, mapping)
        return set(mapping.values())

    def _leftovers(self, labels: npt.NDArray[np.int32], free_raw: npt.NDArray[np.bool_],
                   domain: npt.NDArray[np.bool_], res: float) -> None:
        """Label domain cells no piece covers yet (small new blobs), in place."""
        if not (domain & (labels == 0)).any():
            return
        fill_gaps(labels, domain, self._fill_iters(res))
        rest = domain & (labels == 0)
        if not rest.any():
            return
        box = bbox(rest, 1)
        n, lab = cv2.connectedComponents(rest[box].astype(np.uint8), connectivity=8)
        if n <= 1:
            return
        rr, cc = np.nonzero(rest[box])             # the few cells of the components
        area = np.bincount(lab[rr, cc][free_raw[box][rr, cc]], minlength=n)
        min_px = self.params.min_region_area_m2 / (res * res)
        sub = labels[box]
        for k in np.flatnonzero(area >= min_px).tolist():
            if k > 0:
                sub[lab == k] = self._fresh()

    def _full(self, free_raw, free_clean, domain, res, prev) -> npt.NDArray[np.int32]:
        labels = np.zeros(domain.shape, dtype=np.int32)
        temp_ids, _ = self._decompose(free_clean, res, labels, None, self._next_id)
        old_area = label_counts(prev) if prev is not None else {}
        self._finish(labels, free_raw, domain, res, temp_ids, prev, old_area, True)
        return labels

    def _incremental(self, free_raw, free_clean, domain, res, prev, prev_known_f):
        labels = prev.copy()
        old_area = label_counts(labels)
        # known free cells that left the cleaned free space: new obstacles, map fixes
        pos = labels > 0
        blocked = pos & prev_known_f & ~free_clean
        lost = pos & ~domain
        if lost.any():
            labels[lost] = 0
            pos &= ~lost
        dirty, blobs = self._new_blobs(labels, free_clean & ~pos, domain.shape, res)
        if blocked.any():
            dirty |= self._blocked_pieces(labels, prev[blocked], free_clean, res, old_area,
                                          dirty)
        if not dirty and blobs is None:
            self._leftovers(labels, free_raw, domain, res)
            return labels, "unchanged", 0, 0, ""
        work = self._work_area(labels, dirty, blobs, old_area)
        n_work = int(np.count_nonzero(work))
        n_dom = max(1, int(np.count_nonzero(domain)))
        if n_work > self.params.inc_full_frac * n_dom:
            full = self._full(free_raw, free_clean, domain, res, prev)
            return full, "full", 0, n_dom, (
                f"work areas {n_work} cells > {self.params.inc_full_frac:.2f} of {n_dom}")
        box = bbox(work, self._fill_iters(res) + self.params.inc_touch_cells + 2)
        if box is None:
            self._leftovers(labels, free_raw, domain, res)
            return labels, "unchanged", 0, 0, ""
        n_areas = self._redo(labels, work, box, free_raw, free_clean, domain, res, old_area)
        self._leftovers(labels, free_raw, domain, res)
        return labels, "incremental", n_areas, n_work, ""

    def _new_blobs(self, labels, new_free, shape, res):
        """(ids of pieces touching a newly seen free blob, mask of those blobs or None).
        Blobs of at most ``inc_min_blob_m2`` are only gap-filled."""
        p = self.params
        dirty: set[int] = set()
        box_new = bbox(new_free, 0)
        if box_new is None:
            return dirty, None
        nf = new_free[box_new].astype(np.uint8)
        n, lab, stats, _ = cv2.connectedComponentsWithStats(nf, connectivity=8)
        big = stats[:, cv2.CC_STAT_AREA] * (res * res) > p.inc_min_blob_m2
        big[0] = False
        if not big.any():
            return dirty, None
        blobs = np.zeros(shape, dtype=bool)
        blobs[box_new] = lookup_mask(big, lab)
        t = p.inc_touch_cells
        bb = bbox(blobs, t + 1)
        near = cv2.dilate(blobs[bb].astype(np.uint8),
                          np.ones((2 * t + 1, 2 * t + 1), np.uint8)) > 0
        dirty.update(label_counts(labels[bb][near]))
        return dirty, blobs

    def _blocked_pieces(self, labels, prev_blocked, free_clean, res, old_area, dirty):
        """Ids of pieces that new obstacles split, took a large share of, or changed so
        that DuDe would now cut them (``prev_blocked``: their old labels of those cells)."""
        p = self.params
        out: set[int] = set()
        bl_cnt = label_counts(prev_blocked)
        for i, c in bl_cnt.items():
            if c > p.inc_lost_frac * old_area[i]:
                out.add(i)
        check = sorted((i for i in bl_cnt if i not in dirty and i not in out),
                       key=lambda i: -bl_cnt[i])
        if not check:
            return out
        from scipy import ndimage
        objs = ndimage.find_objects(labels, max_label=max(check))
        st = dude_settings(p, res)
        tau_cells = p.tau_m / res
        tests = 0
        for i in check:
            sl = objs[i - 1]
            if sl is None:
                continue
            piece = labels[sl] == i
            # split by a new obstacle, or a new structure DuDe would now cut
            if cv2.connectedComponents(piece.astype(np.uint8), connectivity=8)[0] > 2:
                out.add(i)
            elif bl_cnt[i] >= tau_cells and tests < _MAX_SHAPE_TESTS:
                tests += 1
                sub = np.pad((piece & free_clean[sl]).astype(np.uint8), 1)
                n_sub = cv2.connectedComponents(sub, connectivity=4)[0]
                if n_sub > 2 or (n_sub == 2 and find_cuts(sub, st)):
                    out.add(i)
        return out

    @staticmethod
    def _work_area(labels, dirty, blobs, old_area):
        """Cells to decompose again: the dirty pieces and the new blobs."""
        if len(dirty) <= 4:     # a few comparisons are faster than a table look-up
            work = np.zeros(labels.shape, dtype=bool)
            for i in dirty:
                work |= labels == i
        else:
            lut = np.zeros(max(max(old_area, default=0), max(dirty)) + 2, dtype=bool)
            lut[list(dirty)] = True
            work = lookup_mask(lut, labels)
        if blobs is not None:
            work |= blobs
        return work

    def _redo(self, labels, work, box, free_raw, free_clean, domain, res, old_area) -> int:
        """Decompose the work areas inside ``box`` again, in place; the number of areas."""
        lab_c = labels[box]
        work_c = work[box]
        old_c = np.multiply(lab_c, work_c, dtype=np.int32)
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
        return n_areas - 1

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
        pairs = pair_counts(labels[box])
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
        tests = cand[:_MAX_SEAM_TESTS]
        from scipy import ndimage
        objs = ndimage.find_objects(lab_w, max_label=max(max(a, b) for _c, a, b in tests))
        hw, ww = lab_w.shape
        for _c, a, b in tests:
            new, old = (a, b) if a in redone else (b, a)
            if new in used or old in used:
                continue
            sa, sb = objs[new - 1], objs[old - 1]
            if sa is None or sb is None:
                continue
            # bounding box of both pieces' cells in the window, grown by one cell
            bb = (slice(max(0, min(sa[0].start, sb[0].start) - 1),
                        min(hw, max(sa[0].stop, sb[0].stop) + 1)),
                  slice(max(0, min(sa[1].start, sb[1].start) - 1),
                        min(ww, max(sa[1].stop, sb[1].stop) + 1)))
            sub = lab_w[bb]
            both = (sub == new) | (sub == old)
            union = np.pad((both & fc_w[bb]).astype(np.uint8), 1)
            if cv2.connectedComponents(union, connectivity=4)[0] != 2:
                continue
            if max_concavity(union) < tau_px:
                sub[sub == new] = old
                used |= {new, old}



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
    return renumber(labels)

