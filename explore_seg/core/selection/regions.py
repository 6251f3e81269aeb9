"""Region ids of cells and frontiers from DuDe labels (the paper's regionGain input)."""

from __future__ import annotations

from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier
from explore_seg.core.paths import nearest_true


def region_at(labels: npt.NDArray[np.integer], rc: tuple[int, int], radius_cells: int) -> int:
    """Region id at cell ``rc``: its label if > 0, else the nearest label > 0 within
    ``radius_cells`` (Euclidean), else 0 (no region). Cells outside the image give 0.

    Examples
    --------
    >>> labels = np.array([[0, 0, 2], [0, 0, 0]])
    >>> region_at(labels, (0, 2), 1), region_at(labels, (1, 1), 1), region_at(labels, (1, 0), 1)
    (2, 2, 0)
    """
    h, w = labels.shape
    r, c = int(rc[0]), int(rc[1])
    if not (0 <= r < h and 0 <= c < w):
        return 0
    v = int(labels[r, c])
    if v > 0:
        return v
    r0, c0 = max(0, r - radius_cells), max(0, c - radius_cells)
    win = labels[r0:r + radius_cells + 1, c0:c + radius_cells + 1]
    near = nearest_true(win > 0, (r - r0, c - c0), radius_cells)
    if near is None:
        return 0
    return int(win[near])


def frontier_regions(frontiers: Sequence[Frontier], labels: npt.NDArray[np.integer] | None,
                     radius_cells: int) -> npt.NDArray[np.int64]:
    """Region id of each frontier's cPoint (:func:`region_at`); zeros without labels."""
    if labels is None:
        return np.zeros(len(frontiers), dtype=np.int64)
    return np.asarray([region_at(labels, f.point_rc, radius_cells) for f in frontiers],
                      dtype=np.int64)
