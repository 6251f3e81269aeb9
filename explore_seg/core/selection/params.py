"""Parameters of target selection and goal handling, and of the ``target_selector`` node.

:class:`SelectionParams` holds the algorithm's parameters (the strategy, its weights, the
goal manager's rules). :class:`SelectorNodeParams` adds the node's own settings (rate,
pose source, republishing). Frontier detection has its own
:class:`~explore_seg.core.frontiers.FrontierParams` (the ``frontier.*`` parameters).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from explore_seg.core.fields import INT_MAX, check_non_negative, non_negative, param_meta
from explore_seg.core.block_graph import MAX_BLOCK_CELLS
from explore_seg.core.pose_fusion import POSE_SOURCE_DOC, POSE_SOURCES
from explore_seg.core.selection.strategy import get_strategy

#: The built-in strategies (core/selection/strategies/), as the ``strategy`` parameter's
#: description lists them; a test checks it against the registry.
BUILTIN_NAMES = ("paper", "nearest", "explore_lite", "rrt_exploration", "routed", "foresight")

#: Robot pose sources (one home: :mod:`explore_seg.core.pose_fusion`).
POSE_TOPIC_TYPES = POSE_SOURCES
_INF = math.inf


@dataclass(frozen=True)
class SelectionBaseParams:
    """What every strategy shares: the strategy's name, path lengths, region lookup."""

    strategy: str = field(default="routed", metadata=param_meta(
        "target-selection strategy: " + " | ".join(BUILTIN_NAMES)
        + ", or a strategy registered by a plug-in (docs/strategies.md)"))
    region_search_radius_m: float = non_negative(
        "a cell without region takes the nearest labelled cell's within this radius", "m",
        default=0.3)
    path_block_cells: int = field(default=4, metadata=param_meta(
        f"path lengths on blocks of this many cells per side (1 = exact, "
        f"max {MAX_BLOCK_CELLS})", "cells", range=(1, MAX_BLOCK_CELLS)))
    start_search_radius_m: float = non_negative(
        "a robot on a non-passable cell starts from the nearest passable cell within this "
        "radius", "m", default=0.5)
    unknown_path_factor: float = field(default=1.5, metadata=param_meta(
        "when no cPoint is reachable through known free space, distances through unknown "
        "cells are used, multiplied by this factor (>= 1)", range=(1.0, _INF)))
    use_regions: bool = field(default=True, metadata=param_meta(
        "use the regions labels for regionGain (paper strategy) and region_switch_m "
        "(routed)"))

    def __post_init__(self) -> None:
        get_strategy(self.strategy)   # raises ValueError naming the registered ones
        check_non_negative(self, ("region_search_radius_m", "start_search_radius_m"))
        if not 1 <= self.path_block_cells <= MAX_BLOCK_CELLS:
            raise ValueError(f"path_block_cells must be in 1..{MAX_BLOCK_CELLS}, "
                             f"got {self.path_block_cells}")
        if not self.unknown_path_factor >= 1.0:
            raise ValueError(f"unknown_path_factor must be >= 1, got {self.unknown_path_factor}")


@dataclass(frozen=True)
class GoalParams:
    """The goal manager's rules (:class:`~explore_seg.core.selection.goals.GoalManager`):
    keeping and switching goals, progress, arrival, blacklist, DONE."""

    hysteresis_margin: float = non_negative(
        "switch goals only when the new cost < current - margin * |current|", default=0.1)
    progress_timeout_s: float = field(default=30.0, metadata=param_meta(
        "blacklist a goal whose distance did not decrease for this long", "s",
        range=(0.0, _INF)))
    progress_min_m: float = non_negative(
        "decrease of the distance to the goal that counts as progress", "m", default=0.1)
    goal_reached_tolerance_m: float = non_negative(
        "robot closer than this to its goal has reached it", "m", default=0.3)
    frontier_match_radius_m: float = non_negative(
        "a frontier with a cell this close to the goal (plus the goal's distance to its "
        "frontier when set) is the goal's frontier", "m", default=0.5)
    arrival_wait_s: float = non_negative(
        "after reaching a goal, its frontier is judged on the first newer map stamped at "
        "or after the arrival (one that shows the view from the goal), or after this long "
        "without one. Above the map's update period (slam_toolbox map_update_interval, "
        "5 s) plus its delivery and a decision period, so that a renewed map ends the "
        "wait; 0 = judge on the map of the arrival", "s", default=7.0)
    goal_change_min_m: float = non_negative(
        "a new goal closer than this to the current one is not sent", "m", default=0.3)
    blacklist_radius_m: float = non_negative(
        "frontiers whose cPoint lies this close to a blacklisted goal are skipped", "m",
        default=0.5)
    blacklist_max: int = field(default=50, metadata=param_meta(
        "blacklist length (oldest entries dropped)", range=(1, INT_MAX)))
    blacklist_retries: int = field(default=1, metadata=param_meta(
        "times the blacklist is cleared to retry its frontiers before DONE (a retry that "
        "revealed retry_reveal_m2 does not count)",
        range=(0, INT_MAX)))
    retry_reveal_m2: float = non_negative(
        "a blacklist retry after which at least this much more of the map became known "
        "does not count against blacklist_retries, so retries go on while they reveal "
        "space. Raising it makes fewer retries free; 0 = every retry counts", "m^2",
        default=1.0)
    retry_reveal_radius_m: float = non_negative(
        "retry_reveal_m2 counts the cells within this of the retried goals that became "
        "known (a loop-closure re-render that redraws the map elsewhere reveals nothing); "
        "0 = anywhere on the map", "m", default=2.0)
    flicker_vanish_count: int = field(default=3, metadata=param_meta(
        "blacklist a goal area once its frontier vanished this many times before the robot "
        "got there with its cells still unknown (a wall edge flickering next to unknown "
        "space). Raising it follows such a frontier longer; 0 = never",
        range=(0, INT_MAX)))
    abort_retries: int = field(default=3, metadata=param_meta(
        "a goal the navigator aborted (no path on its map) while the explorer's own map "
        "has no path to its frontier either is not blacklisted: the frontier waits until "
        "the map opens a path (map noise in a doorway) or the robot looks at it from an "
        "approach; after this many such aborts in one area (flicker_radius_m) the area's "
        "goals are blacklisted. An abort of a goal the explorer still has a path to is "
        "blacklisted at once; 0 = every abort blacklists at once", range=(0, INT_MAX)))
    flicker_radius_m: float = non_negative(
        "goals within this distance of the first goal of an area count as that area for "
        "flicker_vanish_count, revealed_arrivals_max and abort_retries", "m", default=1.0)
    done_confirmations: int = field(default=3, metadata=param_meta(
        "consecutive decisions without a reachable frontier before DONE",
        range=(1, INT_MAX)))
    return_to_start: bool = field(default=False, metadata=param_meta(
        "drive back to the start pose when exploration is done"))
    lookout_goals: bool = field(default=True, metadata=param_meta(
        "when no frontier has a path, drive to a lookout from which an unreachable one is "
        "in sight (within sensor_range_m) and look, before exploration ends (a gap behind "
        "a passage narrower than the robot)"))
    speckle_max_cells: int = field(default=2, metadata=param_meta(
        "when no frontier (nor lookout) is selectable, occupied 8-connected pieces of at "
        "most this many cells count as map speckle (hits of one or two beams that no other "
        "scan confirmed): frontiers reachable on the map without them get an approach goal "
        "where the path meets the speckle, to look at the passage before exploration ends; "
        "0 = no approach goals", range=(0, INT_MAX)))
    approach_radius_m: float = non_negative(
        "robot radius of the relaxed map (speckle removed) on which approach goals are "
        "found: a passage that map noise (ragged or doubled wall edges) narrowed below the "
        "robot's width but left wider than twice this gets an approach too. Lowering it "
        "opens more passages to a look; at or above the robot radius only speckle does",
        "m", default=0.15)
    approach_keeps_objects: bool = field(default=True, metadata=param_meta(
        "the relaxed map of approach goals keeps the object layer's obstacles. False: it "
        "drops them, so a box that closes a passage (depth points of a wall mapped at a "
        "drifted pose, a real table) gets an approach too: the robot drives up to it and "
        "looks, and the navigator, which keeps the layer, decides whether to pass"))
    approach_trail_radius_m: float = non_negative(
        "the relaxed map of approach goals also takes the cells within this of the robot's "
        "own path (its map-frame positions at the decisions since the last map correction) "
        "as passable: a doorway the robot drove through gets an approach however drift "
        "doubled its walls in the map, and the navigator decides whether to pass; 0 = the "
        "map alone", "m", default=0.1)
    retry_change_m2: float = non_negative(
        "a blacklisted goal is dropped from the blacklist (its frontier a candidate again) "
        "once the map's occupied plus unknown cells within flicker_radius_m of it changed "
        "by this much since it was blacklisted: a doorway that later scans or a "
        "loop-closure re-render opened, space seen; at most change_retries times per area "
        "(flicker_radius_m). Raising it needs a bigger change; 0 = never", "m^2",
        default=0.1)
    change_retries: int = field(default=2, metadata=param_meta(
        "retries of blacklisted goals on a map change (retry_change_m2) per area "
        "(flicker_radius_m); 0 = none", range=(0, INT_MAX)))
    turn_looks: int = field(default=2, metadata=param_meta(
        "when frontiers without a path (or blacklisted) remain and none, nor a lookout or "
        "approach, is selectable for done_confirmations decisions, turn in place by half a "
        "turn this many times per "
        "area (flicker_radius_m) before the blacklist retry and DONE: slam_toolbox adds a "
        "scan only after 0.5 m or 0.5 rad of motion (minimum_travel_distance / _heading), "
        "so a robot that stands still adds none, and the scans of a turn clear map noise "
        "(speckle, ragged wall ends) that closes a passage next to it; 0 = no turns",
        range=(0, INT_MAX)))
    revisit_goals: int = field(default=3, metadata=param_meta(
        "when exploration would end (after the waits, turn looks and blacklist retries) "
        "with frontiers without a path left, on a map the SLAM corrected at least once (a "
        "loop closure re-rendered it), drive back to this many places of the robot's own "
        "path first, one at a time: a SLAM closes loops where the robot returns to places "
        "it mapped long before, and a closure re-aligns walls that drift mapped across a "
        "passage; counted anew once a frontier is selectable; 0 = no revisits",
        range=(0, INT_MAX)))
    revisit_min_travel_m: float = non_negative(
        "a revisited place was recorded at least this much travel ago (slam_toolbox "
        "searches for loop closures among scans outside its running buffer, "
        "scan_buffer_maximum_scan_distance 10 m)", "m", default=10.0)
    revisit_max_path_m: float = non_negative(
        "the oldest place within this path length of the robot is revisited (the older, "
        "the more its drift differs from now and the more a closure corrects); none that "
        "close: the nearest", "m", default=20.0)
    revisit_spacing_m: float = non_negative(
        "the places revisited in one spell lie at least this far apart (slam_toolbox's "
        "loop_search_maximum_distance, 3 m: a closer place offers the same loop "
        "candidates)", "m", default=3.0)

    def __post_init__(self) -> None:
        check_non_negative(self, ("hysteresis_margin", "progress_min_m",
                                  "goal_reached_tolerance_m", "frontier_match_radius_m",
                                  "blacklist_radius_m", "arrival_wait_s", "goal_change_min_m",
                                  "flicker_radius_m", "retry_reveal_m2", "approach_radius_m",
                                  "retry_change_m2", "retry_reveal_radius_m",
                                  "approach_trail_radius_m", "revisit_min_travel_m",
                                  "revisit_max_path_m", "revisit_spacing_m"))
        if not (math.isfinite(self.progress_timeout_s) and self.progress_timeout_s > 0):
            raise ValueError(f"progress_timeout_s must be finite and > 0, "
                             f"got {self.progress_timeout_s}")
        if self.blacklist_max < 1:
            raise ValueError(f"blacklist_max must be >= 1, got {self.blacklist_max}")
        if self.blacklist_retries < 0:
            raise ValueError(f"blacklist_retries must be >= 0, got {self.blacklist_retries}")
        if self.flicker_vanish_count < 0:
            raise ValueError(f"flicker_vanish_count must be >= 0, got "
                             f"{self.flicker_vanish_count}")
        if self.abort_retries < 0:
            raise ValueError(f"abort_retries must be >= 0, got {self.abort_retries}")
        if self.done_confirmations < 1:
            raise ValueError(f"done_confirmations must be >= 1, got {self.done_confirmations}")
        if self.speckle_max_cells < 0:
            raise ValueError(f"speckle_max_cells must be >= 0, got {self.speckle_max_cells}")
        for name in ("turn_looks", "change_retries", "revisit_goals"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0, got {getattr(self, name)}")


@dataclass(frozen=True)
class ViewParams:
    """How a viewpoint's view of unknown space is rated (``routed``'s viewpoints and the
    goal manager's lookout goals)."""

    sensor_range_m: float = field(default=5.0, metadata=param_meta(
        "routed and lookout goals: range of the 360-degree sensor whose view of "
        "unknown space rates the viewpoints", "m", range=(0.0, _INF)))
    gain_rays: int = field(default=24, metadata=param_meta(
        "routed and lookout goals: rays cast over 360 degrees per viewpoint candidate",
        range=(4, 720)))
    viewpoint_step_m: float = field(default=0.3, metadata=param_meta(
        "routed and lookout goals: spacing of the viewpoint candidates' lattice", "m",
        range=(0.0, _INF)))
    viewpoint_gain_tolerance: float = field(default=0.1, metadata=param_meta(
        "routed and lookout goals: among candidates seeing at least (1 - this) of the "
        "best view, the one closest to the robot is the viewpoint", range=(0.0, 1.0)))
    min_gain_m2: float = non_negative(
        "routed and lookout goals: a group whose viewpoint (lookout) sees less unknown "
        "area than this is not a goal (it would reveal nothing: exploration ends instead "
        "of chasing it)", "m^2",
        default=0.25)

    def __post_init__(self) -> None:
        check_non_negative(self, ("min_gain_m2",))
        if not (math.isfinite(self.sensor_range_m) and self.sensor_range_m > 0):
            raise ValueError(f"sensor_range_m must be finite and > 0, got {self.sensor_range_m}")
        if not (math.isfinite(self.viewpoint_step_m) and self.viewpoint_step_m > 0):
            raise ValueError(f"viewpoint_step_m must be finite and > 0, "
                             f"got {self.viewpoint_step_m}")
        if not 4 <= self.gain_rays <= 720:
            raise ValueError(f"gain_rays must be in 4..720, got {self.gain_rays}")
        if not 0.0 <= self.viewpoint_gain_tolerance <= 1.0:
            raise ValueError(f"viewpoint_gain_tolerance must be in [0, 1], "
                             f"got {self.viewpoint_gain_tolerance}")


@dataclass(frozen=True)
class PaperParams:
    """The weights of eq. 1-3 (bound flat as ROS parameters through ``SelectionParams``)."""

    alpha: float = non_negative("paper: weight of distGain", default=1.0)
    beta: float = non_negative("paper: weight of 1/sizeGain", default=0.001)
    gamma: float = non_negative(
        "paper: regionGain of a frontier outside the robot's region", default=1.0)

    def __post_init__(self) -> None:
        check_non_negative(self, ("alpha", "beta", "gamma"))


@dataclass(frozen=True)
class ExploreLiteParams:
    """explore_lite's cost weights (bound flat as ROS parameters through
    ``SelectionParams``)."""

    potential_scale: float = non_negative(
        "explore_lite: weight of the path length", "1/m", default=3.0)
    gain_scale: float = non_negative(
        "explore_lite: weight of the frontier length", "1/m", default=1.0)

    def __post_init__(self) -> None:
        check_non_negative(self, ("potential_scale", "gain_scale"))


@dataclass(frozen=True)
class RrtExplorationParams:
    """The assigner's revenue weights (bound flat as ROS parameters through
    ``SelectionParams``; the RRT detector's own are :class:`explore_seg.core.rrt.RrtParams`,
    ``rrt.*``)."""

    info_multiplier: float = non_negative(
        "rrt_exploration: weight of a candidate's information gain (unknown area, m^2) "
        "against its path length in the revenue", "1/m", default=3.0)
    hysteresis_radius_m: float = non_negative(
        "rrt_exploration: candidates within this path length of the robot have their "
        "information gain multiplied by hysteresis_gain", "m", default=3.0)
    hysteresis_gain: float = non_negative(
        "rrt_exploration: information gain factor of candidates near the robot (> 1 keeps "
        "it exploring where it is)", default=2.0)

    def __post_init__(self) -> None:
        check_non_negative(self, ("info_multiplier", "hysteresis_radius_m", "hysteresis_gain"))


@dataclass(frozen=True)
class RoutedParams:
    """Viewpoints, tour and goal handling of ``routed`` (bound flat as ROS parameters
    through ``SelectionParams``)."""

    viewpoint_radius_m: float = non_negative(
        "routed: viewpoint candidates lie within this distance of their frontier's cells",
        "m", default=0.75)
    frontier_split_m: float = non_negative(
        "routed: a frontier group extending more than this along its main axis is split "
        "(at its mean, recursively) into parts, each with its own viewpoint in the tour. "
        "Raising it gives fewer, longer parts; 0 = off", "m",
        default=3.0)
    region_switch_m: float = non_negative(
        "routed: extra tour cost of an edge between viewpoints of two different regions "
        "(finish a region unless its rest is a longer detour)", "m", default=1.0)
    leftover_gain_m2: float = non_negative(
        "routed: a viewpoint that sees less unknown area than this is a leftover, kept out "
        "of the tour while a viewpoint that sees more remains and visited last. Raising it "
        "defers more views; 0 = off", "m^2", default=2.0)
    leftover_max_length_m: float = non_negative(
        "routed: a group with at least this much frontier (cells x cell size) is never a "
        "leftover, whatever its viewpoint sees (the map's ragged edge, whose view the edge "
        "cuts short). Raising it lets longer groups wait; 0 = any group can be one", "m",
        default=3.0)
    gain_weight_m_per_m2: float = non_negative(
        "routed: a group's cost is its tour length minus this times the unknown area its "
        "viewpoint sees (big views first when the detour is small)", "m/m^2", default=0.1)
    tour_refresh_rows: int = field(default=8, metadata=param_meta(
        "routed: number of kept viewpoints (oldest first) whose path lengths to the others "
        "are recomputed each decision, besides the new viewpoints'. Raising it keeps lengths "
        "fresher at more cost; at or above the number of viewpoints every length is "
        "recomputed every decision", range=(0, INT_MAX)))
    handover_m: float = non_negative(
        "routed: a goal this close to the robot counts as reached, so its frontier is "
        "judged and the next goal sent while the robot still drives. Raising it judges "
        "goals earlier; below goal_reached_tolerance_m it has no effect", "m",
        default=1.0)
    reached_unknown_fraction: float = field(default=0.5, metadata=param_meta(
        "routed: a reached goal whose frontier remains is blacklisted only when at least "
        "this share of its frontier's cells (as last matched before arrival) are still "
        "unknown; otherwise the frontier stays selectable (the space goes on, as in a "
        "corridor longer than the sensor range). Raising it blacklists fewer reached goals; "
        "0 = always blacklist, as the other strategies do", range=(0.0, 1.0)))
    revealed_arrivals_max: int = field(default=2, metadata=param_meta(
        "routed, with reached_unknown_fraction > 0: number of arrivals that revealed cells "
        "at one goal area (within flicker_radius_m of its first goal) after which the "
        "area's goals are blacklisted. Raising it lets a small leftover be re-chosen more "
        "often; 0 = no limit", range=(0, INT_MAX)))
    blocked_views_unreachable: bool = field(default=True, metadata=param_meta(
        "routed: a group that no reachable viewpoint candidate sees (less than "
        "min_gain_m2) while an unreachable one does, and whose own cPoint has no path, "
        "keeps its cPoint and counts as unreachable, so lookouts, approach goals and turn "
        "looks seek a way to it before exploration ends (a doorway that map drift shut). "
        "False: it drops out of the tour as a group with nothing to see"))

    def __post_init__(self) -> None:
        check_non_negative(self, ("viewpoint_radius_m", "frontier_split_m", "region_switch_m",
                                  "gain_weight_m_per_m2", "leftover_gain_m2",
                                  "leftover_max_length_m", "handover_m"))
        if not 0.0 <= self.reached_unknown_fraction <= 1.0:
            raise ValueError(f"reached_unknown_fraction must be in [0, 1], "
                             f"got {self.reached_unknown_fraction}")
        if self.revealed_arrivals_max < 0:
            raise ValueError(f"revealed_arrivals_max must be >= 0, got "
                             f"{self.revealed_arrivals_max}")
        if self.tour_refresh_rows < 0:
            raise ValueError(f"tour_refresh_rows must be >= 0, got {self.tour_refresh_rows}")


@dataclass(frozen=True)
class ForesightParams:
    """The floor-plan prediction of ``foresight`` (bound flat as ROS parameters through
    ``SelectionParams``; its viewpoints and tour are ``routed``'s, :class:`RoutedParams`)."""

    prediction_gain_weight: float = field(default=0.75, metadata=param_meta(
        "foresight: a viewpoint's gain is this share of the free area it is expected to "
        "newly see on the predicted floor plan plus the rest of the unknown area it sees on "
        "the map (as routed rates it). Raising it trusts the prediction more; 0 = routed's "
        "gains", range=(0.0, 1.0)))
    prediction_margin_m: float = non_negative(
        "foresight: unknown space added around the map before the prediction, so the "
        "predicted plan reaches past the map's current edge", "m", default=5.0)
    prediction_weights: str = field(default="", metadata=param_meta(
        "foresight: the predictor's weight file (.npz); '' = the package's "
        "explore_seg/core/prediction/weights/floorplan_unet.npz (make train-predictor "
        "writes it). Without torch or the file, "
        "foresight rates viewpoints as routed does and says so once in the log"))
    prediction_threads: int = field(default=1, metadata=param_meta(
        "foresight: torch CPU threads of the prediction (process-wide torch setting); "
        "0 = leave torch's setting", range=(0, 256)))

    def __post_init__(self) -> None:
        check_non_negative(self, ("prediction_margin_m",))
        if not 0.0 <= self.prediction_gain_weight <= 1.0:
            raise ValueError(f"prediction_gain_weight must be in [0, 1], "
                             f"got {self.prediction_gain_weight}")
        if not 0 <= self.prediction_threads <= 256:
            raise ValueError(f"prediction_threads must be in 0..256, "
                             f"got {self.prediction_threads}")
        if not isinstance(self.prediction_weights, str):
            raise TypeError(f"prediction_weights must be a str, got "
                            f"{type(self.prediction_weights).__name__}")


#: The parts of :class:`SelectionParams`, in the order their fields (and ROS parameters)
#: are listed; each validates its own fields.
SELECTION_PARTS: tuple[type, ...] = (SelectionBaseParams, GoalParams, ViewParams, PaperParams,
                                     ExploreLiteParams, RrtExplorationParams, RoutedParams,
                                     ForesightParams)


@dataclass(frozen=True)
class SelectionParams(ForesightParams, RoutedParams, RrtExplorationParams, ExploreLiteParams,
                      PaperParams, ViewParams, GoalParams, SelectionBaseParams):
    """Parameters of target selection: the shared ones (:class:`SelectionBaseParams`), the
    goal manager's (:class:`GoalParams`), the view rating's (:class:`ViewParams`) and each
    built-in strategy's (:class:`PaperParams`, :class:`ExploreLiteParams`,
    :class:`RrtExplorationParams`, :class:`RoutedParams`, :class:`ForesightParams`; its
    ``Strategy.params``). The parts are bases, so every field is one flat ROS parameter
    (``alpha``, ``handover_m``, ...) and code reads ``params.alpha``."""

    def __post_init__(self) -> None:
        for part in SELECTION_PARTS:
            part.__post_init__(self)


@dataclass(frozen=True)
class SelectorNodeParams(SelectionParams):
    """Parameters of the ``target_selector`` node: the algorithm's plus the node's own."""

    rate_hz: float = field(default=1.0, metadata=param_meta(
        "decision rate", "Hz", range=(0.0, _INF)))
    pose_topic_type: str = field(default="odom", metadata=param_meta(POSE_SOURCE_DOC))
    pose_timeout_s: float = field(default=5.0, metadata=param_meta(
        "a pose older than this is not used", "s", range=(0.0, _INF)))
    goal_republish_s: float = non_negative(
        "re-publish the current goal this often (0 = only when it changes)", "s")
    autostart: bool = field(default=True, metadata=param_meta(
        "start exploring without a call to ~/start"))
    map_transient_local: bool = field(default=True, metadata=param_meta(
        "transient-local map/object_costmap/regions subscriptions (false for volatile "
        "publishers)"))
    nav_action: str = field(default="navigate_to_pose", metadata=param_meta(
        "the navigator's action (its <name>/_action/status tells how each goal ended, "
        "<name>/_action/cancel_goal cancels it); '' = publish goal_pose only (goals end by "
        "progress_timeout_s)"))
    nav_accept_timeout_s: float = field(default=5.0, metadata=param_meta(
        "a goal no action status lists this long after its publish counts as rejected "
        "(only while a status publisher exists)", "s", range=(0.0, _INF)))
    cancel_timeout_s: float = field(default=2.0, metadata=param_meta(
        "a cancel request not answered within this time is logged", "s",
        range=(0.0, _INF)))

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.pose_topic_type not in POSE_TOPIC_TYPES:
            raise ValueError(f"pose_topic_type must be one of {POSE_TOPIC_TYPES}, "
                             f"got {self.pose_topic_type!r}")
        if self.nav_action and not re.fullmatch(r"[A-Za-z_/][A-Za-z0-9_/]*", self.nav_action):
            raise ValueError(f"nav_action must be a ROS name (letters, digits, _ and /) or "
                             f"'', got {self.nav_action!r}")
        for name in ("rate_hz", "pose_timeout_s", "nav_accept_timeout_s", "cancel_timeout_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not (math.isfinite(self.goal_republish_s) and self.goal_republish_s >= 0):
            raise ValueError(f"goal_republish_s must be finite and >= 0, "
                             f"got {self.goal_republish_s}")
