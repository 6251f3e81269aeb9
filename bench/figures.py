"""The benchmark's figures, from the run records of a folder (:mod:`bench.records`).

* ``coverage_<world>.png``: coverage vs sim time, mean +- std over the runs of each
  strategy (the paper's Fig. 10). A run that stopped keeps its final coverage.
* ``time_to_95.png``: box plots of the time to 95 % coverage per world and strategy
  (runs that never reached it are counted in the table, not drawn).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from bench.records import as_float, by_world_strategy
from bench.store import slug


def coverage_curves(runs: list[dict[str, Any]], step_s: float = 5.0
                    ) -> dict[str, dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """world -> strategy -> (t, mean %, std %) on a common time grid."""
    out: dict[str, dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
    for (world, strat), rs in by_world_strategy(runs).items():
        t_end = max(r["sim_time_s"] for r in rs)
        grid = np.arange(0.0, t_end + step_s, step_s)
        curves = []
        for r in rs:
            s = np.asarray([(a, b if b is not None else np.nan)
                            for a, b, _ in r["coverage_samples"]], dtype=np.float64)
            if s.size == 0:
                continue
            ok = np.isfinite(s[:, 1])
            curves.append(np.interp(grid, s[ok, 0], s[ok, 1]) if ok.any()
                          else np.zeros_like(grid))
        if curves:
            c = np.vstack(curves)
            out.setdefault(world, {})[strat] = (grid, c.mean(axis=0), c.std(axis=0))
    return out


def plot_coverage(runs: list[dict[str, Any]], out: Path) -> list[Path]:
    """One ``coverage_<world>.png`` per world; returns the paths."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    groups = by_world_strategy(runs)
    for world, per in coverage_curves(runs).items():
        fig, ax = plt.subplots(figsize=(7, 4.2))
        for strat in dict.fromkeys(st for (w, st) in groups if w == world):
            rs = groups[(world, strat)]
            k = sum(1 for r in rs if r.get("coverage_samples"))
            if strat not in per:
                ax.plot([], [], " ", label=f"{strat} (no run with samples, {len(rs)} runs)")
                continue
            t, m, s = per[strat]
            ax.plot(t, m, label=f"{strat} (n={k}" + (f" of {len(rs)} runs" if k < len(rs)
                                                       else "") + ")")
            ax.fill_between(t, np.clip(m - s, 0, 100), np.clip(m + s, 0, 100), alpha=0.2)
        ax.set_xlabel("sim time [s]")
        ax.set_ylabel("coverage [% of explorable area]")
        ax.set_ylim(0, 101)
        ax.grid(alpha=0.3)
        partial = any(not r.get("coverage_samples") for (w, _), rs in groups.items()
                      if w == world for r in rs)
        ax.set_title(f"{world}: coverage vs time (mean ± std"
                     + (", runs with coverage samples only)" if partial else ")"))
        ax.legend(loc="lower right", fontsize=8)
        fig.tight_layout()
        p = out / f"coverage_{slug(world)}.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    return paths


def plot_time_to(runs: list[dict[str, Any]], out: Path, milestone: str = "95") -> Path | None:
    """Box plot of the time to ``milestone`` % per world and strategy."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = by_world_strategy(runs)
    worlds = list(dict.fromkeys(r["world"] for r in runs))
    strats = list(dict.fromkeys(r["strategy"] for r in runs))
    if not worlds:
        return None
    ncol = min(3, len(worlds))
    nrow = int(math.ceil(len(worlds) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.4 * nrow), squeeze=False)
    for i, world in enumerate(worlds):
        ax = axes[i // ncol][i % ncol]
        data, labels = [], []
        for s in strats:
            vals = [as_float(r["time_to_s"].get(milestone)) for r in g.get((world, s), [])]
            vals = [v for v in vals if math.isfinite(v)]
            data.append(vals if vals else [np.nan])
            n = len(g.get((world, s), []))
            labels.append(f"{s}\n{len(vals)}/{n}")
        ax.boxplot(data, tick_labels=labels) if _mpl_has_tick_labels() else \
            ax.boxplot(data, labels=labels)
        ax.set_title(world, fontsize=9)
        ax.set_ylabel(f"time to {milestone} % [s]")
        ax.tick_params(axis="x", labelsize=7)
        ax.grid(alpha=0.3, axis="y")
    for j in range(len(worlds), nrow * ncol):
        axes[j // ncol][j % ncol].axis("off")
    fig.suptitle(f"time to {milestone} % coverage (reached/runs under each box)", fontsize=10)
    fig.tight_layout()
    p = out / f"time_to_{milestone}.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return p


def _mpl_has_tick_labels() -> bool:
    import matplotlib
    major, minor = (int(x) for x in matplotlib.__version__.split(".")[:2])
    return (major, minor) >= (3, 9)
