"""Simulated sensors of the 2.5D world: a planar lidar and an RGB-D camera.

* :class:`Lidar` casts ``num_beams`` rays in the scan plane against the rectangles and
  circles that the plane cuts out of the world's primitives (analytic ray/segment and
  ray/circle intersection). Each scan first culls primitives beyond the range and then
  tests every primitive only against the beams inside its angular extent, so the work
  grows with what the robot sees, not with the size of the world.
* :class:`DepthCamera` ray-casts every pixel against the upright boxes and cylinders in
  3D (slab test) and the floor ``z = 0``. Primitives are culled by range and view
  frustum, projected to a screen rectangle (exactly, with near-plane clipping) and
  drawn front to back; only the pixels of that rectangle are tested, and a primitive
  wholly behind what is already drawn in its rectangle is skipped.

Conventions: robot poses are ``(x, y, yaw)`` of ``base_footprint`` in the world frame;
mounts are given relative to ``base_footprint``. Beam ``k`` of a scan points at
``angle_min + k * angle_increment`` from the robot heading with ``angle_min = -pi`` and
``angle_increment = 2 pi / num_beams``. The camera optical frame is REP-103 optical
(x right, y down, z forward); depth is the optical z, NaN where nothing is hit within
``range_max_m``.

Modules: :mod:`~sim_bridge.sensors.lidar`, :mod:`~sim_bridge.sensors.camera` and
:mod:`~sim_bridge.sensors.common` (the semantic class table); this package re-exports
their public names.
"""

from sim_bridge.sensors.camera import CameraFrame, CameraParams, DepthCamera, camera_pose_in_world
from sim_bridge.sensors.common import CLASS_IDS, CLASS_NAMES, CLASS_RGB, FLOOR_RGB
from sim_bridge.sensors.lidar import Lidar, LidarParams

__all__ = ["CLASS_IDS", "CLASS_NAMES", "CLASS_RGB", "FLOOR_RGB", "CameraFrame", "CameraParams",
           "DepthCamera", "Lidar", "LidarParams", "camera_pose_in_world"]
