"""Percentiles of per-call timings, as the micro-benchmarks in bench/ print them."""

from __future__ import annotations

from typing import Iterable

import numpy as np


def pct(values: Iterable[float], q: float) -> float:
    """The ``q``-th percentile of ``values`` (numpy's linear interpolation); NaN when empty.

    >>> pct([1.0, 2.0, 3.0, 4.0], 50), pct([], 95)
    (2.5, nan)
    """
    a = np.asarray(list(values), dtype=np.float64)
    return float(np.percentile(a, q)) if a.size else float("nan")


def pct_ms(values_s: Iterable[float], decimals: int = 2, count: bool = False) -> str:
    """``"p50 X ms  p95 Y ms"`` of durations given in seconds (``"n/a"`` when empty);
    with ``count``, ``" (n=N)"`` follows.

    >>> pct_ms([0.001, 0.002, 0.003], count=True)
    'p50    2.00 ms  p95    2.90 ms (n=3)'
    """
    ms = np.asarray(list(values_s), dtype=np.float64) * 1e3
    if ms.size == 0:
        return "n/a"
    width = decimals + 5
    text = (f"p50 {np.percentile(ms, 50):{width}.{decimals}f} ms  "
            f"p95 {np.percentile(ms, 95):{width}.{decimals}f} ms")
    return text + (f" (n={ms.size})" if count else "")
