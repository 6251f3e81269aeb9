"""The demo's outputs: ``final_map.png``, ``exploration.gif``, ``coverage.png``,
``object_history.jsonl`` and ``metrics.json``."""

from __future__ import annotations

import json
import math
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from scripts.demo_lib.config import DemoConfig
from scripts.demo_lib.monitor import Monitor
from sim_bridge.lockstep import strategy_spec


def write_outputs(cfg: DemoConfig, out: Path, mon: Monitor, gif, sim_json: dict[str, Any],
                   stop_reason: str, error: str, wall_s: float) -> dict[str, Any]:
    """Write the outputs of a finished (or failed) run into ``out``; the metrics written."""
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
        # The node's own counts: depth frames that reached its callback, and processed.
        "object_frames_received": mon.object_frames_received,
        "object_frames_received_processed": mon.object_frames_counted,
        "object_frame_ms_p50_p95": ([round(float(np.percentile(mon.object_frame_ms, q)), 1)
                                     for q in (50, 95)] if mon.object_frame_ms else None),
        # How navigation ended goals, and the sim seconds from each abort to the next goal.
        "nav_outcomes": mon.nav_outcomes(),
        "nav_raw": {"ends": sorted(mon.nav_ends.values(), key=lambda e: e[1]),
                    "goal_times": mon.goal_times},
        "camera_frames_rendered": (int(mon.sim_time_s * cfg.camera_rate_hz)
                                   if strategy_spec(cfg.strategy).use_objects else 0),
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
