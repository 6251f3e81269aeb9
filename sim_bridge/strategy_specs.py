"""The benchmark's arms: which registered strategy runs with which parts of the pipeline.

An arm (:class:`StrategySpec`) names a strategy of the registry
(:mod:`explore_seg.core.selection.strategy`) and says whether the lock step runs the
segmentation and the object costmap for it. :data:`STRATEGY_SPECS` lists the benchmark's
arms (the strategies and the paper's two ablations); :func:`strategy_spec` also gives any
other registered strategy its default arm, so a plug-in runs in the lock step without an
entry here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from explore_seg.core.selection.strategy import get_strategy, strategy_names


@dataclass(frozen=True)
class StrategySpec:
    """One arm of the benchmark: a registered strategy and what runs around it.

    Attributes
    ----------
    selection : str
        The registered strategy (``SelectionParams.strategy``;
        :mod:`explore_seg.core.selection.strategies`).
    use_regions : bool
        Run the segmentation and give its labels to the strategy.
    use_objects : bool
        Run the object costmap; its layer blocks frontiers, selection paths and plans.
    description : str
    nav_feedback : bool
        Feed the navigation stand-in's outcome to the decision core in this arm's runs
        even when :attr:`LockstepParams.nav_feedback` (on by default) is off.
    """

    selection: str
    use_regions: bool
    use_objects: bool
    description: str
    nav_feedback: bool = False

    @classmethod
    def of(cls, name: str, *, use_objects: bool = False, description: str = "",
           **overrides: Any) -> StrategySpec:
        """The arm of a registered strategy: regions when its cost reads them, navigation
        feedback when it asks for it, the object costmap only when told.

        Raises
        ------
        ValueError
            When no strategy is registered under ``name``.
        """
        strategy = get_strategy(name)
        fields = {"use_regions": strategy.region_term, "nav_feedback": strategy.nav_feedback}
        fields.update(overrides)
        return cls(selection=name, use_objects=use_objects,
                   description=description or strategy.summary, **fields)


#: The arms of the benchmark. The baselines run as their original packages would: no
#: object costmap anywhere and no regions; ``paper_noseg`` and ``paper_noobj`` are the
#: paper's ablations.
STRATEGY_SPECS: dict[str, StrategySpec] = {
    "paper": StrategySpec.of(
        "paper", use_objects=True,
        description="eq. 1-3 with DuDe regions and the object costmap"),
    "paper_noseg": StrategySpec.of(
        "paper", use_objects=True, use_regions=False,
        description="eq. 1-3 without regions (gamma = 0), with the object costmap"),
    "paper_noobj": StrategySpec.of(
        "paper", description="eq. 1-3 with regions, without the object costmap"),
    "nearest": StrategySpec.of(
        "nearest", description="nearest frontier by path length (no object costmap)"),
    "explore_lite": StrategySpec.of(
        "explore_lite",
        description="explore_lite cost 3 * dist - 1 * length (no object costmap)"),
    "rrt_exploration": StrategySpec.of(
        "rrt_exploration",
        description="Umari & Mukhopadhyay 2017: local + global RRT frontier points, mean "
                    "shift, revenue 3 * gain - dist (no object costmap)"),
    "routed": StrategySpec.of(
        "routed", use_objects=True,
        description="viewpoints + region-routed tour (DuDe regions, object costmap), "
                    "navigation outcome fed back"),
    "foresight": StrategySpec.of(
        "foresight", use_objects=True,
        description="routed with viewpoints rated on a predicted floor plan (DuDe regions, "
                    "object costmap), navigation outcome fed back"),
}
STRATEGIES: tuple[str, ...] = tuple(STRATEGY_SPECS)
#: Arms that run only when asked for: ``foresight`` ships without predictor weights, and
#: without them it decides exactly as ``routed``.
EXPERIMENTAL: tuple[str, ...] = ("foresight",)
#: The arms of the full benchmark matrix (``bench/run_bench.py``'s default).
MATRIX_STRATEGIES: tuple[str, ...] = tuple(s for s in STRATEGIES if s not in EXPERIMENTAL)


def strategy_spec(name: str) -> StrategySpec:
    """The benchmark arm ``name``, else the default arm of a registered strategy of that
    name (:meth:`StrategySpec.of`: a plug-in runs without writing an arm for it).

    Raises
    ------
    ValueError
        When ``name`` is neither an arm nor a registered strategy.
    """
    if name in STRATEGY_SPECS:
        return STRATEGY_SPECS[name]
    if name not in strategy_names():
        raise ValueError(f"strategy must be one of {STRATEGIES} or a registered strategy "
                         f"({strategy_names()}), got {name!r}")
    return StrategySpec.of(name)

