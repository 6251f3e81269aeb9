"""Shared entry point and small helpers for the package's rclpy nodes."""

from __future__ import annotations

import functools
import math
import os
import signal
import threading
import time
import traceback
from pathlib import Path
from typing import Any, Callable, Sequence, TypeVar

import rclpy
from rclpy.executors import (ExternalShutdownException, MultiThreadedExecutor,
                             SingleThreadedExecutor)
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions


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

    SIGINT (Ctrl-C), SIGTERM and external shutdown end the spin; the nodes are destroyed
    and the context shut down. ``num_threads > 1`` spins with a MultiThreadedExecutor (each
    node keeps its default mutually exclusive callback group, so one node's callbacks never
    overlap); beware that rclpy's MultiThreadedExecutor busy-waits while such a callback
    runs (see :mod:`explore_seg.explorer`). Returns 0.

    rclpy's own signal handler is off: it shuts the context down from the signal, which
    races with the executor building its wait set and with node teardown (a crash or a hang
    on Ctrl-C). Here a signal only sets a flag; the spin loop sees it within
    :data:`STOP_POLL_S` and the teardown runs in order on the main thread. A second SIGINT
    raises KeyboardInterrupt at once, for a stop that hangs in a callback.
    """
    classes = list(node_cls) if isinstance(node_cls, (list, tuple)) else [node_cls]
    stop = StopFlag()
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    nodes: list[Node] = []
    executor = (MultiThreadedExecutor(num_threads=num_threads) if num_threads > 1
                else SingleThreadedExecutor())
    try:
        for cls in classes:
            if stop.is_set():
                break
            node = cls()
            nodes.append(node)
            executor.add_node(node)
        if nodes and not stop.is_set():
            nodes[0].get_logger().info(
                "running " + ", ".join(n.get_name() for n in nodes) + " (Ctrl-C to stop)")
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=STOP_POLL_S)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError:
        # A context shut down from elsewhere while the executor builds its wait set makes
        # rclpy raise RCLError (a RuntimeError, "context is not valid"): a clean stop too.
        if rclpy.ok():
            raise
    finally:
        # Stop the executor (and its worker threads) before the nodes go away, so no
        # callback runs on a destroyed node.
        executor.shutdown(timeout_sec=5.0)
        for node in nodes:
            node.destroy_node()
        rclpy.try_shutdown()
        stop.restore()
    return 0


#: Longest wait of the spin loop before it looks at the stop flag (s).
STOP_POLL_S = 0.1


class StopFlag:
    """SIGINT / SIGTERM set this flag instead of raising; :meth:`restore` puts the previous
    handlers back. After the first SIGINT the default handler is back, so a second Ctrl-C
    raises KeyboardInterrupt in whatever runs."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self._event = threading.Event()
        self._previous = {sig: signal.signal(sig, self._on_signal) for sig in self.SIGNALS}

    def _on_signal(self, signum: int, _frame: Any) -> None:
        self._event.set()
        if signum == signal.SIGINT:
            signal.signal(signal.SIGINT, signal.default_int_handler)

    def is_set(self) -> bool:
        """Whether a stop signal arrived."""
        return self._event.is_set()

    def restore(self) -> None:
        """Put back the handlers that were installed before this flag."""
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


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
        if self._due(key):
            self._logger.warn(msg)

    def info(self, key: str, msg: str) -> None:
        """The same at info level."""
        if self._due(key):
            self._logger.info(msg)

    def error(self, key: str, msg: str) -> None:
        """The same at error level."""
        if self._due(key):
            self._logger.error(msg)

    def _due(self, key: str) -> bool:
        now = time.monotonic()
        if now - self._last.get(key, -math.inf) < self._period_s:
            return False
        self._last[key] = now
        return True


#: Set to 1 (the tests do) to let an exception in a node's periodic work propagate
#: instead of being logged and survived (:func:`failsafe`).
STRICT_ENV = "EXPLORE_SEG_STRICT"
#: Seconds between two logged failures of the same work in one node.
FAILURE_LOG_PERIOD_S = 10.0

_F = TypeVar("_F", bound=Callable[..., Any])


def failsafe(what: str, on_error: str | None = None) -> Callable[[_F], _F]:
    """Decorator for a node's periodic work (a timer callback method): an exception in
    it is logged as an error with its traceback (once per :data:`FAILURE_LOG_PERIOD_S`),
    counted in the node's ``failures`` attribute, and that cycle is skipped; the node
    keeps its state and runs the next cycle. One bad map or an algorithm bug on one
    input then costs a cycle instead of the whole exploration (all nodes of ``explorer``
    share one process). ``on_error`` names a method called after a failure (e.g. to
    drop a half-updated incremental state). With ``EXPLORE_SEG_STRICT=1`` the exception
    propagates (tests).
    """
    def deco(fn: _F) -> _F:
        @functools.wraps(fn)
        def wrapper(self: Node, *args: Any, **kwargs: Any) -> Any:
            try:
                return fn(self, *args, **kwargs)
            except Exception as err:
                if os.environ.get(STRICT_ENV, "") not in ("", "0"):
                    raise
                self.failures = getattr(self, "failures", 0) + 1
                log = getattr(self, "_failure_log", None)
                if log is None:
                    log = self._failure_log = WarnThrottle(self, FAILURE_LOG_PERIOD_S)
                log.error(what, f"{what} failed ({self.failures} failure(s) so far); skipped "
                                f"this cycle, the node keeps running: {type(err).__name__}: "
                                f"{err}\n" + traceback.format_exc())
                if on_error is not None:
                    getattr(self, on_error)()
                return None
        return wrapper  # type: ignore[return-value]
    return deco
