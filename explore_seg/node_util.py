"""Shared entry point and small helpers for the package's rclpy nodes."""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Callable, Sequence

import rclpy
from rclpy.executors import (ExternalShutdownException, MultiThreadedExecutor,
                             SingleThreadedExecutor)
from rclpy.node import Node


def config_file(name: str) -> Path | None:
    """``config/<name>`` of the package: from its installed share folder (colcon), else
    from the source tree; None when neither has it."""
    try:
        from ament_index_python.packages import get_package_share_directory

        cand = Path(get_package_share_directory("explore_seg")) / "config" / name
        if cand.is_file():
            return cand
    except Exception:  # noqa: BLE001 - PackageNotFoundError or ament_index missing
        pass
    cand = Path(__file__).resolve().parents[1] / "config" / name
    return cand if cand.is_file() else None


def run(node_cls: Callable[..., Node] | Sequence[Callable[..., Node]],
        args: list[str] | None = None, num_threads: int = 1) -> int:
    """Main for console scripts: init, spin one or several nodes, exit cleanly.

    SIGINT (Ctrl-C) and external shutdown end the spin; the nodes are destroyed and the
    context shut down. ``num_threads > 1`` spins with a MultiThreadedExecutor (each node
    keeps its default mutually exclusive callback group, so one node's callbacks never
    overlap); beware that rclpy's MultiThreadedExecutor busy-waits while such a callback
    runs (see :mod:`explore_seg.explorer`). Returns 0.
    """
    classes = list(node_cls) if isinstance(node_cls, (list, tuple)) else [node_cls]
    rclpy.init(args=args)
    nodes: list[Node] = []
    executor = (MultiThreadedExecutor(num_threads=num_threads) if num_threads > 1
                else SingleThreadedExecutor())
    try:
        for cls in classes:
            node = cls()
            nodes.append(node)
            executor.add_node(node)
        nodes[0].get_logger().info(
            "running " + ", ".join(n.get_name() for n in nodes) + " (Ctrl-C to stop)")
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:
        # SIGINT shuts the context down from rclpy's signal handler; when that lands while
        # the executor builds its wait set, rclpy raises RCLError (a RuntimeError, "context
        # is not valid") instead of ExternalShutdownException: the same clean stop.
        if rclpy.ok():
            raise
    finally:
        # Stop the executor (and its worker threads) before the nodes go away, so no
        # callback runs on a destroyed node.
        executor.shutdown(timeout_sec=5.0)
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0



class WarnThrottle:
    """Warn at most once per ``period_s`` (wall time) for each cause.

    rclpy's ``throttle_duration_sec`` throttles per call site; malformed input of several
    kinds arriving through one callback needs a throttle per cause instead.
    """

    def __init__(self, node: Node, period_s: float = 5.0) -> None:
        self._logger = node.get_logger()
        self._period_s = period_s
        self._last: dict[str, float] = {}

    def __call__(self, key: str, msg: str) -> None:
        """Log ``msg`` unless a warning of cause ``key`` was logged less than a period ago."""
        now = time.monotonic()
        if now - self._last.get(key, -math.inf) >= self._period_s:
            self._last[key] = now
            self._logger.warn(msg)
