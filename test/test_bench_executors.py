"""What ``run_bench.py --executor ray`` tells a user whose Ray is missing or unreachable.

Runs without Ray: the module ``ray`` is replaced (absent, or a stand-in whose
``init`` cannot reach a cluster), as on a machine without the extra or with a cluster
that is down or asks for a token this machine lacks.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
import types
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import executors, run_bench  # noqa: E402

ARGS = ["--worlds", "small_house", "--strategies", "nearest", "--runs", "1", "--jobs", "1",
        "--max-sim-time", "5", "--no-tour", "--yolo-frames", "0", "--md", ""]


def test_ray_executor_without_ray_says_how_to_install_it(tmp_path, monkeypatch, capsys):
    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "ray" else find_spec(name, *a))
    with pytest.raises(SystemExit) as ex:
        run_bench.main(ARGS + ["--out", str(tmp_path), "--executor", "ray"])
    assert ex.value.code == 2
    assert "requirements-ray.txt" in capsys.readouterr().err
    assert not (tmp_path / "runs.csv").exists()
    monkeypatch.setitem(sys.modules, "ray", None)      # import ray -> ImportError
    with pytest.raises(ValueError, match="requirements-ray.txt"):
        executors.make_pool("ray", 1)


def _unreachable_ray() -> types.ModuleType:
    ray = types.ModuleType("ray")
    ray.__spec__ = importlib.machinery.ModuleSpec("ray", None)
    ray.is_initialized = lambda: False

    def init(address=None, **kw):
        raise ConnectionError(f"Failed to connect to Ray cluster at {address}")
    ray.init = init
    return ray


def test_unreachable_cluster_names_the_address_and_the_token(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "ray", _unreachable_ray())
    with pytest.raises(ValueError, match=r"10\.0\.0\.9:6379.*auth_token"):
        executors.make_pool("ray", 2, "10.0.0.9:6379")
    assert run_bench.main(ARGS + ["--out", str(tmp_path), "--executor", "ray",
                                  "--address", "10.0.0.9:6379"]) == 2
    assert "RAY_AUTH_TOKEN" in capsys.readouterr().err


def test_unknown_executor_is_refused():
    with pytest.raises(ValueError, match="executor must be one of"):
        executors.make_pool("dask", 1)


def _record_sigterm(folder: str) -> None:
    """Pool initializer of the test below: what SIGTERM does in the worker before
    bench.tasks' own initializer runs."""
    import os
    import signal

    Path(folder, str(os.getpid())).write_text(
        "default" if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL else "handler")


def test_workers_do_not_inherit_the_stop_handler(tmp_path, monkeypatch):
    """With the main process's SIGTERM stop handler set, a forked worker takes SIGTERM's
    default from the fork on: a worker stuck in C before its initializer (a lock another
    thread held at the fork) dies at the pool's terminate instead of hanging its join
    (seen as a 600 s timeout of test_bench_records.py under load)."""
    import functools

    from bench import tasks as bench_tasks

    monkeypatch.setattr(bench_tasks, "_worker_init",
                        functools.partial(_record_sigterm, str(tmp_path)))
    old = bench_tasks.catch_stop_signals()
    try:
        pool = bench_tasks.worker_pool(2)
        try:
            assert pool.apply(int, ("7",)) == 7
        finally:
            pool.terminate()
            pool.join()
    finally:
        bench_tasks.restore_signals(old)
    seen = [p.read_text() for p in tmp_path.iterdir()]
    assert seen and set(seen) == {"default"}


def test_a_sigterm_before_the_fork_hook_still_stops_the_worker(tmp_path):
    """A pool terminated right after it forked a worker: the SIGTERM reaches the child
    before the at-fork hook that restores SIGTERM's default. It waits (blocked across the
    fork) and then kills the child, instead of going to the parent's Python-level handler,
    which a child stuck in C never runs. A fresh interpreter, so that the test's own
    at-fork hook runs before the benchmark's."""
    import subprocess
    import sys
    from pathlib import Path

    script = (
        "import os, signal\n"
        "armed = [False]\n"
        "os.register_at_fork(after_in_child=lambda: armed[0] and "
        "os.kill(os.getpid(), signal.SIGTERM))\n"
        "from bench import tasks\n"
        "tasks.install_fork_hooks()\n"
        "old = tasks.catch_stop_signals()\n"
        "armed[0] = True\n"
        "pid = os.fork()\n"
        "if pid == 0:\n"
        "    os._exit(0)\n"
        "armed[0] = False\n"
        "_, status = os.waitpid(pid, 0)\n"
        "print('killed' if os.WIFSIGNALED(status) and "
        "os.WTERMSIG(status) == signal.SIGTERM else f'exit {status}')\n"
        "print(signal.SIGTERM in signal.pthread_sigmask(signal.SIG_BLOCK, set()))\n")
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-c", script], cwd=root, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["killed", "False"], out.stdout + out.stderr
