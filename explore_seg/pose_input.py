"""The robot pose of ``object_costmap`` and ``target_selector``: subscriptions + PoseFusion.

``pose_topic_type`` picks the source (:data:`explore_seg.core.pose_fusion.POSE_SOURCES`):
``odom`` subscribes nav_msgs/Odometry on ``odom`` (map frame), ``pose``
geometry_msgs/PoseWithCovarianceStamped on ``pose`` (map frame), ``fused`` both (odometry in
``pose_fusion.odom_frame``) and composes them in
:class:`~explore_seg.core.pose_fusion.PoseFusion`. Malformed messages (wrong frame, NaN,
negative stamp) are dropped with a throttled warning; fusion events (reset on time going
back, loop-closure re-key, a SLAM pose without odometry) are logged once per period.
The callbacks may run in their own callback group while a timer reads the pose on another
thread: every access to the fusion holds a lock.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable

from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile

from explore_seg import convert
from explore_seg.core.grid import GridMap
from explore_seg.core.limits import InputLimits
from explore_seg.core.pose_fusion import Pose2D, PoseFusion, PoseFusionParams

#: (stamp ns, map-frame pose) -> None: called for every new newest pose.
PoseCallback = Callable[[int, Pose2D], None]


@dataclass(frozen=True)
class PoseHooks:
    """What a :class:`PoseInput` asks of its node.

    ``map_frame()`` names the frame map-frame poses must be in (None: not known yet, not
    checked); ``limits()`` the node's current input limits; ``on_stamp("pose", t_ns)``
    sees every accepted stamp of the stream that sets the pose's rate (the node's time
    model; not the SLAM poses of ``fused``), ``on_pose`` every new newest pose;
    ``grid()`` is the node's current map (None before one): a map-frame pose beyond its
    bounds by more than the limits' margin is dropped;
    ``warn(key, text)`` is the node's throttled warning, ``drop(text)`` its (throttled,
    counted) report of a dropped pose message.
    """

    map_frame: Callable[[], str | None]
    limits: Callable[[], InputLimits]
    warn: Callable[[str, str], None]
    drop: Callable[[str], None]
    on_pose: PoseCallback | None = None
    on_stamp: Callable[[str, int], None] | None = None
    grid: Callable[[], GridMap | None] | None = None


class PoseInput:
    """Pose subscriptions of one node feeding a :class:`PoseFusion`.

    ``hooks`` (:class:`PoseHooks`) are what it asks of the node. ``subscribe`` creates the
    subscriptions (default ``node.create_subscription``; a
    :class:`~explore_seg.done_gate.DoneGate`'s to drop them while idle after done), in
    ``callback_group``.
    """

    def __init__(self, node: Node, source: str, params: PoseFusionParams, qos: QoSProfile,
                 hooks: PoseHooks, *, callback_group: Any = None,
                 subscribe: Callable[..., Any] | None = None) -> None:
        self.fusion = PoseFusion(source, params)
        self._clock = node.get_clock()
        #: ROS time (ns) of the last accepted pose message, None before the first.
        self.arrival_ns: int | None = None
        self._lock = threading.Lock()
        self._map_frame, self._limits = hooks.map_frame, hooks.limits
        self._warn, self._drop = hooks.warn, hooks.drop
        self._on_pose, self._on_stamp, self._grid = hooks.on_pose, hooks.on_stamp, hooks.grid
        sub = subscribe if subscribe is not None else node.create_subscription
        if source in ("odom", "fused"):
            sub(Odometry, "odom", self._on_odom, qos, callback_group=callback_group)
        if source in ("pose", "fused"):
            sub(PoseWithCovarianceStamped, "pose", self._on_slam, qos,
                callback_group=callback_group)

    @property
    def source(self) -> str:
        """``odom``, ``pose`` or ``fused``."""
        return self.fusion.source

    # ------------------------------------------------------------- callbacks
    def _on_odom(self, msg: Odometry) -> None:
        frame = (self.fusion.params.odom_frame if self.source == "fused"
                 else self._map_frame())
        self._add("odom", msg, frame, convert.pose2d_from_odometry, self.fusion.add_odom)

    def _on_slam(self, msg: PoseWithCovarianceStamped) -> None:
        self._add("pose", msg, self._map_frame(), convert.pose2d_from_pose_msg,
                  self.fusion.add_map_pose)

    def _add(self, stream: str, msg: Any, frame: str | None, to_2d: Callable[..., Pose2D],
             add: Callable[[int, Pose2D], Any]) -> None:
        try:
            if frame is not None:
                convert.check_frame(msg.header.frame_id, frame, "pose")
            pose = to_2d(msg, self._limits())
            grid_now = self._grid() if self._grid is not None else None
            in_map_frame = stream == "pose" or self.source == "odom"
            if grid_now is not None and in_map_frame:
                self._limits().check_near_map(pose[0], pose[1], grid_now)
            t_ns = convert.checked_stamp_ns(msg.header.stamp, "pose")
            with self._lock:
                event = add(t_ns, pose)
                newest = self.fusion.latest()
        except ValueError as err:
            self._drop(f"{type(msg).__name__} on '{stream}': {err}")
            return
        self.arrival_ns = self._clock.now().nanoseconds
        if event is not None:
            self._warn(f"pose_fusion_{event.kind}", f"pose fusion: {event.message}")
        # Only the stream that sets the pose's rate feeds the node's time model: SLAM poses
        # of the fused source lag behind the odometry and pause while the robot stands
        # still (the fusion checks their time line itself).
        if self._on_stamp is not None and (stream == "pose") == (self.source == "pose"):
            self._on_stamp("pose", t_ns)
        if newest is not None and self._on_pose is not None:
            self._on_pose(*newest)

    # --------------------------------------------------------------- queries
    def pose_at(self, t_ns: int, tol_ns: int) -> Pose2D | None:
        """Map-frame pose at ``t_ns`` (inputs within ``tol_ns``), None when there is none."""
        with self._lock:
            return self.fusion.pose_at(t_ns, tol_ns)

    def latest(self) -> tuple[int, Pose2D] | None:
        """Newest (stamp ns, map-frame pose)."""
        with self._lock:
            return self.fusion.latest()

    def newest_ns(self) -> int | None:
        """Newest stamp a pose can be given for."""
        with self._lock:
            return self.fusion.newest_ns()

    def span_ns(self) -> tuple[int, int] | None:
        """(oldest, newest) stamp a pose can be given for, None before the first."""
        with self._lock:
            return self.fusion.span_ns()

    def describe(self) -> str:
        """What the fusion holds, for a log line."""
        with self._lock:
            return f"{self.source}: {self.fusion.describe()}"

    def drop_newer(self, horizon_ns: int) -> None:
        """Forget inputs stamped after ``horizon_ns`` (the node's clock jumped back)."""
        with self._lock:
            self.fusion.drop_newer(horizon_ns)

    def clear(self) -> None:
        """Forget every input."""
        with self._lock:
            self.fusion.clear()

    def set_params(self, params: PoseFusionParams) -> None:
        """New ``pose_fusion.*`` settings."""
        with self._lock:
            self.fusion.set_params(params)
