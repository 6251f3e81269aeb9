"""Exploration benchmark: seeded lock-step runs x worlds x strategies -> CSV, plots, BENCHMARKS.md.

Every run is :func:`sim_bridge.lockstep.run_exploration` (the explorer's core code on the
simulator, no ROS, no real-time waiting), so results are reproducible from the seed:
run ``k`` of every (world, strategy) uses seed ``--seed0 + k``. Runs are spread over
``--jobs`` processes. Per world the full-knowledge coverage tour
(:mod:`sim_bridge.coverage_tour`) is computed once from the unperturbed start.

Outputs in ``--out``: ``runs.csv`` (one row per run), ``runs.jsonl`` (everything,
coverage samples and per-update timings included; tens of MB, not in git),
``runs.jsonl.gz`` (every run without its per-update timings, ~1-10 kB gzipped each: commit
it with the results, so that a new checkout can ``--resume``; :mod:`bench.records`),
``tours.csv``, ``yolo.json`` (the
real detector timed on rendered frames), ``maps/`` (final map of the first run of every
world x strategy), the figures of :mod:`bench.report`, and ``BENCHMARKS.md`` at ``--md``
(default: the repository root).

World names: the generated worlds (``house``, ``maze``, ``house_cluttered``,
``small_house``, ``small_cluttered``), ``shared/NAME`` for the package's
``worlds/NAME.world.yaml`` and ``eb/NAME`` for the Explore-Bench map
``worlds/explore_bench/NAME.yaml``, or a path to a world file. Without ``--worlds`` the
benchmark runs all 20 (:func:`bench.worlds.default_worlds`); a world that cannot be found
stops it before any run, naming the world. ``--list`` prints the worlds a command would
run, with the file each one loads, and runs nothing.

Usage::

    .venv/bin/python bench/run_bench.py --runs 20 --jobs 2 --out out/bench
    .venv/bin/python bench/run_bench.py --runs 3 --worlds house --strategies paper,nearest
    .venv/bin/python bench/run_bench.py --report-only --out out/bench
    .venv/bin/python bench/run_bench.py --list
    .venv/bin/python bench/run_bench.py --ros 2 --runs 2 --worlds small_house
    .venv/bin/python bench/run_bench.py --executor ray --address auto --jobs 64 --runs 20

Executors (:mod:`bench.executors`): ``--executor process`` (default) forks ``--jobs``
worker processes; ``--executor ray`` runs the same tasks on a local Ray (``--jobs`` CPUs)
or, with ``--address``, on a Ray cluster (at most ``--jobs`` runs in flight). The records,
resume and merge are the same, and so are the results of every run.

Stopping: SIGINT/SIGTERM stop at once (the runs in flight are lost); ``kill -USR1 PID``
finishes the runs in flight and starts no new ones. Either way the runs so far are
reported, the part is marked interrupted, and ``--resume`` continues.

The full matrix: every strategy x the 20 worlds, ``--runs`` seeds (20), at most
``--world-runs`` in the long generated worlds (10 in ``maze`` and ``office_floor``).
It runs in parts: ``--resume`` continues where the last part stopped; ``--shard K/N``
runs the K-th of N interleaved slices (each on its own machine, into its own ``--out``),
and ``--resume --merge DIR`` adds a finished slice to the main folder. Every run records
the commit it ran on and its CPU seconds; the report (:mod:`bench.report`) is of one
code version and refuses runs of several (exit status 3) unless ``--allow-mixed``. The
last line gives the matrix's wall time (all parts) and CPU seconds (all runs).
"""


from __future__ import annotations

import argparse
import importlib.util
import json
import os
import resource
import shlex
import signal
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench import records, report, store  # noqa: E402
from bench.executors import EXECUTORS, make_pool  # noqa: E402
from bench.crosscheck import compare_with_ros, time_yolo  # noqa: E402
from bench.progress import Progress, hms  # noqa: E402
from bench.rows import runs_csv_rows  # noqa: E402
from bench.tasks import catch_stop_signals, explorer_params, fix_explorer_params, \
    restore_signals, run_drainable, stop_signals_deferred, tour_task  # noqa: E402
from bench.worlds import FULL_RUNS, MAX_SIM_TIME_S, MIN_SIM_TIME_S, \
    PAPER_CAMERA_MOUNT, TIME_PER_AREA_S, WORLD_RUNS, default_worlds, load, sim_params_for, \
    sim_time_limit, world_path  # noqa: E402
from sim_bridge.engine import SimParams  # noqa: E402
from sim_bridge.lockstep import STRATEGIES, LockstepParams, load_explorer_params, \
    run_exploration  # noqa: E402
from sim_bridge.strategy_specs import MATRIX_STRATEGIES  # noqa: E402

#: What scripts import from here (the benchmark's world loading and run settings).
__all__ = ["PAPER_CAMERA_MOUNT", "Progress", "compare_with_ros", "default_worlds",
           "explorer_params", "load", "load_explorer_params", "main", "run_exploration",
           "sim_params_for", "sim_time_limit", "time_yolo", "world_path"]


# -------------------------------------------------------------------------- main


def _parse(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=FULL_RUNS, help="seeded runs per world x strategy")
    ap.add_argument("--world-runs", default=",".join(f"{w}={n}" for w, n in WORLD_RUNS.items()),
                    metavar="WORLD=N,...",
                    help="at most N runs in these worlds (the long ones; default: "
                         "%(default)s; '' = --runs everywhere)")
    ap.add_argument("--shard", default="", metavar="K/N",
                    help="run only part K of N of the matrix (every N-th world x strategy x "
                         "seed from the K-th on): the parts run on several machines, each "
                         "into its own --out, and are put together with --resume --merge")
    ap.add_argument("--worlds", default="", help="comma-separated world specs "
                    "(default: the 20 of bench.worlds.default_worlds)")
    ap.add_argument("--list", action="store_true",
                    help="print the worlds (with the file each loads), strategies and runs "
                         "this command would run, and run nothing")
    ap.add_argument("--strategies", default=",".join(MATRIX_STRATEGIES),
                    help=f"comma-separated, from {','.join(STRATEGIES)}")
    ap.add_argument("--jobs", type=int, default=2,
                    help="worker processes; with --executor ray: runs in flight")
    ap.add_argument("--executor", default="process", choices=EXECUTORS,
                    help="process: a pool of forked processes on this machine; ray: Ray "
                         "tasks (a local Ray, or the cluster at --address)")
    ap.add_argument("--address", default="",
                    help="with --executor ray: the Ray cluster to join ('auto', HOST:6379 "
                         "or ray://HOST:10001; default: start a local Ray)")
    ap.add_argument("--out", default="out/bench", help="output folder")
    ap.add_argument("--md", default=None,
                    help="where to write the report ('' = not at all); default: the "
                         "repository's BENCHMARKS.md for the matrix's own folder (out/bench), "
                         "OUT/BENCHMARKS.md for any other --out")
    ap.add_argument("--seed0", type=int, default=0, help="seed of the first run")
    ap.add_argument("--max-sim-time", type=float, default=0.0,
                    help=f"sim time limit per run in s (0 = {TIME_PER_AREA_S} s per m^2 "
                         f"within [{MIN_SIM_TIME_S:.0f}, {MAX_SIM_TIME_S:.0f}])")
    ap.add_argument("--no-tour", action="store_true", help="skip the coverage tours")
    ap.add_argument("--yolo-frames", type=int, default=10,
                    help="frames to time the real detector on (0 = skip)")
    ap.add_argument("--ros", type=int, default=0,
                    help="also run this many seeds of the first world through ROS "
                         "(sim_bridge + explorer processes) and compare")
    ap.add_argument("--ros-strategy", default="paper", help="strategy of the ROS runs")
    ap.add_argument("--ros-rtf", type=float, default=4.0,
                    help="real-time factor of the ROS runs")
    ap.add_argument("--camera-mount", default="paper",
                    help="RGB-D camera mount of the runs: 'paper' (0.894 m up, pitched 0.1 rad "
                         "down, as on the paper's robot), 'sim' (the simulator's default) or "
                         "HEIGHT_M,PITCH_RAD")
    ap.add_argument("--nav-margin", type=float, default=None,
                    help="clearance in m that the navigation stand-in keeps beyond the robot "
                         "radius (sim_bridge's nav_inflation_margin_m; default: its default, "
                         f"{SimParams().nav_inflation_margin_m:g})")
    ap.add_argument("--mapping-noise", default="none", metavar="PROFILE",
                    help="SLAM-like mapping error of the runs (SimParams.mapping_error): "
                         "none, realistic, harsh or custom")
    ap.add_argument("--report-only", action="store_true",
                    help="only redo plots and BENCHMARKS.md from --out")
    ap.add_argument("--allow-mixed", action="store_true",
                    help="report runs of several code versions, every row marked with its "
                         "versions (bench/report.py; without it such runs get no report "
                         "and the exit status is 3)")
    ap.add_argument("--resume", action="store_true",
                    help="keep the runs and tours already in --out that this command asks "
                         "for (same world, strategy, seed) and run only the missing ones; "
                         "when --out also holds runs the command does not ask for, it stops "
                         "and names them (see --prune)")
    ap.add_argument("--prune", action="store_true",
                    help="with --resume: drop the runs in --out that this command does not "
                         "ask for (a copy stays in runs.jsonl.bak*) instead of stopping")
    ap.add_argument("--redo", default="",
                    help="with --resume: comma-separated STRATEGY or WORLD:STRATEGY whose "
                         "kept runs are run again (after a change that affects them; the "
                         "old runs are copied to runs.jsonl.bak*). An interrupted redo is "
                         "continued with --resume alone (with --redo it starts over)")
    ap.add_argument("--no-runs", action="store_true",
                    help="with --resume: keep every run and tour in --out and run none; "
                         "only the --yolo-frames timing and the --ros comparison, then the "
                         "report (a part of its own in meta.json)")
    ap.add_argument("--merge", default="", metavar="DIR",
                    help="with --resume: first add the runs of another output folder made "
                         "with the same settings (e.g. a part run on another machine) to "
                         "--out; its parts are listed with --out's")
    a = ap.parse_args(argv)
    if a.md is None:
        a.md = str(store.default_report_path(Path(a.out)))
    if a.address and a.executor != "ray":
        ap.error("--address needs --executor ray")
    if a.executor == "ray" and importlib.util.find_spec("ray") is None:
        ap.error("--executor ray needs Ray: pip install -r requirements-ray.txt "
                 "(or pip install -e .[ray])")
    if a.merge and not a.resume:
        ap.error("--merge needs --resume")
    if a.no_runs and not a.resume:
        ap.error("--no-runs needs --resume")
    if a.prune and (not a.resume or a.no_runs):
        ap.error("--prune needs --resume (and runs: not with --no-runs)")
    if a.no_runs and a.redo:
        ap.error("--no-runs runs nothing: no --redo")
    if a.nav_margin is not None:
        try:
            sim_params_for(None, a.nav_margin).nav_params()
        except ValueError as err:
            ap.error(f"--nav-margin {a.nav_margin}: {err}")
    try:
        sim_params_for(None, None, a.mapping_noise)
    except ValueError as err:
        ap.error(f"--mapping-noise {a.mapping_noise}: {err}")
    if a.runs < 1 or a.jobs < 1:
        ap.error("--runs and --jobs must be >= 1")
    try:
        a.world_runs = parse_world_runs(a.world_runs)
        a.shard_kn = parse_shard(a.shard)
    except ValueError as err:
        ap.error(str(err))
    try:
        a.mount = _camera_mount(a.camera_mount)
    except ValueError as err:
        ap.error(str(err))
    strategies = [s for s in a.strategies.split(",") if s]
    bad = [s for s in strategies if s not in STRATEGIES]
    if bad or not strategies:
        ap.error(f"unknown strategies {bad}; choose from {list(STRATEGIES)}")
    a.redo_keys = []
    worlds = [w for w in a.worlds.split(",") if w] if a.worlds else None
    for item in (x.strip() for x in a.redo.split(",") if x.strip()):
        world, _, strat = item.rpartition(":")
        if strat not in strategies:
            ap.error(f"--redo {item!r}: strategy {strat!r} is not among --strategies")
        if world and worlds is not None and world not in worlds:
            ap.error(f"--redo {item!r}: world {world!r} is not among --worlds")
        a.redo_keys.append((world or None, strat))
    if a.redo_keys and not a.resume:
        ap.error("--redo needs --resume")
    return a


def parse_world_runs(text: str) -> dict[str, int]:
    """``--world-runs`` (``WORLD=N,...``) as {world: N}.

    Raises
    ------
    ValueError
        On an item that is not WORLD=N with N >= 1 (the message names it).
    """
    out: dict[str, int] = {}
    for item in (x.strip() for x in text.split(",") if x.strip()):
        world, _, n = item.rpartition("=")
        try:
            k = int(n)
        except ValueError:
            k = 0
        if not world or k < 1:
            raise ValueError(f"--world-runs: expected WORLD=N with N >= 1, got {item!r}")
        out[world] = k
    return out


def parse_shard(text: str) -> tuple[int, int] | None:
    """``--shard K/N`` as (K, N) with 1 <= K <= N, None for ''.

    Raises
    ------
    ValueError
        On anything else (the message names it).
    """
    if not text:
        return None
    k, _, n = text.partition("/")
    try:
        kn = int(k), int(n)
    except ValueError:
        kn = (0, 0)
    if not 1 <= kn[0] <= kn[1]:
        raise ValueError(f"--shard: expected K/N with 1 <= K <= N, got {text!r}")
    return kn


def runs_of(world: str, runs: int, world_runs: dict[str, int]) -> int:
    """Runs per strategy of ``world``: ``runs``, at most its ``world_runs`` cap."""
    return min(runs, world_runs.get(world, runs))


def matrix_tasks(specs: list[str], strategies: list[str], runs: int, seed0: int,
                 world_runs: dict[str, int], shard: tuple[int, int] | None
                 ) -> list[tuple[str, str, int]]:
    """(world, strategy, seed) of the matrix in world x strategy x seed order, only shard
    K of N (every N-th from the K-th) when ``shard`` is given: the N shards together are
    the matrix, each run in exactly one."""
    keys = [(w, st, seed0 + k) for w in specs for st in strategies
            for k in range(runs_of(w, runs, world_runs))]
    if shard is None:
        return keys
    k, n = shard
    return keys[k - 1::n]


def _camera_mount(text: str) -> tuple[float, float] | None:
    """``--camera-mount`` value -> (height m, pitch rad), None for the sim default."""
    if text == "paper":
        return PAPER_CAMERA_MOUNT
    if text == "sim":
        return None
    try:
        z, pitch = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--camera-mount must be paper, sim or HEIGHT_M,PITCH_RAD, "
                         f"got {text!r}") from None
    return z, pitch


def _settings(a: argparse.Namespace) -> dict[str, Any]:
    """What must match for runs of two parts to be comparable (``--resume``), as it reads
    back from meta.json."""
    settings: dict[str, Any] = {
        "max_sim_time": a.max_sim_time,
        "camera_mount": list(a.mount) if a.mount is not None else None,
        "lockstep_params": {k: v for k, v in vars(LockstepParams()).items()},
        "nav_inflation_margin_m": sim_params_for(None, a.nav_margin).nav_inflation_margin_m,
        "nav_inflation_soft_margin_m": SimParams().nav_inflation_soft_margin_m,
        "nav_arc_check_edges": SimParams().nav_arc_check_edges,
        "nav_inflation_edge_cost": SimParams().nav_inflation_edge_cost,
        "object_confirm_hits": explorer_params().objects.confirm_hits,
        "mapping_error": a.mapping_noise}
    return json.loads(json.dumps(settings))


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (see the module docstring); returns the exit status."""
    a = _parse(argv)
    out = Path(a.out)
    if a.report_only:
        out.mkdir(parents=True, exist_ok=True)
        return 0 if _report(out, a, None) else 3
    specs = [w for w in (a.worlds.split(",") if a.worlds else default_worlds()) if w]
    strategies = [s for s in a.strategies.split(",") if s]
    resolved, missing = {}, []
    for s in specs:
        try:
            resolved[s] = world_path(s)
        except ValueError as err:
            missing.append(str(err))
    for err in missing:
        print(f"[bench] {err}", file=sys.stderr)
    if missing:
        return 2
    if a.list:
        keys = matrix_tasks(specs, strategies, a.runs, a.seed0, a.world_runs, a.shard_kn)
        caps = [f"{w}: {n}" for w, n in a.world_runs.items() if w in specs and n < a.runs]
        extra = "; ".join(([f"at most {', '.join(caps)}"] if caps else [])
                          + ([f"shard {a.shard}"] if a.shard_kn else []))
        print(f"[bench] {len(specs)} worlds x {len(strategies)} strategies "
              f"({', '.join(strategies)}) x {a.runs} runs"
              + (f" ({extra}; {len(keys)} runs in all)" if extra else "") + ":")
        for s in specs:
            print(f"{s}\t{resolved[s] if resolved[s] != s else '(generated)'}")
        return 0
    out.mkdir(parents=True, exist_ok=True)
    command = "bench/run_bench.py " + " ".join(shlex.quote(x) for x in (argv if argv is not None
                                                                        else sys.argv[1:]))
    meta = {"command": command, "runs": a.runs, "seed0": a.seed0, "worlds": specs,
            "world_runs": a.world_runs, "shard": a.shard or None,
            "strategies": strategies, "jobs": a.jobs, "cpus": os.cpu_count(),
            "settings": _settings(a), "code": store.code_version(),
            "lockstep_params": {k: v for k, v in vars(LockstepParams()).items()},
            "camera_mount": (list(a.mount) if a.mount is not None else
                             [SimParams().camera_mount_z_m, SimParams().camera_pitch_rad]),
            "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    t_start, cpu_start = time.monotonic(), _cpu_s()
    old_meta = store.read_json(out / "meta.json") if a.resume else {}
    if old_meta:
        old_settings = old_meta.get("settings")
        if old_settings is not None and not store.same_settings(old_settings, meta["settings"]):
            print(f"[bench] --resume: the runs in {out} were made with other settings "
                  f"({old_settings}, now {meta['settings']}); use another --out",
                  file=sys.stderr)
            return 2
        old_codes = {p.get("code") for p in old_meta.get("parts") or [old_meta]}
        if a.merge:
            err = store.merge(out, Path(a.merge), meta, old_meta)
            if err:
                print(f"[bench] --merge: {err}", file=sys.stderr)
                return 2
            old_codes = {p.get("code") for p in old_meta.get("parts") or [old_meta]}
        if old_codes != {meta["code"]}:
            print(f"[bench] --resume: warning: earlier parts ran on code {sorted(map(str, old_codes))}, "
                  f"this one on {meta['code']} (listed in the report)", file=sys.stderr)
    if a.resume and not a.no_runs and not a.prune:
        unasked = store.unasked_runs(
            out, matrix_tasks(specs, strategies, a.runs, a.seed0, a.world_runs, a.shard_kn))
        if unasked:
            print(f"[bench] --resume: {out} holds {unasked}, which this command does not "
                  "ask for: add them to --worlds / --strategies / --runs, run into another "
                  "--out and --merge, or pass --prune to drop them (a copy stays in "
                  "runs.jsonl.bak*)", file=sys.stderr)
            return 2
    interrupted: int = 0          # the signal that stopped the runs, 0 = none
    counter = [0]                 # runs run so far
    failed: list[str] = []        # runs that raised: "world/strategy/seed: error"
    tours: list[dict[str, Any]] = []
    results: list[dict[str, Any]] = []
    areas: dict[str, float] = {}
    old_handlers = catch_stop_signals()
    try:
        # Worlds, ground truths and explorable areas before the workers fork (they
        # inherit the cache).
        areas = {s: float(load(s)[1].explorable_area_m2) for s in specs}
        fix_explorer_params()
        if a.no_runs:
            results += records.read(out)
            tours += [dict(r, tour_m=float(r["tour_m"])) for r in
                      store.read_csv(out / "tours.csv")] if (out / "tours.csv").is_file() else []
            stray = sorted({f"{d['world']}:{d['strategy']}" for d in results
                            if d["world"] not in specs or d["strategy"] not in strategies})
            if stray:
                print(f"[bench] --no-runs: --out holds runs of worlds/strategies not among "
                      f"--worlds/--strategies: {', '.join(stray)}", file=sys.stderr)
                return 2
        else:
            try:
                pool_cm = make_pool(a.executor, a.jobs, a.address)
            except ValueError as err:
                print(f"[bench] {err}", file=sys.stderr)
                return 2
            with pool_cm as pool:
                try:
                    _run_all(a, out, specs, strategies, areas, pool, tours, results, counter,
                             failed, meta["code"])
                except KeyboardInterrupt as err:
                    interrupted = int(err.args[0]) if err.args else int(signal.SIGINT)
                    pool.terminate()
                    how = ("stopped" if interrupted == signal.SIGUSR1 else "interrupted")
                    print(f"\n[bench] {how} after {counter[0]} runs: reporting what "
                          "ran (continue with --resume)", file=sys.stderr)
    except KeyboardInterrupt as err:      # before the pool existed
        interrupted = int(err.args[0]) if err.args else int(signal.SIGINT)
        print("\n[bench] interrupted before any run", file=sys.stderr)
    finally:
        restore_signals(old_handlers)
    store.write_csv(out / "runs.csv", runs_csv_rows(results, specs, strategies, tours))
    if a.yolo_frames > 0 and not interrupted:
        yolo = time_yolo(a.yolo_frames)
        (out / "yolo.json").write_text(json.dumps(yolo, indent=1))
        print(f"[bench] real detector: {yolo}", file=sys.stderr)
    if a.ros > 0 and not interrupted:
        ros = compare_with_ros(specs[0], a.ros_strategy, [a.seed0 + k for k in range(a.ros)],
                               out / "ros", a.ros_rtf,
                               sim_time_limit(areas[specs[0]], a.max_sim_time), a.mount,
                               a.nav_margin)
        ros["code"] = meta["code"]          # the commit its runs ran on
        (out / "ros.json").write_text(json.dumps(ros, indent=1))
    part = {"command": command, "started": meta["started"], "code": meta["code"],
            "executor": a.executor,
            "runs_run": counter[0], "wall_s": round(time.monotonic() - t_start, 1),
            "cpu_s": round(_cpu_s() - cpu_start, 1)}
    if interrupted:
        part["interrupted"] = True
    if failed:
        part["failed"] = failed
    store.write_meta(out, meta, old_meta, part)
    reported = _report(out, a, command)
    print(f"[bench] {len(results)} runs; results in {out}"
          + (f", summary in {a.md}" if a.md and reported else ""), file=sys.stderr)
    print(matrix_summary(results, meta, part), file=sys.stderr)
    if failed:
        print(f"[bench] {len(failed)} runs failed (not in the results; --resume runs them "
              "again): " + "; ".join(failed), file=sys.stderr)
    return 128 + interrupted if interrupted else (1 if failed else (0 if reported else 3))


def _report(out: Path, a: argparse.Namespace, command: str | None) -> bool:
    """Figures and BENCHMARKS.md (:func:`bench.report.write_all`); False, with the reason
    on stderr, when the report refuses the runs (several code versions without
    ``--allow-mixed``, a malformed certificate): the runs are kept either way."""
    try:
        report.write_all(out, Path(a.md) if a.md else None, command=command,
                         allow_mixed=a.allow_mixed)
    except ValueError as err:
        print(f"[bench] no report: {err}", file=sys.stderr)
        return False
    return True


def _cpu_s() -> float:
    """CPU seconds of this process and of its children that have ended (the pool's
    workers, once the pool is closed)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(
        resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def matrix_summary(results: list[dict[str, Any]], meta: dict[str, Any],
                   part: dict[str, Any]) -> str:
    """The line that ends a benchmark: the matrix's wall time and CPU seconds over all
    parts (CPU of every process of a part, tours and report included: on this machine's
    process pool; parts from before it was recorded are counted and named), the runs'
    own CPU seconds, and the same of this part."""
    parts = meta.get("parts") or []
    wall = float(meta.get("wall_s") or 0.0)
    cpu_parts = sum(float(p.get("cpu_s") or 0.0) for p in parts)
    no_cpu = sum(1 for p in parts if p.get("cpu_s") is None)
    runs_cpu = [float(d["cpu_time_s"]) for d in results if d.get("cpu_time_s") is not None]
    new = results[len(results) - int(part.get("runs_run") or 0):]
    missing = len(results) - len(runs_cpu)
    return (f"[bench] matrix: {len(results)} runs in {len(parts)} parts, {hms(wall)} wall "
            f"({wall:.0f} s), {cpu_parts:.0f} CPU s"
            + (f" ({no_cpu} parts recorded without it)" if no_cpu else "")
            + f", {sum(runs_cpu):.0f} of them in the runs"
            + (f" ({missing} runs recorded without a CPU figure)" if missing else "")
            + f"; this part: {len(new)} runs, {hms(float(part.get('wall_s') or 0.0))} wall, "
            f"{float(part.get('cpu_s') or 0.0):.0f} CPU s")


def _run_all(a: argparse.Namespace, out: Path, specs: list[str], strategies: list[str],
             areas: dict[str, float], pool: Any, tours: list[dict[str, Any]],
             results: list[dict[str, Any]], counter: list[int], failed: list[str],
             code: str) -> None:
    """Tours and runs, filling ``tours`` and ``results`` (and ``failed`` with the runs
    that raised); ``counter[0]`` counts the runs run (read it after an interrupt); every
    new record gets ``code``, the code version it ran on."""
    if not a.no_tour:
        if a.resume:
            tours += [dict(r, tour_m=float(r["tour_m"]))
                      for r in store.read_csv(out / "tours.csv") if r["world"] in specs]
        in_shard = {w for w, _, _ in matrix_tasks(specs, strategies, a.runs, a.seed0,
                                                  a.world_runs, a.shard_kn)}
        todo = [s for s in specs if s in in_shard and s not in {r["world"] for r in tours}]
        prog = Progress(len(todo), "tours")
        for row in pool.imap_unordered(tour_task, todo):
            tours.append(row)
            prog.update(f"{row['world']}: {row['tour_m']} m")
        store.write_csv(out / "tours.csv", sorted(tours, key=lambda r: specs.index(r["world"])))
    (out / "maps").mkdir(exist_ok=True)
    tasks = [(s, strat, seed, sim_time_limit(areas[s], a.max_sim_time),
              (str(out / "maps" / f"{store.slug(s)}_{strat}.png") if seed == a.seed0 else None),
              a.mount, a.nav_margin, a.mapping_noise)
             for s, strat, seed in matrix_tasks(specs, strategies, a.runs, a.seed0,
                                                a.world_runs, a.shard_kn)]
    if a.resume:
        kept, tasks = store.resume(out, tasks, a.redo_keys)
        results += kept
    # Seed by seed (an interrupted benchmark has as many runs of every world x strategy,
    # +-1), long worlds first within a seed so the pool does not end on one slow run.
    tasks.sort(key=lambda t: (t[2], -areas[t[0]]))
    prog = Progress(len(tasks), "runs")
    records.write_compact(out, results)
    with open(out / records.FULL, "w") as jl:
        for d in results:
            jl.write(json.dumps(d) + "\n")
        jl.flush()
        for d in run_drainable(pool, a.jobs, tasks, failed):
            d["code"] = code       # the commit the run ran on (bench.report checks it)
            # an interrupt waits until the run is in both files and counted
            with stop_signals_deferred():
                jl.write(json.dumps(d) + "\n")
                jl.flush()
                records.append_compact(out, d)
                results.append(d)
                counter[0] += 1
            prog.update(f"{d['world']}/{d['strategy']}/{d['seed']}: "
                        f"{d['coverage_pct'] or 0:.1f} % {d['stop_reason']} "
                        f"({d['wall_time_s']:.0f} s)")


if __name__ == "__main__":
    raise SystemExit(main())
