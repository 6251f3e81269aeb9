"""Parameters of the DuDe room segmentation: metric (SegmentationParams, the node's
SegmentationNodeParams) and the pixel-unit settings of the decomposition (DudeSettings)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from explore_seg.core.fields import param_meta


@dataclass(frozen=True)
class SegmentationParams:
    """Parameters of the DuDe room segmentation (DuDe spec shared/docs/dude.md §13).

    Raises
    ------
    ValueError
        From ``__post_init__`` when a value is out of range.
    """

    tau_m: float = field(default=1.6, metadata=param_meta(
        "DuDe max concavity tau: boundary vertices deeper than this in the dual space "
        "are cut (small: corridors over-segmented; large: rooms merged through doors). "
        "1.6 m is the best of a sweep on generated houses (bench/eval_segmentation.py); "
        "the draft's optimum is 2.5 m, the seed code uses 3.0 m", "m", range=(0.0, math.inf)))
    free_max_occupancy: int = field(default=10, metadata=param_meta(
        "a cell is free when 0 <= occupancy < this", "%", range=(1, 100)))
    occupied_min_occupancy: int = field(default=90, metadata=param_meta(
        "a cell is an obstacle when occupancy > this", "%", range=(0, 99)))
    obstacle_inflation_m: float = field(default=0.20, metadata=param_meta(
        "obstacles are grown by this before decomposing (closes gaps in walls)", "m",
        range=(0.0, math.inf)))
    free_close_m: float = field(default=0.25, metadata=param_meta(
        "free space is grown by this into unknown cells (fills unobserved specks)", "m",
        range=(0.0, math.inf)))
    obstacle_speck_area_m2: float = field(default=0.0075, metadata=param_meta(
        "occupied components of at most this area are ignored (scan salt noise)", "m^2",
        range=(0.0, math.inf)))
    min_component_area_m2: float = field(default=1.0, metadata=param_meta(
        "cleaned free components smaller than this are not decomposed", "m^2",
        range=(0.0, math.inf)))
    min_hole_area_m2: float = field(default=0.0125, metadata=param_meta(
        "obstacle islands of at most this area are ignored by the decomposition", "m^2",
        range=(0.0, math.inf)))
    clutter_max_extent_m: float = field(default=6.0, metadata=param_meta(
        "holes of the cleaned free space (free-standing furniture and the unknown cells "
        "around it) at most this wide and high are filled before decomposing, so "
        "furniture does not cut rooms (6 m, 16 m^2, 1.6 m: best of a sweep on "
        "bench/eval_segmentation.py --set furnished); 0 disables", "m",
        range=(0.0, math.inf)))
    clutter_max_area_m2: float = field(default=16.0, metadata=param_meta(
        "holes filled as clutter are at most this large", "m^2", range=(0.0, math.inf)))
    clutter_max_object_m: float = field(default=1.6, metadata=param_meta(
        "a hole holding an occupied component whose bounding-box diagonal exceeds this "
        "(a wall piece, a long sofa) is structure, never filled as clutter", "m",
        range=(0.0, math.inf)))
    small_object_max_m: float = field(default=0.5, metadata=param_meta(
        "free-standing obstacle components (8-connected, specks dropped) whose bounding-box "
        "diagonal is at most this (chair legs, castors, a chair, a bin) are not inflated "
        "and count as free space for the decomposition, so rows and rings of chairs do "
        "not wall off parts of a room; one whose inflation would touch a larger "
        "obstacle's (a cabinet row, a broken wall) keeps it; 0 disables", "m",
        range=(0.0, math.inf)))
    furniture_min_thickness_m: float = field(default=0.7, metadata=param_meta(
        "obstacle bulges at least this thick (a disk of this diameter fits in them) and "
        "thinner than furniture_max_thickness_m are furniture against a wall (a pillar, "
        "a shelf, a desk): filled before decomposing when at most furniture_max_extent_m "
        "wide and the free space along it is one stretch; walls must be thinner; a "
        "free-standing block this thick nearly all over and at most "
        "furniture_max_extent_m wide is clutter (clutter_max_object_m does not apply); 0 "
        "disables", "m",
        range=(0.0, math.inf)))
    furniture_max_extent_m: float = field(default=2.5, metadata=param_meta(
        "furniture bulges wider or higher than this are structure, never filled", "m",
        range=(0.0, math.inf)))
    furniture_max_thickness_m: float = field(default=2.0, metadata=param_meta(
        "obstacles this thick (the outside of the building, a courtyard block) are "
        "structure, and so are bulges of them thinner than furniture_min_thickness_m",
        "m", range=(0.0, math.inf)))
    simplify_epsilon_m: float = field(default=0.075, metadata=param_meta(
        "Douglas-Peucker tolerance applied to traced contours", "m", range=(0.0, math.inf)))
    min_region_area_m2: float = field(default=1.0, metadata=param_meta(
        "regions smaller than this are merged into the neighbour sharing the longest "
        "border; isolated free specks smaller than this get no region", "m^2",
        range=(0.0, math.inf)))
    min_region_width_m: float = field(default=0.4, metadata=param_meta(
        "regions thinner than this (twice the largest distance to their border) are "
        "merged into a neighbour", "m", range=(0.0, math.inf)))
    corridor_merge: bool = field(default=False, metadata=param_meta(
        "merge two adjacent regions whose shared border is longer than "
        "max_door_width_m and whose union stays convex enough (DuDe spec "
        "shared/docs/dude.md §15)"))
    passage_merge_ratio: float = field(default=0.7, metadata=param_meta(
        "two neighbouring regions whose shared border is longer than max_door_width_m "
        "and at least this times the larger one's inscribed diameter are parts of one "
        "passage (a corridor round a corner or a block) and are merged; 0 disables",
        range=(0.0, math.inf)))
    max_door_width_m: float = field(default=1.2, metadata=param_meta(
        "passage and corridor merges: borders at most this long are doors and never "
        "merged", "m",
        range=(0.0, math.inf)))
    merge_concavity_factor: float = field(default=2.0, metadata=param_meta(
        "corridor merge: the union's deepest concavity must stay below this times tau",
        range=(0.0, math.inf)))
    max_rounds: int = field(default=16, metadata=param_meta(
        "bound on decomposition rounds per piece", range=(1, 2**31 - 1)))
    max_cut_candidates: int = field(default=24, metadata=param_meta(
        "per notch, how many nearest boundary points are tested as cut ends",
        range=(1, 2**31 - 1)))
    inc_min_blob_m2: float = field(default=0.25, metadata=param_meta(
        "incremental: newly seen free blobs of at most this area are only gap-filled",
        "m^2", range=(0.0, math.inf)))
    inc_touch_cells: int = field(default=2, metadata=param_meta(
        "incremental: a piece within this many cells of a new blob is redone", "cells",
        range=(0, 2**31 - 1)))
    inc_lost_frac: float = field(default=0.05, metadata=param_meta(
        "incremental: a piece that lost more than this fraction of its cells is redone",
        range=(0.0, 1.0)))
    inc_full_frac: float = field(default=0.5, metadata=param_meta(
        "incremental: when the work areas exceed this fraction of the free space, a full "
        "batch run is done instead", range=(0.0, 1.0)))
    id_keep_frac: float = field(default=0.5, metadata=param_meta(
        "an old id passes to the new piece holding at least this share of its cells",
        range=(0.0, 1.0)))

    def __post_init__(self) -> None:
        pos = ("tau_m", "max_door_width_m", "merge_concavity_factor")
        nonneg = ("obstacle_inflation_m", "free_close_m", "obstacle_speck_area_m2",
                  "min_component_area_m2", "min_hole_area_m2", "clutter_max_extent_m",
                  "clutter_max_area_m2", "clutter_max_object_m", "small_object_max_m",
                  "furniture_min_thickness_m", "furniture_max_thickness_m",
                  "furniture_max_extent_m", "simplify_epsilon_m",
                  "passage_merge_ratio",
                  "min_region_area_m2", "min_region_width_m", "inc_min_blob_m2")
        for name in pos:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        for name in nonneg:
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        if not 0 < self.free_max_occupancy <= 100:
            raise ValueError(
                f"free_max_occupancy must be in 1..100, got {self.free_max_occupancy}")
        if not self.free_max_occupancy - 1 <= self.occupied_min_occupancy < 100:
            raise ValueError(
                f"occupied_min_occupancy must be in [free_max_occupancy - 1, 99], got "
                f"{self.occupied_min_occupancy} (free_max_occupancy "
                f"{self.free_max_occupancy})")
        for name in ("max_rounds", "max_cut_candidates"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.inc_touch_cells < 0:
            raise ValueError(f"inc_touch_cells must be >= 0, got {self.inc_touch_cells}")
        for name in ("inc_lost_frac", "inc_full_frac", "id_keep_frac"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0 <= v <= 1):
                raise ValueError(f"{name} must be in [0, 1], got {v}")


@dataclass(frozen=True)
class SegmentationNodeParams(SegmentationParams):
    """Parameters of the ``segmentation`` node: the algorithm's plus the node's own."""

    map_transient_local: bool = field(default=True, metadata=param_meta(
        "subscribe to the map with transient-local durability (false: volatile); read "
        "only", read_only=True))
    incremental: bool = field(default=True, metadata=param_meta(
        "update the segmentation incrementally (false: full batch on every map)"))
    process_period_s: float = field(default=0.1, metadata=param_meta(
        "period of the timer that processes the latest map", "s", range=(0.0, math.inf)))
    idle_when_done: bool = field(default=True, metadata=param_meta(
        "pause segmenting while exploration_done (from target_selector) is true; the "
        "newest map is segmented when it turns false"))

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.process_period_s) and self.process_period_s > 0):
            raise ValueError(f"process_period_s must be > 0, got {self.process_period_s}")


@dataclass(frozen=True)
class DudeSettings:
    """Pixel-unit settings of the decomposition (built by :func:`dude_settings`).

    Parameters
    ----------
    tau_px : float
        Maximum concavity tau, in pixels (> 0).
    simplify_eps_px : float
        Douglas-Peucker tolerance applied to every traced ring (>= 0).
    min_hole_area_px : float
        Holes (obstacle islands) of at most this area are ignored entirely.
    min_component_px : int
        Components smaller than this are final pieces without decomposition.
    max_rounds : int
        Bound on the decomposition rounds of one piece (>= 1).
    max_tip_candidates : int
        For every notch, at most this many nearest plain boundary points are tested as
        far ends of a cut.
    max_notch_candidates : int
        For every notch, at most this many nearest other notches are tested.
    sliver_factor : float
        A cut whose ends are within ``sliver_factor * tau`` of each other along their
        ring is a sliver cut and is not used (§9.2).
    max_pocket_depth : int
        Bound on the nesting depth of the pocket tree.
    max_pieces : int
        Bound on the number of pieces processed for one mask (safety net).
    """

    tau_px: float
    simplify_eps_px: float = 1.5
    min_hole_area_px: float = 5.0
    min_component_px: int = 400
    max_rounds: int = 16
    max_tip_candidates: int = 24
    max_notch_candidates: int = 16
    sliver_factor: float = 2.0
    max_pocket_depth: int = 6
    max_pieces: int = 20000

    def __post_init__(self) -> None:
        if not (math.isfinite(self.tau_px) and self.tau_px > 0):
            raise ValueError(f"tau_px must be finite and > 0, got {self.tau_px}")
        if not self.simplify_eps_px >= 0:
            raise ValueError(f"simplify_eps_px must be >= 0, got {self.simplify_eps_px}")
        if self.max_rounds < 1:
            raise ValueError(f"max_rounds must be >= 1, got {self.max_rounds}")


def dude_settings(params: SegmentationParams, res: float) -> DudeSettings:
    """The pixel-unit DuDe settings of ``params`` on a grid of ``res`` metres per cell."""
    area = res * res
    return DudeSettings(
        tau_px=params.tau_m / res,
        simplify_eps_px=params.simplify_epsilon_m / res,
        min_hole_area_px=params.min_hole_area_m2 / area,
        min_component_px=int(math.ceil(params.min_component_area_m2 / area)),
        max_rounds=params.max_rounds,
        max_tip_candidates=params.max_cut_candidates,
    )

