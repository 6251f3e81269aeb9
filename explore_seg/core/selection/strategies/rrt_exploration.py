"""``rrt_exploration``: Umari & Mukhopadhyay (IROS 2017): RRT frontier points, mean shift,
the assigner's revenue."""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.selection.params import RrtExplorationParams
from explore_seg.core.selection.strategy import CostInputs, Strategy


def rrt_exploration_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """rrt_exploration's assigner (Umari & Mukhopadhyay 2017), as a cost (-revenue)::

        revenue = info_multiplier * gain - dist
        gain    = info_gain_m2 * (hysteresis_gain if dist <= hysteresis_radius_m else 1)

    ``info_gain_m2``: unknown area within ``rrt.info_radius_m`` of the cluster centre
    (NaN counts as 0). Deviations: ``dist`` is the path length to the cPoint, where the
    assigner uses the straight-line distance robot -> centre for both terms; the assigner's
    second bonus (centres near the robot's current goal while it is busy) is left to the
    goal manager's ``hysteresis_margin``, as for every strategy.
    """
    f = inp.finite
    d = inp.dist_m[f]
    gain = np.zeros(len(d)) if inp.info_gain_m2 is None else \
        np.nan_to_num(np.asarray(inp.info_gain_m2, dtype=np.float64)[f], nan=0.0)
    gain = np.where(d <= params.hysteresis_radius_m, gain * params.hysteresis_gain, gain)
    return d - params.info_multiplier * gain


STRATEGY = Strategy("rrt_exploration", rrt_exploration_cost,
                    "rrt_exploration: RRT frontier points, mean shift, "
                    "info_multiplier * gain - dist", candidates="rrt", params=RrtExplorationParams)
