"""SLAM corrections seen from a node's inputs: re-exported from
:mod:`explore_seg.core.corrections` (the object layer and the scan overlay share them)."""

from explore_seg.core.corrections import (OCCUPIED_THRESHOLD, Correction, CorrectionDetector,
                                          CorrectionParams, Pose2D, moved_cells,
                                          occupied_xy, pose_jump)

__all__ = ["OCCUPIED_THRESHOLD", "Correction", "CorrectionDetector", "CorrectionParams",
           "Pose2D", "moved_cells", "occupied_xy", "pose_jump"]
