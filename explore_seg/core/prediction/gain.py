"""Expected newly seen free area from a viewpoint, on a predicted floor plan.

A 360-degree sensor of range ``range_m`` at a map cell casts ``rays`` rays over the
coarse lattice of a :class:`~.inference.PredictedMap`, one sample per coarse cell of
distance. With ``p`` the cell's probability of free space and ``u`` its unknown share, a
sample lets the ray pass with probability ``p`` (0 in a cell holding an occupied map cell)
and newly shows ``u * p`` of its area element ``r * dtheta * dr`` as free space; the
expected newly seen area is the sum over samples of that area times the probability that
every earlier sample of the ray let it pass. Where the guess says wall or outside, rays
stop and nothing is counted; where it says room, the view goes on into the unknown.

Examples
--------
>>> import numpy as np
>>> from explore_seg.core.prediction.features import CoarseFrame
>>> from explore_seg.core.prediction.inference import PredictedMap
>>> p = np.ones((20, 20), np.float32); frac = np.zeros((3, 20, 20), np.float32)
>>> frac[0, :, :10] = 1; frac[2, :, 10:] = 1      # left half known free, right unknown
>>> pm = PredictedMap(p, frac, CoarseFrame(1, (0, 0), (20, 20)), 0.2)
>>> g = expected_view_gain(pm, np.array([[10, 2], [10, 9]]), range_m=1.0, rays=16)
>>> bool(g[1] > g[0] == 0.0)
True
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from explore_seg.core.prediction.inference import PredictedMap


def expected_view_gain(pred: PredictedMap, cells_rc: npt.ArrayLike, range_m: float = 5.0,
                       rays: int = 24) -> npt.NDArray[np.float64]:
    """Expected free area (m^2) newly seen from each map cell (module docstring).

    Parameters
    ----------
    pred : PredictedMap
    cells_rc : array_like of int, shape (C, 2)
        Sensor positions (row, col) on the map the prediction was made from.
    range_m : float
        Sensor range, > 0.
    rays : int
        Rays over 360 degrees, >= 4.

    Returns
    -------
    ndarray of float64, shape (C,)

    Raises
    ------
    ValueError
        On a bad range or ray count.
    """
    if not (math.isfinite(range_m) and range_m > 0):
        raise ValueError(f"range_m must be finite and > 0, got {range_m}")
    if int(rays) < 4:
        raise ValueError(f"rays must be >= 4, got {rays}")
    rc = np.asarray(cells_rc, dtype=np.int64).reshape(-1, 2)
    if rc.shape[0] == 0:
        return np.zeros(0)
    cell = pred.cell_m
    steps = max(1, int(math.ceil(range_m / cell)))
    r = (np.arange(steps) + 1.0) * cell
    theta = np.arange(int(rays)) * (2.0 * math.pi / int(rays))
    dr = np.rint(np.sin(theta)[:, None] * r[None, :] / cell).astype(np.int64)
    dc = np.rint(np.cos(theta)[:, None] * r[None, :] / cell).astype(np.int64)
    free, occ, unk = pred.fractions
    passing = np.where(occ > 0, 0.0, pred.p_free).astype(np.float32)
    value = np.where(occ > 0, 0.0, np.clip(pred.p_free - free, 0.0, None)).astype(np.float32)
    # Blocking border so no ray leaves the lattice.
    pad = steps + 1
    h, w = passing.shape
    wp = w + 2 * pad
    pass_p = np.zeros((h + 2 * pad, wp), dtype=np.float32)
    pass_p[pad:pad + h, pad:pad + w] = passing
    value_p = np.zeros_like(pass_p)
    value_p[pad:pad + h, pad:pad + w] = value
    origin = pred.frame.coarse_of(rc) + pad
    flat = (origin[:, 0] * wp + origin[:, 1])[:, None] + (dr * wp + dc).ravel()[None, :]
    shape = (rc.shape[0], int(rays), steps)
    t = pass_p.ravel()[flat].reshape(shape)
    v = value_p.ravel()[flat].reshape(shape)
    before = np.cumprod(np.concatenate([np.ones(shape[:2] + (1,), dtype=np.float32),
                                        t[:, :, :-1]], axis=2), axis=2)
    area = (r * (2.0 * math.pi / int(rays)) * cell).astype(np.float32)
    return ((before * v) @ area).sum(axis=1).astype(np.float64)


__all__ = ["expected_view_gain"]
