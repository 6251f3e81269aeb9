"""Room segmentation of an occupancy grid by (incremental) Dual-Space Decomposition.

Implements DuDe spec shared/docs/dude.md: cleaning of the grid into a free-space mask
(§4), DuDe on every free component (§5-§9, in :mod:`.dude`, raster shortcut), labelling
back onto the true free cells with gap filling and small-region merging (§10, §15), the
incremental update that redoes only the pieces touched by newly seen free space (§11)
and region ids that persist between updates (§12).

Label images follow :class:`~explore_seg.core.grid.GridMap`: int32 ``(H, W)``, row = y,
``0`` = no region (a wall or other obstacle, unknown, undecided occupancy, or a free speck
smaller than ``min_region_area_m2`` that touches no region), ``k > 0`` a region id.
Free-standing furniture the cleaning counts as room (the occupied cells of clutter holes
and small objects) carries the id of the region around it: a table belongs to its
office, as in hand-drawn room maps. Furniture against a wall keeps 0: there furniture
and wall are one obstacle.

Internally every cell of the *domain* (cleaned free space F united with the raw free
cells) carries a label; the published labels are the domain labels restricted to the raw
free cells and those furniture cells. Keeping the F margin labelled (F reaches
``free_close_m`` into unknown space at frontiers) is what lets the incremental update
tell newly seen space from old.

Modules: :mod:`.params` (parameters), :mod:`.cleaning` (grid -> free-space masks, with
:mod:`.furniture`: furniture against walls), :mod:`.dude` (decomposition of a mask, with
:mod:`.polygon`, :mod:`.rings` and :mod:`.cuts`), :mod:`.labels` (label-image helpers),
:mod:`.merging` (small, thin and corridor regions, with :mod:`.passages`: parts of one
passage), :mod:`.incremental` (the stateful segmenter, :func:`segment`, on the known
cells' crop of :mod:`.crop`) and
:mod:`.eval` (recall / precision against ground-truth rooms).
"""

from explore_seg.core.segmentation.cleaning import clean_free_space
from explore_seg.core.segmentation.dude import decompose_mask, find_cuts
from explore_seg.core.segmentation.eval import evaluate
from explore_seg.core.segmentation.incremental import IncrementalSegmenter, UpdateInfo, segment
from explore_seg.core.segmentation.params import (DudeSettings, SegmentationNodeParams,
                                                  SegmentationParams)

__all__ = [
    "DudeSettings", "IncrementalSegmenter", "SegmentationNodeParams", "SegmentationParams",
    "UpdateInfo", "clean_free_space", "decompose_mask", "evaluate", "find_cuts", "segment",
]
