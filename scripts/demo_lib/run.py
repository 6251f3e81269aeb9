"""One demo run: start the children, spin the monitor until a stop condition, stop the
children and write the outputs (:func:`run_demo`)."""

from __future__ import annotations

import json
import math
import os
import threading
import time
from pathlib import Path
from typing import Any

from scripts.demo_lib.config import GIF_SIDE_PX, ROOT, DemoConfig, DemoError
from scripts.demo_lib.monitor import Monitor, progress_line
from scripts.demo_lib.outputs import write_outputs
from scripts.demo_lib.processes import Child, explorer_command, sim_command


def run_demo(cfg: DemoConfig, log=print) -> dict[str, Any]:
    """Run the demo (see the module docstring); returns the metrics written.

    The children are always stopped (SIGINT, then SIGTERM, then SIGKILL) before this
    returns or raises.

    Raises
    ------
    DemoError
        When a child dies, nothing progresses or the wall timeout passes; the outputs
        gathered so far are written first.
    """
    from sim_bridge.render import GifWriter

    out = Path(cfg.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    env = child_env(out)
    ctx, ex, mon = start_monitor("fused" if cfg.real_robot_pose else "odom")
    gif = GifWriter(out / "exploration.gif", max_frames=cfg.gif_max_frames, frame_ms=120,
                    max_side_px=GIF_SIDE_PX)
    children: list[Child] = []
    t0 = time.monotonic()
    stop_reason, error = "", ""
    try:
        # The explorer first: the simulator's clock starts only once it is listening, so
        # no sim time passes while the explorer imports and builds its nodes.
        if cfg.explorer:
            children.append(Child("explorer", explorer_command(cfg),
                                   out / "logs" / "explorer.log", env))
            wait_for_explorer(cfg, ex, mon, children[0], t0)
        children.insert(0, Child("sim_bridge", sim_command(cfg),
                                  out / "logs" / "sim_bridge.log", env))
        log(f"[demo] world {cfg.world}, strategy {cfg.strategy}, seed {cfg.seed}, "
            f"real-time factor {cfg.real_time_factor}, sim limit {cfg.max_sim_time_s:.0f} s, "
            f"ROS_DOMAIN_ID={os.environ.get('ROS_DOMAIN_ID', '0')}; logs in {out / 'logs'}")
        stop_reason = _watch(cfg, ex, mon, children, gif, t0, log)
        if stop_reason == "interrupted":
            error = "interrupted"
    except DemoError as err:
        error, stop_reason = str(err), "failed"
    except KeyboardInterrupt:
        error, stop_reason = "interrupted", "interrupted"
    except Exception as err:  # noqa: BLE001 - reported, children stopped, outputs kept
        error, stop_reason = f"internal error: {type(err).__name__}: {err}", "failed"
    try:
        wall = time.monotonic() - t0
        log(progress_line(mon, wall))
        sims = [ch for ch in children if ch.name == "sim_bridge"]
        sim_json = _save_sim_metrics(ex, mon.node, sims[0]) if sims else {}
    finally:
        for ch in reversed(children):
            ch.stop()
    metrics = write_outputs(cfg, out, mon, gif, sim_json, stop_reason, error, wall)
    stop_monitor(ctx, ex, mon)
    if error:
        raise DemoError(error)
    return metrics


def child_env(out: Path) -> dict[str, str]:
    """The children's environment: this repository importable, ROS logs under ``out``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    env.setdefault("ROS_LOG_DIR", str(out / "logs" / "ros"))
    return env


def start_monitor(pose_source: str = "odom"):
    """(context, executor, :class:`Monitor`) on a private rclpy context; the monitor
    follows the robot through ``pose_source`` (odom | fused)."""
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    ctx = Context()
    # Python's own SIGINT handling (KeyboardInterrupt): rclpy's handler would only shut
    # the monitor's context down, and Ctrl-C would not stop the demo and its children.
    rclpy.init(context=ctx, signal_handler_options=SignalHandlerOptions.NO)
    ex = SingleThreadedExecutor(context=ctx)
    mon = Monitor(ctx, pose_source)
    ex.add_node(mon.node)
    return ctx, ex, mon


def stop_monitor(ctx, ex, mon: Monitor) -> None:
    """Destroy the monitor node and shut its context down."""
    import rclpy

    ex.remove_node(mon.node)
    mon.node.destroy_node()
    ex.shutdown()
    rclpy.try_shutdown(context=ctx)


#: Set by SIGINT / SIGTERM (see :func:`main`): the demo stops its children, writes its
#: outputs and exits with stop reason "interrupted".
STOP = threading.Event()


def wait_for_explorer(cfg: DemoConfig, ex, mon: Monitor, child: Child, t0: float) -> None:
    """Spin until the explorer publishes ``goal_pose`` (its selector is up).

    Raises
    ------
    DemoError
        When the explorer exits or is not up within ``startup_timeout_s``.
    """
    while mon.node.count_publishers("goal_pose") == 0:
        ex.spin_once(timeout_sec=0.1)
        if STOP.is_set():
            raise KeyboardInterrupt
        if not child.alive():
            raise DemoError(f"{child.name} exited with code {child.proc.returncode}; last "
                            f"lines of {child.log_path}:\n{child.tail()}")
        if time.monotonic() - t0 > cfg.startup_timeout_s:
            raise DemoError(f"the explorer did not come up within {cfg.startup_timeout_s:.0f} s "
                            f"(no goal_pose publisher); see {child.log_path}")


def _watch(cfg: DemoConfig, ex, mon: Monitor, children: list[Child], gif, t0: float,
           log) -> str:
    """Spin the monitor until a stop condition; returns the stop reason.

    Raises
    ------
    DemoError
        On a dead child, no progress or the wall timeout.
    """
    from sim_bridge.render import render_map

    next_print = t0
    next_frame_sim = 0.0
    best_cov, best_cov_t = -1.0, 0.0
    while True:
        ex.spin_once(timeout_sec=0.05)
        if STOP.is_set():
            return "interrupted"
        now = time.monotonic()
        wall = now - t0
        for ch in children:
            if not ch.alive():
                raise DemoError(f"{ch.name} exited with code {ch.proc.returncode}; last "
                                f"lines of {ch.log_path}:\n{ch.tail()}")
        if not mon.metrics:
            if wall > cfg.startup_timeout_s:
                raise DemoError(f"no sim/metrics within {cfg.startup_timeout_s:.0f} s of the "
                                "start (simulator not publishing, or DDS discovery failing)")
            continue
        if now - mon.metrics_wall > cfg.stall_wall_s:
            raise DemoError(f"no progress: no sim/metrics for {cfg.stall_wall_s:.0f} s")
        t_sim, cov = mon.sim_time_s, mon.coverage_pct
        if math.isfinite(cov) and cov > best_cov + 0.05:
            best_cov, best_cov_t = cov, t_sim
        if mon.grid is not None and t_sim >= next_frame_sim:
            next_frame_sim = t_sim + cfg.frame_period_sim_s
            side = max(mon.grid.width, mon.grid.height, 1)
            gif.add(render_map(mon.grid, mon.overlays(), scale=max(1, round(GIF_SIDE_PX / side))))
        if now >= next_print:
            next_print = now + cfg.progress_period_s
            log(progress_line(mon, wall))
        if mon.done:
            return "exploration_done"
        if cfg.stop_coverage_pct and cov >= cfg.stop_coverage_pct:
            return "coverage"
        if t_sim >= cfg.max_sim_time_s:
            return "sim_time_limit"
        if t_sim - best_cov_t > cfg.stall_sim_s:
            raise DemoError(f"no progress: coverage stayed at {best_cov:.1f} % for "
                            f"{cfg.stall_sim_s:.0f} sim seconds")
        if wall > cfg.wall_timeout_s:
            raise DemoError(f"timeout: {cfg.wall_timeout_s:.0f} s wall time passed at sim time "
                            f"{t_sim:.0f} s, coverage {cov:.1f} %")


def _save_sim_metrics(ex, node, sim: Child, timeout_s: float = 10.0) -> dict[str, Any]:
    """Ask the simulator to write its metrics + map (``sim/save_metrics``); its JSON."""
    from std_srvs.srv import Trigger

    if not sim.alive():
        return {}
    cli = node.create_client(Trigger, "sim/save_metrics")
    try:
        end = time.monotonic() + timeout_s
        while not cli.service_is_ready() and time.monotonic() < end:
            ex.spin_once(timeout_sec=0.1)
        if not cli.service_is_ready():
            return {}
        fut = cli.call_async(Trigger.Request())
        while not fut.done() and time.monotonic() < end:
            ex.spin_once(timeout_sec=0.1)
        resp = fut.result() if fut.done() else None
        if resp is None or not resp.success:
            return {}
        js = Path(resp.message.split()[0])
        return json.loads(js.read_text()) if js.is_file() else {}
    except (OSError, ValueError, IndexError):
        return {}
    finally:
        node.destroy_client(cli)
