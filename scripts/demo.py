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
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from sim_bridge.lockstep import STRATEGY_SPECS, LockstepParams  # noqa: E402
#: Longer side of the animation frames (px).
GIF_SIDE_PX = 480
#: Exit codes of :func:`main`.
EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


@dataclass(frozen=True)
class DemoConfig:
    """Settings of one demo run (see the module docstring)."""

    out_dir: str
    world: str = "house_cluttered"
    strategy: str = "paper"
    seed: int = 0
    real_time_factor: float = 4.0
    max_sim_time_s: float = 1500.0
    wall_timeout_s: float = 900.0
    stall_wall_s: float = 30.0
    stall_sim_s: float = 300.0
    startup_timeout_s: float = 60.0
    progress_period_s: float = 5.0
    frame_period_sim_s: float = 5.0
    gif_max_frames: int = 120
    camera_scale: float = 0.5
    camera_rate_hz: float = 2.0
    explorer: bool = True
    #: Executor threads of the explorer process (its --threads).
    explorer_threads: int = 1
    params_file: str = ""
    stop_coverage_pct: float = 0.0
    sim_args: tuple[str, ...] = field(default_factory=tuple)
    explorer_args: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        if self.strategy not in STRATEGY_SPECS:
            raise ValueError(f"strategy must be one of {tuple(STRATEGY_SPECS)}, "
                             f"got {self.strategy!r}")
        for name in ("real_time_factor", "max_sim_time_s", "wall_timeout_s", "stall_wall_s",
                     "stall_sim_s", "startup_timeout_s", "progress_period_s",
                     "frame_period_sim_s", "camera_scale", "camera_rate_hz"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if self.camera_scale > 1:
            raise ValueError(f"camera_scale must be <= 1, got {self.camera_scale}")
        if self.explorer_threads < 1:
            raise ValueError(f"explorer_threads must be >= 1, got {self.explorer_threads}")
        if self.gif_max_frames < 2:
            raise ValueError(f"gif_max_frames must be >= 2, got {self.gif_max_frames}")


class DemoError(RuntimeError):
    """The demo failed (message says why)."""


# ---------------------------------------------------------------- child processes


def sim_command(cfg: DemoConfig) -> list[str]:
    """Command line of the simulator process."""
    from sim_bridge.engine import SimParams

    spec = STRATEGY_SPECS[cfg.strategy]
    sp = SimParams()
    w = max(16, int(round(sp.camera_width_px * cfg.camera_scale)))
    h = max(16, int(round(sp.camera_height_px * cfg.camera_scale)))
    params = {
        "world": cfg.world, "seed": cfg.seed, "real_time_factor": float(cfg.real_time_factor),
        "enable_camera": spec.use_objects, "camera_rate_hz": float(cfg.camera_rate_hz),
        "camera_width_px": w, "camera_height_px": h,
        "camera_fx_px": sp.camera_fx_px * w / sp.camera_width_px,
        "camera_fy_px": sp.camera_fy_px * h / sp.camera_height_px,
        "camera_cx_px": (w - 1) / 2.0, "camera_cy_px": (h - 1) / 2.0,
        "output_dir": str(Path(cfg.out_dir) / "sim"),
    }
    cmd = [sys.executable, "-m", "sim_bridge.node", "--ros-args"]
    for k, v in params.items():
        cmd += ["-p", f"{k}:={_ros_value(v)}"]
    return cmd + list(cfg.sim_args)


def explorer_command(cfg: DemoConfig) -> list[str]:
    """Command line of the explorer process (strategy mapped onto its parameters)."""
    spec = STRATEGY_SPECS[cfg.strategy]
    cmd = [sys.executable, "-m", "explore_seg.explorer", "--threads", str(cfg.explorer_threads)]
    if not spec.use_objects:
        cmd += ["--without", "object_costmap"]
    if not spec.use_regions:
        cmd += ["--without", "segmentation"]
    cmd += ["--ros-args"]
    if cfg.params_file:
        cmd += ["--params-file", cfg.params_file]
    params = {"use_sim_time": True, "strategy": spec.selection,
              "use_regions": spec.use_regions, "use_object_costmap": spec.use_objects}
    if spec.use_objects:
        # The oracle backend as in the lock-step runs (LockstepParams): boxes from the
        # simulator's semantic image with 10 % misses and 2 px corner jitter.
        lp = LockstepParams()
        params.update({"detector.backend": "oracle",
                       "detector.oracle_miss_prob": lp.oracle_miss_prob,
                       "detector.oracle_jitter_px": lp.oracle_jitter_px,
                       "detector.oracle_seed": int(cfg.seed)})
    for k, v in params.items():
        cmd += ["-p", f"{k}:={_ros_value(v)}"]
    return cmd + list(cfg.explorer_args)


def _ros_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


class _Child:
    """A started process with its log file; stopped by SIGINT, then SIGTERM, then SIGKILL."""

    def __init__(self, name: str, cmd: list[str], log_path: Path, env: dict[str, str]) -> None:
        self.name = name
        self.log_path = log_path
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log = open(log_path, "w")
        self._log.write("$ " + " ".join(cmd) + "\n")
        self._log.flush()
        self.proc = subprocess.Popen(cmd, stdout=self._log, stderr=subprocess.STDOUT,
                                     cwd=str(ROOT), env=env, start_new_session=True)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def tail(self, n: int = 25) -> str:
        try:
            lines = self.log_path.read_text(errors="replace").splitlines()
        except OSError:
            return ""
        return "\n".join(lines[-n:])

    def stop(self, timeout_s: float = 10.0) -> None:
        for sig, wait in ((signal.SIGINT, timeout_s), (signal.SIGTERM, 5.0),
                          (signal.SIGKILL, 5.0)):
            if self.proc.poll() is not None:
                break
            try:
                self.proc.send_signal(sig)
            except ProcessLookupError:
                break
            try:
                self.proc.wait(wait)
            except subprocess.TimeoutExpired:
                continue
        self._log.close()


# -------------------------------------------------------------------------- monitor


def metrics_from_diagnostics(msg) -> dict[str, float | str]:
    """The ``sim_bridge`` status of a DiagnosticArray as a dict (numbers parsed).

    Raises
    ------
    ValueError
        When the array holds no ``sim_bridge`` status.
    """
    for st in msg.status:
        if st.name == "sim_bridge":
            out: dict[str, float | str] = {}
            for kv in st.values:
                try:
                    out[kv.key] = float(kv.value)
                except ValueError:
                    out[kv.key] = kv.value
            return out
    raise ValueError(f"no 'sim_bridge' status in sim/metrics, got "
                     f"{[s.name for s in msg.status]}")


def boxes_from_markers(msg) -> list[np.ndarray]:
    """Footprints (4 x 2 corners) of the CUBE markers of namespace ``objects``.

    The object costmap publishes a DELETEALL then one cube per object, so every message
    is the full set.
    """
    from explore_seg.core.grid import yaw_from_quaternion
    from explore_seg.core.objects import rect_corners

    out = []
    for m in msg.markers:
        if m.ns != "objects" or m.type != m.CUBE or m.action != m.ADD:
            continue
        q = m.pose.orientation
        yaw = yaw_from_quaternion(q.x, q.y, q.z, q.w)
        out.append(rect_corners((m.pose.position.x, m.pose.position.y),
                                (m.scale.x, m.scale.y), yaw))
    return out


class Monitor:
    """Subscriptions of the demo (one rclpy node); the state is read by :func:`run_demo`."""

    def __init__(self, context) -> None:
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import PoseStamped
        from nav_msgs.msg import MapMetaData, OccupancyGrid, Odometry
        from rclpy.node import Node
        from sensor_msgs.msg import Image
        from std_msgs.msg import Bool, Float64MultiArray
        from visualization_msgs.msg import MarkerArray

        from explore_seg.qos import MAP_QOS, RELIABLE_QOS

        self.node = Node("demo_monitor", context=context)
        n = self.node
        self.metrics: dict[str, float | str] = {}
        self.metrics_wall = time.monotonic()
        self.samples: list[tuple[float, float]] = []
        self.goals: list[tuple[float, float]] = []
        self.done = False
        self.grid = None
        self.labels = None
        self._regions_img = None
        self._regions_info = None
        self.boxes: list[np.ndarray] = []
        # (sim time, footprints) each time the set of boxes changed: what the object
        # costmap believed when, e.g. at a collision (object_history.jsonl).
        self.box_history: list[tuple[float, list[np.ndarray]]] = []
        self.pose: tuple[float, float, float] | None = None
        self.trail: list[tuple[float, float]] = []
        self.trail_spacing_m = 0.05
        self.trail_max = 20000
        self.dropped: dict[str, str] = {}
        n.create_subscription(DiagnosticArray, "sim/metrics", self._on_metrics, RELIABLE_QOS)
        n.create_subscription(PoseStamped, "goal_pose", self._on_goal, RELIABLE_QOS)
        n.create_subscription(Bool, "exploration_done", self._on_done, MAP_QOS)
        n.create_subscription(OccupancyGrid, "map", self._on_map, MAP_QOS)
        n.create_subscription(Odometry, "odom", self._on_odom, RELIABLE_QOS)
        n.create_subscription(Image, "regions", self._on_regions, MAP_QOS)
        n.create_subscription(MapMetaData, "regions/info", self._on_regions_info, MAP_QOS)
        n.create_subscription(MarkerArray, "object_costmap/markers", self._on_markers,
                              RELIABLE_QOS)
        # One timing message per camera frame the object costmap processed.
        self.object_frames = 0
        n.create_subscription(Float64MultiArray, "object_costmap/timing",
                              self._on_object_timing, 10)

    def _drop(self, what: str, err: Exception) -> None:
        self.dropped[what] = str(err)
        self.node.get_logger().warn(f"dropped {what}: {err}", throttle_duration_sec=5.0)

    def _on_metrics(self, msg) -> None:
        try:
            m = metrics_from_diagnostics(msg)
        except ValueError as err:
            self._drop("sim/metrics", err)
            return
        self.metrics = m
        self.metrics_wall = time.monotonic()
        t, c = m.get("sim_time_s"), m.get("coverage_pct")
        if isinstance(t, float) and isinstance(c, float) and math.isfinite(c):
            if not self.samples or t > self.samples[-1][0]:
                self.samples.append((t, c))

    def _on_goal(self, msg) -> None:
        self.goals.append((msg.pose.position.x, msg.pose.position.y))

    def _on_done(self, msg) -> None:
        self.done = self.done or bool(msg.data)

    def _on_map(self, msg) -> None:
        from explore_seg import convert
        try:
            self.grid = convert.grid_from_msg(msg)
        except ValueError as err:
            self._drop("map", err)
            return
        self._match_regions()

    def _on_odom(self, msg) -> None:
        from explore_seg import convert
        try:
            self.pose = convert.pose2d_from_odometry(msg)
        except ValueError as err:
            self._drop("odom", err)
            return
        x, y = self.pose[0], self.pose[1]
        if not self.trail or math.hypot(x - self.trail[-1][0],
                                        y - self.trail[-1][1]) >= self.trail_spacing_m:
            self.trail.append((x, y))
            if len(self.trail) >= self.trail_max:  # bounded: halve, coarser spacing
                self.trail = self.trail[::2]
                self.trail_spacing_m *= 2.0

    def _on_regions(self, msg) -> None:
        self._regions_img = msg
        self._match_regions()

    def _on_regions_info(self, msg) -> None:
        self._regions_info = msg
        self._match_regions()

    def _match_regions(self) -> None:
        """Labels of the latest regions image when they share the map's geometry."""
        from explore_seg import convert
        img, info = self._regions_img, self._regions_info
        if img is None or info is None or self.grid is None:
            return
        # Image and info are separate messages: use them only as a pair (same stamp).
        st, lt = img.header.stamp, info.map_load_time
        if (st.sec, st.nanosec) != (lt.sec, lt.nanosec) or \
                (img.height, img.width) != (info.height, info.width):
            return
        try:
            labels, geom = convert.labels_from_msgs(self._regions_img, self._regions_info)
        except ValueError as err:
            self._drop("regions", err)
            return
        if geom.shape == self.grid.shape and geom.same_geometry(self.grid):
            self.labels = labels

    def _on_object_timing(self, msg) -> None:
        self.object_frames += 1

    def _on_markers(self, msg) -> None:
        boxes = boxes_from_markers(msg)
        changed = len(boxes) != len(self.boxes) or any(
            not np.allclose(a, b, atol=1e-3) for a, b in zip(boxes, self.boxes))
        self.boxes = boxes
        if changed:
            self.box_history.append((self.sim_time_s, boxes))

    @property
    def sim_time_s(self) -> float:
        v = self.metrics.get("sim_time_s", 0.0)
        return float(v) if isinstance(v, float) else 0.0

    @property
    def coverage_pct(self) -> float:
        v = self.metrics.get("coverage_pct", math.nan)
        return float(v) if isinstance(v, float) else math.nan

    def n_regions(self) -> int:
        return 0 if self.labels is None else int(len(np.unique(self.labels[self.labels > 0])))

    def overlays(self, collisions: list[tuple[float, float]] | None = None):
        from sim_bridge.render import Overlays
        labels = self.labels if (self.labels is not None and self.grid is not None
                                 and self.labels.shape == self.grid.shape) else None
        return Overlays(robot_path=np.asarray(self.trail) if len(self.trail) >= 2 else None,
                        robot_pose=self.pose, regions=labels, boxes=list(self.boxes),
                        goals=list(self.goals), collisions=collisions or [])


def _progress_line(mon: Monitor, wall_s: float) -> str:
    m = mon.metrics
    return (f"[demo] wall {wall_s:6.1f} s | sim {mon.sim_time_s:7.1f} s | coverage "
            f"{mon.coverage_pct:5.1f} % | goals {len(mon.goals):3d} | collisions "
            f"{int(m.get('collisions', 0) or 0)} | objects {len(mon.boxes)} "
            f"({mon.object_frames} frames) | regions "
            f"{mon.n_regions()} | nav {m.get('nav_state', '-')}")


# ------------------------------------------------------------------------------ run


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
    import rclpy
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    from sim_bridge.render import GifWriter

    out = Path(cfg.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH", "")) if p)
    env.setdefault("ROS_LOG_DIR", str(out / "logs" / "ros"))
    ctx = Context()
    # Python's own SIGINT handling (KeyboardInterrupt): rclpy's handler would only shut
    # the monitor's context down, and Ctrl-C would not stop the demo and its children.
    rclpy.init(context=ctx, signal_handler_options=SignalHandlerOptions.NO)
    ex = SingleThreadedExecutor(context=ctx)
    mon = Monitor(ctx)
    ex.add_node(mon.node)
    gif = GifWriter(out / "exploration.gif", max_frames=cfg.gif_max_frames, frame_ms=120,
                    max_side_px=GIF_SIDE_PX)
    children: list[_Child] = []
    t0 = time.monotonic()
    stop_reason, error = "", ""
    try:
        # The explorer first: the simulator's clock starts only once it is listening, so
        # no sim time passes while the explorer imports and builds its nodes.
        if cfg.explorer:
            children.append(_Child("explorer", explorer_command(cfg),
                                   out / "logs" / "explorer.log", env))
            _wait_for_explorer(cfg, ex, mon, children[0], t0)
        children.insert(0, _Child("sim_bridge", sim_command(cfg),
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
        log(_progress_line(mon, wall))
        sims = [ch for ch in children if ch.name == "sim_bridge"]
        sim_json = _save_sim_metrics(ex, mon.node, sims[0]) if sims else {}
    finally:
        for ch in reversed(children):
            ch.stop()
    metrics = _write_outputs(cfg, out, mon, gif, sim_json, stop_reason, error, wall)
    ex.remove_node(mon.node)
    mon.node.destroy_node()
    ex.shutdown()
    rclpy.try_shutdown(context=ctx)
    if error:
        raise DemoError(error)
    return metrics


#: Set by SIGINT / SIGTERM (see :func:`main`): the demo stops its children, writes its
#: outputs and exits with stop reason "interrupted".
STOP = threading.Event()


def _wait_for_explorer(cfg: DemoConfig, ex, mon: Monitor, child: _Child, t0: float) -> None:
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


def _watch(cfg: DemoConfig, ex, mon: Monitor, children: list[_Child], gif, t0: float,
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
            log(_progress_line(mon, wall))
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


def _save_sim_metrics(ex, node, sim: _Child, timeout_s: float = 10.0) -> dict[str, Any]:
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


def _write_outputs(cfg: DemoConfig, out: Path, mon: Monitor, gif, sim_json: dict[str, Any],
                   stop_reason: str, error: str, wall_s: float) -> dict[str, Any]:
    from sim_bridge.render import render_map_png

    collisions = [(e["x_m"], e["y_m"]) for e in sim_json.get("collision_events", [])]
    files = []
    if mon.grid is not None:
        render_map_png(out / "final_map.png", mon.grid, mon.overlays(collisions))
        files.append("final_map.png")
        if len(gif) == 0:
            from sim_bridge.render import render_map
            gif.add(render_map(mon.grid, mon.overlays(collisions)))
        gif.write()
        files.append("exploration.gif")
    samples = sim_json.get("coverage_history") or [list(s) for s in mon.samples]
    if samples:
        _plot_coverage(out / "coverage.png", samples, cfg)
        files.append("coverage.png")
    if mon.box_history:
        # One line per change of the object set (compact: it grows with the run).
        (out / "object_history.jsonl").write_text("".join(
            json.dumps({"t": round(t, 2), "boxes": [np.round(b, 3).tolist() for b in bs]},
                       separators=(",", ":")) + "\n" for t, bs in mon.box_history))
        files.append("object_history.jsonl")
    m = mon.metrics
    metrics = {
        "config": asdict(cfg), "stop_reason": stop_reason, "error": error,
        "exploration_done": mon.done, "wall_time_s": round(wall_s, 1),
        "sim_time_s": mon.sim_time_s, "coverage_pct": _num(mon.coverage_pct),
        "path_length_m": _num(m.get("path_length_m")), "collisions": _num(m.get("collisions")),
        "goals_sent": len(mon.goals), "goals_received": _num(m.get("goals_received")),
        "goals_reached": _num(m.get("goals_reached")),
        "goals_aborted": _num(m.get("goals_aborted")), "n_objects": len(mon.boxes),
        "n_regions": mon.n_regions(), "dropped_inputs": mon.dropped,
        # Camera frames the object costmap processed, of those rendered (sim time x rate):
        # below the rendered count the layer lags (CPU too slow for the real-time factor).
        "object_frames_processed": mon.object_frames,
        "camera_frames_rendered": (int(mon.sim_time_s * cfg.camera_rate_hz)
                                   if STRATEGY_SPECS[cfg.strategy].use_objects else 0),
        "objects": [np.round(b, 3).tolist() for b in mon.boxes],
        "collision_events": sim_json.get("collision_events", []),
        "coverage_history": samples, "files": files,
    }
    (out / "metrics.json").write_text(json.dumps(metrics, indent=1))
    return metrics


def _num(v: Any) -> float | None:
    return float(v) if isinstance(v, (int, float)) and math.isfinite(v) else None


def _plot_coverage(path: Path, samples: list, cfg: DemoConfig) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.asarray(samples, dtype=np.float64)
    fig, ax = plt.subplots(figsize=(6, 3.6))
    ax.plot(s[:, 0], s[:, 1])
    ax.set_xlabel("sim time [s]")
    ax.set_ylabel("coverage [%]")
    ax.set_ylim(0, 101)
    ax.grid(alpha=0.3)
    ax.set_title(f"{cfg.world} / {cfg.strategy}: coverage vs time")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------- main


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
