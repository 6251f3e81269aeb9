"""Headless demo: ``sim_bridge`` + ``explorer`` as two ROS processes, watched by a monitor.

:func:`run_demo` starts ``python -m sim_bridge.node`` (the simulator owning ``/clock``,
faster than real time) and ``python -m explore_seg.explorer`` (with ``use_sim_time``),
then spins a monitor node in this process that subscribes to ``sim/metrics``,
``goal_pose``, ``exploration_done``, ``map``, ``odom``, ``regions`` (+ ``regions/info``)
and ``object_costmap/markers``. It prints a progress line (sim time, coverage, goals,
collisions, objects, regions), collects animation frames and stops at
``exploration_done``, at the sim time limit, or on a failure:

* a child process exits (its log tail is printed);
* no ``sim/metrics`` for ``stall_wall_s`` wall seconds, or the coverage did not grow for
  ``stall_sim_s`` sim seconds while exploration is not done ("no progress");
* ``wall_timeout_s`` passed.

Outputs in the output folder: ``final_map.png`` (map, path, regions, object boxes, goals,
collisions), ``coverage.png`` (coverage vs sim time), ``exploration.gif``,
``metrics.json`` (with the collision events and the final object footprints),
``object_history.jsonl`` (``{"t": sim time, "boxes": footprints}`` each time the set of
boxes changed), ``sim/`` (the simulator's own metrics and map) and ``logs/``.

The environment should hold ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` and a private
``ROS_DOMAIN_ID``; :func:`main` sets both when absent, and ``scripts/run_demo.sh`` also
runs everything in a private network namespace when the kernel allows it.

Usage (``scripts/run_demo.sh`` adds the network namespace)::

    .venv/bin/python scripts/demo.py OUT [--world house_cluttered] [--rtf 4] [--max-sim-time 1500]
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from scripts.demo_lib import STOP, DemoConfig, DemoError, boxes_from_markers, \
    explorer_command, metrics_from_diagnostics, run_demo, sim_command  # noqa: E402
from sim_bridge.lockstep import STRATEGY_SPECS  # noqa: E402

#: What tests and scripts import from here (the demo's parts live in scripts/demo_lib/).
__all__ = ["DemoConfig", "DemoError", "boxes_from_markers", "explorer_command", "main",
           "metrics_from_diagnostics", "run_demo", "sim_command"]
#: Exit codes of :func:`main`.
EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


def _parse(argv: list[str] | None) -> DemoConfig:
    d = DemoConfig(out_dir="")
    ap = argparse.ArgumentParser(prog="scripts/demo.py",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="output folder")
    ap.add_argument("--world", default=d.world, help="world name or file")
    ap.add_argument("--strategy", default=d.strategy, choices=list(STRATEGY_SPECS))
    ap.add_argument("--seed", type=int, default=d.seed)
    ap.add_argument("--rtf", type=float, default=d.real_time_factor,
                    help="sim seconds per wall second")
    ap.add_argument("--max-sim-time", type=float, default=d.max_sim_time_s)
    ap.add_argument("--wall-timeout", type=float, default=d.wall_timeout_s)
    ap.add_argument("--stall-sim", type=float, default=d.stall_sim_s,
                    help="fail when coverage does not grow for this many sim seconds")
    ap.add_argument("--stop-coverage", type=float, default=0.0,
                    help="also stop at this coverage %% (0 = only at exploration_done)")
    ap.add_argument("--explorer-threads", type=int, default=d.explorer_threads,
                    help="executor threads of the explorer (1 = single-threaded)")
    ap.add_argument("--params-file", default="", help="explorer parameter file")
    ap.add_argument("--no-explorer", action="store_true",
                    help="run the simulator and the monitor only")
    ap.add_argument("--odom-in-map", action="store_true",
                    help="simulator odometry is the map-frame pose (no drift, no SLAM pose "
                         "topic; explorer pose_topic_type odom) instead of the real-robot "
                         "contract (drifting odom + scan-rate pose, fused)")
    ap.add_argument("--sim-arg", action="append", default=[],
                    help="extra ROS argument for the simulator (repeatable)")
    ap.add_argument("--explorer-arg", action="append", default=[],
                    help="extra argument for the explorer (repeatable)")
    a = ap.parse_args(argv)
    return DemoConfig(out_dir=a.out, world=a.world, strategy=a.strategy, seed=a.seed,
                      real_time_factor=a.rtf, max_sim_time_s=a.max_sim_time,
                      wall_timeout_s=a.wall_timeout, stall_sim_s=a.stall_sim,
                      stop_coverage_pct=a.stop_coverage, params_file=a.params_file,
                      explorer=not a.no_explorer, explorer_threads=a.explorer_threads,
                      real_robot_pose=not a.odom_in_map,
                      sim_args=tuple(a.sim_arg),
                      explorer_args=tuple(a.explorer_arg))


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns 0 on success, 1 on a failed demo, 2 on bad arguments."""
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    try:
        cfg = _parse(argv)
    except ValueError as err:
        print(f"[demo] {err}", file=sys.stderr)
        return EXIT_USAGE
    def _on_signal(signum, frame):
        # Only a flag: an exception raised wherever the signal lands (inside rclpy's wait,
        # a subprocess call) could surface as another error; the loops check STOP.
        STOP.set()

    signal.signal(signal.SIGINT, _on_signal)
    signal.signal(signal.SIGTERM, _on_signal)
    try:
        m = run_demo(cfg, log=lambda s: print(s, flush=True))
    except DemoError as err:
        print(f"[demo] FAILED: {err}", file=sys.stderr, flush=True)
        return EXIT_FAILED
    print(f"[demo] done ({m['stop_reason']}): coverage {m['coverage_pct']} %, sim "
          f"{m['sim_time_s']:.0f} s in {m['wall_time_s']:.0f} s wall, {m['goals_sent']} goals, "
          f"{m['collisions']} collisions; outputs in {cfg.out_dir}: "
          + ", ".join(m["files"] + ["metrics.json"]), flush=True)
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())
