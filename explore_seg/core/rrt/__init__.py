"""The ``rrt_exploration`` baseline's frontier detection (Umari & Mukhopadhyay, "Autonomous
robotic exploration based on multiple rapidly-exploring randomized trees", IROS 2017).

One concern per module:

* :mod:`.params`: :class:`RrtParams` (the ``rrt.*`` parameters);
* :mod:`.tree`: :class:`RrtTree` and the edge check that finds frontier points;
* :mod:`.mean_shift`: the filter's clustering;
* :mod:`.info_gain`: unknown area around points (information gain);
* :mod:`.detector`: :class:`RrtFrontierDetector` (trees + filter -> frontier candidates).

The assigner's revenue is the strategy ``rrt_exploration`` of
:mod:`explore_seg.core.selection.strategies`; the decision core
:class:`explore_seg.core.explorer.Explorer` wires the two.
"""

from explore_seg.core.rrt.detector import RrtFrontierDetector
from explore_seg.core.rrt.info_gain import disc_offsets, information_gain_m2, unknown_within
from explore_seg.core.rrt.mean_shift import mean_shift
from explore_seg.core.rrt.params import RrtParams
from explore_seg.core.rrt.tree import CellClasses, RrtTree, walk_edge

__all__ = ["CellClasses", "RrtFrontierDetector", "RrtParams", "RrtTree", "disc_offsets",
           "information_gain_m2", "mean_shift", "unknown_within", "walk_edge"]
