"""Helper process for test_transport: republishes map, cloud and image on *_echo topics.

Run as ``python echo_node.py``; the parent sets ROS_DOMAIN_ID and LOCALHOST discovery.
Exits on SIGINT/SIGTERM or after ``--timeout`` seconds.
"""

from __future__ import annotations

import argparse
import signal
import sys
import time

import rclpy
from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from sensor_msgs.msg import Image, PointCloud2

sys.path.insert(0, __file__.rsplit("/test/", 1)[0])
from explore_seg import convert  # noqa: E402
from explore_seg.qos import MAP_QOS, RELIABLE_QOS  # noqa: E402


class Echo(Node):
    def __init__(self) -> None:
        super().__init__("echo_node")
        self.pubs = {}
        for topic, typ, qos in (("map", OccupancyGrid, MAP_QOS), ("cloud", PointCloud2, RELIABLE_QOS),
                                ("image", Image, RELIABLE_QOS)):
            self.pubs[topic] = self.create_publisher(typ, topic + "_echo", qos)
            self.create_subscription(typ, topic, self._make_cb(topic, typ), qos)

    def _make_cb(self, topic, typ):
        def cb(msg):
            # decode + re-encode through convert, so the round trip goes through our code
            if typ is OccupancyGrid:
                out = convert.grid_to_msg(convert.grid_from_msg(msg))
            elif typ is PointCloud2:
                out = convert.cloud_to_msg(convert.cloud_from_msg(msg), msg.header)
            else:
                out = convert.image_to_msg(convert.image_from_msg(msg), msg.encoding, msg.header)
            self.pubs[topic].publish(out)
        return cb


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--timeout", type=float, default=60.0)
    a = ap.parse_args()
    rclpy.init()
    node = Echo()
    stop = {"flag": False}
    signal.signal(signal.SIGTERM, lambda *_: stop.update(flag=True))
    print("READY", flush=True)
    end = time.monotonic() + a.timeout
    try:
        while rclpy.ok() and not stop["flag"] and time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.05)
    except KeyboardInterrupt:
        pass
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
