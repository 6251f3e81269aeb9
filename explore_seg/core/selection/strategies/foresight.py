"""``foresight``: ``routed`` with viewpoints rated on a predicted floor plan.

The planner is ``routed``'s :class:`~explore_seg.core.selection.router.Router` (frontier
parts, viewpoints, a global tour over DuDe regions, the same goal handling); what changes
is the gain that picks each group's viewpoint, decides which groups are worth a visit
(``min_gain_m2``, ``leftover_gain_m2``) and weighs in the tour cost
(``gain_weight_m_per_m2``). :class:`PredictedGains` rates a candidate as

    prediction_gain_weight * expected newly seen free area on the predicted plan
    + (1 - prediction_gain_weight) * unknown area in view on the map (routed's gain)

The predicted plan (:mod:`explore_seg.core.prediction`) is made once per map version; on
it a view through a doorway into a predicted room counts the room, a view of unknown
space the prediction places outside the building or inside a wall counts little. The
second term keeps every frontier that routed would visit worth a visit, so a wrong guess
delays a region rather than dropping it.

Without torch or the weight file the planner rates viewpoints as ``routed`` does and says
so once in the log (``load_predictor`` gives the reason).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.prediction.gain import expected_view_gain
from explore_seg.core.prediction.inference import (FloorPlanPredictor, PredictedMap,
                                                   load_predictor)
from explore_seg.core.selection.params import ForesightParams
from explore_seg.core.selection.strategies.routed import routed_cost
from explore_seg.core.selection.strategy import GoalOptions, Strategy
from explore_seg.core.selection.viewpoints import GainCache

if TYPE_CHECKING:
    from explore_seg.core.frontiers import FrontierParams
    from explore_seg.core.selection.params import SelectionParams
    from explore_seg.core.selection.router import Router

LOG = logging.getLogger(__name__)


class PredictedGains:
    """Viewpoint gains from the predicted floor plan blended with routed's (module
    docstring); a :class:`~explore_seg.core.selection.router.GainSource`.

    Parameters
    ----------
    predictor : FloorPlanPredictor or None
        None: routed's gains alone.
    range_m, rays, occupied_threshold : see :func:`~.viewpoints.view_gain`
    weight : float
        ``prediction_gain_weight`` in [0, 1].

    Attributes
    ----------
    predicted : PredictedMap or None
        The prediction of the last map rated.
    predict_cpu_s : float
        CPU seconds of the last prediction (0 when the map was already predicted).
    """

    def __init__(self, predictor: FloorPlanPredictor | None, range_m: float, rays: int,
                 occupied_threshold: int, weight: float) -> None:
        if not 0.0 <= weight <= 1.0:
            raise ValueError(f"weight must be in [0, 1], got {weight}")
        self._predictor = predictor
        self._plain = GainCache(range_m, rays, occupied_threshold)
        self._range, self._rays, self._w = float(range_m), int(rays), float(weight)
        self._key: GridMap | None = None
        self.predicted: PredictedMap | None = None
        self.predict_cpu_s = 0.0

    def reset(self) -> None:
        """Forget the kept gains and the prediction (a new map)."""
        self._plain.reset()
        self._key, self.predicted = None, None

    def gains(self, grid: GridMap, cells_rc: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Blended gain (m^2) of each cell on ``grid``, shape (C,)."""
        plain = self._plain.gains(grid, cells_rc)
        if self._predictor is None or self._w == 0.0:
            return plain
        self.predict_cpu_s = 0.0
        if grid is not self._key or self.predicted is None:
            self.predicted = self._predictor.predict(grid)
            self.predict_cpu_s = self._predictor.last_cpu_s
            self._key = grid
        expected = expected_view_gain(self.predicted, cells_rc, self._range, self._rays)
        return self._w * expected + (1.0 - self._w) * plain


def make_foresight_router(frontier: FrontierParams, selection: SelectionParams) -> Router:
    """``routed``'s planner with :class:`PredictedGains` (imported here: the router imports
    the selection params, which import the registry)."""
    from explore_seg.core.selection.router import Router

    predictor, why = load_predictor(selection.prediction_weights or None,
                                    selection.prediction_margin_m,
                                    frontier.occupied_threshold, selection.prediction_threads)
    if predictor is None:
        LOG.warning("foresight: no floor-plan prediction (%s); viewpoints are rated as "
                    "routed rates them", why)
    gains = PredictedGains(predictor, selection.sensor_range_m, selection.gain_rays,
                           frontier.occupied_threshold, selection.prediction_gain_weight)
    return Router(frontier, selection, gains)


def foresight_cost(inp: Any, params: Any) -> npt.NDArray[np.float64]:
    """The tour length (m) when the group is visited next, minus the weighted gain
    (routed's cost, on the blended gains)."""
    return routed_cost(inp, params)


STRATEGY = Strategy("foresight", foresight_cost,
                    "routed's viewpoints and tour, viewpoints rated on a predicted floor plan",
                    region_term=True, make_planner=make_foresight_router,
                    goals=GoalOptions(handover=True, reveal_on_arrival=True),
                    nav_feedback=True, params=ForesightParams)
