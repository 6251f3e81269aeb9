"""Recall / precision of a room segmentation against ground-truth rooms.

The metric of Bormann et al. (ICRA 2016), as computed by IPA's
``evaluation_segmentation.cpp`` (DuDe spec shared/docs/dude.md §17, caveat 3):

* ground-truth rooms are the distinct ids > 0 of ``gt_labels`` (or, with
  ``gt_connected=True``, the 8-connected components of ``gt_labels > 0``, which is how
  IPA reads its colour-less ground-truth drawings); predicted segments are the cells
  sharing an id > 0 in ``labels``;
* rooms and segments of at most ``min_segment_px`` cells are dropped;
* **recall** = mean over rooms of (largest overlap with one segment / room size);
* **precision** = mean over segments of (largest overlap with one room / segment size).

Over-segmentation lowers recall, merging rooms lowers precision. The area-weighted
versions (sums of the overlaps over sums of the sizes) are returned as well.
"""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt


def _sizes(lab: npt.NDArray[np.int64], min_px: int) -> dict[int, int]:
    ids, cnt = np.unique(lab[lab > 0], return_counts=True)
    return {int(i): int(c) for i, c in zip(ids, cnt) if c > min_px}


def evaluate(labels: npt.ArrayLike, gt_labels: npt.ArrayLike, min_segment_px: int = 100,
             gt_connected: bool = False) -> dict:
    """Bormann-style recall and precision of ``labels`` against ``gt_labels``.

    Parameters
    ----------
    labels : array_like of int, shape (H, W)
        Predicted region ids (0 = none).
    gt_labels : array_like of int, shape (H, W)
        Ground-truth room ids (0 = none).
    min_segment_px : int
        Rooms and segments with at most this many cells are ignored (IPA: 100).
    gt_connected : bool
        Use the 8-connected components of ``gt_labels > 0`` as rooms.

    Returns
    -------
    dict
        ``recall``, ``precision`` (fractions in [0, 1], NaN when there is no room or
        no segment), ``recall_weighted``, ``precision_weighted``, ``n_rooms``,
        ``n_segments``, ``rooms`` ({room id: {"size", "best_segment", "overlap",
        "recall"}}) and ``segments`` ({segment id: {"size", "best_room", "overlap",
        "precision"}}).

    Raises
    ------
    ValueError
        When the shapes differ, an input is not 2D or ``min_segment_px`` < 0.

    Examples
    --------
    >>> gt = np.array([[1, 1, 2, 2]])
    >>> evaluate(np.array([[5, 5, 5, 5]]), gt, min_segment_px=0)["precision"]
    0.5
    """
    lab = np.asarray(labels)
    gt = np.asarray(gt_labels)
    if lab.ndim != 2 or gt.ndim != 2:
        raise ValueError(f"labels and gt_labels must be 2D, got shapes {lab.shape} and "
                         f"{gt.shape}")
    if lab.shape != gt.shape:
        raise ValueError(f"labels shape {lab.shape} differs from gt_labels shape {gt.shape}")
    if min_segment_px < 0:
        raise ValueError(f"min_segment_px must be >= 0, got {min_segment_px}")
    lab = lab.astype(np.int64)
    gt = gt.astype(np.int64)
    if gt_connected:
        _n, comp = cv2.connectedComponents((gt > 0).astype(np.uint8), connectivity=8)
        gt = comp.astype(np.int64)
    rooms = _sizes(gt, min_segment_px)
    segs = _sizes(lab, min_segment_px)
    m = (lab > 0) & (gt > 0)
    pair_r = gt[m]
    pair_s = lab[m]
    ok = np.isin(pair_r, list(rooms)) & np.isin(pair_s, list(segs))
    best_room: dict[int, tuple[int, int]] = {}
    best_seg: dict[int, tuple[int, int]] = {}
    if ok.any():
        keys, cnt = np.unique(pair_r[ok] * (1 << 32) + pair_s[ok], return_counts=True)
        for key, c in zip(keys.tolist(), cnt.tolist()):
            r, s = key >> 32, key & 0xFFFFFFFF
            if r not in best_room or c > best_room[r][1]:
                best_room[r] = (s, c)
            if s not in best_seg or c > best_seg[s][1]:
                best_seg[s] = (r, c)
    room_out = {}
    for r, size in rooms.items():
        s, c = best_room.get(r, (0, 0))
        room_out[r] = {"size": size, "best_segment": s, "overlap": c, "recall": c / size}
    seg_out = {}
    for s, size in segs.items():
        r, c = best_seg.get(s, (0, 0))
        seg_out[s] = {"size": size, "best_room": r, "overlap": c, "precision": c / size}
    nan = float("nan")
    recall = float(np.mean([v["recall"] for v in room_out.values()])) if room_out else nan
    precision = (float(np.mean([v["precision"] for v in seg_out.values()]))
                 if seg_out else nan)
    rw = (sum(v["overlap"] for v in room_out.values()) / sum(rooms.values())
          if rooms else nan)
    pw = (sum(v["overlap"] for v in seg_out.values()) / sum(segs.values())
          if segs else nan)
    return {"recall": recall, "precision": precision, "recall_weighted": rw,
            "precision_weighted": pw, "n_rooms": len(rooms), "n_segments": len(segs),
            "rooms": room_out, "segments": seg_out}
