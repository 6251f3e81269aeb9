"""QoS profiles shared by every node (one place, so publishers and subscribers match)."""

from __future__ import annotations

from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy,
                       qos_profile_sensor_data)

#: Maps, the object costmap, region labels and the done flag: reliable and latched, so a
#: late subscriber still receives the last message (what map_server/slam_toolbox publish).
MAP_QOS = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)

#: Sensor streams (scan, images, camera info): best effort, keep last 5.
SENSOR_QOS = qos_profile_sensor_data

#: Poses, goals, plans and other small command/state messages.
RELIABLE_QOS = QoSProfile(depth=10, history=HistoryPolicy.KEEP_LAST,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)


#: Pose streams (odom at up to 100 Hz): reliable, deep enough to keep every pose that
#: arrives while a node is busy with a camera frame (poses are matched to image stamps).
POSE_QOS = QoSProfile(depth=100, history=HistoryPolicy.KEEP_LAST,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


def map_qos(transient_local: bool = True) -> QoSProfile:
    """Map QoS; ``transient_local=False`` subscribes to a volatile map publisher.

    A transient-local subscriber never matches a volatile publisher, so nodes expose the
    durability of their map subscription as a parameter.
    """
    if transient_local:
        return MAP_QOS
    return QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


#: An action's ``_action/status`` topic: what rclpy/rclcpp action servers publish with
#: (reliable, transient local, depth 1: a late subscriber gets the latest array).
ACTION_STATUS_QOS = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                               reliability=ReliabilityPolicy.RELIABLE,
                               durability=DurabilityPolicy.TRANSIENT_LOCAL)
