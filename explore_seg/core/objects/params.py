"""Parameters of the object costmap: the pipeline's (:class:`ObjectParams`) and the
``object_costmap`` node's own (:class:`ObjectCostmapNodeParams`: rate, inputs, frames,
sensor mounts)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

from explore_seg.core.corrections import CorrectionParams
from explore_seg.core.fields import check_non_negative, param_meta
from explore_seg.core.pose_fusion import POSE_SOURCE_DOC, POSE_SOURCES

#: Class name given to objects found from laser legs without a detection.
UNKNOWN_CLASS = "unknown"

#: Values of ``ObjectParams.orientation_method`` (see ``footprint_orientation``).
ORIENTATION_METHODS = ("pca", "min_area_rect")


@dataclass(frozen=True)
class ObjectParams:
    """Parameters of the object costmap pipeline: detection -> 3D box, unclassified
    objects, fusion and outputs (the node's own settings: :class:`ObjectCostmapNodeParams`).

    Raises
    ------
    ValueError
        From ``__post_init__`` on any out-of-range value (message names field and value).
    """

    # --- detection -> 3D box
    min_score: float = field(default=0.3, metadata=param_meta(
        "Detections below this confidence are ignored", "0..1", range=(0.0, 1.0)))
    max_depth_m: float = field(default=4.0, metadata=param_meta(
        "Depth readings farther than this are ignored", "m", range=(0.0, math.inf)))
    pixel_stride: int = field(default=2, metadata=param_meta(
        "Use every n-th pixel (rows and columns) inside a detection box", "px",
        range=(1, 2**31 - 1)))
    max_box_samples: int = field(default=8000, metadata=param_meta(
        "Larger boxes are sampled with a larger stride so that at most about this many "
        "pixels are used per detection", range=(1, 2**31 - 1)))
    voxel_size_m: float = field(default=0.03, metadata=param_meta(
        "Voxel edge for downsampling the cropped cloud (0 disables)", "m", range=(0.0, math.inf)))
    floor_height_m: float = field(default=0.05, metadata=param_meta(
        "Points lower than this above the floor (map z) are floor and dropped", "m"))
    ceiling_height_m: float = field(default=2.2, metadata=param_meta(
        "Points higher than this above the floor are dropped", "m", range=(0.0, math.inf)))
    sor_k: int = field(default=8, metadata=param_meta(
        "Statistical outlier removal: number of neighbours", range=(1, 2**31 - 1)))
    sor_std: float = field(default=2.5, metadata=param_meta(
        "Statistical outlier removal: keep points whose mean neighbour distance is below "
        "mean + sor_std * std", range=(0.0, math.inf)))
    cluster_tolerance_m: float = field(default=0.08, metadata=param_meta(
        "Euclidean clustering: points closer than this join one cluster", "m",
        range=(0.0, math.inf)))
    min_grazing_angle_rad: float = field(default=0.07, metadata=param_meta(
        "Euclidean clustering: points of neighbouring sampled pixels are also linked when "
        "as far apart as a surface seen at this angle gives (a table top from a low "
        "camera is sampled in strips); larger = fewer links", "rad", range=(0.0, 0.5 * math.pi)))
    min_cluster_points: int = field(default=15, metadata=param_meta(
        "Euclidean clustering: smaller clusters are discarded", range=(1, 2**31 - 1)))
    near_vote_share: float = field(default=0.2, metadata=param_meta(
        "Clusters with at least this share of the best cluster's centre-weighted votes "
        "compete on depth: the nearest is the object (objects occlude the wall or desk "
        "behind them); 1 = most votes win", "0..1", range=(0.0, 1.0)))
    merge_parts_fraction: float = field(default=0.5, metadata=param_meta(
        "After choosing a cluster and clamping its box, other clusters with at least this "
        "fraction of their points inside that footprint (grown by cluster_tolerance_m) join "
        "it (a chair's backrest, seat and base split at the thin stem; a table's far legs "
        "below a top seen at a grazing angle); 1 disables it", "0..1", range=(0.0, 1.0)))
    orientation_method: str = field(default="min_area_rect", metadata=param_meta(
        "Footprint orientation: 'min_area_rect' (minimum-area enclosing rectangle) or "
        "'pca' (the paper; tilts by 5-10 deg on partly seen, unevenly sampled tops)"))
    boxes_on_floor: bool = field(default=True, metadata=param_meta(
        "Extend every box down to the floor (furniture stands on it)"))
    priors_path: str = field(default="", metadata=param_meta(
        "YAML of per-class size priors; empty = the package's config/object_priors.yaml. "
        "Classes without a prior are ignored", read_only=True))
    # --- fusion
    merge_distance_m: float = field(default=0.5, metadata=param_meta(
        "Re-detections of a class whose centres are closer than this merge", "m",
        range=(0.0, math.inf)))
    merge_iou: float = field(default=0.2, metadata=param_meta(
        "Re-detections whose footprints overlap more than this (IoU) merge", "0..1",
        range=(0.0, 1.0)))
    drop_wall_points: bool = field(default=True, metadata=param_meta(
        "Drop the depth points over walls of the 2D map (occupied components at least "
        "wall_min_length_m long, grown by wall_margin_m) before clustering: a desk against "
        "a wall then forms its own cluster instead of one merged with the wall, and a door "
        "jamb is never taken for the detected object"))
    wall_min_length_m: float = field(default=0.5, metadata=param_meta(
        "Occupied components of the 2D map whose bounding box is shorter than this on both "
        "sides are furniture legs or bases, not walls: their depth points are kept (the "
        "legs give a table's extent)", "m", range=(0.0, math.inf)))
    wall_margin_m: float = field(default=0.05, metadata=param_meta(
        "Growth of the map's wall cells for drop_wall_points", "m", range=(0.0, math.inf)))
    robot_radius_m: float = field(default=0.22, metadata=param_meta(
        "Robot radius: object boxes reaching into the robot's disk are wrong", "m",
        range=(0.0, math.inf)))
    robot_clear_fraction: float = field(default=0.5, metadata=param_meta(
        "Drop boxes that reach this fraction of robot_radius_m into the robot's disk "
        "(1 = only boxes over the robot's centre; a box that merely touches the robot, "
        "as an object does the robot bumps into, is kept; 0 = never)", "0..1", range=(0.0, 1.0)))
    swept_clear_radius_m: float = field(default=0.22, metadata=param_meta(
        "The layer and the virtual cloud are cleared within this distance of the path the "
        "robot has driven (its body proved the floor free there), so boxes grown from "
        "partial views never close the way the robot came in (0 = off)", "m",
        range=(0.0, math.inf)))
    prior_reject_factor: float = field(default=1.2, metadata=param_meta(
        "Drop a detection whose cluster footprint or height exceeds this factor times its "
        "class prior's maximum (0 = never drop, only clamp)", range=(0.0, math.inf)))
    min_extent_fraction: float = field(default=0.5, metadata=param_meta(
        "A cluster whose footprint's longer side is below this fraction of its class "
        "prior's min_xy_m is a fragment (a leg, a corner at the image border) and is not "
        "taken for the object: it gives neither the orientation nor the extent, and growing "
        "it to the prior places the box at random (0 = never)", "0..1", range=(0.0, 1.0)))
    merge_growth_max: float = field(default=1.25, metadata=param_meta(
        "Largest growth factor of a fused box's size per merged observation (>= 1)",
        range=(1.0, math.inf)))
    merge_extend_margin_m: float = field(default=0.05, metadata=param_meta(
        "Fusion of the measured footprints (see fuse_boxes): a re-detection measuring the "
        "same extent along an axis (within this, both sides seen) is averaged with the "
        "box, noise does not inflate it; otherwise a side farther out than the box's by "
        "more than this extends it (another part seen), sides within it are averaged, and "
        "sides where the view was cut only push outwards", "m", range=(0.0, math.inf)))
    max_objects: int = field(default=200, metadata=param_meta(
        "Most objects kept; the least confirmed are dropped first", range=(1, 2**31 - 1)))
    clear_after_misses: int = field(default=3, metadata=param_meta(
        "An object is removed after this many frames in which the camera sees past where "
        "its points were measured (its surface; not the empty space under a table top)",
        range=(1, 2**31 - 1)))
    explained_fraction: float = field(default=0.6, metadata=param_meta(
        "A new detection with at least this fraction of its measured points inside the "
        "footprint (+ miss_sample_spacing_m) of a confirmed object of another class is that "
        "object seen again, not a new one (a desk's box fitted to the chair in front of it "
        "and grown to the desk's size, closing the way past both); 0 = off", "0..1",
        range=(0.0, 1.0)))
    confirm_hits: int = field(default=2, metadata=param_meta(
        "An object detected in fewer frames is tentative (a false detection, or a box fitted "
        "to a neighbour's points): it is removed after tentative_max_unmatched frames that "
        "see its place unoccluded without detecting it (its measured body stays in the "
        "depth obstacles); 1 = every object is confirmed at once", range=(1, 2**31 - 1)))
    tentative_max_unmatched: int = field(default=3, metadata=param_meta(
        "Frames seeing a tentative object's centre unoccluded, without detecting it, before "
        "it is removed", range=(1, 2**31 - 1)))
    miss_depth_margin_m: float = field(default=0.15, metadata=param_meta(
        "Depth must exceed an object's surface point by this to count as seeing past it",
        "m", range=(0.0, math.inf)))
    miss_free_fraction: float = field(default=0.6, metadata=param_meta(
        "Fraction of the object's visible surface points that must be seen past for a miss",
        "0..1", range=(0.0, 1.0)))
    miss_min_samples: int = field(default=6, metadata=param_meta(
        "Fewest visible surface points of an object needed to judge a miss", range=(1, 2**31 - 1)))
    miss_sample_spacing_m: float = field(default=0.1, metadata=param_meta(
        "Voxel size of an object's measured surface points (kept to judge misses; a box "
        "without them is sampled on its faces at this spacing)", "m", range=(0.0, math.inf)))
    # --- outputs
    object_value: int = field(default=100, metadata=param_meta(
        "Layer value inside object footprints", "0..100", range=(0, 100)))
    background_value: int = field(default=0, metadata=param_meta(
        "Layer value outside objects (0 = no object known, -1 = unknown)", "-1..100",
        range=(-1, 100)))
    cloud_spacing_m: float = field(default=0.05, metadata=param_meta(
        "Spacing of the virtual point cloud filling each box", "m", range=(0.0, math.inf)))
    max_cloud_points: int = field(default=200000, metadata=param_meta(
        "Most virtual cloud points; the spacing grows to stay below", range=(1, 2**31 - 1)))
    # --- unclassified objects (laser legs)
    unknown_enabled: bool = field(default=True, metadata=param_meta(
        "Find unclassified objects from laser leg clusters and depth above them"))
    leg_cluster_gap_m: float = field(default=0.05, metadata=param_meta(
        "Scan points closer than this form one cluster", "m", range=(0.0, math.inf)))
    leg_min_width_m: float = field(default=0.0, metadata=param_meta(
        "Narrowest leg cluster (extent of its points; one-point clusters have 0)", "m",
        range=(0.0, math.inf)))
    leg_max_width_m: float = field(default=0.15, metadata=param_meta(
        "Widest leg cluster", "m", range=(0.0, math.inf)))
    leg_min_points: int = field(default=1, metadata=param_meta("Fewest scan points in a leg",
    range=(1, 2**31 - 1)))
    leg_isolation_m: float = field(default=0.15, metadata=param_meta(
        "A leg has no other scan point within this distance of its centre", "m",
        range=(0.0, math.inf)))
    leg_group_distance_m: float = field(default=1.6, metadata=param_meta(
        "Legs closer than this belong to one piece of furniture", "m", range=(0.0, math.inf)))
    min_legs: int = field(default=2, metadata=param_meta("Fewest legs of an unclassified object",
    range=(1, 2**31 - 1)))
    leg_max_range_m: float = field(default=4.0, metadata=param_meta(
        "Only scan points closer than this to the robot are used", "m", range=(0.0, math.inf)))
    unknown_radius_m: float = field(default=0.3, metadata=param_meta(
        "Depth points within this of the legs' rectangle belong to the object", "m",
        range=(0.0, math.inf)))
    unknown_min_height_m: float = field(default=0.2, metadata=param_meta(
        "Lowest depth point (above the lidar plane) of an unclassified object", "m"))
    unknown_max_height_m: float = field(default=1.2, metadata=param_meta(
        "Highest depth point of an unclassified object", "m", range=(0.0, math.inf)))
    unknown_min_points: int = field(default=20, metadata=param_meta(
        "Fewest depth points over a leg group to make an object", range=(1, 2**31 - 1)))
    unknown_top_band_m: float = field(default=0.1, metadata=param_meta(
        "Height band of a horizontal top: the densest band of this height must hold "
        "unknown_top_fraction of an unclassified object's depth points", "m",
        range=(0.0, math.inf)))
    unknown_top_fraction: float = field(default=0.5, metadata=param_meta(
        "Share of the depth points in the densest unknown_top_band_m band; walls and door "
        "jambs (vertical surfaces over leg-like wall ends) spread over all heights and fail",
        range=(0.0, 1.0)))
    unknown_min_top_cover: float = field(default=0.5, metadata=param_meta(
        "Share of the legs' rectangle that depth points of the top must cover (cells of "
        "unknown_cover_cell_m); legs of two objects grouped across open floor fail", "0..1",
        range=(0.0, 1.0)))
    unknown_cover_cell_m: float = field(default=0.1, metadata=param_meta(
        "Cell size for unknown_min_top_cover", "m", range=(0.0, math.inf)))
    post_max_width_m: float = field(default=0.7, metadata=param_meta(
        "Isolated laser clusters wider than leg_max_width_m and up to this wide are posts "
        "(a bin, a pedestal, a plant pot): depth points above one that reach more than "
        "post_overhang_m beyond its laser points (a rim, a top) make an unclassified "
        "object, since the lidar sees only the post (0 or <= leg_max_width_m = off)", "m",
        range=(0.0, math.inf)))
    post_overhang_m: float = field(default=0.04, metadata=param_meta(
        "Depth points farther than this from every laser point of a post overhang it", "m",
        range=(0.0, math.inf)))
    post_link_m: float = field(default=0.15, metadata=param_meta(
        "Depth points (in plan view) closer than this to a post or to its overhang belong "
        "to it; others near it (a table top beside a bin) do not", "m", range=(0.0, math.inf)))
    post_band_m: float = field(default=0.3, metadata=param_meta(
        "unknown_top_fraction of a post's overhanging depth points must lie in a height "
        "band this tall (a rim or a top; a face over all heights is a wall)", "m",
        range=(0.0, math.inf)))
    unknown_pixel_stride: int = field(default=4, metadata=param_meta(
        "Use every n-th depth pixel (rows and columns) for unclassified objects", "px",
        range=(1, 2**31 - 1)))
    # --- generic obstacles from depth (Nav2 voxel/obstacle layer idea; depth_obstacles.py)
    depth_obstacles: bool = field(default=True, metadata=param_meta(
        "Mark every depth point between depth_min_height_m and depth_max_height_m in the "
        "object layer (voxels, cleared where the camera sees through them), whatever its "
        "class: an undetected object the lidar does not cut (a low box, a bin's rim, an "
        "overhang) becomes an obstacle"))
    depth_min_height_m: float = field(default=0.05, metadata=param_meta(
        "Floor margin: depth points lower than this above the floor do not mark", "m",
        range=(0.0, math.inf)))
    depth_max_height_m: float = field(default=1.1, metadata=param_meta(
        "Depth points at or above this height (the robot's) do not mark", "m",
        range=(0.0, math.inf)))
    depth_max_range_m: float = field(default=3.0, metadata=param_meta(
        "Depth beyond this neither marks nor clears", "m", range=(0.0, math.inf)))
    depth_pixel_stride: int = field(default=4, metadata=param_meta(
        "Use every n-th depth pixel (rows and columns) for marking", "px",
        range=(1, 2**31 - 1)))
    depth_voxel_m: float = field(default=0.05, metadata=param_meta(
        "Voxel size on the floor (x, y)", "m", range=(0.0, math.inf)))
    depth_voxel_height_m: float = field(default=0.1, metadata=param_meta(
        "Voxel height", "m", range=(0.0, math.inf)))
    depth_min_points: int = field(default=2, metadata=param_meta(
        "A voxel is marked by a frame with at least this many of its points in it",
        range=(1, 2**31 - 1)))
    depth_evidence_window_s: float = field(default=3.0, metadata=param_meta(
        "A voxel with fewer than depth_min_points points in a frame is marked when its "
        "points over the frames of this window reach depth_min_points (an object seen "
        "only from afar or along a thin strip); the lidar-height columns of "
        "depth_lidar_band_m count over it too; 0 = each frame alone", "s",
        range=(0.0, math.inf)))
    depth_max_score: int = field(default=3, metadata=param_meta(
        "Marks a voxel can collect (each frame that sees through it takes one away; at "
        "zero it is cleared)", range=(1, 32767)))
    depth_clear_margin_m: float = field(default=0.1, metadata=param_meta(
        "A voxel is seen through when the depth at its pixel lies this much beyond it", "m",
        range=(0.0, math.inf)))
    depth_lidar_height_m: float = field(default=0.17, metadata=param_meta(
        "Height of the 2D lidar's scan plane above the floor (the 2D map's obstacles are "
        "what it cuts; sim_bridge's and a TurtleBot3's LDS: about 0.17 m)", "m",
        range=(0.0, math.inf)))
    depth_lidar_band_m: float = field(default=0.02, metadata=param_meta(
        "A voxel column holding a depth point within this of depth_lidar_height_m, in "
        "the frame or in a frame of depth_evidence_window_s, does not mark: the lidar sees "
        "what stands there and the 2D map has it, wherever the (drifting) map draws it; "
        "desk tops, chair seats and objects lower than the scan plane still mark "
        "(0 = off)", "m",
        range=(0.0, math.inf)))
    depth_forget_on_correction: bool = field(default=True, metadata=param_meta(
        "When a SLAM correction (a loop closure) re-renders the map, forget the voxels "
        "marked since the previous correction: they lie where the uncorrected poses put "
        "them (a wall seen from a drifted pose stays across a door) and are re-observed "
        "(the lock step is told of corrections by the simulator; the object_costmap node "
        "detects them: correction_* parameters)"))
    boxes_forget_on_correction: bool = field(default=True, metadata=param_meta(
        "At such a correction, also drop the tracked boxes last seen since the previous "
        "one: their evidence came at uncorrected poses (a box seen from a drifted pose "
        "stands in a passage of the corrected map); the camera finds them again where "
        "the corrected map has them"))
    correction_move_recent_s: float = field(default=10.0, metadata=param_meta(
        "At such a correction, the boxes and voxels last seen within this long before it "
        "are moved with the robot's pose jump instead of forgotten, when the jump is known "
        "(the lock step: the simulator's; the object_costmap node: when the map-frame "
        "poses showed the correction, correction_pose_jump_*): they were placed at the pose error the robot "
        "had just before, which the jump corrects, and an obstacle beside the robot, "
        "outside the camera's view, is not found again (0 = forget them too)", "s",
        range=(0.0, math.inf)))
    depth_decay_s: float = field(default=300.0, metadata=param_meta(
        "A voxel not marked again for this long is forgotten (0 = never)", "s",
        range=(0.0, math.inf)))
    depth_max_voxels: int = field(default=200000, metadata=param_meta(
        "Most voxels kept (the oldest are dropped first)", range=(1, 2**31 - 1)))

    def __post_init__(self) -> None:
        self._check_field_groups()
        self._check_bounds()
        self._check_orders()
        self._check_choices()

    def _check_field_groups(self) -> None:
        """Fields checked by kind: > 0, >= 0, finite, fractions, integers >= 1."""
        positive = ("max_depth_m", "ceiling_height_m", "cluster_tolerance_m",
                    "merge_distance_m", "miss_sample_spacing_m", "cloud_spacing_m",
                    "leg_cluster_gap_m", "leg_max_width_m", "leg_isolation_m",
                    "leg_group_distance_m", "leg_max_range_m", "unknown_max_height_m",
                    "unknown_cover_cell_m", "post_link_m",
                    "sor_std", "depth_max_height_m", "depth_max_range_m", "depth_voxel_m",
                    "depth_voxel_height_m")
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        check_non_negative(self, (
            "voxel_size_m", "miss_depth_margin_m", "leg_min_width_m", "unknown_radius_m",
            "post_max_width_m", "post_overhang_m", "post_band_m", "depth_min_height_m",
            "depth_clear_margin_m", "depth_decay_s", "depth_lidar_height_m",
            "depth_lidar_band_m", "depth_evidence_window_s", "correction_move_recent_s"))
        for name in ("floor_height_m", "unknown_min_height_m"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v}")
        fractions = ("min_score", "merge_iou", "miss_free_fraction", "explained_fraction",
                     "min_extent_fraction",
                     "merge_parts_fraction", "unknown_top_fraction", "near_vote_share", "robot_clear_fraction",
                     "unknown_min_top_cover")
        for name in fractions:
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        at_least_one = ("pixel_stride", "max_box_samples", "sor_k", "min_cluster_points", "max_objects",
                        "clear_after_misses", "confirm_hits", "tentative_max_unmatched",
                        "miss_min_samples", "max_cloud_points",
                        "leg_min_points", "min_legs", "unknown_min_points",
                        "unknown_pixel_stride", "depth_pixel_stride", "depth_min_points",
                        "depth_max_score", "depth_max_voxels")
        for name in at_least_one:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")

    def _check_bounds(self) -> None:
        """Fields with a bound of their own."""
        if not (self.prior_reject_factor == 0 or self.prior_reject_factor >= 1.0):
            raise ValueError(f"prior_reject_factor must be 0 or >= 1, got {self.prior_reject_factor}")
        if not self.wall_margin_m >= 0:
            raise ValueError(f"wall_margin_m must be >= 0, got {self.wall_margin_m}")
        if not (math.isfinite(self.wall_min_length_m) and self.wall_min_length_m >= 0):
            raise ValueError(f"wall_min_length_m must be finite and >= 0, "
                             f"got {self.wall_min_length_m}")
        if not (math.isfinite(self.swept_clear_radius_m) and self.swept_clear_radius_m >= 0):
            raise ValueError(f"swept_clear_radius_m must be finite and >= 0, "
                             f"got {self.swept_clear_radius_m}")
        if not self.robot_radius_m >= 0:
            raise ValueError(f"robot_radius_m must be >= 0, got {self.robot_radius_m}")
        if not (math.isfinite(self.merge_extend_margin_m) and self.merge_extend_margin_m >= 0):
            raise ValueError(f"merge_extend_margin_m must be finite and >= 0, "
                             f"got {self.merge_extend_margin_m}")
        if not self.merge_growth_max >= 1.0:
            raise ValueError(f"merge_growth_max must be >= 1, got {self.merge_growth_max}")
        if not self.unknown_top_band_m > 0:
            raise ValueError(f"unknown_top_band_m must be > 0, got {self.unknown_top_band_m}")
        if not 0.0 < self.min_grazing_angle_rad <= 0.5 * math.pi:
            raise ValueError(f"min_grazing_angle_rad must be in (0, pi/2], "
                             f"got {self.min_grazing_angle_rad}")

    def _check_orders(self) -> None:
        """Lower limits below their upper ones."""
        if self.floor_height_m >= self.ceiling_height_m:
            raise ValueError(
                f"floor_height_m ({self.floor_height_m}) must be below ceiling_height_m "
                f"({self.ceiling_height_m})")
        if self.depth_min_height_m >= self.depth_max_height_m:
            raise ValueError(
                f"depth_min_height_m ({self.depth_min_height_m}) must be below "
                f"depth_max_height_m ({self.depth_max_height_m})")
        if self.depth_max_score > 32767:
            raise ValueError(f"depth_max_score must be <= 32767, got {self.depth_max_score}")
        if self.unknown_min_height_m >= self.unknown_max_height_m:
            raise ValueError(
                f"unknown_min_height_m ({self.unknown_min_height_m}) must be below "
                f"unknown_max_height_m ({self.unknown_max_height_m})")
        if self.leg_min_width_m > self.leg_max_width_m:
            raise ValueError(
                f"leg_min_width_m ({self.leg_min_width_m}) must not exceed leg_max_width_m "
                f"({self.leg_max_width_m})")

    def _check_choices(self) -> None:
        """The orientation method and the cost values."""
        if self.orientation_method not in ORIENTATION_METHODS:
            raise ValueError(f"orientation_method must be one of {ORIENTATION_METHODS}, "
                             f"got {self.orientation_method!r}")
        if not 0 <= self.object_value <= 100:
            raise ValueError(f"object_value must be in 0..100, got {self.object_value}")
        if not -1 <= self.background_value <= 100:
            raise ValueError(f"background_value must be in -1..100, got {self.background_value}")


@dataclass(frozen=True)
class ObjectCostmapNodeParams(ObjectParams, CorrectionParams):
    """Parameters of the ``object_costmap`` node: the pipeline's plus the node's own (rate,
    input pairing, pose source, frames, camera and lidar mounts, oracle class table).

    Raises
    ------
    ValueError
        From ``__post_init__`` on any out-of-range value (message names field and value).
    """

    rate_hz: float = field(default=2.0, metadata=param_meta(
        "Camera frames processed per second, at most (a camera at this rate has every "
        "frame processed, a faster one the newest after each 0.9 / rate_hz); frames "
        "arriving while one is processed are dropped, never queued", "Hz", range=(0.0, math.inf)))
    idle_when_done: bool = field(default=True, metadata=param_meta(
        "pause frame processing while exploration_done (from target_selector) is true "
        "(false: keep the layer updated, e.g. for navigation after exploring)"))
    sync_tolerance_s: float = field(default=0.05, metadata=param_meta(
        "Largest stamp difference for pairing colour with depth", "s", range=(0.0, math.inf)))
    pose_tolerance_s: float = field(default=0.2, metadata=param_meta(
        "Largest stamp difference between the depth image and the robot pose used for it; "
        "frames without a pose this close are dropped", "s", range=(0.0, math.inf)))
    pose_topic_type: str = field(default="odom", metadata=param_meta(
        POSE_SOURCE_DOC, read_only=True))
    map_frame: str = field(default="map", metadata=param_meta(
        "Frame of the published cloud and markers"))
    map_transient_local: bool = field(default=True, metadata=param_meta(
        "Subscribe to 'map' transient-local (latched); false for a volatile publisher",
        read_only=True))
    camera_x_m: float = field(default=0.064, metadata=param_meta(
        "Camera position in base_link, x (default: sim_bridge's TurtleBot3-like mount)", "m"))
    camera_y_m: float = field(default=0.0, metadata=param_meta(
        "Camera position in base_link, y", "m"))
    camera_z_m: float = field(default=0.2, metadata=param_meta(
        "Camera position in base_link (above the floor), z", "m"))
    camera_roll_rad: float = field(default=0.0, metadata=param_meta(
        "Camera body frame (x forward, z up) roll in base_link", "rad"))
    camera_pitch_rad: float = field(default=0.0, metadata=param_meta(
        "Camera body frame pitch in base_link (positive looks down)", "rad"))
    camera_yaw_rad: float = field(default=0.0, metadata=param_meta(
        "Camera body frame yaw in base_link", "rad"))
    lidar_x_m: float = field(default=-0.064, metadata=param_meta(
        "Lidar position in base_link, x", "m"))
    lidar_y_m: float = field(default=0.0, metadata=param_meta(
        "Lidar position in base_link, y", "m"))
    lidar_yaw_rad: float = field(default=0.0, metadata=param_meta(
        "Lidar yaw in base_link", "rad"))
    oracle_sim_class_ids: tuple[str, ...] = field(default=(
        "none:0", "wall:1", "chair:2", "table:3", "desk:4", "cabinet:5", "sofa:6", "other:7"),
        metadata=param_meta("Oracle detector only: the simulator's semantic class table "
                            "as 'name:id' pairs (mirrors sim_bridge.sensors.CLASS_IDS)"))

    def __post_init__(self) -> None:
        super().__post_init__()
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"rate_hz must be finite and > 0, got {self.rate_hz}")
        self.check_corrections()
        check_non_negative(self, ("sync_tolerance_s", "pose_tolerance_s"))
        for name in ("camera_x_m", "camera_y_m", "camera_z_m", "camera_roll_rad",
                     "camera_pitch_rad", "camera_yaw_rad", "lidar_x_m", "lidar_y_m",
                     "lidar_yaw_rad"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v}")
        if self.pose_topic_type not in POSE_SOURCES:
            raise ValueError(
                f"pose_topic_type must be one of {POSE_SOURCES}, got {self.pose_topic_type!r}")
        if not self.map_frame:
            raise ValueError("map_frame must not be empty")
        parse_class_ids(self.oracle_sim_class_ids)


def parse_class_ids(pairs: Sequence[str]) -> dict[str, int]:
    """Parse ``"name:id"`` pairs (a simulator's semantic class table) into a dict.

    Raises
    ------
    ValueError
        On a pair that is not ``name:non-negative integer`` or a name listed twice.
    """
    out: dict[str, int] = {}
    for pair in pairs:
        name, sep, value = str(pair).partition(":")
        name, value = name.strip(), value.strip()
        if not sep or not name or not value.isdigit():
            raise ValueError(f"class ids must be 'name:id' with an integer id >= 0, got {pair!r}")
        if name in out:
            raise ValueError(f"class id table lists {name!r} twice")
        out[name] = int(value)
    return out
