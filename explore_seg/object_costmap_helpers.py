"""Helpers of the ``object_costmap`` node: stamp pairing, RViz markers, and what the node
does at a SLAM correction (:class:`CorrectionHandler`)."""

from __future__ import annotations

from typing import Any, Callable

from visualization_msgs.msg import Marker, MarkerArray

from explore_seg import convert
from explore_seg.core.grid import quaternion_from_yaw
from explore_seg.core.objects import (UNKNOWN_CLASS, CorrectionDetector, Object3D, ObjectMap)

#: Marker colours (r, g, b) per class; others use the last entry.
_CLASS_RGB = {"chair": (0.9, 0.3, 0.2), "dining table": (0.6, 0.4, 0.2),
              "couch": (0.5, 0.3, 0.6), "bed": (0.3, 0.5, 0.8), UNKNOWN_CLASS: (0.9, 0.8, 0.1),
              "": (0.6, 0.6, 0.6)}


def stamp_ns(msg: Any) -> int:
    """A message's header stamp in ns."""
    return convert.stamp_to_ns(msg.header.stamp)


class CorrectionHandler:
    """The node's SLAM corrections: the detector fed from the pose and map callbacks
    (any thread), and, in the processing thread, :meth:`apply`: each correction found
    drops from ``objects`` what was placed since the previous one, but moves what was
    seen within ``correction_move_recent_s`` before it with the correction's jump when a
    pose jump showed it (:attr:`Correction.jump`), as the lock step does at the
    simulator's closures (:meth:`ObjectMap.forget_since`).

    ``log(text)`` reports each correction once (they are seconds apart at the least).
    """

    def __init__(self, detector: CorrectionDetector, objects: ObjectMap,
                 log: Callable[[str], None]) -> None:
        self.detector = detector
        self._objects = objects
        self._log = log
        self._previous_ns: int | None = None
        #: Corrections applied.
        self.applied = 0

    def apply(self) -> bool:
        """Apply the corrections found since the last call; True when the object layer
        changed."""
        changed = False
        for c in self.detector.take():
            dropped = self._objects.forget_since(self._previous_ns, c.jump, c.stamp_ns)
            self._previous_ns = c.stamp_ns
            self.applied += 1
            changed |= dropped
            what = ("the boxes and depth voxels placed since the previous one are dropped"
                    + ("" if c.jump is None else ", those of the last moments moved with "
                       f"the pose's jump ({c.jump[0]:.2f} m, {c.jump[1]:.2f} m, "
                       f"{c.jump[2]:.3f} rad)"))
            self._log(f"SLAM correction at {c.stamp_ns / 1e9:.3f} s ({c.source}: {c.detail}): "
                      + (what if dropped else "nothing placed since the previous one"))
        return changed

    def time_went_back(self) -> None:
        """The clock jumped back: the previous pose, map and correction are of the old
        time line."""
        self.detector.reset()
        self._previous_ns = None


def closest(msgs, t_ns: int, tol_ns: int):
    """The message of ``msgs`` stamped nearest ``t_ns``, None when none is within ``tol_ns``."""
    best = min(msgs, key=lambda m: abs(stamp_ns(m) - t_ns), default=None)
    if best is None or abs(stamp_ns(best) - t_ns) > tol_ns:
        return None
    return best


def markers(boxes: list[tuple[int, Object3D]], header) -> MarkerArray:
    """A DELETEALL, then a CUBE and a class label per object (marker id = object id)."""
    out = MarkerArray()
    clear = Marker()
    clear.header = header
    clear.action = Marker.DELETEALL
    out.markers.append(clear)
    for oid, obj in boxes:
        qx, qy, qz, qw = quaternion_from_yaw(obj.yaw)
        r, g, b = _CLASS_RGB.get(obj.cls, _CLASS_RGB[""])
        cube = Marker()
        cube.header = header
        cube.ns = "objects"
        cube.id = int(oid)
        cube.type = Marker.CUBE
        cube.action = Marker.ADD
        cube.pose.position.x, cube.pose.position.y, cube.pose.position.z = obj.center_xyz
        cube.pose.orientation.x, cube.pose.orientation.y = qx, qy
        cube.pose.orientation.z, cube.pose.orientation.w = qz, qw
        cube.scale.x, cube.scale.y, cube.scale.z = (max(float(s), 1e-3) for s in obj.size_xyz)
        cube.color.r, cube.color.g, cube.color.b, cube.color.a = r, g, b, 0.5
        out.markers.append(cube)
        text = Marker()
        text.header = header
        text.ns = "labels"
        text.id = int(oid)
        text.type = Marker.TEXT_VIEW_FACING
        text.action = Marker.ADD
        text.pose.position.x, text.pose.position.y = obj.center_xyz[0], obj.center_xyz[1]
        text.pose.position.z = obj.center_xyz[2] + 0.5 * obj.size_xyz[2] + 0.15
        text.pose.orientation.w = 1.0
        text.scale.z = 0.15
        text.color.r = text.color.g = text.color.b = text.color.a = 1.0
        text.text = f"{obj.cls} {obj.score:.2f}"
        out.markers.append(text)
    return out
