"""Object-based costmap: 3D boxes of furniture from 2D detections + depth, and their fusion.

Pipeline (Kim, Kim & Lee, RA-L 2022, Sec. IV-C), per detection of a class with a size prior:

1. crop the depth image by the 2D box (valid depth only, every ``pixel_stride``-th pixel,
   coarser for large boxes: ``max_box_samples``);
2. back-project to the optical frame and move to the map frame (robot pose + extrinsics);
3. drop floor and ceiling points and points over the 2D map's walls, voxel-downsample;
4. statistical outlier removal (mean distance to the k nearest neighbours);
5. Euclidean clustering (connected components of the fixed-radius neighbour graph);
6. keep the cluster that best matches the box (most points, weighted by closeness to
   the box centre; ties to the nearest median depth), plus clusters that lie inside its
   clamped box (parts split at thin links); clusters far larger than the class (a wall,
   a neighbour) or far smaller (a leg, a fragment: ``min_extent_fraction``) are not taken;
7. 3D box: footprint orientation by the minimum-area rectangle (default) or PCA (the
   paper), extents by min/max along the footprint axes, heights from the floor (or the
   lowest point) to the top. Where the view cuts the object (image border, an occluder
   in front) the outline is the view's: those hull edges do not orient the box, and the
   box's sides there are marked open (the object reaches at least that far);
8. clamp the extents by the class's size prior: grown to the minimum away from the camera
   (the hidden side), shrunk to the maximum around the centre.

Unclassified objects (furniture the detector misses): leg-like clusters of the 2D laser
scan (a few cm wide, isolated) are grouped when they are close; depth points above the
lidar plane over such a group (inside the legs' rectangle grown by a radius, in a height
band) give the footprint of an ``"unknown"`` object, so a table whose legs the lidar sees
and whose top it misses becomes an obstacle.

:class:`ObjectMap` fuses the per-frame boxes in the map frame (merging re-detections by
their measured footprints, :func:`fuse_boxes`: partial views add up, noise and the sides
grown by the prior do not; counting misses where the camera sees through an object) and
renders the occupancy layer, the virtual point cloud and the boxes.

Frames: ``map`` (x, y on the floor, z up, z = 0 at the floor), ``base_link`` on the floor
at the robot pose, camera optical frame (see :mod:`explore_seg.core.camera`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Iterable, Protocol, Sequence

import cv2
import numpy as np
import numpy.typing as npt
from scipy import sparse
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from explore_seg.core.camera import CameraIntrinsics, apply_transform, invert_transform
from explore_seg.core.grid import FREE_THRESHOLD, GridMap
from explore_seg.core.swept import SweptPath
from explore_seg.core.fields import param_meta as _doc

#: Class name given to objects found from laser legs without a detection.
UNKNOWN_CLASS = "unknown"

_ORIENTATION_METHODS = ("pca", "min_area_rect")
_POSE_SOURCES = ("odom", "pose")



# ------------------------------------------------------------------------- params


@dataclass(frozen=True)
class ObjectParams:
    """Parameters of the object costmap (core pipeline + the ``object_costmap`` node).

    Raises
    ------
    ValueError
        From ``__post_init__`` on any out-of-range value (message names field and value).
    """

    # --- node: rate, inputs, frames
    rate_hz: float = field(default=2.0, metadata=_doc(
        "Camera frames processed per second, at most (a camera at this rate has every "
        "frame processed, a faster one the newest after each 0.9 / rate_hz); frames "
        "arriving while one is processed are dropped, never queued", "Hz"))
    sync_tolerance_s: float = field(default=0.05, metadata=_doc(
        "Largest stamp difference for pairing colour with depth", "s"))
    pose_tolerance_s: float = field(default=0.2, metadata=_doc(
        "Largest stamp difference between the depth image and the robot pose used for it; "
        "frames without a pose this close are dropped", "s"))
    pose_topic_type: str = field(default="odom", metadata=_doc(
        "Where the robot pose in the map frame comes from: 'odom' (Odometry on "
        "'odom') or 'pose' (PoseWithCovarianceStamped on 'pose')", read_only=True))
    map_frame: str = field(default="map", metadata=_doc(
        "Frame of the published cloud and markers"))
    map_transient_local: bool = field(default=True, metadata=_doc(
        "Subscribe to 'map' transient-local (latched); false for a volatile publisher",
        read_only=True))
    camera_x_m: float = field(default=0.064, metadata=_doc(
        "Camera position in base_link, x (default: sim_bridge's TurtleBot3-like mount)", "m"))
    camera_y_m: float = field(default=0.0, metadata=_doc(
        "Camera position in base_link, y", "m"))
    camera_z_m: float = field(default=0.2, metadata=_doc(
        "Camera position in base_link (above the floor), z", "m"))
    camera_roll_rad: float = field(default=0.0, metadata=_doc(
        "Camera body frame (x forward, z up) roll in base_link", "rad"))
    camera_pitch_rad: float = field(default=0.0, metadata=_doc(
        "Camera body frame pitch in base_link (positive looks down)", "rad"))
    camera_yaw_rad: float = field(default=0.0, metadata=_doc(
        "Camera body frame yaw in base_link", "rad"))
    lidar_x_m: float = field(default=-0.064, metadata=_doc(
        "Lidar position in base_link, x", "m"))
    lidar_y_m: float = field(default=0.0, metadata=_doc("Lidar position in base_link, y", "m"))
    lidar_yaw_rad: float = field(default=0.0, metadata=_doc("Lidar yaw in base_link", "rad"))
    oracle_sim_class_ids: tuple[str, ...] = field(default=(
        "none:0", "wall:1", "chair:2", "table:3", "desk:4", "cabinet:5", "sofa:6", "other:7"),
        metadata=_doc("Oracle detector only: the simulator's semantic class table as "
                      "'name:id' pairs (mirrors sim_bridge.sensors.CLASS_IDS)"))
    # --- detection -> 3D box
    min_score: float = field(default=0.3, metadata=_doc(
        "Detections below this confidence are ignored", "0..1"))
    max_depth_m: float = field(default=4.0, metadata=_doc(
        "Depth readings farther than this are ignored", "m"))
    pixel_stride: int = field(default=2, metadata=_doc(
        "Use every n-th pixel (rows and columns) inside a detection box", "px"))
    max_box_samples: int = field(default=8000, metadata=_doc(
        "Larger boxes are sampled with a larger stride so that at most about this many "
        "pixels are used per detection"))
    voxel_size_m: float = field(default=0.03, metadata=_doc(
        "Voxel edge for downsampling the cropped cloud (0 disables)", "m"))
    floor_height_m: float = field(default=0.05, metadata=_doc(
        "Points lower than this above the floor (map z) are floor and dropped", "m"))
    ceiling_height_m: float = field(default=2.2, metadata=_doc(
        "Points higher than this above the floor are dropped", "m"))
    sor_k: int = field(default=8, metadata=_doc(
        "Statistical outlier removal: number of neighbours"))
    sor_std: float = field(default=2.5, metadata=_doc(
        "Statistical outlier removal: keep points whose mean neighbour distance is below "
        "mean + sor_std * std"))
    cluster_tolerance_m: float = field(default=0.08, metadata=_doc(
        "Euclidean clustering: points closer than this join one cluster", "m"))
    min_grazing_angle_rad: float = field(default=0.07, metadata=_doc(
        "Euclidean clustering: points of neighbouring sampled pixels are also linked when "
        "as far apart as a surface seen at this angle gives (a table top from a low "
        "camera is sampled in strips); larger = fewer links", "rad"))
    min_cluster_points: int = field(default=15, metadata=_doc(
        "Euclidean clustering: smaller clusters are discarded"))
    near_vote_share: float = field(default=0.2, metadata=_doc(
        "Clusters with at least this share of the best cluster's centre-weighted votes "
        "compete on depth: the nearest is the object (objects occlude the wall or desk "
        "behind them); 1 = most votes win", "0..1"))
    merge_parts_fraction: float = field(default=0.5, metadata=_doc(
        "After choosing a cluster and clamping its box, other clusters with at least this "
        "fraction of their points inside that footprint (grown by cluster_tolerance_m) join "
        "it (a chair's backrest, seat and base split at the thin stem; a table's far legs "
        "below a top seen at a grazing angle); 1 disables it", "0..1"))
    orientation_method: str = field(default="min_area_rect", metadata=_doc(
        "Footprint orientation: 'min_area_rect' (minimum-area enclosing rectangle) or "
        "'pca' (the paper; tilts by 5-10 deg on partly seen, unevenly sampled tops)"))
    boxes_on_floor: bool = field(default=True, metadata=_doc(
        "Extend every box down to the floor (furniture stands on it)"))
    priors_path: str = field(default="", metadata=_doc(
        "YAML of per-class size priors; empty = the package's config/object_priors.yaml. "
        "Classes without a prior are ignored", read_only=True))
    # --- fusion
    merge_distance_m: float = field(default=0.5, metadata=_doc(
        "Re-detections of a class whose centres are closer than this merge", "m"))
    merge_iou: float = field(default=0.2, metadata=_doc(
        "Re-detections whose footprints overlap more than this (IoU) merge", "0..1"))
    drop_wall_points: bool = field(default=True, metadata=_doc(
        "Drop the depth points over walls of the 2D map (occupied components at least "
        "wall_min_length_m long, grown by wall_margin_m) before clustering: a desk against "
        "a wall then forms its own cluster instead of one merged with the wall, and a door "
        "jamb is never taken for the detected object"))
    wall_min_length_m: float = field(default=0.5, metadata=_doc(
        "Occupied components of the 2D map whose bounding box is shorter than this on both "
        "sides are furniture legs or bases, not walls: their depth points are kept (the "
        "legs give a table's extent)", "m"))
    wall_margin_m: float = field(default=0.05, metadata=_doc(
        "Growth of the map's wall cells for drop_wall_points", "m"))
    robot_radius_m: float = field(default=0.22, metadata=_doc(
        "Robot radius: object boxes reaching into the robot's disk are wrong", "m"))
    robot_clear_fraction: float = field(default=0.5, metadata=_doc(
        "Drop boxes that reach this fraction of robot_radius_m into the robot's disk "
        "(1 = only boxes over the robot's centre; a box that merely touches the robot, "
        "as an object does the robot bumps into, is kept; 0 = never)", "0..1"))
    swept_clear_radius_m: float = field(default=0.22, metadata=_doc(
        "The layer and the virtual cloud are cleared within this distance of the path the "
        "robot has driven (its body proved the floor free there), so boxes grown from "
        "partial views never close the way the robot came in (0 = off)", "m"))
    prior_reject_factor: float = field(default=1.2, metadata=_doc(
        "Drop a detection whose cluster footprint or height exceeds this factor times its "
        "class prior's maximum (0 = never drop, only clamp)"))
    min_extent_fraction: float = field(default=0.5, metadata=_doc(
        "A cluster whose footprint's longer side is below this fraction of its class "
        "prior's min_xy_m is a fragment (a leg, a corner at the image border) and is not "
        "taken for the object: it gives neither the orientation nor the extent, and growing "
        "it to the prior places the box at random (0 = never)", "0..1"))
    merge_growth_max: float = field(default=1.25, metadata=_doc(
        "Largest growth factor of a fused box's size per merged observation (>= 1)"))
    merge_extend_margin_m: float = field(default=0.05, metadata=_doc(
        "Fusion of the measured footprints (see fuse_boxes): a re-detection measuring the "
        "same extent along an axis (within this, both sides seen) is averaged with the "
        "box, noise does not inflate it; otherwise a side farther out than the box's by "
        "more than this extends it (another part seen), sides within it are averaged, and "
        "sides where the view was cut only push outwards", "m"))
    max_objects: int = field(default=200, metadata=_doc(
        "Most objects kept; the least confirmed are dropped first"))
    clear_after_misses: int = field(default=3, metadata=_doc(
        "An object is removed after this many frames in which the camera sees past where "
        "its points were measured (its surface; not the empty space under a table top)"))
    miss_depth_margin_m: float = field(default=0.15, metadata=_doc(
        "Depth must exceed an object's surface point by this to count as seeing past it",
        "m"))
    miss_free_fraction: float = field(default=0.6, metadata=_doc(
        "Fraction of the object's visible surface points that must be seen past for a miss",
        "0..1"))
    miss_min_samples: int = field(default=6, metadata=_doc(
        "Fewest visible surface points of an object needed to judge a miss"))
    miss_sample_spacing_m: float = field(default=0.1, metadata=_doc(
        "Voxel size of an object's measured surface points (kept to judge misses; a box "
        "without them is sampled on its faces at this spacing)", "m"))
    # --- outputs
    object_value: int = field(default=100, metadata=_doc(
        "Layer value inside object footprints", "0..100"))
    background_value: int = field(default=0, metadata=_doc(
        "Layer value outside objects (0 = no object known, -1 = unknown)", "-1..100"))
    cloud_spacing_m: float = field(default=0.05, metadata=_doc(
        "Spacing of the virtual point cloud filling each box", "m"))
    max_cloud_points: int = field(default=200000, metadata=_doc(
        "Most virtual cloud points; the spacing grows to stay below"))
    # --- unclassified objects (laser legs)
    unknown_enabled: bool = field(default=True, metadata=_doc(
        "Find unclassified objects from laser leg clusters and depth above them"))
    leg_cluster_gap_m: float = field(default=0.05, metadata=_doc(
        "Scan points closer than this form one cluster", "m"))
    leg_min_width_m: float = field(default=0.0, metadata=_doc(
        "Narrowest leg cluster (extent of its points; one-point clusters have 0)", "m"))
    leg_max_width_m: float = field(default=0.15, metadata=_doc(
        "Widest leg cluster", "m"))
    leg_min_points: int = field(default=1, metadata=_doc("Fewest scan points in a leg"))
    leg_isolation_m: float = field(default=0.15, metadata=_doc(
        "A leg has no other scan point within this distance of its centre", "m"))
    leg_group_distance_m: float = field(default=1.6, metadata=_doc(
        "Legs closer than this belong to one piece of furniture", "m"))
    min_legs: int = field(default=2, metadata=_doc("Fewest legs of an unclassified object"))
    leg_max_range_m: float = field(default=4.0, metadata=_doc(
        "Only scan points closer than this to the robot are used", "m"))
    unknown_radius_m: float = field(default=0.3, metadata=_doc(
        "Depth points within this of the legs' rectangle belong to the object", "m"))
    unknown_min_height_m: float = field(default=0.2, metadata=_doc(
        "Lowest depth point (above the lidar plane) of an unclassified object", "m"))
    unknown_max_height_m: float = field(default=1.2, metadata=_doc(
        "Highest depth point of an unclassified object", "m"))
    unknown_min_points: int = field(default=20, metadata=_doc(
        "Fewest depth points over a leg group to make an object"))
    unknown_top_band_m: float = field(default=0.1, metadata=_doc(
        "Height band of a horizontal top: the densest band of this height must hold "
        "unknown_top_fraction of an unclassified object's depth points", "m"))
    unknown_top_fraction: float = field(default=0.5, metadata=_doc(
        "Share of the depth points in the densest unknown_top_band_m band; walls and door "
        "jambs (vertical surfaces over leg-like wall ends) spread over all heights and fail"))
    unknown_min_top_cover: float = field(default=0.5, metadata=_doc(
        "Share of the legs' rectangle that depth points of the top must cover (cells of "
        "unknown_cover_cell_m); legs of two objects grouped across open floor fail", "0..1"))
    unknown_cover_cell_m: float = field(default=0.1, metadata=_doc(
        "Cell size for unknown_min_top_cover", "m"))
    post_max_width_m: float = field(default=0.7, metadata=_doc(
        "Isolated laser clusters wider than leg_max_width_m and up to this wide are posts "
        "(a bin, a pedestal, a plant pot): depth points above one that reach more than "
        "post_overhang_m beyond its laser points (a rim, a top) make an unclassified "
        "object, since the lidar sees only the post (0 or <= leg_max_width_m = off)", "m"))
    post_overhang_m: float = field(default=0.04, metadata=_doc(
        "Depth points farther than this from every laser point of a post overhang it", "m"))
    post_link_m: float = field(default=0.15, metadata=_doc(
        "Depth points (in plan view) closer than this to a post or to its overhang belong "
        "to it; others near it (a table top beside a bin) do not", "m"))
    post_band_m: float = field(default=0.3, metadata=_doc(
        "unknown_top_fraction of a post's overhanging depth points must lie in a height "
        "band this tall (a rim or a top; a face over all heights is a wall)", "m"))
    unknown_pixel_stride: int = field(default=4, metadata=_doc(
        "Use every n-th depth pixel (rows and columns) for unclassified objects", "px"))

    def __post_init__(self) -> None:
        positive = ("rate_hz", "max_depth_m", "ceiling_height_m", "cluster_tolerance_m",
                    "merge_distance_m", "miss_sample_spacing_m", "cloud_spacing_m",
                    "leg_cluster_gap_m", "leg_max_width_m", "leg_isolation_m",
                    "leg_group_distance_m", "leg_max_range_m", "unknown_max_height_m",
                    "unknown_cover_cell_m", "post_link_m",
                    "sor_std")
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        non_negative = ("sync_tolerance_s", "pose_tolerance_s", "voxel_size_m",
                        "miss_depth_margin_m", "leg_min_width_m", "unknown_radius_m",
                        "post_max_width_m", "post_overhang_m", "post_band_m")
        for name in non_negative:
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        finite = ("camera_x_m", "camera_y_m", "camera_z_m", "camera_roll_rad",
                  "camera_pitch_rad", "camera_yaw_rad", "lidar_x_m", "lidar_y_m",
                  "lidar_yaw_rad", "floor_height_m", "unknown_min_height_m")
        for name in finite:
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v}")
        fractions = ("min_score", "merge_iou", "miss_free_fraction", "min_extent_fraction",
                     "merge_parts_fraction", "unknown_top_fraction", "near_vote_share", "robot_clear_fraction",
                     "unknown_min_top_cover")
        for name in fractions:
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        at_least_one = ("pixel_stride", "max_box_samples", "sor_k", "min_cluster_points", "max_objects",
                        "clear_after_misses", "miss_min_samples", "max_cloud_points",
                        "leg_min_points", "min_legs", "unknown_min_points",
                        "unknown_pixel_stride")
        for name in at_least_one:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
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
        if self.floor_height_m >= self.ceiling_height_m:
            raise ValueError(
                f"floor_height_m ({self.floor_height_m}) must be below ceiling_height_m "
                f"({self.ceiling_height_m})")
        if self.unknown_min_height_m >= self.unknown_max_height_m:
            raise ValueError(
                f"unknown_min_height_m ({self.unknown_min_height_m}) must be below "
                f"unknown_max_height_m ({self.unknown_max_height_m})")
        if self.leg_min_width_m > self.leg_max_width_m:
            raise ValueError(
                f"leg_min_width_m ({self.leg_min_width_m}) must not exceed leg_max_width_m "
                f"({self.leg_max_width_m})")
        if self.orientation_method not in _ORIENTATION_METHODS:
            raise ValueError(f"orientation_method must be one of {_ORIENTATION_METHODS}, "
                             f"got {self.orientation_method!r}")
        if self.pose_topic_type not in _POSE_SOURCES:
            raise ValueError(
                f"pose_topic_type must be one of {_POSE_SOURCES}, got {self.pose_topic_type!r}")
        if not 0 <= self.object_value <= 100:
            raise ValueError(f"object_value must be in 0..100, got {self.object_value}")
        if not -1 <= self.background_value <= 100:
            raise ValueError(f"background_value must be in -1..100, got {self.background_value}")
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


# -------------------------------------------------------------------------- priors


@dataclass(frozen=True)
class SizePrior:
    """Plausible size of a class: footprint sides in [min_xy_m, max_xy_m], height in
    [min_z_m, max_z_m] (metres).

    Raises
    ------
    ValueError
        On non-finite, negative or inverted ranges.
    """

    min_xy_m: float
    max_xy_m: float
    min_z_m: float
    max_z_m: float

    def __post_init__(self) -> None:
        vals = (self.min_xy_m, self.max_xy_m, self.min_z_m, self.max_z_m)
        if not all(math.isfinite(v) and v >= 0 for v in vals):
            raise ValueError(f"size prior values must be finite and >= 0, got {vals}")
        if self.min_xy_m > self.max_xy_m or self.min_z_m > self.max_z_m:
            raise ValueError(f"size prior ranges must satisfy min <= max, got {vals}")
        if self.max_xy_m <= 0 or self.max_z_m <= 0:
            raise ValueError(f"size prior maxima must be > 0, got {vals}")


def default_priors_path() -> Path:
    """The source tree's ``config/object_priors.yaml`` (an installed package's nodes pass
    the share folder's file instead: :func:`explore_seg.node_util.config_file`).

    Raises
    ------
    FileNotFoundError
        When the file is not there.
    """
    here = Path(__file__).resolve().parents[2] / "config" / "object_priors.yaml"
    if here.is_file():
        return here
    raise FileNotFoundError(f"object priors not found at {here}: pass the file's path")


def load_priors(path: str | Path | None = None) -> dict[str, SizePrior]:
    """Read per-class size priors.

    Parameters
    ----------
    path : str or Path, optional
        YAML with ``priors: {class_name: {min_xy_m, max_xy_m, min_z_m, max_z_m}}``;
        ``None`` or ``""`` = :func:`default_priors_path`.

    Returns
    -------
    dict of str to SizePrior
        Keyed by class name (COCO names, e.g. ``"chair"``, ``"dining table"``).

    Raises
    ------
    ValueError
        When the file does not hold a ``priors`` mapping of complete, valid entries.
    FileNotFoundError
        When the file does not exist.
    """
    import yaml

    p = default_priors_path() if path in (None, "") else Path(path)
    data = yaml.safe_load(Path(p).read_text())
    if not isinstance(data, dict) or not isinstance(data.get("priors"), dict):
        raise ValueError(
            f"{p}: expected a mapping with a 'priors' mapping, got {type(data).__name__}")
    out: dict[str, SizePrior] = {}
    keys = ("min_xy_m", "max_xy_m", "min_z_m", "max_z_m")
    for name, entry in data["priors"].items():
        if not isinstance(entry, dict) or set(keys) - set(entry):
            raise ValueError(f"{p}: prior {name!r} must have keys {keys}, got {entry!r}")
        try:
            out[str(name)] = SizePrior(*(float(entry[k]) for k in keys))
        except (TypeError, ValueError) as err:
            raise ValueError(f"{p}: prior {name!r}: {err}") from err
    if not out:
        raise ValueError(f"{p}: 'priors' is empty")
    return out


# ------------------------------------------------------------------------- objects


@dataclass(frozen=True)
class Object3D:
    """An oriented 3D box in the map frame.

    Parameters
    ----------
    cls : str
        Class name (COCO name or :data:`UNKNOWN_CLASS`).
    score : float
        Detection confidence (1.0 for unclassified objects).
    center_xyz : tuple of float
        Box centre (metres, map frame).
    size_xyz : tuple of float
        Extent along the box's own x (yaw direction), y and z axes (metres, >= 0).
    yaw : float
        Rotation of the box about z (radians), normalised to [-pi/2, pi/2).
    n_points : int
        Points the box was fitted to.
    measured_xy : tuple of 4 float, optional
        The footprint the points themselves span, before the size prior grew or shrank it:
        centre (x, y) and extents along the box's x and y axes (same ``yaw``). None when
        unknown (the box is then taken as measured). :class:`ObjectMap` fuses these, so
        that parts of an object seen from different sides add up while the sides grown by
        the prior (hidden, not seen) do not.
    open_sides : tuple of 4 bool
        Sides of ``measured_xy`` (-x, +x, -y, +y in the box frame) where the view, not the
        object, ended (image border, an occluder in front): the object reaches at least
        that far. Closed sides are the object's own.
    surface : ndarray of float32, shape (M, 3), optional
        Where the object's points were measured (map frame, one per voxel of
        ``miss_sample_spacing_m``, at most :data:`MAX_SURFACE_POINTS`): what the camera
        must see past before :class:`ObjectMap` counts a miss. A table or chair is mostly
        empty space under its top, which the camera sees through from any side; only its
        own surfaces tell it is gone. None: the box's faces are used instead.
    """

    cls: str
    score: float
    center_xyz: tuple[float, float, float]
    size_xyz: tuple[float, float, float]
    yaw: float
    n_points: int
    measured_xy: tuple[float, float, float, float] | None = None
    open_sides: tuple[bool, bool, bool, bool] = (False, False, False, False)
    surface: npt.NDArray[np.float32] | None = field(default=None, compare=False, repr=False)

    def footprint(self) -> npt.NDArray[np.float64]:
        """The 4 corners (x, y) of the footprint, counter-clockwise, shape (4, 2)."""
        return rect_corners(self.center_xyz[:2], self.size_xyz[:2], self.yaw)


class BoxDetection(Protocol):
    """What the pipeline needs from a 2D detection (``core.detector.Detection`` fits)."""

    cls_name: str
    score: float
    box_xyxy: Sequence[float]


@dataclass(frozen=True)
class DepthFrame:
    """A depth image with its camera model and pose in the map frame.

    Parameters
    ----------
    depth_m : ndarray of float32, shape (H, W)
        Depth along the optical axis (metres), NaN / <= 0 invalid.
    intrinsics : CameraIntrinsics
        Matching ``depth_m``'s size.
    map_from_optical : ndarray of float64, shape (4, 4)
        Transform taking optical-frame points to the map frame.

    Raises
    ------
    ValueError
        On a size mismatch or a malformed transform.
    """

    depth_m: npt.NDArray[np.float32]
    intrinsics: CameraIntrinsics
    map_from_optical: npt.NDArray[np.float64]

    def __post_init__(self) -> None:
        depth = np.asarray(self.depth_m)
        if depth.ndim != 2:
            raise ValueError(f"depth must be 2D (H, W), got shape {depth.shape}")
        if depth.shape != self.intrinsics.shape:
            raise ValueError(f"depth shape {depth.shape} does not match camera info "
                             f"(height, width)={self.intrinsics.shape}")
        t = np.asarray(self.map_from_optical, dtype=np.float64)
        if t.shape != (4, 4) or not np.all(np.isfinite(t)):
            raise ValueError(f"map_from_optical must be a finite 4x4 matrix, got shape {t.shape}")
        object.__setattr__(self, "depth_m", depth.astype(np.float32, copy=False))
        object.__setattr__(self, "map_from_optical", t)

    @property
    def camera_xyz(self) -> npt.NDArray[np.float64]:
        """Camera position in the map frame, shape (3,)."""
        return self.map_from_optical[:3, 3].copy()


# ----------------------------------------------------------------- geometry steps


def rect_corners(center_xy: Sequence[float], size_xy: Sequence[float], yaw: float
                 ) -> npt.NDArray[np.float64]:
    """Corners of a rotated rectangle, counter-clockwise, shape (4, 2)."""
    c, s = math.cos(yaw), math.sin(yaw)
    hx, hy = 0.5 * float(size_xy[0]), 0.5 * float(size_xy[1])
    local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.asarray(center_xy, dtype=np.float64)[:2]


def box_mask(box_xyxy: Sequence[float], shape: tuple[int, int], stride: int = 1
             ) -> npt.NDArray[np.bool_]:
    """Pixel mask of a 2D box (inclusive corners, clipped to the image).

    Parameters
    ----------
    box_xyxy : sequence of 4 float
        ``(x0, y0, x1, y1)`` pixel corners, x = column, y = row.
    shape : tuple of int
        Image ``(H, W)``.
    stride : int
        Only every ``stride``-th row and column (counted from the image origin) is set.

    Returns
    -------
    ndarray of bool, shape (H, W)

    Raises
    ------
    ValueError
        If the box is not 4 finite numbers, is inverted or lies entirely outside the image.
    """
    b = np.asarray(box_xyxy, dtype=np.float64).reshape(-1)
    if b.shape != (4,) or not np.all(np.isfinite(b)):
        raise ValueError(f"box must be 4 finite numbers (x0, y0, x1, y1), got {box_xyxy!r}")
    x0, y0, x1, y1 = b
    if x1 < x0 or y1 < y0:
        raise ValueError(f"box must have x0 <= x1 and y0 <= y1, got {tuple(b)}")
    h, w = shape
    c0, r0 = max(int(math.floor(x0)), 0), max(int(math.floor(y0)), 0)
    c1, r1 = min(int(math.ceil(x1)), w - 1), min(int(math.ceil(y1)), h - 1)
    if c0 > c1 or r0 > r1:
        raise ValueError(f"box {tuple(b)} lies outside the {w}x{h} image")
    mask = np.zeros((h, w), dtype=bool)
    r0s = r0 + (-r0) % stride
    c0s = c0 + (-c0) % stride
    mask[r0s:r1 + 1:stride, c0s:c1 + 1:stride] = True
    return mask


def box_stride(box_xyxy: Sequence[float], min_stride: int, max_samples: int) -> int:
    """Pixel stride for a box: at least ``min_stride``, larger for boxes that would
    otherwise give more than ``max_samples`` pixels."""
    b = np.asarray(box_xyxy, dtype=np.float64).reshape(-1)
    area = max(float(b[2] - b[0] + 1), 1.0) * max(float(b[3] - b[1] + 1), 1.0) \
        if b.shape == (4,) and np.all(np.isfinite(b)) else 1.0
    return max(int(min_stride), int(math.ceil(math.sqrt(area / max(max_samples, 1)))))


def voxel_downsample(points: npt.NDArray[np.floating], voxel_m: float,
                     return_inverse: bool = False
                     ) -> npt.NDArray[np.int64] | tuple[npt.NDArray[np.int64],
                                                        npt.NDArray[np.int64]]:
    """Indices of one point per occupied voxel (the first in input order).

    Parameters
    ----------
    points : ndarray, shape (N, 3)
    voxel_m : float
        Voxel edge; ``<= 0`` keeps every point.
    return_inverse : bool
        Also return, for every input point, the position of its voxel's representative
        in the returned index array.

    Returns
    -------
    keep : ndarray of int64, shape (M,)
        Sorted indices into ``points``.
    inverse : ndarray of int64, shape (N,)
        Only with ``return_inverse``: ``points[keep[inverse[i]]]`` shares point i's voxel.
    """
    n = len(points)
    if voxel_m <= 0 or n == 0:
        keep = np.arange(n, dtype=np.int64)
        return (keep, keep.copy()) if return_inverse else keep
    keys = np.floor(np.asarray(points, dtype=np.float64) / voxel_m).astype(np.int64)
    keys -= keys.min(axis=0)
    dims = keys.max(axis=0) + 1
    if np.prod(dims.astype(np.float64)) < 2.0**62:
        flat = np.ravel_multi_index(keys.T, dims)
    else:
        flat = np.unique(keys, axis=0, return_inverse=True)[1].reshape(-1)
    _, first, inverse = np.unique(flat, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    keep = first[order].astype(np.int64)
    if not return_inverse:
        return keep
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return keep, rank[inverse.reshape(-1)].astype(np.int64)


def pixel_grid_edges(pixels_uv: npt.NDArray[np.floating], points: npt.NDArray[np.floating],
                     depth_m: npt.NDArray[np.floating], stride: int, link_m: float,
                     link_ratio: float) -> npt.NDArray[np.int64]:
    """Links between points of neighbouring sampled pixels that are close in 3D.

    Surfaces seen at a grazing angle (a table top from a low camera) are sampled in
    strips farther apart than any fixed clustering distance; neighbouring pixels on them
    are still linked when their 3D distance is at most ``max(link_m, link_ratio * depth)``.

    Parameters
    ----------
    pixels_uv : ndarray, shape (N, 2)
        Pixel (column, row) of each point, on a grid of step ``stride``.
    points : ndarray, shape (N, 3)
    depth_m : ndarray, shape (N,)
    stride : int
    link_m, link_ratio : float

    Returns
    -------
    ndarray of int64, shape (E, 2)
        Index pairs into the inputs (right and down neighbours).
    """
    n = len(points)
    if n == 0:
        return np.zeros((0, 2), dtype=np.int64)
    gc = (np.asarray(pixels_uv[:, 0]) // stride).astype(np.int64)
    gr = (np.asarray(pixels_uv[:, 1]) // stride).astype(np.int64)
    gc -= gc.min()
    gr -= gr.min()
    index = np.full((gr.max() + 2, gc.max() + 2), -1, dtype=np.int64)
    index[gr, gc] = np.arange(n)
    pairs = []
    for dr, dc in ((0, 1), (1, 0)):
        j = index[gr + dr, gc + dc]
        ok = j >= 0
        i, j = np.flatnonzero(ok), j[ok]
        dist = np.linalg.norm(points[i] - points[j], axis=1)
        near = dist <= np.maximum(link_m, link_ratio * np.minimum(depth_m[i], depth_m[j]))
        pairs.append(np.stack([i[near], j[near]], axis=1))
    return np.vstack(pairs).astype(np.int64)


def statistical_outlier_mask(points: npt.NDArray[np.floating], k: int, std_ratio: float
                             ) -> npt.NDArray[np.bool_]:
    """Statistical outlier removal (as PCL / Open3D): keep points whose mean distance to
    their ``k`` nearest neighbours is at most ``mean + std_ratio * std`` over the cloud.

    Parameters
    ----------
    points : ndarray, shape (N, 3)
    k : int
        Neighbours (>= 1).
    std_ratio : float
        Threshold in standard deviations.

    Returns
    -------
    ndarray of bool, shape (N,)
        True for inliers. Clouds of at most ``k`` points are kept whole.

    Raises
    ------
    ValueError
        If ``k < 1``.
    """
    if k < 1:
        raise ValueError(f"k must be >= 1, got {k}")
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n <= k:
        return np.ones(n, dtype=bool)
    dist, _ = cKDTree(pts).query(pts, k=k + 1)
    mean_d = dist[:, 1:].mean(axis=1)
    return mean_d <= mean_d.mean() + std_ratio * mean_d.std()


def euclidean_clusters(points: npt.NDArray[np.floating], tolerance_m: float, min_points: int,
                       extra_edges: npt.NDArray[np.integer] | None = None
                       ) -> npt.NDArray[np.int64]:
    """Euclidean clustering: connected components of the graph linking points closer than
    ``tolerance_m``.

    Parameters
    ----------
    points : ndarray, shape (N, D)
    tolerance_m : float
        Link distance (> 0).
    min_points : int
        Clusters with fewer points get label -1.
    extra_edges : ndarray of int, shape (E, 2), optional
        Further links (index pairs), e.g. from :func:`pixel_grid_edges`.

    Returns
    -------
    ndarray of int64, shape (N,)
        Labels 0, 1, ... ordered by decreasing cluster size; -1 for small clusters.

    Raises
    ------
    ValueError
        If ``tolerance_m <= 0``.
    """
    if not tolerance_m > 0:
        raise ValueError(f"tolerance_m must be > 0, got {tolerance_m}")
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    pairs = cKDTree(pts).query_pairs(tolerance_m, output_type="ndarray").reshape(-1, 2)
    if extra_edges is not None and len(extra_edges):
        pairs = np.vstack([pairs, np.asarray(extra_edges, dtype=pairs.dtype).reshape(-1, 2)])
    graph = sparse.coo_matrix((np.ones(len(pairs), dtype=np.int8), (pairs[:, 0], pairs[:, 1])),
                              shape=(n, n))
    _, comp = connected_components(graph, directed=False)
    counts = np.bincount(comp)
    order = np.argsort(-counts, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    labels = rank[comp].astype(np.int64)
    labels[counts[comp] < min_points] = -1
    return labels


def rank_clusters(labels: npt.NDArray[np.integer], pixels_uv: npt.NDArray[np.floating],
                  depth_m: npt.NDArray[np.floating], box_xyxy: Sequence[float],
                  near_vote_share: float = 1.0) -> list[int]:
    """Clusters in the order in which they are taken to be the detected object.

    Every point votes for its cluster with a weight that falls linearly from 1 at the
    box centre to 0 at the box border in each image direction (a tent); detectors centre
    boxes on the object, while background shows at the borders and through gaps. Objects
    occlude what is behind them, and an object split into parts (a chair's back, seat and
    base) or seen through (legs) can get fewer votes than the wall behind it: clusters
    with at least ``near_vote_share`` of the top votes come first, nearest median depth
    first; the others follow by decreasing votes (ties to the nearest median depth).

    Parameters
    ----------
    labels : ndarray of int, shape (N,)
        Cluster labels (-1 = none).
    pixels_uv : ndarray, shape (N, 2)
        Pixel (column, row) of each point.
    depth_m : ndarray, shape (N,)
        Optical-axis depth of each point.
    box_xyxy : sequence of 4 float
    near_vote_share : float
        In [0, 1]; 1 ranks by votes alone.

    Returns
    -------
    list of int
        Every label >= 0 present in ``labels``, best first.
    """
    valid = labels >= 0
    if not np.any(valid):
        return []
    x0, y0, x1, y1 = (float(v) for v in box_xyxy)
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    hw, hh = max(0.5 * (x1 - x0), 0.5), max(0.5 * (y1 - y0), 0.5)
    weight = (np.clip(1.0 - np.abs(pixels_uv[:, 0] - cx) / hw, 0.0, 1.0)
              * np.clip(1.0 - np.abs(pixels_uv[:, 1] - cy) / hh, 0.0, 1.0))
    lab = labels[valid]
    votes = np.bincount(lab, weights=weight[valid])
    present = np.flatnonzero(np.bincount(lab))
    order = np.argsort(lab, kind="stable")
    bounds = np.searchsorted(lab[order], present)
    dv = np.asarray(depth_m)[valid][order]
    ends = np.append(bounds[1:], len(dv))
    med = {int(k): float(np.median(dv[a:b])) for k, a, b in zip(present, bounds, ends)}
    top = float(votes[present].max())
    share = min(max(float(near_vote_share), 0.0), 1.0)

    def key(k: int) -> tuple:
        v = float(votes[k])
        strong = top > 0 and v >= share * top - 1e-12
        return (0, med[k], -v) if strong else (1, -round(v, 9), med[k])

    return sorted((int(k) for k in present), key=key)


def select_cluster(labels: npt.NDArray[np.integer], pixels_uv: npt.NDArray[np.floating],
                   depth_m: npt.NDArray[np.floating], box_xyxy: Sequence[float],
                   near_vote_share: float = 1.0) -> int:
    """Pick the cluster that is the detected object (the first of :func:`rank_clusters`).

    Returns
    -------
    int
        Chosen label, -1 if there is no cluster.
    """
    ranked = rank_clusters(labels, pixels_uv, depth_m, box_xyxy, near_vote_share)
    return ranked[0] if ranked else -1


def footprint_orientation(points_xy: npt.NDArray[np.floating], method: str = "min_area_rect",
                          cut: npt.NDArray[np.bool_] | None = None
                          ) -> tuple[tuple[float, float], tuple[float, float], float]:
    """Oriented rectangle around footprint points.

    Parameters
    ----------
    points_xy : ndarray, shape (N, 2), N >= 1
    method : {"min_area_rect", "pca"}
        ``"min_area_rect"``: the minimum-area enclosing rectangle (exact for rectangular
        furniture); ``"pca"``: axes from the principal components of the points (the
        paper; biased when the footprint is sampled unevenly or seen in part).
    cut : ndarray of bool, shape (N,), optional
        ``"min_area_rect"`` only: points where the view cuts the object (image border, an
        occluder in front; :func:`view_cut`). A convex-hull edge between two such points
        is the trace of the view, not a side of the object (a desk top cut by the side of
        the image ends along the ray of that side, and the smallest rectangle turns with
        it); the orientation then comes from the other hull edges, the object's own
        outline (see ``_min_area_yaw``).

    Returns
    -------
    center_xy : tuple of float
        Centre of the rectangle (mid-range along each axis, not the point mean).
    size_xy : tuple of float
        Extents along the rectangle's x axis (direction ``yaw``, the long side) and y axis;
        ``size_xy[0] >= size_xy[1]``.
    yaw : float
        In [-pi/2, pi/2).

    Raises
    ------
    ValueError
        On an empty or non-(N, 2) input or an unknown method.

    Examples
    --------
    >>> pts = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    >>> c, s, yaw = footprint_orientation(pts)
    >>> [round(v, 6) for v in (*c, *s, yaw)]
    [1.0, 0.5, 2.0, 1.0, 0.0]
    """
    pts = np.asarray(points_xy, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0:
        raise ValueError(f"points_xy must have shape (N>=1, 2), got {pts.shape}")
    if method not in _ORIENTATION_METHODS:
        raise ValueError(f"method must be one of {_ORIENTATION_METHODS}, got {method!r}")
    if method == "min_area_rect" and len(pts) >= 3:
        yaw = _min_area_yaw(pts, cut)
    elif len(pts) >= 2:
        mean = pts.mean(axis=0)
        cov = np.cov((pts - mean).T)
        evals, evecs = np.linalg.eigh(cov)
        major = evecs[:, int(np.argmax(evals))]
        yaw = math.atan2(major[1], major[0])
    else:
        yaw = 0.0
    yaw = _wrap_half_pi(yaw)
    c, s = math.cos(yaw), math.sin(yaw)
    u = pts[:, 0] * c + pts[:, 1] * s
    v = -pts[:, 0] * s + pts[:, 1] * c
    um, vm = 0.5 * (u.min() + u.max()), 0.5 * (v.min() + v.max())
    center = (um * c - vm * s, um * s + vm * c)
    size_u, size_v = float(np.ptp(u)), float(np.ptp(v))
    if size_u < size_v:     # canonical: x along the long side
        size_u, size_v, yaw = size_v, size_u, _wrap_half_pi(yaw + 0.5 * math.pi)
    return (float(center[0]), float(center[1])), (size_u, size_v), yaw


def _min_area_yaw(pts: npt.NDArray[np.float64], cut: npt.NDArray[np.bool_] | None) -> float:
    """Direction of a side of the rectangle around ``pts`` (N >= 3), see
    :func:`footprint_orientation`.

    Without cut points: the minimum-area rectangle. With them, the footprint's outline is
    partly the view's (an image border's or occluder's trace, along a ray or across the
    view) and the smallest rectangle follows that outline; the object's own outline is the
    convex-hull edges not between two cut points, and on a rectangular object these run
    along two perpendicular directions: the direction (modulo 90 degrees, 2-degree bins,
    +-1 bin) holding the most length of them wins, refined by their length-weighted mean.
    Less than 0.2 m of own outline: the minimum-area rectangle.
    """
    if cut is None or not np.any(cut):
        return math.radians(cv2.minAreaRect(pts.astype(np.float32))[2])
    hull = cv2.convexHull(pts.astype(np.float32), returnPoints=False).reshape(-1)
    cut = np.asarray(cut, dtype=bool)
    nxt = np.roll(hull, -1)
    own = ~(cut[hull] & cut[nxt])
    edge = pts[nxt[own]] - pts[hull[own]]
    length = np.hypot(edge[:, 0], edge[:, 1])
    if len(hull) < 3 or length.sum() < 0.2:
        return math.radians(cv2.minAreaRect(pts.astype(np.float32))[2])
    ang = np.mod(np.arctan2(edge[:, 1], edge[:, 0]), 0.5 * math.pi)
    n_bins = 45
    hist = np.bincount(np.minimum((ang / (0.5 * math.pi) * n_bins).astype(np.int64), n_bins - 1),
                       weights=length, minlength=n_bins)
    smooth = hist + np.roll(hist, 1) + np.roll(hist, -1)
    peak = (int(np.argmax(smooth)) + 0.5) * 0.5 * math.pi / n_bins
    diff = np.mod(ang - peak + 0.25 * math.pi, 0.5 * math.pi) - 0.25 * math.pi
    near = np.abs(diff) <= 1.5 * 0.5 * math.pi / n_bins
    return float(peak + np.sum(diff[near] * length[near]) / np.sum(length[near]))


def _wrap_half_pi(yaw: float) -> float:
    """Wrap an axis direction (defined modulo pi) to [-pi/2, pi/2)."""
    return (yaw + 0.5 * math.pi) % math.pi - 0.5 * math.pi


def clamp_to_prior(center_xyz: Sequence[float], size_xyz: Sequence[float], yaw: float,
                   prior: SizePrior, camera_xy: Sequence[float] | None = None,
                   floor_z_m: float | None = 0.0
                   ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Clamp a box's extents to a size prior.

    Footprint sides shorter than ``prior.min_xy_m`` grow to it: away from the camera when
    ``camera_xy`` is given (the near face was measured, the far side was hidden), around
    the centre otherwise. Sides longer than ``prior.max_xy_m`` shrink around the centre.
    A height below ``prior.min_z_m`` grows upwards from the bottom when ``floor_z_m`` is
    given (the box stands on the floor), around the centre otherwise; above
    ``prior.max_z_m`` it shrinks around the centre (or keeps the bottom on the floor).

    Parameters
    ----------
    center_xyz, size_xyz : sequence of 3 float
    yaw : float
    prior : SizePrior
    camera_xy : sequence of 2 float, optional
    floor_z_m : float, optional

    Returns
    -------
    center_xyz, size_xyz : tuple of float
    """
    cx, cy, cz = (float(v) for v in center_xyz)
    sx, sy, sz = (float(v) for v in size_xyz)
    axes = (np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)]))
    centre = np.array([cx, cy])
    sizes = [sx, sy]
    for i in range(2):
        if sizes[i] < prior.min_xy_m:
            grow = prior.min_xy_m - sizes[i]
            if camera_xy is not None:
                away = float(np.dot(centre - np.asarray(camera_xy, dtype=np.float64), axes[i]))
                sign = 1.0 if away >= 0 else -1.0
                centre = centre + axes[i] * sign * 0.5 * grow
            sizes[i] = prior.min_xy_m
        elif sizes[i] > prior.max_xy_m:
            sizes[i] = prior.max_xy_m
    bottom = cz - 0.5 * sz
    on_floor = floor_z_m is not None and abs(bottom - floor_z_m) < 1e-6
    if sz < prior.min_z_m:
        sz = prior.min_z_m
        cz = bottom + 0.5 * sz if on_floor else cz
    elif sz > prior.max_z_m:
        sz = prior.max_z_m
        cz = bottom + 0.5 * sz if on_floor else cz
    return (float(centre[0]), float(centre[1]), cz), (sizes[0], sizes[1], sz)


#: Most points an object keeps of its measured surface (:attr:`Object3D.surface`).
MAX_SURFACE_POINTS = 400


def surface_points(points: npt.NDArray[np.floating], voxel_m: float
                   ) -> npt.NDArray[np.float32]:
    """One point per voxel of ``voxel_m`` (the first in input order), thinned evenly to at
    most :data:`MAX_SURFACE_POINTS`: an object's measured surface, shape (M, 3)."""
    pts = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    pts = pts[voxel_downsample(pts, voxel_m)]
    if len(pts) > MAX_SURFACE_POINTS:
        pts = pts[np.linspace(0, len(pts) - 1, MAX_SURFACE_POINTS).round().astype(np.int64)]
    return pts


def fit_box(points_map: npt.NDArray[np.floating], cls: str, score: float,
            prior: SizePrior | None, params: ObjectParams,
            camera_xy: Sequence[float] | None = None,
            cut: npt.NDArray[np.bool_] | None = None) -> Object3D:
    """3D box of a cluster in the map frame, clamped by the class's prior.

    Parameters
    ----------
    points_map : ndarray, shape (N, 3), N >= 1
    cls : str
    score : float
    prior : SizePrior or None
        None skips the clamp.
    params : ObjectParams
        ``orientation_method`` and ``boxes_on_floor`` are used.
    camera_xy : sequence of 2 float, optional
        Camera position (map frame): footprints grow away from it.
    cut : ndarray of bool, shape (N,), optional
        Points seen at the image border (see :func:`footprint_orientation`).

    Returns
    -------
    Object3D

    Raises
    ------
    ValueError
        If ``points_map`` is empty or not (N, 3).
    """
    pts = np.asarray(points_map, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise ValueError(f"points_map must have shape (N>=1, 3), got {pts.shape}")
    cxy, sxy, yaw = footprint_orientation(pts[:, :2], params.orientation_method, cut)
    zmin = 0.0 if params.boxes_on_floor else float(pts[:, 2].min())
    zmax = max(float(pts[:, 2].max()), zmin)
    center = (cxy[0], cxy[1], 0.5 * (zmin + zmax))
    size = (sxy[0], sxy[1], zmax - zmin)
    if prior is not None:
        center, size = clamp_to_prior(center, size, yaw, prior, camera_xy,
                                      0.0 if params.boxes_on_floor else None)
    open_sides = (False, False, False, False)
    if cut is not None and np.any(cut):
        open_sides = _open_sides(pts[:, :2], np.asarray(cut, dtype=bool), cxy, sxy, yaw,
                                 0.5 * params.cluster_tolerance_m)
    return Object3D(cls, float(score), tuple(center), tuple(size), yaw, int(len(pts)),
                    (float(cxy[0]), float(cxy[1]), float(sxy[0]), float(sxy[1])), open_sides,
                    surface_points(pts, params.miss_sample_spacing_m))


def _open_sides(points_xy: npt.NDArray[np.float64], cut: npt.NDArray[np.bool_],
                center_xy: Sequence[float], size_xy: Sequence[float], yaw: float,
                band_m: float) -> tuple[bool, bool, bool, bool]:
    """Sides (-x, +x, -y, +y) of a fitted rectangle formed mostly (>= half) by cut points
    (those within ``band_m`` of the side)."""
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = points_xy[:, 0] - center_xy[0], points_xy[:, 1] - center_xy[1]
    coords = (dx * c + dy * s, -dx * s + dy * c)
    out = []
    for i in range(2):
        for sign in (-1.0, 1.0):
            near = sign * coords[i] >= 0.5 * float(size_xy[i]) - band_m
            out.append(bool(np.any(near) and np.mean(cut[near]) >= 0.5))
    return (out[0], out[1], out[2], out[3])


# ----------------------------------------------------------------- per frame


def frame_points(frame: DepthFrame, mask: npt.NDArray[np.bool_], max_depth_m: float
                 ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64],
                            npt.NDArray[np.float32]]:
    """Map-frame points, pixel (u, v) and depth of the valid pixels under ``mask``.

    Returns
    -------
    points_map : ndarray of float64, shape (N, 3)
    pixels_uv : ndarray of float64, shape (N, 2)
    depth : ndarray of float32, shape (N,)
    """
    # Work on the mask's bounding window only (a detection box is a small part of the
    # image); np.nonzero's row-major order is the same as on the whole image.
    any_row = np.flatnonzero(mask.any(axis=1))
    if len(any_row) == 0:
        empty = np.zeros((0, 2), dtype=np.float64)
        return np.zeros((0, 3), dtype=np.float64), empty, np.zeros(0, dtype=np.float32)
    any_col = np.flatnonzero(mask[any_row[0]:any_row[-1] + 1].any(axis=0))
    r0, c0 = int(any_row[0]), int(any_col[0])
    win = (slice(r0, int(any_row[-1]) + 1), slice(c0, int(any_col[-1]) + 1))
    d = frame.depth_m[win]
    with np.errstate(invalid="ignore"):
        valid = mask[win] & np.isfinite(d) & (d > 0) & (d <= max_depth_m)
    rows, cols = np.nonzero(valid)
    z = d[rows, cols]
    rows, cols = rows + r0, cols + c0
    k = frame.intrinsics
    x = (cols - k.cx) * z / k.fx
    y = (rows - k.cy) * z / k.fy
    pts_opt = np.stack([x, y, z], axis=1)
    pts_map = apply_transform(frame.map_from_optical, pts_opt)
    return pts_map, np.stack([cols, rows], axis=1).astype(np.float64), z


def segment_detection(frame: DepthFrame, box_xyxy: Sequence[float], cls: str,
                      score: float, prior: SizePrior | None, params: ObjectParams
                      ) -> tuple[Object3D, npt.NDArray[np.float64], npt.NDArray[np.float32]] | None:
    """Run the detection -> 3D box pipeline for one 2D box, keeping the object's points.

    Parameters
    ----------
    frame : DepthFrame
    box_xyxy : sequence of 4 float
        Pixel box ``(x0, y0, x1, y1)``.
    cls : str
    score : float
    prior : SizePrior or None
    params : ObjectParams

    Returns
    -------
    (Object3D, points_map (N, 3) float64, depth_m (N,) float32) or None
        The box and the (downsampled, outlier-free) cluster points it was fitted to with
        their optical depth; None when no cluster of ``min_cluster_points`` remains.

    Raises
    ------
    ValueError
        When the box is malformed or outside the image (see :func:`box_mask`).
    """
    seg = _cluster_detection(frame, box_xyxy, params, prior=prior)
    if seg is None:
        return None
    for lab in seg.ranked:
        out = _fit_cluster(seg, lab, frame, cls, score, prior, params)
        if out is not None:
            return out
    return None


@dataclass
class _Clusters:
    """Clustered points under one detection box (internal to :func:`process_frame`)."""

    box_xyxy: tuple[float, float, float, float]
    pts: npt.NDArray[np.float64]       # (N, 3) map frame
    uv: npt.NDArray[np.float64]        # (N, 2) pixel (column, row)
    depth: npt.NDArray[np.float32]     # (N,) optical depth
    labels: npt.NDArray[np.int64]      # (N,) cluster labels, -1 = none
    ranked: list[int]                  # labels, best first (rank_clusters)


@dataclass(frozen=True)
class WallMask:
    """Wall cells of the 2D (lidar) map, grown by ``wall_margin_m``: see :func:`wall_mask`.

    ``mask`` has ``grid``'s shape (H, W), bool.
    """

    grid: GridMap
    mask: npt.NDArray[np.bool_]

    def free(self, points_xy: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
        """True for the points (map frame, shape (N, 2)) over cells the 2D map knows as
        free (the lidar saw through them); points outside the map are not."""
        return self._lookup(points_xy, lambda r, c: (self.grid.data[r, c] >= 0)
                            & (self.grid.data[r, c] < FREE_THRESHOLD))

    def on(self, points_xy: npt.NDArray[np.floating]) -> npt.NDArray[np.bool_]:
        """True for the points (map frame, shape (N, 2)) lying on a wall cell; points
        outside the map are not. Returns shape (N,) bool."""
        return self._lookup(points_xy, lambda r, c: self.mask[r, c])

    def _lookup(self, points_xy: npt.NDArray[np.floating],
                cell_test: Callable[[npt.NDArray[np.intp], npt.NDArray[np.intp]],
                                    npt.NDArray[np.bool_]]) -> npt.NDArray[np.bool_]:
        """``cell_test(rows, cols)`` at the cells of the points inside the map, False
        for the others; shape (N,) bool."""
        pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
        out = np.zeros(len(pts), dtype=bool)
        if len(pts) == 0:
            return out
        r, c = self.grid.world_to_cells(pts[:, 0], pts[:, 1])
        ok = (r >= 0) & (r < self.grid.height) & (c >= 0) & (c < self.grid.width)
        out[ok] = cell_test(r[ok], c[ok])
        return out


def wall_mask(grid: GridMap, params: ObjectParams, occupied_threshold: int = 65) -> WallMask:
    """The walls of a 2D map: its long occupied structures, grown by ``wall_margin_m``.

    Occupied cells (``>= occupied_threshold``) form 8-connected components; those whose
    bounding box is at least ``params.wall_min_length_m`` long on one side are walls (and
    door jambs, large furniture seen as a long obstacle), smaller ones are the legs or
    bases of furniture the lidar cuts and are left out. The walls are then grown by
    ``params.wall_margin_m`` (a depth point on a wall face lies on or next to its cell).
    :func:`process_frame` drops depth points on them before clustering.

    Parameters
    ----------
    grid : GridMap
        The 2D (lidar / SLAM) map.
    params : ObjectParams
    occupied_threshold : int
        Cells at or above it are occupied.

    Returns
    -------
    WallMask
    """
    occ = grid.data >= occupied_threshold
    if params.wall_min_length_m > 0 and occ.any():
        _, comp, stats, _ = cv2.connectedComponentsWithStats(occ.astype(np.uint8),
                                                             connectivity=8)
        side_cells = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
        is_wall = side_cells * grid.resolution_m >= params.wall_min_length_m
        is_wall[0] = False                       # label 0: the unoccupied background
        occ = is_wall[comp]
    r = int(round(params.wall_margin_m / grid.resolution_m))
    if r > 0 and occ.any():
        occ = cv2.dilate(occ.astype(np.uint8), np.ones((2 * r + 1, 2 * r + 1), np.uint8)) > 0
    return WallMask(grid, occ)


def _cluster_detection(frame: DepthFrame, box_xyxy: Sequence[float], params: ObjectParams,
                       walls: WallMask | None = None, prior: SizePrior | None = None
                       ) -> _Clusters | None:
    """Steps 1-5 of the pipeline and the cluster ranking for one box (None: too few points).

    With ``walls`` (and ``drop_wall_points``), points over wall cells are dropped with the
    floor and the ceiling, before the pixel links and the clustering: the object's own
    points then form a cluster not merged with the wall behind or beside it. With
    ``prior``, clusters of implausible extent (:func:`plausible_extent`: far larger than
    the class, or a fragment of it) are left out of the ranking, so that they are neither
    taken for the object nor contested between two detections.

    Raises
    ------
    ValueError
        When the box is malformed or outside the image (see :func:`box_mask`).
    """
    stride = box_stride(box_xyxy, params.pixel_stride, params.max_box_samples)
    mask = box_mask(box_xyxy, frame.depth_m.shape, stride)
    pts, uv, depth = frame_points(frame, mask, params.max_depth_m)
    keep = (pts[:, 2] >= params.floor_height_m) & (pts[:, 2] <= params.ceiling_height_m)
    if walls is not None and params.drop_wall_points:
        keep &= ~walls.on(pts[:, :2])
    pts, uv, depth = pts[keep], uv[keep], depth[keep]
    # Links between neighbouring pixels (grazing surfaces), moved to voxel level.
    k = frame.intrinsics
    link_ratio = stride / (0.5 * (k.fx + k.fy)) / math.sin(params.min_grazing_angle_rad)
    pix_edges = pixel_grid_edges(uv, pts, depth, stride, params.cluster_tolerance_m, link_ratio)
    idx, voxel_of = voxel_downsample(pts, params.voxel_size_m, return_inverse=True)
    pts, uv, depth = pts[idx], uv[idx], depth[idx]
    if len(pts) < params.min_cluster_points:
        return None
    inl = statistical_outlier_mask(pts, params.sor_k, params.sor_std)
    new_index = np.cumsum(inl) - 1
    edges = voxel_of[pix_edges]
    edges = edges[(edges[:, 0] != edges[:, 1]) & inl[edges[:, 0]] & inl[edges[:, 1]]]
    pts, uv, depth = pts[inl], uv[inl], depth[inl]
    labels = euclidean_clusters(pts, params.cluster_tolerance_m, params.min_cluster_points,
                                new_index[edges])
    ranked = rank_clusters(labels, uv, depth, box_xyxy, params.near_vote_share)
    if prior is not None:
        ranked = [lab for lab in ranked if plausible_extent(pts[labels == lab], prior, params)]
    if not ranked:
        return None
    box = tuple(float(v) for v in np.asarray(box_xyxy, dtype=np.float64).reshape(-1))
    return _Clusters(box, pts, uv, depth, labels, ranked)


def _fit_cluster(seg: _Clusters, best: int, frame: DepthFrame, cls: str, score: float,
                 prior: SizePrior | None, params: ObjectParams
                 ) -> tuple[Object3D, npt.NDArray[np.float64], npt.NDArray[np.float32]] | None:
    """Steps 6-8 for the cluster ``best`` of ``seg`` (None: implausible for the prior)."""
    pts, labels = seg.pts, seg.labels
    cam_xy = frame.camera_xyz[:2]
    chosen = labels == best
    if prior is not None and not plausible_extent(pts[chosen], prior, params):
        return None  # cluster merged with a wall or a neighbour: clamping would misplace it
    # Where the view cuts the object (image border, something in front): not its sides.
    cut = view_cut(frame, seg.uv, seg.depth,
                   box_stride(seg.box_xyxy, params.pixel_stride, params.max_box_samples),
                   params.cluster_tolerance_m)
    obj = fit_box(pts[chosen], cls, score, prior, params, cam_xy, cut[chosen])
    if params.merge_parts_fraction < 1.0 and labels.max() > 0:
        # Other parts of the same object (split at thin links) lie in the clamped box.
        lab = labels[labels >= 0]
        inside = points_in_rect(pts[labels >= 0, :2], obj.center_xyz[:2], obj.size_xyz[:2],
                                obj.yaw, params.cluster_tolerance_m)
        frac = np.bincount(lab, weights=inside) / np.bincount(lab)
        parts = np.flatnonzero(frac >= params.merge_parts_fraction)
        if len(parts) > 1 or (len(parts) == 1 and parts[0] != best):
            # Only the parts' points inside the box join: a cluster half inside (the edge
            # of a desk top beside a chair) must not stretch or turn the box.
            merged = labels == best
            merged[labels >= 0] |= np.isin(lab, parts) & inside
            if prior is None or plausible_extent(pts[merged], prior, params):
                chosen = merged
                obj = fit_box(pts[chosen], cls, score, prior, params, cam_xy, cut[chosen])
    return obj, pts[chosen], seg.depth[chosen]


def view_cut(frame: DepthFrame, pixels_uv: npt.NDArray[np.floating],
             depth_m: npt.NDArray[np.floating], step_px: int, margin_m: float
             ) -> npt.NDArray[np.bool_]:
    """Points where the view, not the object, ends: at the image border or beside a
    nearer surface (an occluder).

    Parameters
    ----------
    frame : DepthFrame
    pixels_uv : ndarray, shape (N, 2)
        Pixel (column, row) of each point.
    depth_m : ndarray, shape (N,)
        Optical depth of each point.
    step_px : int
        The sampling step: a point within ``step_px`` of the border, or whose pixel
        ``step_px`` away (left, right, up, down) is nearer by more than ``margin_m``, is cut.
    margin_m : float

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    k = frame.intrinsics
    uv = np.asarray(pixels_uv, dtype=np.int64).reshape(-1, 2)
    z = np.asarray(depth_m, dtype=np.float64).reshape(-1)
    step = max(int(step_px), 1)
    u, v = uv[:, 0], uv[:, 1]
    cut = (u <= step) | (u >= k.width - 1 - step) | (v <= step) | (v >= k.height - 1 - step)
    d = frame.depth_m
    for du, dv in ((step, 0), (-step, 0), (0, step), (0, -step)):
        nd = d[np.clip(v + dv, 0, k.height - 1), np.clip(u + du, 0, k.width - 1)]
        with np.errstate(invalid="ignore"):
            cut |= np.isfinite(nd) & (nd > 0) & (nd < z - margin_m)
    return cut


def _voxel_keys(points: npt.NDArray[np.floating], voxel_m: float) -> npt.NDArray[np.int64]:
    """Sorted unique int64 codes of the voxels (edge ``voxel_m``) holding ``points``."""
    k = np.floor(np.asarray(points, dtype=np.float64) / voxel_m).astype(np.int64)
    k = np.clip(k + (1 << 20), 0, (1 << 21) - 1)
    return np.unique((k[:, 0] << 42) | (k[:, 1] << 21) | k[:, 2])


def _box_fit(seg: _Clusters, lab: int) -> float:
    """IoU of a cluster's pixel bounding box with the detection box (how well it fills it)."""
    uv = seg.uv[seg.labels == lab]
    x0, y0, x1, y1 = seg.box_xyxy
    u0, v0 = uv.min(axis=0)
    u1, v1 = uv.max(axis=0)
    iw = max(min(x1, u1) - max(x0, u0), 0.0)
    ih = max(min(y1, v1) - max(y0, v0), 0.0)
    inter = iw * ih
    union = (x1 - x0) * (y1 - y0) + (u1 - u0) * (v1 - v0) - inter
    return inter / union if union > 0 else 0.0


def _assign_clusters(segs: list[_Clusters | None], params: ObjectParams) -> list[int]:
    """One cluster per detection, no cluster for two detections (index into ``ranked``).

    Each detection takes its best-ranked cluster. When two detections take the same
    points (more than half of the smaller cluster's voxels shared: a chair in front of a
    desk is the nearest cluster in both boxes), the detection whose box the cluster fills
    better (IoU of the cluster's pixel bounding box with the box) keeps it and the other
    moves on to its next cluster. Returns -1 for detections left without a cluster.
    """
    voxel = params.voxel_size_m if params.voxel_size_m > 0 else params.cluster_tolerance_m
    pick = [0 if s is not None else -1 for s in segs]
    cache: dict[tuple[int, int], tuple[npt.NDArray[np.int64], float]] = {}

    def info(i: int) -> tuple[npt.NDArray[np.int64], float]:
        key = (i, pick[i])
        if key not in cache:
            s = segs[i]
            lab = s.ranked[pick[i]]
            cache[key] = (_voxel_keys(s.pts[s.labels == lab], voxel), _box_fit(s, lab))
        return cache[key]

    changed = True
    while changed:
        changed = False
        for i in range(len(segs)):
            for j in range(i + 1, len(segs)):
                if pick[i] < 0 or pick[j] < 0:
                    continue
                ki, fi = info(i)
                kj, fj = info(j)
                shared = len(np.intersect1d(ki, kj, assume_unique=True))
                if shared <= 0.5 * min(len(ki), len(kj)):
                    continue
                loser = j if fi >= fj else i
                pick[loser] += 1
                if pick[loser] >= len(segs[loser].ranked):
                    pick[loser] = -1
                changed = True
    return pick


def plausible_extent(points_map: npt.NDArray[np.floating], prior: SizePrior,
                     params: ObjectParams) -> bool:
    """False when a cluster is far larger or far smaller than its class can be.

    The footprint (minimum-area rectangle) or height exceeding ``prior_reject_factor``
    times the prior's maximum means the cluster took in a wall or a neighbouring object;
    clamping such a cluster to the prior would still place the box wrongly, so the
    observation is dropped. ``prior_reject_factor`` 0 disables the test.

    A footprint whose longer side is below ``min_extent_fraction`` times the prior's
    ``min_xy_m`` is a fragment (a table leg, a chair leg in front of the chair, the corner
    of a top cut by the image border): its minimum-area rectangle has an arbitrary
    orientation, and growing it to the prior's minimum puts the box anywhere around it.
    ``min_extent_fraction`` 0 disables this test.
    """
    if len(points_map) == 0:
        return True
    f, g = params.prior_reject_factor, params.min_extent_fraction
    if f <= 0 and g <= 0:
        return True
    pts = np.asarray(points_map, dtype=np.float64)
    _, sxy, _ = footprint_orientation(pts[:, :2], params.orientation_method)
    if g > 0 and max(sxy) < g * prior.min_xy_m:
        return False
    if f <= 0:
        return True
    height = float(pts[:, 2].max() - (0.0 if params.boxes_on_floor else pts[:, 2].min()))
    return max(sxy) <= f * prior.max_xy_m and height <= f * prior.max_z_m


def object_from_detection(frame: DepthFrame, box_xyxy: Sequence[float], cls: str,
                          score: float, prior: SizePrior | None, params: ObjectParams
                          ) -> Object3D | None:
    """The box of :func:`segment_detection` alone (None when there is none).

    Raises
    ------
    ValueError
        When the box is malformed or outside the image (see :func:`box_mask`).
    """
    seg = segment_detection(frame, box_xyxy, cls, score, prior, params)
    return None if seg is None else seg[0]


#: Scan points, their cluster labels, and per cluster the point count and extent.
_ScanClusters = tuple[npt.NDArray[np.float64], npt.NDArray[np.intp], npt.NDArray[np.intp],
                      npt.NDArray[np.float64]]


def scan_legs(scan_xy: npt.NDArray[np.floating], params: ObjectParams,
              robot_xy: Sequence[float] | None = None,
              _clusters: _ScanClusters | None = None) -> npt.NDArray[np.float64]:
    """Centres of leg-like clusters in a 2D scan.

    A leg is a cluster (link distance ``leg_cluster_gap_m``) of ``leg_min_points`` or
    more points whose extent is within [``leg_min_width_m``, ``leg_max_width_m``] and
    with no other scan point within ``leg_isolation_m`` of its centre (walls, boxes and
    people's bodies are wider or not isolated).

    Parameters
    ----------
    scan_xy : ndarray, shape (N, 2)
        Scan points (any planar frame, usually map).
    params : ObjectParams
    robot_xy : sequence of 2 float, optional
        Points farther than ``leg_max_range_m`` from it are ignored.

    Returns
    -------
    ndarray of float64, shape (M, 2)

    Raises
    ------
    ValueError
        If ``scan_xy`` is not (N, 2).
    """
    pts, labels, counts, widths = (_clusters if _clusters is not None
                                   else _scan_clusters(scan_xy, params, robot_xy))
    if len(pts) == 0:
        return np.zeros((0, 2))
    candidates = np.flatnonzero((counts >= params.leg_min_points)
                                & (widths >= params.leg_min_width_m)
                                & (widths <= params.leg_max_width_m))
    tree = cKDTree(pts)
    centres = []
    for lab in candidates:
        sel = pts[labels == lab]
        width = float(widths[lab])
        centre = sel.mean(axis=0)
        radius = params.leg_isolation_m + 0.5 * width
        if len(tree.query_ball_point(centre, radius)) > len(sel):
            continue
        centres.append(centre)
    return np.array(centres, dtype=np.float64).reshape(-1, 2)


def _scan_clusters(scan_xy: npt.ArrayLike, params: ObjectParams,
                   robot_xy: Sequence[float] | None) -> _ScanClusters:
    """Finite scan points within ``leg_max_range_m`` of ``robot_xy``, their cluster labels
    (link ``leg_cluster_gap_m``), and each cluster's point count and extent (diagonal of
    its bounding box)."""
    pts = np.asarray(scan_xy, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"scan_xy must have shape (N, 2), got {pts.shape}")
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if robot_xy is not None and len(pts):
        near = np.hypot(pts[:, 0] - robot_xy[0], pts[:, 1] - robot_xy[1]) <= params.leg_max_range_m
        pts = pts[near]
    if len(pts) == 0:
        empty = np.zeros(0, dtype=np.intp)
        return pts.reshape(0, 2), empty, empty, np.zeros(0)
    labels = euclidean_clusters(pts, params.leg_cluster_gap_m, 1)
    # Size and width of every cluster at once (walls give many clusters, few are legs).
    order = np.argsort(labels, kind="stable")
    counts = np.bincount(labels)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    ptp = np.maximum.reduceat(pts[order], starts) - np.minimum.reduceat(pts[order], starts)
    return pts, labels, counts, np.hypot(ptp[:, 0], ptp[:, 1])


def scan_posts(scan_xy: npt.NDArray[np.floating], params: ObjectParams,
               robot_xy: Sequence[float] | None = None,
               _clusters: _ScanClusters | None = None
               ) -> tuple[list[npt.NDArray[np.float64]], npt.NDArray[np.float64]]:
    """Isolated compact clusters of a 2D scan wider than a leg: posts.

    A post is a cluster (as in :func:`scan_legs`) of ``leg_min_points`` or more points
    whose extent lies in (``leg_max_width_m``, ``post_max_width_m``] with no other scan
    point within ``leg_isolation_m`` of its points.

    Returns
    -------
    posts : list of ndarray, shape (K, 2)
        The points of every post.
    others : ndarray, shape (M, 2)
        The remaining scan points (within ``leg_max_range_m``).

    Raises
    ------
    ValueError
        If ``scan_xy`` is not (N, 2).
    """
    pts, labels, counts, widths = (_clusters if _clusters is not None
                                   else _scan_clusters(scan_xy, params, robot_xy))
    if len(pts) == 0 or params.post_max_width_m <= params.leg_max_width_m:
        return [], pts
    candidates = np.flatnonzero((counts >= params.leg_min_points)
                                & (widths > params.leg_max_width_m)
                                & (widths <= params.post_max_width_m))
    if candidates.size == 0:
        return [], pts
    tree = cKDTree(pts)
    posts, used = [], np.zeros(len(pts), dtype=bool)
    for lab in candidates:
        mine = labels == lab
        near = tree.query_ball_point(pts[mine], params.leg_isolation_m)
        if any(not mine[j] for idx in near for j in idx):
            continue
        posts.append(pts[mine])
        used |= mine
    return posts, pts[~used]


def group_legs(legs_xy: npt.NDArray[np.floating], max_distance_m: float, min_legs: int
               ) -> list[npt.NDArray[np.float64]]:
    """Group legs closer than ``max_distance_m`` (single linkage).

    Returns
    -------
    list of ndarray, each shape (K, 2), K >= ``min_legs``
        Largest group first.
    """
    legs = np.asarray(legs_xy, dtype=np.float64).reshape(-1, 2)
    if len(legs) == 0:
        return []
    labels = euclidean_clusters(legs, max_distance_m, min_legs)
    return [legs[labels == lab] for lab in range(int(labels.max()) + 1)] if labels.max() >= 0 \
        else []


def points_in_rect(points_xy: npt.NDArray[np.floating], center_xy: Sequence[float],
                   size_xy: Sequence[float], yaw: float, margin_m: float = 0.0
                   ) -> npt.NDArray[np.bool_]:
    """True for points inside a rotated rectangle grown by ``margin_m`` on every side."""
    pts = np.asarray(points_xy, dtype=np.float64)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = pts[:, 0] - center_xy[0], pts[:, 1] - center_xy[1]
    u, v = dx * c + dy * s, -dx * s + dy * c
    return (np.abs(u) <= 0.5 * size_xy[0] + margin_m) & (np.abs(v) <= 0.5 * size_xy[1] + margin_m)


def top_fraction(heights_m: npt.NDArray[np.floating], band_m: float) -> float:
    """Largest share of ``heights_m`` inside any window of height ``band_m``.

    A horizontal top seen by a depth camera gives one dense band of heights; a vertical
    surface spreads its points over all heights. Returns 0 for no points.

    Examples
    --------
    >>> float(top_fraction(np.array([0.70, 0.72, 0.74, 0.3, 0.9]), 0.1))
    0.6
    """
    z = np.sort(np.asarray(heights_m, dtype=np.float64).reshape(-1))
    if z.size == 0:
        return 0.0
    upper = np.searchsorted(z, z + band_m, side="right")
    return float((upper - np.arange(z.size)).max() / z.size)


def top_cover(points_xy: npt.NDArray[np.floating], center_xy: Sequence[float],
              size_xy: Sequence[float], yaw: float, cell_m: float) -> float:
    """Share of a rotated rectangle covered by points (x, y).

    The rectangle is cut into cells of about ``cell_m``; a cell is covered when a point
    lies within ``cell_m`` of its centre. A table top covers its legs' rectangle; legs of
    two tables grouped together leave the floor between them uncovered.

    Parameters
    ----------
    points_xy : ndarray, shape (N, 2)
    center_xy, size_xy : sequence of 2 float
    yaw : float
    cell_m : float
        > 0.

    Returns
    -------
    float
        In [0, 1]; 0 without points.

    Raises
    ------
    ValueError
        If ``cell_m`` is not > 0.
    """
    if not cell_m > 0:
        raise ValueError(f"cell_m must be > 0, got {cell_m}")
    pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return 0.0
    c, s = math.cos(yaw), math.sin(yaw)
    nu = max(int(math.ceil(float(size_xy[0]) / cell_m)), 1)
    nv = max(int(math.ceil(float(size_xy[1]) / cell_m)), 1)
    gu, gv = np.meshgrid(((np.arange(nu) + 0.5) / nu - 0.5) * float(size_xy[0]),
                         ((np.arange(nv) + 0.5) / nv - 0.5) * float(size_xy[1]), indexing="ij")
    cells = np.column_stack([center_xy[0] + gu.ravel() * c - gv.ravel() * s,
                             center_xy[1] + gu.ravel() * s + gv.ravel() * c])
    d, _ = cKDTree(pts).query(cells, distance_upper_bound=cell_m)
    return float(np.mean(np.isfinite(d)))


def unknown_objects(frame: DepthFrame, scan_xy_map: npt.NDArray[np.floating],
                    params: ObjectParams, known: Iterable[Object3D] = (),
                    prior: SizePrior | None = None,
                    walls: WallMask | None = None) -> list[Object3D]:
    """Unclassified objects: leg groups in the scan with depth points above them, and
    posts (:func:`scan_posts`) with depth points overhanging them.

    Depth points (every ``unknown_pixel_stride``-th pixel) between
    ``unknown_min_height_m`` and ``unknown_max_height_m`` inside the legs' minimum-area
    rectangle grown by ``unknown_radius_m``, and farther than ``leg_max_width_m`` from
    every leg (the legs alone are no top), make the object when there are at least
    ``unknown_min_points`` of them; its box spans them and the legs.

    Parameters
    ----------
    frame : DepthFrame
    scan_xy_map : ndarray, shape (N, 2)
        Laser points in the map frame.
    params : ObjectParams
    known : iterable of Object3D
        Objects already found; leg groups lying inside one of them (grown by
        ``unknown_radius_m``) and posts whose centre lies inside one (grown by
        ``leg_isolation_m``) are skipped.
    prior : SizePrior, optional
        Prior of the ``unknown`` class (clamps the boxes).
    walls : WallMask, optional
        Of the current 2D map: a post's depth points overhang it only over cells the map
        knows as free; without it, every one farther than ``post_overhang_m`` from the
        post's laser points does (and either way they must lie mostly within
        ``post_band_m`` of height).

    Returns
    -------
    list of Object3D
        With ``cls == UNKNOWN_CLASS`` and score 1.0.
    """
    cam_xy = frame.camera_xyz[:2]
    known = list(known)
    clusters = _scan_clusters(scan_xy_map, params, cam_xy)
    legs = scan_legs(scan_xy_map, params, cam_xy, clusters)
    # Legs of objects already found are no evidence of another object (and would join
    # two neighbouring desks into one group spanning the floor between them).
    for obj in known:
        if len(legs) == 0:
            break
        legs = legs[~points_in_rect(legs, obj.center_xyz[:2], obj.size_xyz[:2], obj.yaw,
                                    params.unknown_radius_m)]
    kept = group_legs(legs, params.leg_group_distance_m, params.min_legs)
    posts, others = (scan_posts(scan_xy_map, params, cam_xy, clusters)
                     if params.post_max_width_m > 0
                     else ([], np.zeros((0, 2))))
    # Posts of objects already found (their face lies on the box's edge) are skipped.
    posts = [g for g in posts
             if not any(points_in_rect(g.mean(axis=0, keepdims=True), o.center_xyz[:2],
                                       o.size_xyz[:2], o.yaw, params.leg_isolation_m)[0]
                        for o in known)]
    if not kept and not posts:
        return []
    stride = params.unknown_pixel_stride
    mask = np.zeros(frame.depth_m.shape, dtype=bool)
    mask[::stride, ::stride] = True
    pts, _, _ = frame_points(frame, mask, params.max_depth_m)
    band = (pts[:, 2] >= params.unknown_min_height_m) & (pts[:, 2] <= params.unknown_max_height_m)
    pts = pts[band]
    out = []
    for i, g in enumerate(posts):
        rest = np.vstack([others] + [h for j, h in enumerate(posts) if j != i])
        obj = _post_object(g, pts, rest, params, prior, cam_xy, walls)
        if obj is not None:
            out.append(obj)
    for g in kept:
        if len(g) >= 3:
            (rcx, rcy), (w, h), ang = cv2.minAreaRect(g.astype(np.float32))
            rc, rs, ryaw = (rcx, rcy), (w, h), math.radians(ang)
        else:
            rc, rs, ryaw = footprint_orientation(g, "pca")
        if prior is not None and max(rs) > prior.max_xy_m:
            continue  # legs of several objects: the rectangle spans open floor
        sel = pts[points_in_rect(pts[:, :2], rc, rs, ryaw, params.unknown_radius_m)]
        # The legs themselves are not evidence of a top: drop points right above them.
        if len(sel):
            on_leg = cKDTree(g).query(sel[:, :2], distance_upper_bound=params.leg_max_width_m)[0]
            sel = sel[~np.isfinite(on_leg)]
        if len(sel) < params.unknown_min_points:
            continue
        if top_fraction(sel[:, 2], params.unknown_top_band_m) < params.unknown_top_fraction:
            continue  # a vertical surface (wall, door jamb, cabinet front): no table top
        inl = statistical_outlier_mask(sel, params.sor_k, params.sor_std)
        sel = sel[inl]
        if top_cover(sel[:, :2], rc, rs, ryaw, params.unknown_cover_cell_m) \
                < params.unknown_min_top_cover:
            continue  # no top over most of the legs' rectangle (open floor between them)
        legs3d = np.column_stack([g, np.full(len(g), float(sel[:, 2].min()))])
        obj = fit_box(np.vstack([sel, legs3d]), UNKNOWN_CLASS, 1.0, prior, params, cam_xy)
        out.append(replace(obj, n_points=int(len(sel))))
    return out


def _post_object(post: npt.NDArray[np.float64], pts: npt.NDArray[np.float64],
                 others: npt.NDArray[np.float64], params: ObjectParams,
                 prior: SizePrior | None, cam_xy: Sequence[float],
                 walls: WallMask | None = None) -> Object3D | None:
    """An unclassified object over a post (see :func:`scan_posts`) when at least
    ``unknown_min_points`` depth points above it (``pts``, already in the height band)
    overhang its laser points (a bin's rim, a pedestal table's top); None otherwise.

    Overhanging: farther than ``post_overhang_m`` from every laser point of the post and,
    with the map (``walls``), over a cell the map knows as free, i.e. where the lidar sees
    through under it (the faces of a pillar that this scan does not see are no overhang).
    Like a table top over legs, the overhanging points must be mostly at one height
    (``unknown_top_fraction`` of them within ``post_band_m``): a face spread over all
    heights is a wall or pillar side, whichever map cell it falls into.
    Depth points within ``leg_isolation_m`` of other scan points belong to what the lidar
    sees there and are left out."""
    lo, hi = post.min(axis=0), post.max(axis=0)
    r = params.unknown_radius_m
    near = np.all((pts[:, :2] >= lo - r) & (pts[:, :2] <= hi + r), axis=1)
    sel = pts[near]
    if len(sel) and len(others):
        d_other = cKDTree(others).query(sel[:, :2], distance_upper_bound=params.leg_isolation_m)[0]
        sel = sel[~np.isfinite(d_other)]
    if len(sel) < params.unknown_min_points:
        return None
    # Only what hangs together with the post (in plan view) is its overhang: a table top
    # beside a bin is not the bin's rim.
    both = np.vstack([post, sel[:, :2]])
    labels = euclidean_clusters(both, params.post_link_m, 1)
    sel = sel[np.isin(labels[len(post):], labels[:len(post)])]
    if len(sel) < params.unknown_min_points:
        return None
    over = cKDTree(post).query(sel[:, :2])[0] > params.post_overhang_m
    if walls is not None:
        over &= walls.free(sel[:, :2])
    if np.count_nonzero(over) < params.unknown_min_points:
        return None
    if top_fraction(sel[over, 2], params.post_band_m) < params.unknown_top_fraction:
        return None  # a face spread over all heights (a pillar side the scan missed)
    # No outlier filter: the top seen at a grazing angle is sparse next to the dense
    # faces and would be cut off; the selection is bounded by the post's grown box.
    base = np.column_stack([post, np.full(len(post), float(sel[:, 2].min()))])
    obj = fit_box(np.vstack([sel, base]), UNKNOWN_CLASS, 1.0, prior, params, cam_xy)
    return replace(obj, n_points=int(len(sel)))


# ------------------------------------------------------------------------- fusion


def footprint_iou(a: Object3D, b: Object3D) -> float:
    """Intersection over union of two footprints (rotated rectangles)."""
    pa = a.footprint().astype(np.float32)
    pb = b.footprint().astype(np.float32)
    area_a = a.size_xyz[0] * a.size_xyz[1]
    area_b = b.size_xyz[0] * b.size_xyz[1]
    if area_a <= 0 or area_b <= 0:
        return 0.0
    inter, _ = cv2.intersectConvexConvex(pa, pb)
    inter = max(float(inter), 0.0)
    union = area_a + area_b - inter
    return inter / union if union > 0 else 0.0


@dataclass
class TrackedObject:
    """An object of the :class:`ObjectMap` with its bookkeeping."""

    id: int
    obj: Object3D
    hits: int = 1
    misses: int = 0
    last_seen_ns: int = 0


def box_samples(obj: Object3D, spacing_m: float, surface_only: bool = True
                ) -> npt.NDArray[np.float64]:
    """Points on (or filling) a box on a grid of ``spacing_m`` (cell centres), shape (N, 3).

    ``surface_only`` keeps only the outer layer of the grid.
    """
    n = [max(int(math.ceil(s / spacing_m)), 1) for s in obj.size_xyz]
    axes = [((np.arange(k) + 0.5) / k - 0.5) * s for k, s in zip(n, obj.size_xyz)]
    gx, gy, gz = np.meshgrid(*axes, indexing="ij")
    if surface_only:
        ix, iy, iz = np.meshgrid(*(np.arange(k) for k in n), indexing="ij")
        outer = ((ix == 0) | (ix == n[0] - 1) | (iy == 0) | (iy == n[1] - 1)
                 | (iz == 0) | (iz == n[2] - 1))
        gx, gy, gz = gx[outer], gy[outer], gz[outer]
    local = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], axis=1)
    c, s = math.cos(obj.yaw), math.sin(obj.yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return local @ rot.T + np.asarray(obj.center_xyz)


def _fuse_side(a: float, a_open: bool, b: float, b_open: bool, w_a: float, w_b: float,
               margin: float, outward: float) -> tuple[float, bool]:
    """One side of :func:`fuse_boxes` (position along ``outward`` = +-1, open flag).

    Two open sides (lower bounds): the farther. An open and a closed side: the closed one
    unless the open one lies beyond it by more than ``margin``. Two closed sides: the
    weighted mean when within ``margin``, else the farther (a part seen only once).
    """
    d = (b - a) * outward
    if a_open and b_open:
        return (b, True) if d > 0 else (a, True)
    if a_open != b_open:
        (o, c) = (a, b) if a_open else (b, a)
        return (o, True) if (o - c) * outward > margin else (c, False)
    if abs(d) > margin:
        return (b, False) if d > 0 else (a, False)
    return (a * w_a + b * w_b) / (w_a + w_b), False


def fuse_boxes(old: Object3D, new: Object3D, params: ObjectParams,
               prior: SizePrior | None = None) -> Object3D:
    """Fuse a re-detection into a tracked box.

    The yaw is the point-weighted mean (``new`` turned by a multiple of 90 degrees to
    ``old``'s axes: a box is the same under such turns). Along each axis of the fused box
    the *measured* footprints (:attr:`Object3D.measured_xy`, the extent of the points
    before the prior's clamp) are fused:

    * both boxes saw both sides (none open) and measure the same length (within
      ``merge_extend_margin_m``): the sides are averaged (a shifted re-detection, noise,
      does not inflate the box);
    * otherwise side by side: two closed sides within ``merge_extend_margin_m`` are
      averaged, else the farther wins (two partial views of a long desk add up); an open
      side (:attr:`Object3D.open_sides`, where the view was cut: a lower bound) gives way
      to a closed one unless it lies beyond it by more than the margin; of two open sides
      the farther wins.

    Growth beyond a closed side of ``old`` is limited to ``merge_growth_max`` times the
    longer of the two extents (one cluster that took in a neighbour cannot blow the box
    up). The size prior then clamps the fused extents: a side shorter than ``min_xy_m``
    grows to it around the measured part, towards the point-weighted mean of the two
    boxes' centres (each grown away from its camera); a side longer than ``max_xy_m``
    shrinks around its centre. Heights: the larger, growing at most ``merge_growth_max``
    times.

    Parameters
    ----------
    old, new : Object3D
    params : ObjectParams
    prior : SizePrior, optional
        The class's prior; None = no clamp.

    Returns
    -------
    Object3D
        With the classified class (over :data:`UNKNOWN_CLASS`), the higher score, the
        summed point count and the fused measured footprint.
    """
    cls = old.cls if old.cls != UNKNOWN_CLASS else new.cls
    w_old, w_new = float(max(old.n_points, 1)), float(max(new.n_points, 1))
    mo = old.measured_xy or (*old.center_xyz[:2], *old.size_xyz[:2])
    mn = new.measured_xy or (*new.center_xyz[:2], *new.size_xyz[:2])
    # Align the new box's axes to the old one (boxes are symmetric under 90 degrees).
    d = _wrap_half_pi(new.yaw - old.yaw)
    swap = abs(d) > 0.25 * math.pi
    if swap:
        d = d - math.copysign(0.5 * math.pi, d)
    yaw = _wrap_half_pi(old.yaw + d * w_new / (w_old + w_new))
    axes = (np.array([math.cos(yaw), math.sin(yaw)]), np.array([-math.sin(yaw), math.cos(yaw)]))
    # Both boxes keep their extents and turn about their centres to the fused yaw.
    m_old = [(float(np.dot(mo[:2], ax)), mo[2 + i]) for i, ax in enumerate(axes)]
    m_new = [(float(np.dot(mn[:2], ax)), mn[3 - i] if swap else mn[2 + i])
             for i, ax in enumerate(axes)]
    # Open flags of the new box's sides, by the fused side their outward normal is nearest.
    cn, sn = math.cos(new.yaw), math.sin(new.yaw)
    normals = [(-cn, -sn), (cn, sn), (sn, -cn), (-sn, cn)]
    open_new = []
    for ax in axes:
        for sign in (-1.0, 1.0):
            k = int(np.argmax([sign * (nx * ax[0] + ny * ax[1]) for nx, ny in normals]))
            open_new.append(new.open_sides[k])
    g, margin = params.merge_growth_max, params.merge_extend_margin_m
    centre_xy = np.zeros(2)
    meas_xy = np.zeros(2)
    size_xy, meas_size = [0.0, 0.0], [0.0, 0.0]
    open_out = [False] * 4
    for i, ax in enumerate(axes):
        (ca, la), (cb, lb) = m_old[i], m_new[i]
        a0, a1, b0, b1 = ca - 0.5 * la, ca + 0.5 * la, cb - 0.5 * lb, cb + 0.5 * lb
        flags = (old.open_sides[2 * i], old.open_sides[2 * i + 1],
                 open_new[2 * i], open_new[2 * i + 1])
        if not any(flags) and abs(lb - la) <= margin:
            # The same extent measured twice, shifted by noise: average both sides.
            lo = (a0 * w_old + b0 * w_new) / (w_old + w_new)
            hi = (a1 * w_old + b1 * w_new) / (w_old + w_new)
        else:
            lo, open_out[2 * i] = _fuse_side(a0, flags[0], b0, flags[2], w_old, w_new,
                                             margin, -1.0)
            hi, open_out[2 * i + 1] = _fuse_side(a1, flags[1], b1, flags[3], w_old, w_new,
                                                 margin, 1.0)
            hi = max(hi, lo)
        # Growth beyond a closed side contradicts it (a cluster that took in a neighbour):
        # at most merge_growth_max times the longer extent. Beyond an open side (a lower
        # bound) it is what the old view could not see.
        cap = g * max(la, lb)
        ext_lo = 0.0 if flags[0] else max(a0 - lo, 0.0)
        ext_hi = 0.0 if flags[1] else max(hi - a1, 0.0)
        if hi - lo > cap and ext_lo + ext_hi > 0:
            excess = min(hi - lo - cap, ext_lo + ext_hi)
            lo += excess * ext_lo / (ext_lo + ext_hi)
            hi -= excess * ext_hi / (ext_lo + ext_hi)
        # Where the clamped boxes put the object along this axis (their grown sides).
        grown = (float(np.dot(old.center_xyz[:2], ax)) * w_old
                 + float(np.dot(new.center_xyz[:2], ax)) * w_new) / (w_old + w_new)
        length, mid = hi - lo, 0.5 * (lo + hi)
        meas_xy += mid * ax
        meas_size[i] = length
        if prior is not None and length < prior.min_xy_m:
            half = 0.5 * prior.min_xy_m
            mid = min(max(grown, hi - half), lo + half)
            length = prior.min_xy_m
        elif prior is not None and length > prior.max_xy_m:
            length = prior.max_xy_m
        centre_xy += mid * ax
        size_xy[i] = length
    sz = max(old.size_xyz[2], min(new.size_xyz[2], g * old.size_xyz[2]))
    if prior is not None:
        sz = min(sz, prior.max_z_m)
    cz = 0.5 * sz if params.boxes_on_floor else \
        (old.center_xyz[2] * w_old + new.center_xyz[2] * w_new) / (w_old + w_new)
    surfaces = [o.surface for o in (new, old) if o.surface is not None]
    # The newest view first: when the union is thinned, the latest points stay densest.
    surface = (surface_points(np.vstack(surfaces), params.miss_sample_spacing_m)
               if surfaces else None)
    return Object3D(cls, max(old.score, new.score),
                    (float(centre_xy[0]), float(centre_xy[1]), float(cz)),
                    (float(size_xy[0]), float(size_xy[1]), float(sz)), yaw,
                    int(min(old.n_points + new.n_points, 2**31 - 1)),
                    (float(meas_xy[0]), float(meas_xy[1]), meas_size[0], meas_size[1]),
                    (open_out[0], open_out[1], open_out[2], open_out[3]), surface)


class ObjectMap:
    """Objects fused in the map frame.

    Parameters
    ----------
    params : ObjectParams
    priors : dict of str to SizePrior
        Merged sizes are capped by the class's ``max_xy_m`` / ``max_z_m``.
    """

    def __init__(self, params: ObjectParams, priors: dict[str, SizePrior]) -> None:
        self.params = params
        self.priors = dict(priors)
        self._objects: list[TrackedObject] = []
        self._next_id = 0
        self._swept = SweptPath()

    def __len__(self) -> int:
        return len(self._objects)

    def note_robot_position(self, x_m: float, y_m: float) -> None:
        """Record where the robot is (map frame; call at the pose rate): the layer and
        the cloud are cleared along this path (``swept_clear_radius_m``)."""
        self._swept.add(float(x_m), float(y_m))

    @property
    def swept(self) -> SweptPath:
        """The robot's recorded path."""
        return self._swept

    @property
    def tracked(self) -> list[TrackedObject]:
        """Current objects with bookkeeping (copy of the list)."""
        return list(self._objects)

    def objects(self) -> list[Object3D]:
        """Current objects."""
        return [t.obj for t in self._objects]

    def clear(self) -> None:
        """Forget every object."""
        self._objects.clear()

    # ------------------------------------------------------------------ update
    def update(self, observations: Sequence[Object3D], frame: DepthFrame | None = None,
               stamp_ns: int = 0, robot_xy: Sequence[float] | None = None) -> None:
        """Fuse one frame's observations; count misses of unseen objects.

        Parameters
        ----------
        observations : sequence of Object3D
            Boxes found in this frame (detections and unclassified).
        frame : DepthFrame, optional
            The frame they came from; needed to count misses (objects in view that the
            camera sees through). Without it nothing is missed.
        stamp_ns : int
            Frame time.
        robot_xy : sequence of 2 float, optional
            Robot position (map frame). The robot's own body proves that no object stands
            there: observations and tracked objects whose footprint reaches at least
            ``robot_clear_fraction`` of ``robot_radius_m`` into the robot's disk are
            dropped (else a misplaced box can enclose the robot and end exploration).
        """
        if robot_xy is not None:
            self.note_robot_position(robot_xy[0], robot_xy[1])
        if robot_xy is not None and self.params.robot_clear_fraction > 0:
            observations = [o for o in observations if not self._on_robot(o, robot_xy)]
            self._objects = [t for t in self._objects if not self._on_robot(t.obj, robot_xy)]
        matched: set[int] = set()
        for obs in observations:
            t = self._best_match(obs)
            if t is None:
                t = TrackedObject(self._next_id, obs, last_seen_ns=stamp_ns)
                self._next_id += 1
                self._objects.append(t)
            else:
                t.obj = self._merge(t.obj, obs)
                t.hits += 1
                t.misses = 0
                t.last_seen_ns = stamp_ns
            matched.add(t.id)
        self._merge_overlapping()
        if frame is not None:
            for t, visible in zip(self._objects, self._in_view(frame)):
                if visible and t.id not in matched and self._seen_through(t.obj, frame):
                    t.misses += 1
            self._objects = [t for t in self._objects
                             if t.misses < self.params.clear_after_misses]
        if len(self._objects) > self.params.max_objects:
            self._objects.sort(key=lambda t: (t.misses, -t.hits, -t.last_seen_ns, t.id))
            del self._objects[self.params.max_objects:]
            self._objects.sort(key=lambda t: t.id)

    def _on_robot(self, obj: Object3D, robot_xy: Sequence[float]) -> bool:
        """True when ``obj``'s footprint reaches ``robot_clear_fraction`` of the radius
        into the robot's disk (see :meth:`update`)."""
        # Reaching depth f * R into the disk = the centre within (1 - f) * R of the box
        # (Euclidean distance to the rectangle, 0 inside it).
        margin = self.params.robot_radius_m * (1.0 - self.params.robot_clear_fraction)
        c, s = math.cos(obj.yaw), math.sin(obj.yaw)
        dx, dy = robot_xy[0] - obj.center_xyz[0], robot_xy[1] - obj.center_xyz[1]
        out_u = max(abs(dx * c + dy * s) - 0.5 * obj.size_xyz[0], 0.0)
        out_v = max(abs(-dx * s + dy * c) - 0.5 * obj.size_xyz[1], 0.0)
        return math.hypot(out_u, out_v) <= margin

    @staticmethod
    def _compatible(a: str, b: str) -> bool:
        return a == b or a == UNKNOWN_CLASS or b == UNKNOWN_CLASS

    def _centres_radii(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Footprint centres (N, 2) and circumradii (N,) of the tracked objects."""
        if not self._objects:
            return np.zeros((0, 2)), np.zeros(0)
        c = np.array([t.obj.center_xyz[:2] for t in self._objects], dtype=np.float64)
        r = 0.5 * np.array([math.hypot(t.obj.size_xyz[0], t.obj.size_xyz[1])
                            for t in self._objects], dtype=np.float64)
        return c, r

    def _best_match(self, obs: Object3D) -> TrackedObject | None:
        if not self._objects:
            return None
        centres, radii = self._centres_radii()
        dist = np.hypot(centres[:, 0] - obs.center_xyz[0], centres[:, 1] - obs.center_xyz[1])
        r_obs = 0.5 * math.hypot(obs.size_xyz[0], obs.size_xyz[1])
        # Only footprints whose circumcircles meet can overlap (vectorised pre-filter).
        near = np.flatnonzero((dist <= self.params.merge_distance_m) | (dist < radii + r_obs))
        best, best_key = None, None
        for i in near:
            t = self._objects[int(i)]
            if not self._compatible(t.obj.cls, obs.cls):
                continue
            iou = footprint_iou(t.obj, obs)
            if dist[i] <= self.params.merge_distance_m or iou > self.params.merge_iou:
                key = (iou, -float(dist[i]))
                if best_key is None or key > best_key:
                    best, best_key = t, key
        return best

    def _merge(self, old: Object3D, new: Object3D) -> Object3D:
        """Fuse a re-detection ``new`` into ``old`` (see :func:`fuse_boxes`)."""
        return fuse_boxes(old, new, self.params, self.priors.get(
            old.cls if old.cls != UNKNOWN_CLASS else new.cls))

    def _merge_overlapping(self) -> None:
        """Merge tracked objects that came to overlap (same class, IoU > merge_iou).

        Only pairs whose footprint circumcircles meet are tested (vectorised pre-filter).
        """
        while True:
            centres, radii = self._centres_radii()
            n = len(self._objects)
            if n < 2:
                return
            d = np.hypot(centres[:, None, 0] - centres[None, :, 0],
                         centres[:, None, 1] - centres[None, :, 1])
            ii, jj = np.nonzero(np.triu(d < radii[:, None] + radii[None, :], k=1))
            pair = next(((int(i), int(j)) for i, j in zip(ii, jj)
                         if self._compatible(self._objects[i].obj.cls, self._objects[j].obj.cls)
                         and footprint_iou(self._objects[i].obj, self._objects[j].obj)
                         > self.params.merge_iou), None)
            if pair is None:
                return
            a, b = self._objects[pair[0]], self._objects[pair[1]]
            a.obj = self._merge(a.obj, b.obj)
            a.hits += b.hits
            a.misses = min(a.misses, b.misses)
            a.last_seen_ns = max(a.last_seen_ns, b.last_seen_ns)
            del self._objects[pair[1]]

    def _in_view(self, frame: DepthFrame) -> npt.NDArray[np.bool_]:
        """Objects whose bounding sphere meets the camera's view frustum (up to
        ``max_depth_m``), shape (N,) bool (vectorised pre-filter of :meth:`_seen_through`)."""
        if not self._objects:
            return np.zeros(0, dtype=bool)
        c = np.array([t.obj.center_xyz for t in self._objects], dtype=np.float64)
        r = 0.5 * np.linalg.norm(np.array([t.obj.size_xyz for t in self._objects]), axis=1)
        opt = apply_transform(invert_transform(frame.map_from_optical), c)
        x, y, z = opt[:, 0], opt[:, 1], opt[:, 2]
        k = frame.intrinsics
        ok = (z > -r) & (z < self.params.max_depth_m + r)
        # Side planes through the optical centre (u = -0.5, u = W - 0.5, same for v).
        for f, cc, n, coord in ((k.fx, k.cx, k.width, x), (k.fy, k.cy, k.height, y)):
            lo, hi = -0.5 - cc, n - 0.5 - cc
            ok &= (f * coord - lo * z) / math.hypot(f, lo) >= -r
            ok &= (hi * z - f * coord) / math.hypot(f, hi) >= -r
        return ok

    def _seen_through(self, obj: Object3D, frame: DepthFrame) -> bool:
        """True when the camera sees beyond most of the object's visible measured surface
        points (:attr:`Object3D.surface`; the box's faces when it has none)."""
        p = self.params
        samples = (obj.surface.astype(np.float64) if obj.surface is not None
                   and len(obj.surface) >= p.miss_min_samples
                   else box_samples(obj, p.miss_sample_spacing_m, surface_only=True))
        opt = apply_transform(invert_transform(frame.map_from_optical), samples)
        z = opt[:, 2]
        k = frame.intrinsics
        front = (z > 1e-6) & (z <= p.max_depth_m)
        if not np.any(front):
            return False
        opt, z = opt[front], z[front]
        u = np.round(k.fx * opt[:, 0] / z + k.cx).astype(np.int64)
        v = np.round(k.fy * opt[:, 1] / z + k.cy).astype(np.int64)
        inside = (u >= 0) & (u < k.width) & (v >= 0) & (v < k.height)
        u, v, z = u[inside], v[inside], z[inside]
        measured = frame.depth_m[v, u]
        ok = np.isfinite(measured) & (measured > 0)
        if np.count_nonzero(ok) < p.miss_min_samples:
            return False
        through = measured[ok] > z[ok] + p.miss_depth_margin_m
        return float(np.mean(through)) >= p.miss_free_fraction

    # ----------------------------------------------------------------- outputs
    def rasterize(self, grid: GridMap) -> GridMap:
        """The object layer on ``grid``'s geometry.

        Parameters
        ----------
        grid : GridMap
            Geometry (size, resolution, origin, frame, stamp) to align with; its data is
            not read.

        Returns
        -------
        GridMap
            ``object_value`` inside every footprint (cells whose centre is inside, plus
            the outline so thin objects keep at least one cell), ``background_value``
            elsewhere.
        """
        p = self.params
        img = np.full(grid.shape, p.background_value, dtype=np.int8)
        shift = 4
        polys = []
        for t in self._objects:
            corners = t.obj.footprint()
            rows, cols = grid.world_to_cell_float(corners[:, 0], corners[:, 1])
            # Cell (r, c) spans [c, c + 1): its centre is at c + 0.5 -> pixel c in cv2.
            pts = np.stack([cols - 0.5, rows - 0.5], axis=1) * (1 << shift)
            polys.append(np.round(pts).astype(np.int32))
        # One fill per box: a single fillPoly over all boxes fills even-odd, so the
        # overlap of two boxes (a chair pushed under a desk) would be left out.
        for poly in polys:
            cv2.fillConvexPoly(img, poly, int(p.object_value), lineType=cv2.LINE_8,
                               shift=shift)
        if polys:
            cv2.polylines(img, polys, True, int(p.object_value), lineType=cv2.LINE_8,
                          shift=shift)
            if p.swept_clear_radius_m > 0 and len(self._swept):
                img[self._swept.mask(grid, p.swept_clear_radius_m)] = p.background_value
        return grid.with_data(img)

    def virtual_cloud(self, spacing_m: float | None = None) -> npt.NDArray[np.float32]:
        """Points filling every box (for a Nav2 voxel/obstacle layer), shape (N, 3).

        The spacing grows (doubling) until at most ``max_cloud_points`` points remain.

        Raises
        ------
        ValueError
            If ``spacing_m`` is not > 0.
        """
        spacing = self.params.cloud_spacing_m if spacing_m is None else float(spacing_m)
        if not spacing > 0:
            raise ValueError(f"spacing_m must be > 0, got {spacing_m}")
        if not self._objects:
            return np.zeros((0, 3), dtype=np.float32)
        while True:
            total = sum(int(np.prod([max(math.ceil(s / spacing), 1) for s in t.obj.size_xyz]))
                        for t in self._objects)
            if total <= self.params.max_cloud_points:
                break
            spacing *= 2.0
        clouds = [box_samples(t.obj, spacing, surface_only=False) for t in self._objects]
        cloud = np.vstack(clouds)
        r = self.params.swept_clear_radius_m
        if r > 0 and len(self._swept) and len(cloud):
            # Rasterise the swept corridor over the cloud's extent (cells of half the
            # spacing) and drop the points on it, as rasterize() drops the cells.
            res = 0.5 * spacing
            lo = cloud[:, :2].min(axis=0) - res
            shape = tuple(int(v) for v in np.ceil((cloud[:, :2].max(axis=0) - lo) / res) + 2)
            geo = GridMap(np.zeros((shape[1], shape[0]), np.int8), res,
                          (float(lo[0]), float(lo[1])))
            rows, cols = geo.world_to_cells(cloud[:, 0], cloud[:, 1])
            cloud = cloud[~self._swept.mask(geo, r)[rows, cols]]
        return cloud.astype(np.float32)

    def boxes(self) -> list[tuple[int, Object3D]]:
        """``(id, Object3D)`` of every object (for markers)."""
        return [(t.id, t.obj) for t in self._objects]


# ---------------------------------------------------------------------- pipeline


@dataclass
class FrameResult:
    """Objects found in one frame and the boxes dropped on the way (with reasons)."""

    objects: list[Object3D]
    unknown: list[Object3D]
    dropped: list[str]


def process_frame(frame: DepthFrame, detections: Iterable[BoxDetection],
                  priors: dict[str, SizePrior], params: ObjectParams,
                  scan_xy_map: npt.NDArray[np.floating] | None = None,
                  walls: WallMask | None = None) -> FrameResult:
    """Detections + depth (+ scan) of one frame -> 3D boxes in the map frame.

    Detections below ``min_score`` or of classes without a prior are skipped; malformed
    or out-of-image boxes are dropped and named in ``FrameResult.dropped``.

    Parameters
    ----------
    frame : DepthFrame
    detections : iterable of BoxDetection
    priors : dict of str to SizePrior
    params : ObjectParams
    scan_xy_map : ndarray, shape (N, 2), optional
        Laser points in the map frame; None or empty skips unclassified objects.
    walls : WallMask, optional
        From :func:`wall_mask` of the current 2D map: depth points on walls are dropped
        before clustering (``drop_wall_points``), so a desk against a wall is not merged
        with it and a chair seen through a doorway is not the jamb; a post's overhang
        must lie over free map cells (:func:`unknown_objects`).

    Returns
    -------
    FrameResult
    """
    objects: list[Object3D] = []
    dropped: list[str] = []
    dets: list[BoxDetection] = []
    segs: list[_Clusters | None] = []
    for det in detections:
        if det.score < params.min_score or det.cls_name == UNKNOWN_CLASS \
                or det.cls_name not in priors:
            continue
        try:
            seg = _cluster_detection(frame, det.box_xyxy, params, walls, priors[det.cls_name])
        except ValueError as err:
            dropped.append(f"{det.cls_name}: {err}")
            continue
        dets.append(det)
        segs.append(seg)
    for det, seg, first in zip(dets, segs, _assign_clusters(segs, params)):
        if seg is None or first < 0:
            continue
        for lab in seg.ranked[first:]:
            fit = _fit_cluster(seg, lab, frame, det.cls_name, det.score,
                               priors[det.cls_name], params)
            if fit is not None:
                objects.append(fit[0])
                break
    unknown: list[Object3D] = []
    if params.unknown_enabled and scan_xy_map is not None and len(scan_xy_map):
        unknown = unknown_objects(frame, scan_xy_map, params, objects,
                                  priors.get(UNKNOWN_CLASS), walls)
    return FrameResult(objects, unknown, dropped)
