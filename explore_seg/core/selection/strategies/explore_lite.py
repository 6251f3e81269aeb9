"""``explore_lite``: m-explore's ``frontierCost`` with ``orientation_scale`` 0."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.selection.params import ExploreLiteParams
from explore_seg.core.selection.strategy import CostInputs, Strategy


def explore_lite_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """explore_lite's ``frontierCost`` (orientation_scale 0):
    ``potential_scale * dist - gain_scale * length``."""
    f = inp.finite
    return params.potential_scale * inp.dist_m[f] - params.gain_scale * inp.length_m[f]


STRATEGY = Strategy("explore_lite", explore_lite_cost,
                    "explore_lite: potential_scale * dist - gain_scale * length",
                    params=ExploreLiteParams)
