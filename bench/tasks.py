"""The benchmark's worker side: one seeded lock-step run or coverage tour per task, the
pool that runs them (drainable by SIGUSR1) and the signal handling around it.

A run task is ``(world spec, strategy, seed, sim time limit s, picture path or None,
camera mount or None, navigation margin m or None[, mapping error profile])``; the
run_bench settings record the profile. The workers are forked from the
main process and inherit what it loaded before: the worlds (:func:`bench.worlds.load`'s
cache) and the explorer parameters (:func:`fix_explorer_params`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import multiprocessing as mp
import os
import queue
import signal
import sys
import threading
import time
from typing import Any, Callable, Iterator

import numpy as np

from bench.worlds import load, sim_params_for
from sim_bridge.coverage_tour import TourParams, coverage_tours
from sim_bridge.lockstep import ExplorerParams, LockstepParams, LockstepState, \
    load_explorer_params, run_exploration

#: The nodes' parameters of this benchmark, read once before the workers fork (an edit
#: of config/explorer.yaml during a long benchmark must not change its later runs).
_EXPLORER_PARAMS: ExplorerParams | None = None


def fix_explorer_params() -> ExplorerParams:
    """Read the nodes' parameters (``config/explorer.yaml``) now: the runs of this process
    and of the workers it forks later use them."""
    global _EXPLORER_PARAMS
    _EXPLORER_PARAMS = load_explorer_params()
    return _EXPLORER_PARAMS


def explorer_params() -> ExplorerParams:
    """The parameters :func:`fix_explorer_params` read, read now when it has not run."""
    return _EXPLORER_PARAMS if _EXPLORER_PARAMS is not None else fix_explorer_params()


def run_task(task: tuple[Any, ...]) -> dict[str, Any]:
    """One run (see the module docstring): its :meth:`RunResult.to_dict` with
    ``cpu_time_s``, the process CPU seconds the run took (the benchmark's cost, which
    other load on the machine does not inflate as it does the wall time); the final map
    is drawn to the picture path when one is given."""
    c0 = time.process_time()
    spec, strategy, seed, max_t, picture, mount, nav_margin, *rest = task
    mapping_error = rest[0] if rest else "none"
    world, gt = load(spec)
    last: dict[str, LockstepState] = {}

    def keep_last(st: LockstepState) -> None:
        last["state"] = st

    res = run_exploration(world, strategy, seed, params=LockstepParams(max_sim_time_s=max_t),
                          ground_truth=gt,
                          sim_params=sim_params_for(mount, nav_margin, mapping_error),
                          explorer_params=_EXPLORER_PARAMS,
                          observer=keep_last if picture else None)
    if picture and "state" in last:
        _save_picture(last["state"], picture)
    return dict(res.to_dict(), cpu_time_s=round(time.process_time() - c0, 2))


def _save_picture(st: LockstepState, path: str) -> None:
    from sim_bridge.render import engine_overlays, render_map_png

    eng = st.engine
    fr = np.zeros(st.grid.shape, dtype=bool)
    for f in st.frontiers:
        fr[f.cells[:, 0], f.cells[:, 1]] = True
    ov = engine_overlays(eng, path_xy=eng.trail)
    ov = dataclasses.replace(
        ov, regions=st.labels, frontiers=fr, goals=list(st.goals),
        boxes=[o.footprint() for o in st.object_map.objects()] if st.object_map else [])
    render_map_png(path, st.grid, ov)


#: Coverage of the second, shorter reference tour (the benchmark's time-to-95 % milestone).
TOUR95_FRACTION = 0.95


def tour_task(spec: str) -> dict[str, Any]:
    """The full-knowledge coverage tours of a world from its unperturbed start: to the
    completion mark (``tour_m``, 99 %) and to 95 % of it in view (``tour95_m``, the
    reference of the path to 95 %)."""
    world, gt = load(spec)
    t0 = time.perf_counter()
    tour, tour95 = coverage_tours(world, (TourParams().coverage_fraction, TOUR95_FRACTION),
                                  ground_truth=gt)
    return {"world": spec, "tour_m": round(tour.length_m, 2),
            "viewpoints": int(len(tour.viewpoints_xy)),
            "coverable_fraction": round(tour.coverable_fraction, 4),
            "explorable_area_m2": round(gt.explorable_area_m2, 2),
            "wall_s": round(time.perf_counter() - t0, 1),
            "tour95_m": round(tour95.length_m, 2),
            "viewpoints95": int(len(tour95.viewpoints_xy))}


#: Set by SIGUSR1: start no new run (see :func:`run_drainable`).
_DRAIN = [False]


def _request_drain(signum: int, frame: Any) -> None:
    _DRAIN[0] = True


def _raise_interrupt(signum: int, frame: Any) -> None:
    """SIGTERM in the main process: stop like Ctrl-C (report what has run)."""
    raise KeyboardInterrupt(signum)


def _worker_init() -> None:
    """Workers leave interrupts to the main process (which terminates them)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGUSR1, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _stop_handler_not_inherited() -> None:
    """In a child just forked: SIGTERM back to its default (the child dies) when the
    parent had :func:`catch_stop_signals`' handler, then unblocked (:func:`_hold_stop`).
    A Python-level handler runs only when the child runs bytecode, so a worker stuck in C
    before :func:`_worker_init` (a lock another thread of the parent held at the fork,
    such as stderr's) would survive the pool's terminate, and its join would hang."""
    if signal.getsignal(signal.SIGTERM) is _raise_interrupt:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
    _release_stop()


def _hold_stop() -> None:
    """Before a fork: block SIGTERM in the forking thread, so that one sent to the child
    before :func:`_stop_handler_not_inherited` runs (a pool terminated right after it
    forked a worker) waits for the default disposition instead of reaching the parent's
    Python-level handler, which a child stuck in C never runs. The parent's other threads
    still take a SIGTERM meant for the parent."""
    _FORK_MASK.blocked = signal.SIGTERM in signal.pthread_sigmask(signal.SIG_BLOCK,
                                                                   {signal.SIGTERM})


def _release_stop() -> None:
    """After a fork (parent and child): SIGTERM unblocked again unless it was before."""
    if not getattr(_FORK_MASK, "blocked", True):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})


_FORK_MASK = threading.local()
_AT_FORK_HOOK = [False]


def install_fork_hooks() -> None:
    """Register the fork hooks above once per process (:func:`worker_pool` does)."""
    if not _AT_FORK_HOOK[0]:
        os.register_at_fork(before=_hold_stop, after_in_parent=_release_stop,
                            after_in_child=_stop_handler_not_inherited)
        _AT_FORK_HOOK[0] = True


def worker_pool(jobs: int) -> Any:
    """``jobs`` forked worker processes (they inherit the loaded worlds and parameters)."""
    install_fork_hooks()
    return mp.get_context("fork").Pool(jobs, initializer=_worker_init, maxtasksperchild=20)


def catch_stop_signals() -> tuple[Any, Any]:
    """SIGTERM stops like Ctrl-C and SIGUSR1 drains the pool (:func:`run_drainable`), in
    this process; returns the handlers replaced, for :func:`restore_signals`."""
    old_term = signal.signal(signal.SIGTERM, _raise_interrupt)
    _DRAIN[0] = False
    old_usr1 = signal.signal(signal.SIGUSR1, _request_drain)
    return old_term, old_usr1


@contextlib.contextmanager
def stop_signals_deferred() -> Iterator[None]:
    """SIGINT / SIGTERM arriving inside the block stop the process only after it (raised
    on exit as ``KeyboardInterrupt(signum)``), so a run is written to both files and
    counted, or to neither. ``pthread_sigmask`` would block them in this thread only: the
    pool's helper threads would still take them, and Python would run the handler inside
    the block."""
    pending: list[int] = []

    def hold(signum: int, frame: Any) -> None:
        pending.append(signum)

    old = {s: signal.signal(s, hold) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)
    if pending:
        raise KeyboardInterrupt(pending[0])


def restore_signals(old: tuple[Any, Any]) -> None:
    """Put back the handlers :func:`catch_stop_signals` replaced."""
    signal.signal(signal.SIGTERM, old[0])
    signal.signal(signal.SIGUSR1, old[1])


def run_drainable(pool: Any, jobs: int, tasks: list[tuple], failed: list[str],
                  fn: Callable[[tuple], Any] | None = None, parts: int = 3) -> Any:
    """Yield the results of ``fn(task)`` (:func:`run_task` when None) for ``tasks`` as
    they finish, at most ``jobs`` in flight.

    A run that raises is reported on stderr (with its traceback) and added to ``failed``
    as its first ``parts`` task fields joined by "/" (``"world/strategy/seed"``) and the
    error; the others go on (it is not in the output files, so ``--resume`` runs it
    again).

    SIGUSR1 makes it start no further task and end once the ones in flight have finished
    (raising ``KeyboardInterrupt(SIGUSR1)`` then, so the caller reports like after an
    interrupt): a long benchmark is stopped without losing the work of its running runs.
    The next task is handed out before a result is yielded, so a run that is in the
    output files is never the last one started.
    """
    done: queue.Queue = queue.Queue()
    todo = list(tasks)
    in_flight = 0
    said = False

    def top_up() -> int:
        n = 0
        while todo and in_flight + n < max(1, jobs) and not _DRAIN[0]:
            task = todo.pop(0)
            pool.apply_async(fn or run_task, (task,),
                             callback=lambda r: done.put((r, None, None)),
                             error_callback=lambda e, t=task: done.put((None, e, t)))
            n += 1
        return n

    in_flight += top_up()
    while in_flight:
        try:
            item = done.get(timeout=0.2)
        except queue.Empty:
            item = None
        # Said once the signal is seen, before the result that arrived with it counts
        # (a signal during the wait that ends with the last run in flight is said too).
        if _DRAIN[0] and not said:
            said = True
            print(f"\n[bench] SIGUSR1: finishing the {in_flight} run(s) in flight, starting "
                  "no new ones", file=sys.stderr)
        if item is None:
            continue
        result, err, task = item
        in_flight -= 1
        in_flight += top_up()
        if err is None:
            yield result
            continue
        name = "/".join(str(x) for x in task[:parts])
        cause = getattr(err, "__cause__", None)     # the worker's traceback, as text
        print(f"\n[bench] run {name} failed: {type(err).__name__}: {err}"
              + (f"\n{cause}" if cause is not None else ""), file=sys.stderr)
        failed.append(f"{name}: {type(err).__name__}: {err}")
    if _DRAIN[0] and todo:
        raise KeyboardInterrupt(int(signal.SIGUSR1))
