"""``routed``: a viewpoint per frontier part and a global tour over them, with DuDe regions
as the routing structure (:class:`~explore_seg.core.selection.router.Router`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.selection.params import RoutedParams
from explore_seg.core.selection.strategy import CostInputs, GoalOptions, Strategy

if TYPE_CHECKING:
    from explore_seg.core.frontiers import FrontierParams
    from explore_seg.core.selection.params import SelectionParams
    from explore_seg.core.selection.router import Router


def routed_cost(inp: CostInputs, params: Any) -> npt.NDArray[np.float64]:
    """The tour length (m) when the group is visited next (region changes included)."""
    if inp.tour_cost_m is None:
        raise ValueError("the routed strategy needs tour costs (explore_seg.core.selection."
                         "router.Router, run by explore_seg.core.explorer.Explorer)")
    return np.asarray(inp.tour_cost_m, dtype=np.float64)[inp.finite]


def make_router(frontier: FrontierParams, selection: SelectionParams) -> Router:
    """The strategy's planner (imported here: the router imports the selection params,
    which import the registry)."""
    from explore_seg.core.selection.router import Router

    return Router(frontier, selection)


STRATEGY = Strategy("routed", routed_cost,
                    "viewpoints + a global tour over them, DuDe regions as routing structure",
                    region_term=True, make_planner=make_router,
                    goals=GoalOptions(handover=True, reveal_on_arrival=True),
                    nav_feedback=True, params=RoutedParams)
