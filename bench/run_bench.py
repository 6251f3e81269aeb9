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
``small_house``, ``small_cluttered``), ``shared/NAME`` for ``<shared>/worlds/NAME.world.yaml``
and ``eb/NAME`` for the Explore-Bench map ``<shared>/worlds/explore_bench/NAME.yaml``
(``<shared>`` = ``$EXPLORE_SEG_SHARED`` or ``../shared`` beside the repository), or a
path to a world file.

Usage::

    .venv/bin/python bench/run_bench.py --runs 20 --jobs 2 --out out/bench
    .venv/bin/python bench/run_bench.py --runs 3 --worlds house --strategies paper,nearest
    .venv/bin/python bench/run_bench.py --report-only --out out/bench
    .venv/bin/python bench/run_bench.py --ros 2 --runs 2 --worlds small_house

Stopping: SIGINT/SIGTERM stop at once (the runs in flight are lost); ``kill -USR1 PID``
finishes the runs in flight and starts no new ones. Either way the runs so far are
reported, the part is marked interrupted, and ``--resume`` continues.
"""

from __future__ import annotations

import argparse
import csv
import functools
import json
import math
import multiprocessing as mp
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from bench import records  # noqa: E402
from sim_bridge import worlds as sim_worlds  # noqa: E402
from sim_bridge.coverage_tour import TourParams, coverage_tour  # noqa: E402
from sim_bridge.engine import SimParams, load_world  # noqa: E402
from sim_bridge.observable import with_observable  # noqa: E402
from sim_bridge.lockstep import STRATEGIES, STRATEGY_SPECS, ExplorerParams, LockstepParams, \
    LockstepState, RunResult, load_explorer_params, run_exploration  # noqa: E402

GENERATED_WORLDS = ("house", "maze", "house_cluttered")
SHARED_WORLDS = ("house", "house_cluttered", "house_cluttered_plus", "maze")
#: Sim time limit per m^2 of explorable area, and its bounds (s).
TIME_PER_AREA_S = 5.0
MIN_SIM_TIME_S = 600.0
MAX_SIM_TIME_S = 7200.0


def shared_dir() -> Path | None:
    """``$EXPLORE_SEG_SHARED`` or ``../shared`` beside the repository, when present."""
    env = os.environ.get("EXPLORE_SEG_SHARED")
    cand = Path(env) if env else ROOT.parent / "shared"
    return cand if cand.is_dir() else None


def default_worlds() -> list[str]:
    """Generated worlds, plus the shared worlds and Explore-Bench maps when present."""
    names = list(GENERATED_WORLDS)
    sh = shared_dir()
    if sh is not None:
        names += [f"shared/{n}" for n in SHARED_WORLDS
                  if (sh / "worlds" / f"{n}.world.yaml").is_file()]
        eb = sh / "worlds" / "explore_bench"
        names += [f"eb/{p.stem}" for p in sorted(eb.glob("*.yaml")) if p.stem != "starts"]
    return names


def world_path(spec: str) -> str:
    """Resolve a world spec to what :func:`sim_bridge.engine.load_world` takes.

    Raises
    ------
    ValueError
        When a ``shared/`` or ``eb/`` world is asked for and the shared folder is absent.
    """
    for prefix, sub, suffix in (("shared/", "", ".world.yaml"), ("eb/", "explore_bench", ".yaml")):
        if spec.startswith(prefix):
            sh = shared_dir()
            if sh is None:
                raise ValueError(f"world {spec!r} needs the shared folder (../shared or "
                                 "$EXPLORE_SEG_SHARED), which is absent")
            return str(sh / "worlds" / sub / f"{spec[len(prefix):]}{suffix}")
    return spec


@functools.lru_cache(maxsize=64)
def load(spec: str):
    """(World, GroundTruth with its observable cells) of a spec, cached per process (the
    main process fills it before the workers fork)."""
    world = load_world(world_path(spec))
    world.name = spec
    sp = SimParams()
    return world, with_observable(world, sim_worlds.ground_truth(world), sp.lidar_params(),
                                  sp.robot_radius_m)


def sim_time_limit(area_m2: float, override: float | None) -> float:
    """``override`` or ``TIME_PER_AREA_S`` per m^2 within [MIN_SIM_TIME_S, MAX_SIM_TIME_S]."""
    if override:
        return float(override)
    return float(min(MAX_SIM_TIME_S, max(MIN_SIM_TIME_S, TIME_PER_AREA_S * area_m2)))


# ----------------------------------------------------------------------- workers


#: RGB-D camera mount of the paper's robot (height above the floor m, pitch rad down).
PAPER_CAMERA_MOUNT = (0.894, 0.1)


def sim_params_for(camera_mount: tuple[float, float] | None,
                   nav_margin_m: float | None = None) -> SimParams:
    """Simulator parameters of the runs: the defaults, with the camera at
    ``camera_mount`` = (height m, pitch rad) unless None, and the navigation stand-in's
    clearance beyond the robot radius (``nav_inflation_margin_m``) unless None."""
    kw: dict[str, float] = {}
    if camera_mount is not None:
        kw.update(camera_mount_z_m=camera_mount[0], camera_pitch_rad=camera_mount[1])
    if nav_margin_m is not None:
        kw["nav_inflation_margin_m"] = nav_margin_m
    return SimParams(**kw)


#: The nodes' parameters of this benchmark, read once before the workers fork (an edit
#: of config/explorer.yaml during a long benchmark must not change its later runs).
_EXPLORER_PARAMS: ExplorerParams | None = None


def _run_task(task: tuple[str, str, int, float, str | None, tuple[float, float] | None,
                          float | None]) -> dict[str, Any]:
    spec, strategy, seed, max_t, picture, mount, nav_margin = task
    world, gt = load(spec)
    last: dict[str, LockstepState] = {}

    def keep_last(st: LockstepState) -> None:
        last["state"] = st

    res = run_exploration(world, strategy, seed, max_sim_time_s=max_t, ground_truth=gt,
                          sim_params=sim_params_for(mount, nav_margin),
                          explorer_params=_EXPLORER_PARAMS,
                          observer=keep_last if picture else None)
    if picture and "state" in last:
        _save_picture(last["state"], picture)
    return res.to_dict()


def _save_picture(st: LockstepState, path: str) -> None:
    import dataclasses

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


def _tour_task(spec: str) -> dict[str, Any]:
    world, gt = load(spec)
    t0 = time.perf_counter()
    tour = coverage_tour(world, params=TourParams(), ground_truth=gt)
    return {"world": spec, "tour_m": round(tour.length_m, 2),
            "viewpoints": int(len(tour.viewpoints_xy)),
            "coverable_fraction": round(tour.coverable_fraction, 4),
            "explorable_area_m2": round(gt.explorable_area_m2, 2),
            "wall_s": round(time.perf_counter() - t0, 1)}


def time_yolo(frames: int, world_spec: str = "house_cluttered") -> dict[str, Any]:
    """Time the real detector (auto backend) on frames rendered along the world.

    Returns a dict with the backend, per-frame milliseconds (p50, p95, mean) and the
    frame size, or ``{"error": ...}`` when the model files are missing.
    """
    from explore_seg.core.detector import Detector, DetectorParams
    from sim_bridge.sensors import CameraParams, DepthCamera

    try:
        det = Detector(DetectorParams())
    except (FileNotFoundError, ImportError, ValueError) as err:
        return {"error": f"{type(err).__name__}: {err}"}
    world, gt = load(world_spec)
    cam = DepthCamera(world, CameraParams())
    rng = np.random.default_rng(0)
    free = np.argwhere(gt.inside)
    times, n_dets = [], []
    for k in range(frames + 1):
        r, c = free[rng.integers(len(free))]
        x, y = gt.lidar.cell_to_world(int(r), int(c))
        frame = cam.render((x, y, float(rng.uniform(-math.pi, math.pi))))
        t0 = time.perf_counter()
        dets = det.detect(frame.rgb)
        if k:  # the first call warms up (graph build, allocations)
            times.append((time.perf_counter() - t0) * 1e3)
            n_dets.append(len(dets))
    a = np.asarray(times)
    return {"backend": det.backend_name, "input_size": det.params.input_size,
            "threads": det.params.num_threads, "frames": frames,
            "frame_size": [cam.params.width, cam.params.height],
            "ms_p50": round(float(np.percentile(a, 50)), 1),
            "ms_p95": round(float(np.percentile(a, 95)), 1),
            "ms_mean": round(float(a.mean()), 1),
            "detections_mean": round(float(np.mean(n_dets)), 2)}


# ---------------------------------------------------------------------- progress


class Progress:
    """Plain-text progress bar on stderr (one line per update when not a terminal)."""

    def __init__(self, total: int, label: str, width: int = 30) -> None:
        self.total, self.label, self.width = total, label, width
        self.done = 0
        self.t0 = time.monotonic()
        self.tty = sys.stderr.isatty()

    def update(self, note: str = "") -> None:
        self.done += 1
        el = time.monotonic() - self.t0
        eta = el / self.done * (self.total - self.done)
        fill = int(self.width * self.done / max(self.total, 1))
        line = (f"[{self.label}] [{'#' * fill}{'.' * (self.width - fill)}] "
                f"{self.done}/{self.total} {_hms(el)} elapsed, eta {_hms(eta)} {note}")
        if self.tty:
            sys.stderr.write("\r" + line[:160].ljust(160))
            if self.done == self.total:
                sys.stderr.write("\n")
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()


def _hms(s: float) -> str:
    s = int(round(s))
    return f"{s // 3600}h{s % 3600 // 60:02d}m{s % 60:02d}s" if s >= 3600 else \
        f"{s // 60}m{s % 60:02d}s"


# -------------------------------------------------------------------------- main


def _parse(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=20, help="seeded runs per world x strategy")
    ap.add_argument("--worlds", default="", help="comma-separated world specs "
                    "(default: generated + shared worlds)")
    ap.add_argument("--strategies", default=",".join(STRATEGIES),
                    help=f"comma-separated, from {','.join(STRATEGIES)}")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes")
    ap.add_argument("--out", default="out/bench", help="output folder")
    ap.add_argument("--md", default=str(ROOT / "BENCHMARKS.md"),
                    help="where to write BENCHMARKS.md ('' = not at all)")
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
    ap.add_argument("--report-only", action="store_true",
                    help="only redo plots and BENCHMARKS.md from --out")
    ap.add_argument("--resume", action="store_true",
                    help="keep the runs and tours already in --out that this command asks "
                         "for (same world, strategy, seed) and run only the missing ones; "
                         "runs of other worlds/strategies/seeds are dropped")
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
    if a.merge and not a.resume:
        ap.error("--merge needs --resume")
    if a.no_runs and not a.resume:
        ap.error("--no-runs needs --resume")
    if a.no_runs and a.redo:
        ap.error("--no-runs runs nothing: no --redo")
    if a.nav_margin is not None:
        try:
            sim_params_for(None, a.nav_margin).nav_params()
        except ValueError as err:
            ap.error(f"--nav-margin {a.nav_margin}: {err}")
    if a.runs < 1 or a.jobs < 1:
        ap.error("--runs and --jobs must be >= 1")
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


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (see the module docstring); returns the exit status."""
    global _EXPLORER_PARAMS
    a = _parse(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    command = "bench/run_bench.py " + " ".join(shlex.quote(x) for x in (argv if argv is not None
                                                                        else sys.argv[1:]))
    from bench import report

    if a.report_only:
        report.write_all(out, Path(a.md) if a.md else None, command=None)
        return 0
    specs = [w for w in (a.worlds.split(",") if a.worlds else default_worlds()) if w]
    strategies = [s for s in a.strategies.split(",") if s]
    try:
        for s in specs:
            world_path(s)
    except ValueError as err:
        print(f"[bench] {err}", file=sys.stderr)
        return 2
    meta = {"command": command, "runs": a.runs, "seed0": a.seed0, "worlds": specs,
            "strategies": strategies, "jobs": a.jobs, "cpus": os.cpu_count(),
            "settings": _settings(a), "code": _code_version(),
            "lockstep_params": {k: v for k, v in vars(LockstepParams()).items()},
            "camera_mount": (list(a.mount) if a.mount is not None else
                             [SimParams().camera_mount_z_m, SimParams().camera_pitch_rad]),
            "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    t_start = time.monotonic()
    old_meta = _read_json(out / "meta.json") if a.resume else {}
    if old_meta:
        old_settings = old_meta.get("settings")
        if old_settings is not None and not _same_settings(old_settings, meta["settings"]):
            print(f"[bench] --resume: the runs in {out} were made with other settings "
                  f"({old_settings}, now {meta['settings']}); use another --out",
                  file=sys.stderr)
            return 2
        old_codes = {p.get("code") for p in old_meta.get("parts") or [old_meta]}
        if a.merge:
            err = _merge(out, Path(a.merge), meta, old_meta)
            if err:
                print(f"[bench] --merge: {err}", file=sys.stderr)
                return 2
            old_codes = {p.get("code") for p in old_meta.get("parts") or [old_meta]}
        if old_codes != {meta["code"]}:
            print(f"[bench] --resume: warning: earlier parts ran on code {sorted(map(str, old_codes))}, "
                  f"this one on {meta['code']} (listed in the report)", file=sys.stderr)
    interrupted: int = 0          # the signal that stopped the runs, 0 = none
    counter = [0]                 # runs run so far
    failed: list[str] = []        # runs that raised: "world/strategy/seed: error"
    tours: list[dict[str, Any]] = []
    results: list[dict[str, Any]] = []
    areas: dict[str, float] = {}
    old_term = signal.signal(signal.SIGTERM, _raise_interrupt)
    _DRAIN[0] = False
    old_usr1 = signal.signal(signal.SIGUSR1, _request_drain)
    try:
        # Worlds, ground truths and explorable areas before the workers fork (they
        # inherit the cache).
        areas = {s: float(load(s)[1].explorable_area_m2) for s in specs}
        _EXPLORER_PARAMS = load_explorer_params()
        if a.no_runs:
            results += records.read(out)
            tours += [dict(r, tour_m=float(r["tour_m"])) for r in
                      report.read_csv(out / "tours.csv")] if (out / "tours.csv").is_file() else []
            stray = sorted({f"{d['world']}:{d['strategy']}" for d in results
                            if d["world"] not in specs or d["strategy"] not in strategies})
            if stray:
                print(f"[bench] --no-runs: --out holds runs of worlds/strategies not among "
                      f"--worlds/--strategies: {', '.join(stray)}", file=sys.stderr)
                return 2
        else:
            ctx = mp.get_context("fork")
            with ctx.Pool(a.jobs, initializer=_worker_init, maxtasksperchild=20) as pool:
                try:
                    _run_all(a, out, specs, strategies, areas, pool, tours, results, counter,
                             failed)
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
        signal.signal(signal.SIGTERM, old_term)
        signal.signal(signal.SIGUSR1, old_usr1)
    tour_by_world = {t["world"]: t["tour_m"] for t in tours}
    rows = []
    order = {(s, st): i for i, (s, st) in enumerate((s, st) for s in specs for st in strategies)}
    for d in sorted(results, key=lambda d: (order[(d["world"], d["strategy"])], d["seed"])):
        row = _row_from_dict(d)
        tour = tour_by_world.get(d["world"])
        row["tour_m"] = tour if tour is not None else ""
        row["path_over_tour"] = (round(d["path_length_m"] / tour, 3)
                                 if tour and d["completed"] else "")
        rows.append(row)
    _write_csv(out / "runs.csv", rows)
    if a.yolo_frames > 0 and not interrupted:
        yolo = time_yolo(a.yolo_frames)
        (out / "yolo.json").write_text(json.dumps(yolo, indent=1))
        print(f"[bench] real detector: {yolo}", file=sys.stderr)
    if a.ros > 0 and not interrupted:
        ros = compare_with_ros(specs[0], a.ros_strategy, [a.seed0 + k for k in range(a.ros)],
                               out / "ros", a.ros_rtf,
                               sim_time_limit(areas[specs[0]], a.max_sim_time), a.mount,
                               a.nav_margin)
        (out / "ros.json").write_text(json.dumps(ros, indent=1))
    part = {"command": command, "started": meta["started"], "code": meta["code"],
            "runs_run": counter[0], "wall_s": round(time.monotonic() - t_start, 1)}
    if interrupted:
        part["interrupted"] = True
    if failed:
        part["failed"] = failed
    parts = (old_meta.get("parts") or ([_part_of(old_meta)] if old_meta else [])) + [part]
    meta["parts"] = parts
    meta["wall_s"] = round(sum(float(p.get("wall_s") or 0.0) for p in parts), 1)
    (out / "meta.json").write_text(json.dumps(meta, indent=1))
    report.write_all(out, Path(a.md) if a.md else None, command=command)
    print(f"[bench] {len(results)} runs in {_hms(meta['wall_s'])}; results in {out}"
          + (f", summary in {a.md}" if a.md else ""), file=sys.stderr)
    if failed:
        print(f"[bench] {len(failed)} runs failed (not in the results; --resume runs them "
              "again): " + "; ".join(failed), file=sys.stderr)
    return 128 + interrupted if interrupted else (1 if failed else 0)


def _run_all(a: argparse.Namespace, out: Path, specs: list[str], strategies: list[str],
             areas: dict[str, float], pool: Any, tours: list[dict[str, Any]],
             results: list[dict[str, Any]], counter: list[int], failed: list[str]) -> None:
    """Tours and runs, filling ``tours`` and ``results`` (and ``failed`` with the runs
    that raised); ``counter[0]`` counts the runs
    run (read it after an interrupt)."""
    from bench import report

    if not a.no_tour:
        if a.resume:
            tours += [dict(r, tour_m=float(r["tour_m"]))
                      for r in report.read_csv(out / "tours.csv") if r["world"] in specs]
        todo = [s for s in specs if s not in {r["world"] for r in tours}]
        prog = Progress(len(todo), "tours")
        for row in pool.imap_unordered(_tour_task, todo):
            tours.append(row)
            prog.update(f"{row['world']}: {row['tour_m']} m")
        _write_csv(out / "tours.csv", sorted(tours, key=lambda r: specs.index(r["world"])))
    (out / "maps").mkdir(exist_ok=True)
    tasks = []
    for s in specs:
        limit = sim_time_limit(areas[s], a.max_sim_time)
        for strat in strategies:
            for k in range(a.runs):
                pic = (str(out / "maps" / f"{_slug(s)}_{strat}.png") if k == 0 else None)
                tasks.append((s, strat, a.seed0 + k, limit, pic, a.mount, a.nav_margin))
    if a.resume:
        wanted = {t[:3] for t in tasks
                  if not any(st == t[1] and w in (None, t[0]) for w, st in a.redo_keys)}
        old = records.read(out)
        for d in old:
            key = (d["world"], d["strategy"], d["seed"])
            if key in wanted:
                wanted.discard(key)  # a duplicate line counts once
                results.append(d)
        if len(results) < len(old):  # runs this command does not ask for: keep a copy
            baks = [_backup(out / name) for name in (records.FULL, records.COMPACT)
                    if (out / name).is_file()]
            print(f"[bench] resume: {len(old) - len(results)} runs not asked for or to "
                  f"redo are left out (copy in {', '.join(map(str, baks))})", file=sys.stderr)
        done = {(d["world"], d["strategy"], d["seed"]) for d in results}
        tasks = [t for t in tasks if t[:3] not in done]
        print(f"[bench] resume: {len(results)} runs kept, {len(tasks)} to run",
              file=sys.stderr)
    # Seed by seed (an interrupted benchmark has as many runs of every world x strategy,
    # +-1), long worlds first within a seed so the pool does not end on one slow run.
    tasks.sort(key=lambda t: (t[2], -areas[t[0]]))
    prog = Progress(len(tasks), "runs")
    records.write_compact(out, results)
    with open(out / records.FULL, "w") as jl:
        for d in results:
            jl.write(json.dumps(d) + "\n")
        jl.flush()
        for d in _run_drainable(pool, a.jobs, tasks, failed):
            # an interrupt waits until the run is in both files and counted
            mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
            try:
                jl.write(json.dumps(d) + "\n")
                jl.flush()
                records.append_compact(out, d)
                results.append(d)
                counter[0] += 1
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)
            prog.update(f"{d['world']}/{d['strategy']}/{d['seed']}: "
                        f"{d['coverage_pct'] or 0:.1f} % {d['stop_reason']} "
                        f"({d['wall_time_s']:.0f} s)")


def _run_drainable(pool: Any, jobs: int, tasks: list[tuple], failed: list[str]) -> Any:
    """Yield the results of ``tasks`` as they finish, at most ``jobs`` in flight.

    A run that raises is reported on stderr (with its traceback) and added to ``failed``
    as ``"world/strategy/seed: error"``; the others go on (it is not in the output files,
    so ``--resume`` runs it again).

    SIGUSR1 makes it start no further task and end once the ones in flight have finished
    (raising ``KeyboardInterrupt(SIGUSR1)`` then, so the caller reports like after an
    interrupt): a long benchmark is stopped without losing the work of its running runs.
    The next task is handed out before a result is yielded, so a run that is in the
    output files is never the last one started.
    """
    import queue

    done: queue.Queue = queue.Queue()
    todo = list(tasks)
    in_flight = 0
    said = False

    def top_up() -> int:
        n = 0
        while todo and in_flight + n < max(1, jobs) and not _DRAIN[0]:
            task = todo.pop(0)
            pool.apply_async(_run_task, (task,), callback=lambda r: done.put((r, None, None)),
                             error_callback=lambda e, t=task: done.put((None, e, t)))
            n += 1
        return n

    in_flight += top_up()
    while in_flight:
        if _DRAIN[0] and not said:
            said = True
            print(f"\n[bench] SIGUSR1: finishing the {in_flight} run(s) in flight, starting "
                  "no new ones", file=sys.stderr)
        try:
            result, err, task = done.get(timeout=0.2)
        except queue.Empty:
            continue
        in_flight -= 1
        in_flight += top_up()
        if err is None:
            yield result
            continue
        name = f"{task[0]}/{task[1]}/{task[2]}"
        cause = getattr(err, "__cause__", None)     # the worker's traceback, as text
        print(f"\n[bench] run {name} failed: {type(err).__name__}: {err}"
              + (f"\n{cause}" if cause is not None else ""), file=sys.stderr)
        failed.append(f"{name}: {type(err).__name__}: {err}")
    if _DRAIN[0] and todo:
        raise KeyboardInterrupt(int(signal.SIGUSR1))


#: Settings that parts of earlier versions did not record, with the value they ran on.
SETTING_DEFAULTS: dict[str, Any] = {"nav_inflation_margin_m": 0.0}


def _settings(a: argparse.Namespace) -> dict[str, Any]:
    """What must match for runs of two parts to be comparable (``--resume``), as it reads
    back from meta.json."""
    settings: dict[str, Any] = {
        "max_sim_time": a.max_sim_time,
        "camera_mount": list(a.mount) if a.mount is not None else None,
        "lockstep_params": {k: v for k, v in vars(LockstepParams()).items()},
        "nav_inflation_margin_m": sim_params_for(None, a.nav_margin).nav_inflation_margin_m}
    return json.loads(json.dumps(settings))


def _code_version() -> str:
    """Git commit of the repository, ``+modified`` when the code differs from it."""
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=12", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "diff", "--quiet", "HEAD", "--", "explore_seg",
                                "sim_bridge", "bench", "config", ":(exclude)bench/results"],
                               cwd=ROOT, timeout=10).returncode != 0
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return (rev or "unknown") + ("+modified" if dirty and rev else "")


#: Set by SIGUSR1: start no new run (see :func:`_run_drainable`).
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


def compare_with_ros(world: str, strategy: str, seeds: list[int], out: Path, rtf: float,
                     max_sim_time_s: float, camera_mount: tuple[float, float] | None = None,
                     nav_margin: float | None = None) -> dict[str, Any]:
    """The same world/strategy/seeds in lock step and through ROS (``scripts/demo.py``:
    ``sim_bridge`` + ``explorer`` processes), both stopping at 99 % coverage.

    The lock-step runs use the unperturbed start (the simulator node has no start
    perturbation); sensor noise and message timing still differ, so the two agree in
    distribution, not run for run.
    """
    import subprocess

    rows = []
    world_obj, gt = load(world)
    for seed in seeds:
        r = run_exploration(world_obj, strategy, seed, max_sim_time_s=max_sim_time_s,
                            ground_truth=gt, sim_params=sim_params_for(camera_mount, nav_margin),
                            params=LockstepParams(start_jitter_m=0.0, start_yaw_jitter_rad=0.0))
        rows.append({"seed": seed, "mode": "lock-step", "stop": r.stop_reason,
                     "coverage_pct": r.coverage_pct, "sim_time_s": r.sim_time_s,
                     "path_length_m": r.path_length_m, "collisions": r.collisions,
                     "goals": r.goals_sent, "objects": r.n_objects,
                     "object_frames": "every frame" if STRATEGY_SPECS[strategy].use_objects
                     else "-"})
        d = out / f"seed{seed}"
        cmd = [sys.executable, str(ROOT / "scripts" / "demo.py"), str(d), "--world",
               world_path(world), "--strategy", strategy, "--seed", str(seed), "--rtf", str(rtf),
               "--max-sim-time", str(max_sim_time_s), "--stop-coverage", "99"]
        if camera_mount is not None:   # the same mount in the simulator and the node
            z, pitch = camera_mount
            cmd += ["--sim-arg=-p", f"--sim-arg=camera_mount_z_m:={z}",
                    "--sim-arg=-p", f"--sim-arg=camera_pitch_rad:={pitch}",
                    "--explorer-arg=-p", f"--explorer-arg=camera_z_m:={z}",
                    "--explorer-arg=-p", f"--explorer-arg=camera_pitch_rad:={pitch}"]
        if nav_margin is not None:
            cmd += ["--sim-arg=-p", f"--sim-arg=nav_inflation_margin_m:={nav_margin}"]
        proc = subprocess.run(cmd, cwd=str(ROOT), capture_output=True, text=True)
        mj = d / "metrics.json"
        m = json.loads(mj.read_text()) if mj.is_file() else {}
        rows.append({"seed": seed, "mode": "ROS",
                     "stop": m.get("stop_reason") or f"rc={proc.returncode}",
                     "coverage_pct": m.get("coverage_pct"), "sim_time_s": m.get("sim_time_s"),
                     "path_length_m": m.get("path_length_m"),
                     "collisions": m.get("collisions"), "goals": m.get("goals_sent"),
                     "objects": m.get("n_objects"),
                     "object_frames": (f"{m['object_frames_processed']} of "
                                       f"{m['camera_frames_rendered']}"
                                       if m.get("camera_frames_rendered") else "-")})
        print(f"[bench] ROS seed {seed}: {rows[-1]}", file=sys.stderr)
    note = (f"World `{world}`, strategy `{strategy}`, unperturbed start; the ROS runs use "
            f"`sim_bridge` + `explorer` processes at real-time factor {rtf} "
            "(`scripts/demo.py`). Both stop at 99 % coverage. Object frames: camera frames "
            "the object costmap processed, of those rendered.")
    return {"note": note, "rows": rows}


def _read_json(path: Path) -> dict[str, Any]:
    """A JSON object file, {} when absent or unreadable."""
    try:
        d = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return d if isinstance(d, dict) else {}


def _backup(path: Path) -> Path:
    """A copy of ``path`` as ``<name>.bak``, ``.bak1``, ... (never over an earlier copy)."""
    bak, k = path.with_name(path.name + ".bak"), 1
    while bak.exists():
        bak, k = path.with_name(f"{path.name}.bak{k}"), k + 1
    shutil.copyfile(path, bak)
    return bak


def _merge(out: Path, other: Path, meta: dict[str, Any], old_meta: dict[str, Any]) -> str:
    """Add the runs of ``other`` to ``out`` (a run of both: ``other``'s is kept) and its
    parts to ``old_meta``'s; '' or what is wrong (then nothing was changed). Merging a
    folder again adds no part twice."""
    o_meta = _read_json(other / "meta.json")
    if not o_meta:
        return f"{other} has no meta.json"
    if not _same_settings(o_meta.get("settings"), meta["settings"]):
        return (f"the runs in {other} were made with other settings ({o_meta.get('settings')}, "
                f"now {meta['settings']})")
    theirs = records.read(other)
    if not theirs:
        return f"{other} holds no runs"
    stray = sorted({f"{d['world']}:{d['strategy']}" for d in theirs
                    if d["world"] not in meta["worlds"] or d["strategy"] not in meta["strategies"]})
    if stray:
        return f"{other} holds runs of worlds/strategies this command does not name: {stray}"
    mine = {records.key_of(d): d for d in records.read(out)}
    keys = {records.key_of(d) for d in theirs}
    if any(k in mine for k in keys):
        for name in (records.FULL, records.COMPACT):
            if (out / name).is_file():
                _backup(out / name)
    merged = [d for k, d in mine.items() if k not in keys] + theirs
    with open(out / records.FULL, "w") as jl:        # both files hold the merged runs
        for d in merged:
            jl.write(json.dumps(d) + "\n")
    records.write_compact(out, merged)
    parts = (old_meta.get("parts") or ([_part_of(old_meta)] if old_meta else []))
    have = {(p.get("started"), p.get("command")) for p in parts}
    o_parts = [dict(p, merged_from=str(other)) for p in (o_meta.get("parts") or [_part_of(o_meta)])
               if (p.get("started"), p.get("command")) not in have]
    old_meta["parts"] = parts + o_parts
    old_meta.setdefault("settings", meta["settings"])
    tours = out / "tours.csv"
    if (other / "tours.csv").is_file():
        from bench import report
        have_t = {r["world"] for r in report.read_csv(tours)}
        extra = [r for r in report.read_csv(other / "tours.csv") if r["world"] not in have_t]
        if extra:
            _write_csv(tours, report.read_csv(tours) + extra)
    print(f"[bench] --merge: {len(theirs)} runs and {len(o_parts)} parts of {other} added",
          file=sys.stderr)
    return ""


def _same_settings(old: dict[str, Any] | None, new: dict[str, Any]) -> bool:
    """Settings of two parts compare equal; a setting an older part did not record had
    the value it was always run with (:data:`SETTING_DEFAULTS`)."""
    if old is None:
        return False
    return ({**SETTING_DEFAULTS, **old} == {**SETTING_DEFAULTS, **new})


def _part_of(meta: dict[str, Any]) -> dict[str, Any]:
    """A pre-``parts`` meta.json as one part."""
    return {"command": meta.get("command"), "started": meta.get("started"),
            "runs_run": None, "wall_s": meta.get("wall_s")}


def _row_from_dict(d: dict[str, Any]) -> dict[str, Any]:
    """The CSV row of a run stored as :meth:`RunResult.to_dict` (None -> NaN)."""
    cls = RunResult
    fields = {k: v for k, v in d.items() if k in cls.__dataclass_fields__}
    for k in ("time_to_s", "path_to_m"):
        fields[k] = {kk: (math.nan if vv is None else vv) for kk, vv in fields[k].items()}
    for k in ("coverage_pct", "explorable_area_m2"):
        if fields.get(k) is None:
            fields[k] = math.nan
    row = cls(**fields).summary_row()
    if "timings_ms" not in d:              # compact or CSV record: its per-run percentiles
        for key, (p50, p95) in (d.get("timing_p") or {}).items():
            row[f"{key}_ms_p50"] = p50 if p50 is not None else math.nan
            row[f"{key}_ms_p95"] = p95 if p95 is not None else math.nan
    return row


def _slug(spec: str) -> str:
    return spec.replace("/", "_").replace(".", "_")


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    if not rows:
        path.write_text("")
        return
    keys = list(rows[0])
    for r in rows[1:]:
        keys += [k for k in r if k not in keys]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    raise SystemExit(main())
