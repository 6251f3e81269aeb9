"""``paper``: Kim, Kim & Lee (RA-L 2022), eq. 1-3 (formulas and defaults in
:mod:`explore_seg.core.selection.costs`)."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.selection.params import PaperParams
from explore_seg.core.selection.strategy import CostInputs, Strategy


def paper_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """The paper's eq. 1-3: ``alpha * distGain + beta / sizeGain + regionGain``."""
    d = inp.dist_m[inp.finite]
    total_d = float(d.sum())
    dist_gain = d / total_d if total_d > 0 else np.zeros(len(d))
    size_gain = inp.size_cells[inp.finite] / float(inp.size_cells.sum())
    region_gain = np.zeros(len(d))
    if inp.regions is not None:
        reg = np.asarray(inp.regions)[inp.finite]
        region_gain = np.where((reg > 0) & (reg != inp.robot_region), params.gamma, 0.0)
    return params.alpha * dist_gain + params.beta / size_gain + region_gain


STRATEGY = Strategy("paper", paper_cost,
                    "eq. 1-3 of the paper: alpha * distGain + beta / sizeGain + regionGain",
                    region_term=True, params=PaperParams)
