"""``nearest``: the greedy nearest frontier (Yamauchi 1997), by path length."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.selection.strategy import CostInputs, Strategy


def nearest_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """Greedy nearest frontier (Yamauchi): the path length."""
    return inp.dist_m[inp.finite]


STRATEGY = Strategy("nearest", nearest_cost, "the nearest frontier by path length")
