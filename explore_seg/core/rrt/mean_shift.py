"""Flat-kernel mean shift of 2D points (rrt_exploration's filter clusters frontier points
with scikit-learn's ``MeanShift``; this is the same algorithm in numpy).

Every point seeds a window of radius ``bandwidth`` that moves to the mean of the points
inside it until it stops (shift below ``1e-3 * bandwidth``); the converged windows are
ranked by how many points they hold and a window within ``bandwidth`` of a better-ranked
one is dropped.

All seeds move at once here; scikit-learn's ``MeanShift`` moves them one by one and takes
about 100 times as long on the filter's point sets for the same centres within 1e-9 m
(``bench/bench_libraries.py``).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

#: Iterations per seed at most (scikit-learn's default).
MAX_ITERATIONS = 300


def mean_shift(points: npt.ArrayLike, bandwidth: float
               ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
    """Cluster centres of ``points`` and how many points each centre's window holds.

    Parameters
    ----------
    points : array_like of float, shape (N, 2)
    bandwidth : float
        Window radius (> 0), in the points' unit.

    Returns
    -------
    centres : ndarray of float64, shape (K, 2)
        Best-ranked first (most points; ties by larger x, then larger y).
    counts : ndarray of int64, shape (K,)

    Raises
    ------
    ValueError
        On a bandwidth <= 0 or points not of shape (N, 2).

    Examples
    --------
    >>> c, n = mean_shift([[0, 0], [0.1, 0], [5, 5]], 0.5)
    >>> c.round(2).tolist(), n.tolist()
    ([[0.05, 0.0], [5.0, 5.0]], [2, 1])
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2) if np.size(points) else \
        np.zeros((0, 2))
    if not bandwidth > 0:
        raise ValueError(f"bandwidth must be > 0, got {bandwidth}")
    if p.shape[0] == 0:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    bw2 = float(bandwidth) ** 2
    centres = p.copy()
    active = np.ones(len(p), dtype=bool)
    counts = np.zeros(len(p), dtype=np.int64)
    for _ in range(MAX_ITERATIONS):
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        c = centres[idx]
        inside = ((c[:, None, :] - p[None, :, :]) ** 2).sum(axis=2) <= bw2
        n = inside.sum(axis=1)
        new = (inside.astype(np.float64) @ p) / n[:, None]
        counts[idx] = n
        done = np.hypot(*(new - c).T) < 1e-3 * bandwidth
        centres[idx] = new
        active[idx[done]] = False
    order = np.lexsort((-centres[:, 1], -centres[:, 0], -counts))
    kept: list[int] = []
    for i in order:
        if all(((centres[i] - centres[j]) ** 2).sum() > bw2 for j in kept):
            kept.append(int(i))
    return centres[kept], counts[kept]
