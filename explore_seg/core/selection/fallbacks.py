"""Goals for when no frontier is selectable, before exploration ends.

:class:`Fallbacks` keeps the robot's positions that these goals need and offers them in
turn, each only when the ones before it leave nothing selectable:

1. lookouts (:mod:`.lookout`, ``lookout_goals``): a reachable spot in line of sight of an
   unreachable frontier, to look at it from there;
2. approaches (:mod:`.blockage`, ``speckle_max_cells`` > 0): up to a passage that only map
   speckle closes, on a map relaxed along the robot's trail since the last SLAM
   correction, to look at it (after the navigator aborted there);
3. the revisit under way (:mod:`.revisit`): an old place of the robot's path, for a loop
   closure, started where exploration would end (the goal manager's ``before_done``).

:class:`~explore_seg.core.explorer.Explorer` asks :meth:`Fallbacks.goals` when none of its
frontiers is selectable, feeds it the robot's positions and tells it of resets and SLAM
corrections.

Examples
--------
>>> from explore_seg.core.selection import GoalManager, SelectionParams
>>> fb = Fallbacks(GoalManager(SelectionParams()), lambda frontiers, dist, excluded: False)
>>> fb.add(0.0, 0.0); fb.add(1.0, 0.0)
>>> len(fb.trail) > 0
True
>>> fb.corrected(); len(fb.trail)
0
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Callable

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams
from explore_seg.core.grid import GridMap
from explore_seg.core.selection.blockage import RelaxedMap, approaches
from explore_seg.core.selection.lookout import Reach, lookouts
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.revisit import Revisits
from explore_seg.core.swept import SweptPath

if TYPE_CHECKING:
    from explore_seg.core.selection.goals import GoalManager

#: ``selectable(frontiers, dist, excluded)``: whether a frontier has a path, is not
#: blacklisted and the strategy would take it.
Selectable = Callable[[list[Frontier], npt.NDArray[np.float64], npt.NDArray[np.bool_]], bool]


class Fallbacks:
    """The goals of the module docstring and the positions they need.

    Parameters
    ----------
    manager : GoalManager
        The explorer's: its blacklist and the places where the navigator aborted.
    selectable : callable
        See :data:`Selectable`.
    """

    def __init__(self, manager: GoalManager, selectable: Selectable) -> None:
        self._manager = manager
        self._selectable = selectable
        # The robot's map-frame positions since the last correction (approach goals).
        self.trail = SweptPath()
        self.revisits = Revisits()   # its whole path, for revisits after corrections

    def add(self, x: float, y: float) -> None:
        """The robot's map-frame position at a decision."""
        self.trail.add(x, y)
        self.revisits.add(x, y)

    def reset(self) -> None:
        """Forget the robot's path (a restart, a clock jump)."""
        self.trail = SweptPath()
        self.revisits.reset()

    def corrected(self) -> None:
        """A SLAM correction: the trail starts anew (its positions were uncorrected) and
        revisits may start (:meth:`Revisits.corrected`)."""
        self.trail = SweptPath()
        self.revisits.corrected()

    def goals(self, grid: GridMap, frontiers: list[Frontier], dist: npt.NDArray[np.float64],
              excluded: npt.NDArray[np.bool_], reach: Reach, sp: SelectionParams,
              fp: FrontierParams, extra_obstacles: npt.NDArray[np.bool_] | None
              ) -> tuple[list[Frontier], npt.NDArray[np.float64], npt.NDArray[np.bool_]]:
        """The fallback goals in place of ``frontiers`` (none selectable): the frontiers
        as given when no fallback applies, else the fallback's goals as frontiers, their
        path lengths and blacklist mask (``manager.excluded``).

        Parameters
        ----------
        grid, frontiers, dist, excluded
            The map, the frontiers, their path lengths and blacklist mask.
        reach : Reach
            The robot's reachable cells on the explorer's path graph.
        sp, fp : SelectionParams, FrontierParams
        extra_obstacles : ndarray of bool, shape (H, W), optional
            The object layer's obstacles (kept on the relaxed map when
            ``approach_keeps_objects``).
        """
        manager, selectable = self._manager, self._selectable
        out, d_out, ex_out = frontiers, dist, excluded
        if sp.lookout_goals:
            out, d_out = lookouts(grid, frontiers, dist, reach, sp, fp.occupied_threshold,
                                  excluded)
            ex_out = manager.excluded(out)
        if sp.speckle_max_cells > 0 and not selectable(out, d_out, ex_out):
            # The navigator tries a frontier first; after it aborted there, a look.
            through = np.asarray([not manager.aborted_near(f.point_xy_m) for f in frontiers],
                                 dtype=bool)
            relaxed = RelaxedMap(replace(fp, robot_radius_m=min(fp.robot_radius_m,
                                                                sp.approach_radius_m)),
                                 sp.speckle_max_cells,
                                 extra_obstacles if sp.approach_keeps_objects else None,
                                 self.trail.mask(grid, sp.approach_trail_radius_m)
                                 if sp.approach_trail_radius_m > 0 and len(self.trail)
                                 else None)
            out, d_out = approaches(grid, frontiers, dist, reach, relaxed, excluded, through)
            ex_out = manager.excluded(out)
        revisit = (self.revisits.goals(grid, frontiers, dist, reach, excluded,
                                       manager.blacklist, sp, manager.aborted_near)
                   if self.revisits.active(sp) and not selectable(out, d_out, ex_out)
                   else None)
        if revisit is not None:
            out, d_out = revisit
            ex_out = manager.excluded(out)
        return out, d_out, ex_out


__all__ = ["Fallbacks", "Selectable"]
