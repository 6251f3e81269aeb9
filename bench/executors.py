"""Where the benchmark's tasks run: the local process pool or a Ray cluster.

Both executors offer the part of :class:`multiprocessing.pool.Pool` that
:mod:`bench.run_bench` and :func:`bench.tasks.run_drainable` use (``apply_async`` with
callbacks, ``imap_unordered``, ``terminate``, a context manager), so resume, merge,
records, draining (SIGUSR1) and the progress bar are the same for both, and a run's
results do not depend on where it ran (every run is a pure function of its task and the
explorer parameters, which are sent along with every task).

Ray (``pip install -e .[ray]`` or ``pip install -r requirements-ray.txt``) is optional: it is
imported only when ``--executor ray`` is asked for. Without ``--address`` a local Ray with
``--jobs`` CPUs is started for the sweep; with one, the driver joins that cluster (``auto``
= the cluster this machine belongs to, or ``ray://HOST:10001`` through Ray Client). Every
node needs this repository (its ``worlds/`` folder included) at the path the driver uses
(the workers get ``PYTHONPATH`` from the driver). A task whose worker
process or node dies is retried by Ray (``RAY_MAX_RETRIES`` times); a task that raises is
reported as failed, like in the process pool, and ``--resume`` runs it again.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator

from bench import tasks as bench_tasks

ROOT = Path(__file__).resolve().parents[1]
EXECUTORS = ("process", "ray")
#: Retries of a task whose worker process (or node) died.
RAY_MAX_RETRIES = 3


def make_pool(executor: str, jobs: int, address: str = "") -> Any:
    """The pool of ``executor`` (``process`` or ``ray``) with ``jobs`` workers.

    Raises
    ------
    ValueError
        On an unknown executor, or ``ray`` when Ray is not installed or no cluster
        answers at ``address``.
    """
    if executor == "process":
        return bench_tasks.worker_pool(jobs)
    if executor == "ray":
        return RayPool(jobs, address)
    raise ValueError(f"executor must be one of {EXECUTORS}, got {executor!r}")


def _call(fn: Callable[..., Any], args: tuple, explorer_params: Any) -> Any:
    """Worker side of a Ray task: the driver's explorer parameters, then ``fn(*args)``."""
    bench_tasks._EXPLORER_PARAMS = explorer_params
    return fn(*args)


class RemoteTraceback(Exception):
    """The traceback of a task that raised on a Ray worker, as text (as
    :mod:`multiprocessing` gives it in ``__cause__``)."""


def _unwrap(err: BaseException) -> BaseException:
    """The exception a task raised (what the process pool reports) from Ray's
    ``RayTaskError``, with the worker's traceback as its ``__cause__``."""
    cause = getattr(err, "cause", None)
    if not isinstance(cause, BaseException):
        return err
    cause.__cause__ = RemoteTraceback(str(err))
    return cause


class RayPool:
    """``apply_async``/``imap_unordered`` on Ray tasks (one CPU each); see the module doc."""

    def __init__(self, jobs: int, address: str = "") -> None:
        try:
            import ray
        except ImportError:
            raise ValueError("--executor ray needs Ray: pip install -r requirements-ray.txt "
                             "(or pip install -e .[ray])") from None
        self._ray = ray
        env = {"PYTHONPATH": os.pathsep.join(
                   [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep)
                                  if p]),
               "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        self._started = not ray.is_initialized()
        if self._started:
            kw: dict[str, Any] = {"runtime_env": {"env_vars": env},
                                  "include_dashboard": False, "log_to_driver": True}
            if address:
                try:
                    ray.init(address=address, **kw)
                except ConnectionError as err:
                    raise ValueError(
                        f"--address {address}: no Ray cluster answered ({err}). Is `ray start "
                        "--head` running there, and does this machine hold the cluster's "
                        "token (~/.ray/auth_token from the head node, or RAY_AUTH_TOKEN)? "
                        "See docs/benchmarking.md, 'Ray cluster'") from None
            else:
                ray.init(num_cpus=jobs, **kw)
        self._remote = ray.remote(num_cpus=1, max_retries=RAY_MAX_RETRIES,
                                  retry_exceptions=False)(_call)
        self._params = ray.put(bench_tasks.explorer_params())
        self._refs: set[Any] = set()
        self._lock = threading.Lock()

    def _submit(self, fn: Callable[..., Any], args: tuple) -> Any:
        ref = self._remote.remote(fn, args, self._params)
        with self._lock:
            self._refs.add(ref)
        return ref

    def _forget(self, ref: Any) -> None:
        with self._lock:
            self._refs.discard(ref)

    def apply_async(self, fn: Callable[..., Any], args: tuple = (),
                    callback: Callable[[Any], None] | None = None,
                    error_callback: Callable[[BaseException], None] | None = None) -> Any:
        """Run ``fn(*args)`` on a Ray worker; ``callback(result)`` or
        ``error_callback(exception)`` runs on a driver thread when it ends."""
        ref = self._submit(fn, args)

        def done(fut: Any) -> None:
            self._forget(ref)
            err = fut.exception()
            if err is None:
                if callback is not None:
                    callback(fut.result())
            elif error_callback is not None:
                error_callback(_unwrap(err))

        ref.future().add_done_callback(done)
        return ref

    def imap_unordered(self, fn: Callable[..., Any], items: Iterable[Any]) -> Iterator[Any]:
        """``fn(item)`` for every item, yielded as they finish."""
        pending = [self._submit(fn, (item,)) for item in items]
        while pending:
            ready, pending = self._ray.wait(pending, num_returns=1)
            for ref in ready:
                self._forget(ref)
                yield self._ray.get(ref)

    def terminate(self) -> None:
        """Cancel the tasks in flight (their runs are lost, as in the process pool)."""
        with self._lock:
            refs = list(self._refs)
            self._refs.clear()
        for ref in refs:
            try:
                self._ray.cancel(ref, force=True)
            except Exception:       # already finished or its worker is gone
                pass

    def close(self) -> None:
        """Disconnect (and stop the local Ray this pool started)."""
        if self._started and self._ray.is_initialized():
            self._ray.shutdown()

    def __enter__(self) -> "RayPool":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.terminate()
        self.close()
