"""Soak run (not a test): ``sim_bridge`` + ``explorer`` for N minutes, RSS and CPU watched.

Starts the same two processes as ``scripts/demo.py`` (explorer first, then the simulator,
faster than real time), spins the demo's monitor node to learn ``exploration_done``, and
samples both processes from ``/proc`` every ``--sample-s`` wall seconds: resident memory
(VmRSS) and CPU time (user + system). It prints one line per sample, then

* the explorer's RSS growth per minute (least-squares slope over the samples after the
  first minute, so start-up allocation is not counted as growth);
* the explorer's CPU % (CPU seconds / wall seconds, 100 % = one core) while exploring and
  in the ``--after-done-s`` wall seconds after ``exploration_done`` (the idle cost).

It stops ``--after-done-s`` after done, or after ``--minutes``. Linux only (``/proc``).
``soak.json`` in OUT keeps the samples and the summary; ``logs/`` the children's logs.

Usage (``scripts/run_demo.sh``'s network namespace is advisable on a shared host)::

    nice -n 10 .venv/bin/python scripts/soak.py OUT [--minutes 10] [--world small_cluttered]
        [--rtf 4] [--after-done-s 60] [--sample-s 30]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from scripts.demo_lib import STOP, Child, DemoConfig, DemoError, Monitor, child_env, \
    explorer_command, sim_command, start_monitor, stop_monitor, wait_for_explorer  # noqa: E402

_TICK = os.sysconf("SC_CLK_TCK")
_PAGE = os.sysconf("SC_PAGE_SIZE")


def proc_usage(pid: int) -> tuple[float, float]:
    """(CPU seconds used so far, resident MB) of process ``pid`` from ``/proc``.

    Raises
    ------
    OSError
        When the process is gone.
    """
    stat = Path(f"/proc/{pid}/stat").read_text()
    fields = stat[stat.rindex(")") + 2:].split()       # after "pid (comm) "
    cpu_s = (int(fields[11]) + int(fields[12])) / _TICK  # utime, stime
    rss_pages = int(Path(f"/proc/{pid}/statm").read_text().split()[1])
    return cpu_s, rss_pages * _PAGE / 2**20


@dataclass(frozen=True)
class Sample:
    """One sample of both processes."""

    wall_s: float
    sim_s: float
    coverage_pct: float
    done: bool
    explorer_cpu_s: float
    explorer_rss_mb: float
    sim_cpu_s: float
    sim_rss_mb: float


def slope_per_min(points: list[tuple[float, float]]) -> float:
    """Least-squares slope of (wall seconds, value) points, per minute; 0 for < 2 points."""
    if len(points) < 2:
        return 0.0
    n = len(points)
    mx = sum(p[0] for p in points) / n
    my = sum(p[1] for p in points) / n
    sxx = sum((p[0] - mx) ** 2 for p in points)
    if sxx == 0:
        return 0.0
    return 60.0 * sum((p[0] - mx) * (p[1] - my) for p in points) / sxx


def cpu_pct(a: Sample, b: Sample) -> float:
    """The explorer's CPU % between two samples (100 = one core)."""
    return 100.0 * (b.explorer_cpu_s - a.explorer_cpu_s) / max(1e-9, b.wall_s - a.wall_s)


def summary(samples: list[Sample], done_at: Sample | None) -> dict[str, float | None]:
    """RSS growth per minute and CPU % before / after done (see the module docstring)."""
    after_first_min = [(s.wall_s, s.explorer_rss_mb) for s in samples if s.wall_s >= 60.0]
    out: dict[str, float | None] = {
        "explorer_rss_start_mb": samples[0].explorer_rss_mb if samples else None,
        "explorer_rss_end_mb": samples[-1].explorer_rss_mb if samples else None,
        "explorer_rss_growth_mb_per_min": slope_per_min(after_first_min),
        "sim_rss_growth_mb_per_min": slope_per_min(
            [(s.wall_s, s.sim_rss_mb) for s in samples if s.wall_s >= 60.0]),
        "explorer_cpu_pct_exploring": None, "explorer_cpu_pct_after_done": None,
        "done_at_wall_s": done_at.wall_s if done_at else None,
    }
    if samples:
        end = done_at or samples[-1]
        out["explorer_cpu_pct_exploring"] = cpu_pct(samples[0], end)
        if done_at is not None and samples[-1].wall_s > done_at.wall_s:
            out["explorer_cpu_pct_after_done"] = cpu_pct(done_at, samples[-1])
    return out


def _sample(t0: float, mon: Monitor, explorer: Child, sim: Child) -> Sample:
    e_cpu, e_rss = proc_usage(explorer.proc.pid)
    s_cpu, s_rss = proc_usage(sim.proc.pid)
    return Sample(time.monotonic() - t0, mon.sim_time_s, mon.coverage_pct, mon.done,
                  e_cpu, e_rss, s_cpu, s_rss)


def _line(s: Sample, prev: Sample | None) -> str:
    cpu = f"{cpu_pct(prev, s):5.1f}" if prev is not None else "    -"
    return (f"[soak] wall {s.wall_s:6.0f} s  sim {s.sim_s:6.0f} s  coverage "
            f"{s.coverage_pct:5.1f} %  done {int(s.done)}  explorer RSS {s.explorer_rss_mb:6.1f} MB"
            f"  CPU {cpu} %  sim RSS {s.sim_rss_mb:6.1f} MB")


def soak(cfg: DemoConfig, minutes: float, sample_s: float, after_done_s: float,
         log=print) -> dict:
    """Run the soak (see the module docstring); returns what ``soak.json`` holds."""
    out = Path(cfg.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    env = child_env(out)
    ctx, ex, mon = start_monitor("fused" if cfg.real_robot_pose else "odom")
    children: list[Child] = []
    samples: list[Sample] = []
    done_at: Sample | None = None
    try:
        explorer = Child("explorer", explorer_command(cfg), out / "logs" / "explorer.log", env)
        children.append(explorer)
        wait_for_explorer(cfg, ex, mon, explorer, time.monotonic())
        sim = Child("sim_bridge", sim_command(cfg), out / "logs" / "sim_bridge.log", env)
        children.append(sim)
        t0 = time.monotonic()
        samples.append(_sample(t0, mon, explorer, sim))
        next_sample = t0 + sample_s
        while not STOP.is_set():
            ex.spin_once(timeout_sec=0.1)
            for ch in children:
                if not ch.alive():
                    raise DemoError(f"{ch.name} exited with code {ch.proc.returncode}:\n"
                                    f"{ch.tail()}")
            now = time.monotonic()
            if mon.done and done_at is None:
                done_at = _sample(t0, mon, explorer, sim)
                samples.append(done_at)
                log(_line(done_at, samples[-2]) + "  <- exploration_done")
                next_sample = now + min(sample_s, after_done_s)
            if now >= next_sample:
                samples.append(_sample(t0, mon, explorer, sim))
                log(_line(samples[-1], samples[-2]))
                next_sample = now + sample_s
            if done_at is not None and now - t0 - done_at.wall_s >= after_done_s:
                samples.append(_sample(t0, mon, explorer, sim))
                break
            if now - t0 >= minutes * 60.0:
                break
    finally:
        for ch in reversed(children):
            ch.stop()
        stop_monitor(ctx, ex, mon)
    result = {"config": {"world": cfg.world, "strategy": cfg.strategy, "rtf":
                         cfg.real_time_factor, "minutes": minutes, "sample_s": sample_s,
                         "after_done_s": after_done_s},
              "summary": summary(samples, done_at), "samples": [asdict(s) for s in samples]}
    (out / "soak.json").write_text(json.dumps(result, indent=1))
    return result


def main(argv: list[str] | None = None) -> int:
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.setdefault("ROS_DOMAIN_ID", str(1 + os.getpid() % 100))
    ap = argparse.ArgumentParser(prog="scripts/soak.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="output folder")
    ap.add_argument("--minutes", type=float, default=10.0, help="wall minutes at most")
    ap.add_argument("--world", default="small_cluttered")
    ap.add_argument("--strategy", default="paper")
    ap.add_argument("--rtf", type=float, default=4.0, help="sim seconds per wall second")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sample-s", type=float, default=30.0, help="wall seconds per sample")
    ap.add_argument("--after-done-s", type=float, default=60.0,
                    help="wall seconds measured after exploration_done")
    ap.add_argument("--explorer-arg", action="append", default=[],
                    help="extra argument for the explorer (repeatable)")
    a = ap.parse_args(argv)
    cfg = DemoConfig(out_dir=a.out, world=a.world, strategy=a.strategy, seed=a.seed,
                     real_time_factor=a.rtf, max_sim_time_s=1e9, wall_timeout_s=a.minutes * 60,
                     explorer_args=tuple(a.explorer_arg))
    signal.signal(signal.SIGINT, lambda *_: STOP.set())
    signal.signal(signal.SIGTERM, lambda *_: STOP.set())
    try:
        res = soak(cfg, a.minutes, a.sample_s, a.after_done_s,
                   log=lambda s: print(s, flush=True))
    except DemoError as err:
        print(f"[soak] FAILED: {err}", file=sys.stderr, flush=True)
        return 1
    for k, v in res["summary"].items():
        print(f"[soak] {k}: " + ("-" if v is None else f"{v:.2f}"), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
