"""Test harness: private ROS 2 contexts, LOCALHOST discovery, per-run domain id.

Every test that touches rclpy uses the ``ros`` fixture: a private ``Context`` on this
run's domain id with a ``SingleThreadedExecutor``; ``spin_until`` spins until a condition
holds or fails naming what never arrived. Nothing here sleeps to synchronise.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

# Must happen before rclpy is imported anywhere: DDS stays on this machine, and
# concurrent test runs on one host do not see each other.
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_DOMAIN_ID", str(20 + os.getpid() % 70))
os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="explore_seg_roslog_"))
# An exception in a node's periodic work fails the test instead of being logged and
# survived (explore_seg.node_util.failsafe); test_failsafe_* switch it off.
os.environ.setdefault("EXPLORE_SEG_STRICT", "1")
# The observable-region disk cache (sim_bridge/observable.py) goes to a folder of this
# run, not the user's ~/.cache.
os.environ.setdefault("EXPLORE_SEG_CACHE_DIR", tempfile.mkdtemp(prefix="explore_seg_cache_"))

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))
TEST_DIR = Path(__file__).resolve().parent
if str(TEST_DIR) not in sys.path:
    sys.path.insert(0, str(TEST_DIR))

import pytest  # noqa: E402

DOMAIN_ID = int(os.environ["ROS_DOMAIN_ID"])


class RosHarness:
    """A private rclpy context + executor for one test."""

    def __init__(self) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        self.context = Context()
        rclpy.init(context=self.context, domain_id=DOMAIN_ID)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes: list = []

    def add(self, node):
        """Add a node to the executor (destroyed at teardown); returns it."""
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def node(self, name: str):
        """A plain helper node on this context."""
        from rclpy.node import Node

        return self.add(Node(name, context=self.context))

    def spin_until(self, predicate: Callable[[], bool], timeout_s: float = 10.0,
                   what: str = "condition") -> None:
        """Spin until ``predicate()`` is true; AssertionError naming ``what`` on timeout."""
        deadline = time.monotonic() + timeout_s
        while not predicate():
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out after {timeout_s:.1f} s waiting for {what}")
            self.executor.spin_once(timeout_sec=0.02)

    def spin_for(self, seconds: float) -> None:
        """Process callbacks for a fixed wall time (for 'nothing must happen' checks)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def close(self) -> None:
        import rclpy

        for n in self.nodes:
            try:
                self.executor.remove_node(n)
            except Exception:  # noqa: BLE001 - teardown must not mask the test result
                pass
            n.destroy_node()
        self.executor.shutdown()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def ros():
    """Private rclpy Context + SingleThreadedExecutor on this run's domain id."""
    h = RosHarness()
    try:
        yield h
    finally:
        h.close()
