"""Shared entry point and small helpers for the package's rclpy nodes."""

from __future__ import annotations

from typing import Callable, Sequence

import rclpy
from rclpy.executors import (ExternalShutdownException, MultiThreadedExecutor,
                             SingleThreadedExecutor)
from rclpy.node import Node


def run(node_cls: Callable[..., Node] | Sequence[Callable[..., Node]],
        args: list[str] | None = None, num_threads: int = 1) -> int:
    """Main for console scripts: init, spin one or several nodes, exit cleanly.

    SIGINT (Ctrl-C) and external shutdown end the spin; the nodes are destroyed and the
    context shut down. ``num_threads > 1`` spins with a MultiThreadedExecutor (each node
    keeps its default mutually exclusive callback group, so one node's callbacks never
    overlap, while a slow detector does not hold up target selection). Returns 0.
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
    finally:
        # Stop the executor (and its worker threads) before the nodes go away, so no
        # callback runs on a destroyed node.
        executor.shutdown(timeout_sec=5.0)
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0

