"""bench/percentiles.py: the one percentile helper of the micro-benchmarks."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench.percentiles import pct, pct_ms  # noqa: E402


def test_pct_is_numpys_linear_percentile_and_nan_when_empty():
    rng = np.random.default_rng(0)
    xs = rng.exponential(size=101).tolist()
    for q in (0, 50, 95, 100):
        assert pct(xs, q) == pytest.approx(float(np.percentile(xs, q)), rel=0, abs=0)
    assert math.isnan(pct([], 50))


@pytest.mark.parametrize("values_s, kwargs, expected", [
    ([0.001, 0.002, 0.003], {}, "p50    2.00 ms  p95    2.90 ms"),
    ([0.001, 0.002, 0.003], {"count": True}, "p50    2.00 ms  p95    2.90 ms (n=3)"),
    ([0.0005], {"decimals": 3}, "p50    0.500 ms  p95    0.500 ms"),
    ([], {}, "n/a"),
])
def test_pct_ms_prints_milliseconds(values_s, kwargs, expected):
    assert pct_ms(values_s, **kwargs) == expected
