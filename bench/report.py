"""Figures and BENCHMARKS.md from the files :mod:`bench.run_bench` writes.

* ``coverage_<world>.png``: coverage vs sim time, mean +- std over the runs of each
  strategy (the paper's Fig. 10). A run that stopped keeps its final coverage.
* ``time_to_95.png``: box plots of the time to 95 % coverage per world and strategy
  (runs that never reached it are counted in the table, not drawn).
* ``BENCHMARKS.md``: setup and command, per world x strategy results, the per-module
  timing table (the paper's Table I) with the real detector timed on rendered frames,
  coverage tours and the lock-step vs ROS comparison when present.

Usage: ``.venv/bin/python bench/report.py OUT [--md BENCHMARKS.md]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench import records  # noqa: E402
from bench.causes import contacts_table, early_stop_table  # noqa: E402
from bench.figures import coverage_curves, plot_coverage, plot_time_to  # noqa: E402,F401
from bench.records import TIMING_ROWS, as_float, by_world_strategy  # noqa: E402
from bench.store import read_csv, slug  # noqa: E402

MILESTONES = ("50", "90", "95", "99")


def load_runs(out: Path) -> list[dict[str, Any]]:
    """Every run of ``out`` (:func:`bench.records.read`)."""
    return records.read(out)


def _mean_std(vals: list[float], nd: int = 1) -> str:
    v = np.asarray([x for x in vals if math.isfinite(x)], dtype=np.float64)
    if v.size == 0:
        return "-"
    if v.size == 1:
        return f"{v[0]:.{nd}f}"
    return f"{v.mean():.{nd}f} ± {v.std(ddof=1):.{nd}f}"


# ------------------------------------------------------------------------ tables


def results_table(runs: list[dict[str, Any]], tours: dict[str, float],
                  tours95: dict[str, float] | None = None) -> list[str]:
    """Markdown table: one row per world x strategy (path / tour: path to 99 % over the
    99 % tour; path 95 / tour 95: path to 95 % over the 95 % tour, "-" without it)."""
    tours95 = tours95 or {}
    head = ("| world | strategy | runs | completed | time to 50 / 90 / 95 / 99 % [s] | "
            "path to 99 % [m] | path / tour | path 95 / tour 95 | collisions | goals | "
            "switches | wall per run [s] |")
    lines = [head, "|" + "|".join(["---"] * (head.count("|") - 1)) + "|"]
    for (world, strat), rs in by_world_strategy(runs).items():
        n = len(rs)
        done = sum(1 for r in rs if r["completed"])
        times = " / ".join(
            _mean_std([as_float(r["time_to_s"].get(m)) for r in rs], 0)
            + (f" ({sum(math.isfinite(as_float(r['time_to_s'].get(m))) for r in rs)})"
               if any(not math.isfinite(as_float(r["time_to_s"].get(m))) for r in rs) else "")
            for m in MILESTONES)
        p99 = _mean_std([as_float(r["path_to_m"].get("99")) for r in rs])
        tour = tours.get(world)
        ratio = (_mean_std([as_float(r["path_to_m"].get("99")) / tour for r in rs], 2)
                 if tour else "-")
        tour95 = tours95.get(world)
        ratio95 = (_mean_std([as_float(r["path_to_m"].get("95")) / tour95 for r in rs], 2)
                   if tour95 else "-")
        coll = [r["collisions"] for r in rs]
        early = sum(1 for r in rs if r["stop_reason"] == "done")
        timeout = sum(1 for r in rs if r["stop_reason"] == "timeout")
        stops = ", ".join(x for x in (f"{early} done early" if early else "",
                                      f"{timeout} timed out" if timeout else "") if x)
        lines.append(
            f"| {world} | {strat} | {n} | {done}/{n}{f' ({stops})' if stops else ''} | "
            f"{times} | {p99} | {ratio} | {ratio95} | "
            f"{np.mean(coll):.1f} (max {max(coll)}) | "
            f"{_mean_std([r['goals_sent'] for r in rs], 0)} | "
            f"{_mean_std([r['goal_switches'] for r in rs], 0)} | "
            f"{_mean_std([r['wall_time_s'] for r in rs], 0)} |")
    return lines


def timing_table(runs: list[dict[str, Any]], yolo: dict[str, Any] | None,
                 legacy: dict[str, Any] | None = None) -> list[str]:
    """The paper's Table I: per-module p50 / mean / p95 ms over all updates of all runs.

    Pooled from the runs' timing histograms (:mod:`bench.records`: percentiles within
    half a 1 % bin, means exact). A world none of whose runs has timings left (records
    rebuilt from ``runs.csv``) takes its cells from ``legacy`` (the contents of
    ``timing_legacy.json``: ``worlds``: world -> key -> [p50, mean, p95], pooled when those
    runs' full records still existed, for the table's ``strategy``), marked with †.
    """
    strat = "paper" if any(r["strategy"] == "paper" for r in runs) else None
    sel = [r for r in runs if strat is None or r["strategy"] == strat]
    worlds = list(dict.fromkeys(r["world"] for r in sel))
    # old cells only under the heading of the strategy they were pooled for
    legacy = ((legacy or {}).get("worlds") or {}
              if (legacy or {}).get("strategy", "paper") == (strat or "all") else {})
    head = "| module | " + " | ".join(worlds) + " |"
    lines = [f"Strategy `{strat or 'all'}`; each cell p50 / mean / p95 in ms over every "
             "update of every run (frontier, selection and segmentation once per decision, "
             "detection and costmap once per processed camera frame).", "",
             head, "|" + "|".join(["---"] * (len(worlds) + 1)) + "|"]
    totals = {w: 0.0 for w in worlds}
    marked = partial = False

    def pooled(w: str, key: str) -> tuple[Any, int, int]:
        """(p50, mean, p95) of ``key`` over world ``w``'s runs or None, runs with it, runs."""
        in_w = [r for r in sel if r["world"] == w]
        hists = [h for r in in_w for h in [records.timing_hist(r, key)] if h is not None]
        st = records.hist_stats(records.merge_histograms(hists)) if hists else None
        return st, len(hists), len(in_w)

    for key, label in TIMING_ROWS:
        cells = []
        for w in worlds:
            st, n_hist, n_runs = pooled(w, key)
            if st is not None:
                part = n_hist < n_runs
                cells.append(f"{st[0]:.1f} / {st[1]:.1f} / {st[2]:.1f}"
                             + (f" ‡{n_hist}/{n_runs}" if part else ""))
                partial |= part
                totals[w] += st[1]
            elif not n_hist and key in legacy.get(w, {}):
                p50, mean, p95 = legacy[w][key]
                cells.append(f"{p50:.1f} / {mean:.1f} / {p95:.1f} †")
                totals[w] += mean
                marked = True
            else:
                cells.append("-")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    if yolo and "ms_mean" in yolo:
        lines.append(f"| object detection (real YOLOv3-tiny, {yolo['backend']}, "
                     f"{yolo['input_size']} px, {yolo['threads']} threads) | "
                     + " | ".join(f"{yolo['ms_p50']} / {yolo['ms_mean']} / {yolo['ms_p95']}"
                                  for _ in worlds) + " |")
    lines.append("| total (sum of means, oracle detection) | "
                 + " | ".join(f"{totals[w]:.1f}" for w in worlds) + " |")
    core = []
    for w in worlds:
        st = pooled(w, "core")[0]
        core.append(f"{st[0]:.1f} / {st[1]:.1f} / {st[2]:.1f}" if st is not None else "-")
    if any(c != "-" for c in core):
        lines.append("| decision core (frontier detect + selection of one decision) | "
                     + " | ".join(core) + " |")
    if yolo and "ms_mean" in yolo:
        lines.append("| total with the real detector | "
                     + " | ".join(f"{totals[w] + yolo['ms_mean']:.1f}" for w in worlds) + " |")
    elif yolo:
        lines.append("")
        lines.append(f"Real detector not timed: {yolo.get('error')}")
    if partial:
        lines += ["", "‡k/n: pooled over the k of the world's n runs whose timings are kept "
                  "(the others' records were rebuilt from `runs.csv`)."]
    if marked:
        lines += ["", "†: pooled over the same runs when their full records (every update's "
                  "time) still existed; only their compact records are kept now "
                  f"(`{records.LEGACY_TIMING}`)."]
    return lines


def _mean(rs: list[dict[str, Any]], m: str) -> tuple[float, int]:
    v = [as_float(r["time_to_s"].get(m)) for r in rs]
    v = [x for x in v if math.isfinite(x)]
    return (float(np.mean(v)) if v else math.nan), len(v)


def targets_summary(runs: list[dict[str, Any]]) -> list[str]:
    """The issue's questions answered from the runs: does ``paper`` complete every run,
    its time to 95 % against ``explore_lite`` and ``nearest`` (target <= 0.75x), which
    strategies fail to complete, and collisions with against without the object costmap."""
    g = by_world_strategy(runs)
    worlds = list(dict.fromkeys(r["world"] for r in runs))
    if not any(w for w in worlds if (w, "paper") in g):
        return []
    lines = ["Computed from the table above. Time to 95 %: mean over the runs that reached "
             "it (their number in brackets when not all did); ratio = `paper` / baseline, "
             "target ≤ 0.75 (counted as met only when every `paper` run reached 95 %). "
             "Incomplete: runs below 99 % per strategy. Collisions: per run, "
             "`paper` against `paper_noobj` (the same strategy without the object costmap; "
             "target 0 with it).", "",
             "| world | paper completed | paper t95 [s] | vs explore_lite | vs nearest | "
             "incomplete runs | collisions paper / paper_noobj |",
             "|---|---|---|---|---|---|---|"]
    met = {"complete": 0, "lite": 0, "nearest": 0, "zero": 0, "worlds": 0}
    for w in worlds:
        p = g.get((w, "paper"))
        if not p:
            continue
        met["worlds"] += 1
        n, done = len(p), sum(1 for r in p if r["completed"])
        met["complete"] += done == n
        t_p, k_p = _mean(p, "95")
        ratios = []
        for base, tag in (("explore_lite", "lite"), ("nearest", "nearest")):
            b = g.get((w, base))
            if not b:
                ratios.append("-")
                continue
            t_b, k_b = _mean(b, "95")
            if math.isfinite(t_p) and math.isfinite(t_b):
                r = t_p / t_b
                # counted only when every paper run got there (a mean over the lucky runs
                # would flatter it); a baseline's misses only make the ratio cautious
                met[tag] += r <= 0.75 and k_p == n
                ratios.append(f"{r:.2f}× ({t_b:.0f} s{f', {k_b} of {len(b)}' if k_b < len(b) else ''})")
            elif math.isfinite(t_p):
                ratios.append(f"baseline never reached 95 % ({len(b)} runs)")
            else:
                ratios.append("-")
        fails = ", ".join(f"{st} {sum(1 for r in rs if not r['completed'])}/{len(rs)}"
                          for (ww, st), rs in g.items()
                          if ww == w and any(not r["completed"] for r in rs)) or "none"
        c_p = float(np.mean([r["collisions"] for r in p]))
        met["zero"] += c_p == 0
        no = g.get((w, "paper_noobj"))
        c_no = f"{np.mean([r['collisions'] for r in no]):.1f}" if no else "-"
        t_txt = (f"{t_p:.0f}" + (f" ({k_p} of {n})" if k_p < n else "")) if math.isfinite(t_p) else "-"
        lines.append(f"| {w} | {done}/{n} | {t_txt} | {ratios[0]} | {ratios[1]} | {fails} | "
                     f"{c_p:.1f} / {c_no} |")
    k = met["worlds"]
    lines += ["", f"Targets over {k} worlds: `paper` completes every run in {met['complete']}; "
              f"time to 95 % ≤ 0.75× `explore_lite` in {met['lite']} and ≤ 0.75× `nearest` in "
              f"{met['nearest']}; zero collisions with the object costmap in {met['zero']}."]
    return lines + [""] + _findings(g, worlds)


def _findings(g: dict[tuple[str, str], list[dict[str, Any]]], worlds: list[str]) -> list[str]:
    """The answers in words: is ``paper`` faster to 95 % than each baseline and than its
    ablations, and by how much; which strategies fail to complete; collisions with against
    without the object costmap where there is furniture."""
    out = ["Findings (time-to-95 % ratios as in the table: `paper`'s mean / the other's):", ""]
    for base in ("explore_lite", "nearest", "paper_noseg", "paper_noobj"):
        rs = []
        for w in worlds:
            if (w, "paper") not in g or (w, base) not in g:
                continue
            t_p, _ = _mean(g[(w, "paper")], "95")
            t_b, _ = _mean(g[(w, base)], "95")
            if math.isfinite(t_p):
                rs.append((t_p / t_b if math.isfinite(t_b) else math.inf, w))
        if not rs:
            continue
        ratios = sorted(r for r in rs if math.isfinite(r[0]))
        never = [w for r, w in rs if not math.isfinite(r)]
        text = f"* Time to 95 % against `{base}`: "
        if ratios:
            faster = sum(1 for r, _ in ratios if r < 0.99)
            same = sum(1 for r, _ in ratios if 0.99 <= r <= 1.01)
            med = float(np.median([r for r, _ in ratios]))
            text += (f"`paper` is faster in {faster} of the {len(ratios)} worlds where both "
                     f"reached 95 %" + (f" and within 1 % in {same}" if same else "")
                     + f"; ratio median {med:.2f}×, from {ratios[0][0]:.2f}× "
                     f"({ratios[0][1]}) to {ratios[-1][0]:.2f}× ({ratios[-1][1]})")
        if never:
            text += ("; " if ratios else "") + (f"in {len(never)} more ({', '.join(never)}) "
                                                 f"`{base}` never reached 95 % and `paper` did")
        out.append(text + ".")
    strategies = list(dict.fromkeys(st for _, st in g))
    fails = []
    for st in strategies:
        runs = [r for w in worlds for r in g.get((w, st), [])]
        bad = [w for w in worlds if any(not r["completed"] for r in g.get((w, st), []))]
        n_bad = sum(1 for r in runs if not r["completed"])
        fails.append(f"`{st}` {n_bad}/{len(runs)} runs" + (f" in {len(bad)} worlds" if bad else ""))
    out.append("* Runs that did not complete (below 99 %): " + ", ".join(fails) + ".")
    furnished = [w for w in worlds if (w, "paper") in g and (w, "paper_noobj") in g
                 and any((r.get("n_objects") or 0) > 0 for r in g[(w, "paper")])]
    if furnished:
        with_ = [r["collisions"] for w in furnished for r in g[(w, "paper")]]
        without = [r["collisions"] for w in furnished for r in g[(w, "paper_noobj")]]
        zero = sum(1 for w in furnished if all(r["collisions"] == 0 for r in g[(w, "paper")]))
        out.append(f"* Collisions in the {len(furnished)} worlds with furniture the object "
                   f"costmap found ({', '.join(furnished)}): {np.mean(with_):.2f} per run with "
                   f"it (`paper`), {np.mean(without):.2f} without (`paper_noobj`); no collision "
                   f"in any run with it in {zero} of them.")
    return out


def write_all(out: Path, md: Path | None, command: str | None) -> Path | None:
    """Figures in ``out`` and, when ``md`` is given, the markdown summary there."""
    runs = load_runs(out)
    meta_path = out / "meta.json"
    meta = json.loads(meta_path.read_text()) if meta_path.is_file() else {}
    w_order = {w: i for i, w in enumerate(meta.get("worlds", []))}
    s_order = {st: i for i, st in enumerate(meta.get("strategies", []))}
    runs.sort(key=lambda r: (w_order.get(r["world"], len(w_order)), r["world"],
                             s_order.get(r["strategy"], len(s_order)), r["strategy"], r["seed"]))
    cov = plot_coverage(runs, out)
    box = plot_time_to(runs, out)
    if md is None:
        return None
    cmd = command or meta.get("command", "bench/run_bench.py")
    tours_rows = read_csv(out / "tours.csv")
    tours = {r["world"]: float(r["tour_m"]) for r in tours_rows}
    tours95 = {r["world"]: float(r["tour95_m"]) for r in tours_rows if r.get("tour95_m")}
    yolo_path = out / "yolo.json"
    yolo = json.loads(yolo_path.read_text()) if yolo_path.is_file() else None
    rel = Path(os.path.relpath(out, md.parent))
    L = ["# Benchmarks", "",
         "Generated by `bench/run_bench.py` (via `make bench` / `scripts/run_bench.sh`); "
         "do not edit by hand.", "",
         "Command:", "", "```sh", f".venv/bin/python {cmd}", "```", ""]
    if meta:
        s0, n = meta.get("seed0", 0), meta.get("runs", 1)
        parts = meta.get("parts") or []
        L += [f"Started {parts[0].get('started') if parts else meta.get('started', '?')}, "
              f"{n} seeded runs per world x strategy (seeds {s0}..{s0 + n - 1}), "
              f"{meta.get('jobs')} worker processes on {meta.get('cpus')} CPUs, "
              f"{meta.get('wall_s', '?')} s wall in total.", ""]
        if len(parts) > 1:
            codes = {part.get("code") for part in parts}
            same = (f"on the same code ({next(iter(codes))})" if len(codes) == 1 and None not in codes
                    else "(code version of each part given where recorded)")
            L += [f"Run in {len(parts)} parts {same}, each later part with `--resume` "
                  "(runs already in the output folder that the command asks for are kept, "
                  "the rest are run):", ""]
            for i, part in enumerate(parts, 1):
                ran = part.get("runs_run")
                L.append(f"{i}. started {part.get('started', '?')}, "
                         + (f"{ran} runs, " if ran is not None else "")
                         + f"{part.get('wall_s', '?')} s wall"
                         + (f", code {part['code']}" if part.get("code") and len(codes) != 1
                            else "")
                         + (" (interrupted)" if part.get("interrupted") else "")
                         + (f" ({len(part['failed'])} runs failed: "
                            + "; ".join(f"`{f}`" for f in part["failed"]) + ")"
                            if part.get("failed") else "")
                         + (f" (run in `{part['merged_from']}`, added with `--merge`)"
                            if part.get("merged_from") else "")
                         + f": `{part.get('command')}`")
            L.append("")
    mount = meta.get("camera_mount") if meta else None
    # parts before the setting existed ran on 0.0 (store.SETTING_DEFAULTS)
    margin = float((meta.get("settings") or {}).get("nav_inflation_margin_m", 0.0)) if meta else 0.0
    mount_txt = (f"{mount[0]:g} m above the floor, pitched {mount[1]:g} rad down"
                 + (" (the paper's robot)" if mount and list(mount) == [0.894, 0.1] else "")
                 if mount else "at the simulator's default mount")
    L += ["## Setup", "",
          "* Lock-step runs (`sim_bridge/lockstep.py`): the simulator and the explorer's core "
          "code (frontiers, selection + goal manager, DuDe segmentation, object costmap) in one "
          "loop at the nodes' rates, no real-time waiting. The seed perturbs the start "
          "(±0.2 m, any heading), the lidar noise and the oracle detector (10 % misses, 2 px "
          "jitter).",
          "* Completed = coverage >= 99 % of the ground-truth explorable area: free cells "
          "at the lidar plane connected to the start that a noise-free scan sees from some "
          "pose the robot can reach (robot centres 0.22 m clear of obstacles, sampled every "
          "0.25 m; `sim_bridge/observable.py`; this drops e.g. the inside of a hollow wall "
          "block joined to a corridor by a slit, 1.03 % of the authors' maze). Coverage is "
          "the share of those cells the map knows (observed, free or occupied; see "
          "`sim_bridge/metrics.py`). "
          "A run also stops when the explorer "
          "reports exploration done or at the sim time limit (5 s per m² of explorable area, "
          "600..7200 s).",
          "* Strategies: `paper` (eq. 1-3, regions + object costmap), `paper_noseg` (no "
          "regions, γ = 0), `paper_noobj` (no object costmap), `nearest` (nearest frontier "
          "by path length), `explore_lite` (3·dist − 1·length). The two baselines run as "
          "their packages would: no object costmap (not in frontiers, selection or planning) "
          "and no regions.",
          "* Robot: TurtleBot3-waffle-sized disk (0.22 m), 1.1 m tall: chair seats and table "
          "tops are collisions although the 0.17 m lidar plane only sees legs. RGB-D camera "
          f"{mount_txt}. Navigation stand-in: "
          "grid planner + pure pursuit (arc kept out of the lethal zone: cells closer than "
          + (f"the robot radius + {margin:g} m" if margin else "the robot radius")
          + " to an obstacle); after a collision "
          "it backs off 0.15 m and replans, twice per goal, before aborting the goal "
          "(each contact counts as a collision).",
          "* Coverage tour: full-knowledge reference (`sim_bridge/coverage_tour.py`): "
          "viewpoints from a greedy set cover of a 5 m 360° sensor's view, ordered by nearest "
          "neighbour + 2-opt on geodesic distances (paths 0.27 m clear of the footprint "
          "raster, smoothed to any-angle), pruned while the scans along the tour still bring "
          "99 % into view (the tour to 95 %: the same, pruned and cut where 95 % is in view). "
          "A heuristic, not a proven bound: a lucky run can beat it. "
          "path / tour = path length to 99 % divided by it; path 95 / tour 95 = path length "
          "to 95 % divided by the tour to 95 % (near 1: the strategy already drives about "
          "as far to 95 % as a robot that knows the map; no strategy can be much faster "
          "there).", ""]
    L += ["## Results", "", "Times and paths: mean ± std over the runs that reached the "
          "milestone (their number in brackets when not all did). \"done early\": the "
          "explorer reported exploration done (no reachable frontier left) below 99 %. "
          "Goals: goals sent to navigation; switches: goals replaced by a cheaper frontier "
          "while the old goal's frontier was still there and reachable.", ""]
    L += results_table(runs, tours, tours95) + [""]
    contacts = contacts_table(runs)
    if contacts:
        L += ["## Contacts by cause", "",
              "What each contact touched and whether navigation could have known it "
              "(`sim_bridge/contacts.py`): wall mapped / unmapped (the map had an occupied "
              "cell at the touched point or not); object in layer (the object costmap the "
              "navigation plans around had it), in map only (the lidar map had it, the layer "
              "did not), unseen (neither); unclassified: runs recorded before contacts were "
              "classified. Backing off: contacts during the back-up after an earlier one.", ""]
        L += contacts + [""]
    stops = early_stop_table(runs)
    if stops:
        L += ["## Runs below 99 % by cause", "",
              "Per run that ended below the target (`sim_bridge/early_stop.py`): the cause of "
              "its largest unseen piece of the explorable area (a frontier's reason: "
              "blacklisted, no passable cPoint, no path, not selectable, selectable; or no "
              "frontier: frontier too small, closed by object layer, behind mapped obstacles) "
              "and the frontiers left at the stop; unexplained: runs recorded before the "
              "analysis existed.", ""]
        L += stops + [""]
    summary = targets_summary(runs)
    if summary:
        L += ["## Against the targets", ""] + summary + [""]
    drawn = {p.name for p in cov}
    kept = [out / f"coverage_{slug(w)}.png" for w in dict.fromkeys(r["world"] for r in runs)
            if f"coverage_{slug(w)}.png" not in drawn
            and not any(r.get("coverage_samples") for r in runs if r["world"] == w)
            and (out / f"coverage_{slug(w)}.png").is_file()]
    if cov or box or kept:
        L += ["## Figures", ""]
        partial = [w for w in dict.fromkeys(r["world"] for r in runs)
                   if f"coverage_{slug(w)}.png" in drawn
                   and any(not r.get("coverage_samples") for r in runs if r["world"] == w)]
        if partial:
            L += ["Coverage curves of " + ", ".join(f"`{w}`" for w in partial) + " are over "
                  "the runs whose coverage samples are kept (the legend gives n of the runs "
                  "in the table; the others' records were rebuilt from `runs.csv`).", ""]
        for p in cov:
            L.append(f"![{p.stem}]({(rel / p.name).as_posix()})")
        if kept:
            L += ["", "Drawn when the full records of these worlds' runs still existed (their "
                  "coverage samples are not in the records kept now, so they are not redrawn):", ""]
            L += [f"![{p.stem}]({(rel / p.name).as_posix()})" for p in kept]
            L.append("")
        if box:
            L.append(f"![time to 95 %]({(rel / box.name).as_posix()})")
        maps = sorted((out / "maps").glob("*.png")) if (out / "maps").is_dir() else []
        if maps:
            L += ["", "Final maps of the first run of each world x strategy (path green, "
                  "regions tinted, object boxes yellow, goals purple, collisions red): "
                  + ", ".join(f"[{p.stem}]({(rel / 'maps' / p.name).as_posix()})"
                              for p in maps)]
        L.append("")
    legacy_path = out / records.LEGACY_TIMING
    legacy = json.loads(legacy_path.read_text()) if legacy_path.is_file() else None
    L += (["## Per-module timing (paper's Table I)", ""] + timing_table(runs, yolo, legacy)
          + [""])
    if tours_rows:
        L += ["## Coverage tours", "", "| world | explorable area [m²] | tour [m] | viewpoints "
              "| tour to 95 % [m] | viewpoints | coverable | compute [s] |",
              "|---|---|---|---|---|---|---|---|"]
        L += [f"| {r['world']} | {r['explorable_area_m2']} | {r['tour_m']} | {r['viewpoints']} "
              f"| {r.get('tour95_m') or '-'} | {r.get('viewpoints95') or '-'} "
              f"| {float(r['coverable_fraction']):.3f} | {r['wall_s']} |" for r in tours_rows]
        L.append("")
    ros_path = out / "ros.json"
    if ros_path.is_file():
        ros = json.loads(ros_path.read_text())
        L += ["## Lock-step vs ROS", "", ros.get("note", ""), "",
              "| seed | mode | stop | coverage [%] | sim time [s] | path [m] | collisions | "
              "goals | objects | object frames |", "|---|---|---|---|---|---|---|---|---|---|"]
        for row in ros.get("rows", []):
            L.append(f"| {row['seed']} | {row['mode']} | {row['stop']} | "
                     f"{_fmt(row.get('coverage_pct'))} | {_fmt(row.get('sim_time_s'))} | "
                     f"{_fmt(row.get('path_length_m'))} | {_count(row.get('collisions', '-'))} | "
                     f"{row.get('goals', '-')} | {row.get('objects', '-')} | "
                     f"{row.get('object_frames', '-')} |")
        L.append("")
    L += paired_sections(out)
    n_csv = sum(1 for r in runs if r.get("record") == "csv")
    L += ["Files: `runs.csv` (one row per run), `runs.jsonl.gz` (every run's record without "
          "its per-update timings, which are pooled into histograms: what `--resume` reads "
          "on a new checkout; `bench/records.py`), `runs.jsonl` (the full records: samples "
          "and every update's time; tens of MB, so kept out of git), `tours.csv`, "
          f"`yolo.json`, `meta.json` in `{rel.as_posix()}/`."
          + (f" {n_csv} of the {len(runs)} runs were rebuilt from `runs.csv` after their "
             "full records were lost with a checkout: their table rows are exact, their "
             "coverage curves and pooled timings are the ones drawn and computed before "
             "(figures kept, timing cells marked †)." if n_csv else ""), ""]
    md.write_text("\n".join(L))
    return md


def paired_sections(out: Path) -> list[str]:
    """The reports of ``bench/paired.py`` kept in ``out/paired/*.md`` (by name), under one
    heading: comparisons of parameter settings run since (or beside) the full benchmark,
    each with its command and code version. Empty when there are none."""
    files = sorted((out / "paired").glob("*.md")) if (out / "paired").is_dir() else []
    if not files:
        return []
    L = ["## Paired comparisons", "",
         "Parameter settings compared on the same worlds, strategies and seeded starts with "
         "`bench/paired.py` (the benchmark's settings; ratio = arm / first arm, per seed). "
         "These runs are not in the tables above: they are what a change is decided on "
         "before the full benchmark is rerun.", ""]
    for f in files:
        L += [f.read_text().rstrip(), ""]
    return L


def _fmt(v: Any) -> str:
    return f"{v:.1f}" if isinstance(v, (int, float)) and math.isfinite(v) else str(v)


def _count(v: Any) -> str:
    """A count as an integer (the ROS metrics topic carries counts as floats)."""
    return str(int(v)) if isinstance(v, float) and v.is_integer() else str(v)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="Plots and BENCHMARKS.md from a bench folder.")
    ap.add_argument("out", help="folder written by bench/run_bench.py")
    ap.add_argument("--md", default=str(Path(__file__).resolve().parents[1] / "BENCHMARKS.md"))
    a = ap.parse_args(argv)
    path = write_all(Path(a.out), Path(a.md) if a.md else None, None)
    print(f"[report] wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
