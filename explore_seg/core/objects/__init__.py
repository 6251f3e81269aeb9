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

Generic obstacles (:class:`DepthObstacles`, Nav2's voxel / obstacle layer idea): every depth
point between a floor margin and the robot's height marks a voxel, cleared where the
camera later sees through it; their columns join the boxes in the layer, so an object of
any class (a bin, a box, a shelf overhang) is an obstacle once seen.

:class:`ObjectMap` fuses the per-frame boxes in the map frame (merging re-detections by
their measured footprints, :func:`fuse_boxes`: partial views add up, noise and the sides
grown by the prior do not; counting misses where the camera sees through an object) and
renders the occupancy layer, the virtual point cloud and the boxes.

Frames: ``map`` (x, y on the floor, z up, z = 0 at the floor), ``base_link`` on the floor
at the robot pose, camera optical frame (see :mod:`explore_seg.core.camera`).

Modules, each importing only those above it: :mod:`~.params` (:class:`ObjectParams`,
:class:`ObjectCostmapNodeParams`), :mod:`~.priors` (size priors), :mod:`~.cloud`
(point-cloud steps), :mod:`~.geometry` (footprints), :mod:`~.frame` (the depth frame,
back-projection), :mod:`~.boxes` (:class:`Object3D`, box fitting, the prior's clamp),
:mod:`~.walls` (the 2D map's walls), :mod:`~.depth_obstacles` (generic obstacles from
depth, :class:`DepthObstacles`), :mod:`~.detections` (one detection -> box),
:mod:`~.legs` (unclassified objects), :mod:`~.fusion` (:func:`fuse_boxes`),
:mod:`~.object_map` (:class:`ObjectMap`), :mod:`~.pipeline` (:func:`process_frame`) and
:mod:`~.corrections` (SLAM corrections from poses and maps, :class:`CorrectionDetector`).
This package re-exports their public names.
"""

from explore_seg.core.objects.boxes import (MAX_SURFACE_POINTS, Object3D, clamp_to_prior,
                                            fit_box, plausible_extent, surface_points)
from explore_seg.core.objects.cloud import (box_mask, box_stride, euclidean_clusters,
                                            pixel_grid_edges, statistical_outlier_mask,
                                            voxel_downsample)
from explore_seg.core.objects.depth_obstacles import DepthObstacles
from explore_seg.core.objects.corrections import Correction, CorrectionDetector
from explore_seg.core.objects.detections import (DetectionClusters, assign_clusters,
                                                 cluster_detection, fit_cluster,
                                                 object_from_detection, rank_clusters,
                                                 segment_detection, select_cluster)
from explore_seg.core.objects.frame import BoxDetection, DepthFrame, frame_points, view_cut
from explore_seg.core.objects.fusion import footprint_iou, fuse_boxes
from explore_seg.core.objects.geometry import (footprint_orientation, points_in_rect,
                                               rect_corners, top_cover, top_fraction,
                                               wrap_half_pi)
from explore_seg.core.objects.legs import group_legs, scan_legs, scan_posts, unknown_objects
from explore_seg.core.objects.object_map import ObjectMap, TrackedObject, box_samples
from explore_seg.core.objects.params import (ORIENTATION_METHODS, POSE_SOURCES, UNKNOWN_CLASS,
                                             ObjectCostmapNodeParams, ObjectParams,
                                             parse_class_ids)
from explore_seg.core.objects.pipeline import FrameResult, process_frame
from explore_seg.core.objects.priors import SizePrior, default_priors_path, load_priors
from explore_seg.core.objects.walls import WALL_OCCUPIED_THRESHOLD, WallMask, wall_mask

__all__ = [
    # params, priors
    "UNKNOWN_CLASS", "ORIENTATION_METHODS", "POSE_SOURCES", "ObjectParams",
    "ObjectCostmapNodeParams", "parse_class_ids", "SizePrior", "default_priors_path",
    "load_priors",
    # cloud, geometry, frame
    "box_mask", "box_stride", "voxel_downsample", "pixel_grid_edges",
    "statistical_outlier_mask", "euclidean_clusters", "rect_corners", "points_in_rect",
    "footprint_orientation", "wrap_half_pi", "top_fraction", "top_cover", "BoxDetection",
    "DepthFrame", "frame_points", "view_cut",
    # boxes, walls, detections, legs
    "Object3D", "MAX_SURFACE_POINTS", "surface_points", "clamp_to_prior", "fit_box",
    "plausible_extent", "WALL_OCCUPIED_THRESHOLD", "WallMask", "wall_mask", "rank_clusters", "select_cluster",
    "DetectionClusters", "cluster_detection", "fit_cluster", "segment_detection",
    "object_from_detection", "assign_clusters", "scan_legs", "scan_posts", "group_legs",
    "unknown_objects",
    # fusion, object map, pipeline
    "DepthObstacles", "footprint_iou", "fuse_boxes", "TrackedObject", "box_samples", "ObjectMap",
    "FrameResult", "process_frame",
    # corrections
    "Correction", "CorrectionDetector",
]
