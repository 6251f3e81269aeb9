"""Target-selection strategies as plug-ins: one module per strategy, registered by name.

A strategy is a :class:`~explore_seg.core.selection.strategy.Strategy`: a cost function
over the frontier groups of one decision (:class:`CostInputs` -> costs, lower is better)
plus what it needs around it: where its candidates come from, whether its cost reads region
labels, an optional :class:`Planner` that turns frontier groups into candidates before the
path lengths and adds tour costs after them, and its goal-handling options
(:class:`GoalOptions`). The explorer (:class:`explore_seg.core.explorer.Explorer`), the goal
manager, the ``target_selector`` node and the lock step look a strategy up in the registry
(:mod:`explore_seg.core.selection.strategy`) by ``SelectionParams.strategy``; nothing else
compares strategy names. This package holds the built-in ones and registers them.

=================== ============================ ==========================================
name                module                       candidates / cost
=================== ============================ ==========================================
``paper``           :mod:`.paper`                frontier groups; eq. 1-3 with regionGain
``nearest``         :mod:`.nearest`              frontier groups; path length
``explore_lite``    :mod:`.explore_lite`         frontier groups; explore_lite's frontierCost
``rrt_exploration`` :mod:`.rrt_exploration`      RRT cluster centres; -revenue
``routed``          :mod:`.routed`               viewpoints of frontier parts; tour length
``foresight``       :mod:`.foresight`            routed, viewpoints rated on a predicted plan
=================== ============================ ==========================================

Adding a strategy: write its cost function, wrap it in a :class:`Strategy` and
:func:`register` it before the explorer is built (a module of your own, imported first)::

    >>> import numpy as np
    >>> def widest(inp, params):
    ...     return -inp.length_m[inp.finite]
    >>> _ = register(Strategy("widest_first", widest, "the longest frontier first"))
    >>> get_strategy("widest_first").summary
    'the longest frontier first'
    >>> unregister("widest_first")

``SelectionParams(strategy=...)``, the ``strategy`` ROS parameter and
``sim_bridge.lockstep.run_exploration(world, name, seed)`` then accept the name. A built-in
strategy gets its own module here and one line in :data:`BUILTIN`.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping

from explore_seg.core.selection.strategies import (explore_lite, foresight, nearest,
                                                   paper, routed, rrt_exploration)
from explore_seg.core.selection.strategy import (_REGISTRY, CostFunction, CostInputs,
                                                 GoalOptions, Planner, PlannerFactory,
                                                 Strategy, get_strategy, register,
                                                 strategy_names, unregister)

#: The built-in strategies, in the order the docs list them (``routed`` is the default).
BUILTIN: tuple[Strategy, ...] = (paper.STRATEGY, nearest.STRATEGY, explore_lite.STRATEGY,
                                 rrt_exploration.STRATEGY, routed.STRATEGY,
                                 foresight.STRATEGY)

for _builtin in BUILTIN:
    register(_builtin, replace=True)   # replace: a module reload registers them again


class _CostView(Mapping):
    """Read-only name -> cost function view of the registry (live)."""

    def __getitem__(self, name: str) -> CostFunction:
        if name not in _REGISTRY:
            raise KeyError(name)
        return _REGISTRY[name].cost

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(_REGISTRY))

    def __len__(self) -> int:
        return len(_REGISTRY)


#: Strategy name -> cost function (a live view of the registry).
COST_FUNCTIONS: Mapping[str, CostFunction] = _CostView()
#: The built-in strategies' names (:func:`strategy_names` also lists registered ones).
STRATEGIES: tuple[str, ...] = tuple(s.name for s in BUILTIN)
#: Built-in strategies whose candidates come from the RRT frontier detector.
RRT_STRATEGIES: frozenset[str] = frozenset(s.name for s in BUILTIN if s.candidates == "rrt")
#: Built-in strategies whose cost has a region term.
REGION_STRATEGIES: frozenset[str] = frozenset(s.name for s in BUILTIN if s.region_term)

__all__ = ["BUILTIN", "COST_FUNCTIONS", "CostFunction", "CostInputs", "GoalOptions", "Planner",
           "PlannerFactory", "REGION_STRATEGIES", "RRT_STRATEGIES", "STRATEGIES", "Strategy",
           "get_strategy", "register", "strategy_names", "unregister"]
