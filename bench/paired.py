"""Paired A/B comparison of parameter settings in seeded lock-step runs.

Every arm explores the same worlds with the same strategies from the same seeded starts
(the benchmark's settings: paper camera mount, sim time limit per m^2), differing only by
the parameter overrides the arm names, so the start-to-start spread cancels in the
per-seed ratios. Use it to decide a default before a full ``run_bench.py`` rerun, and to
isolate one change (e.g. the segmenter's clutter filling) from everything else that
landed since the benchmark was last run.

An arm is ``NAME`` (no override: today's defaults) or ``NAME:KEY=VALUE[;KEY=VALUE...]``,
where KEY is

* ``explorer.SECTION.FIELD``: a field of :class:`ExplorerParams` (SECTION frontier,
  selection, segmentation, objects, rrt or overlay), on top of ``config/explorer.yaml``;
* ``sim.FIELD``: a :class:`SimParams` field (e.g. ``sim.nav_inflation_soft_margin_m``);
* ``lockstep.FIELD``: a :class:`LockstepParams` field (e.g. ``lockstep.nav_feedback``).

Values are parsed by the field's type (bool: true/false/1/0). The first arm is the
reference of the ratios; a single arm runs and reports its absolute figures (complete,
contacts, median T95) only, e.g. more seeds of today's defaults. Runs are appended to
``OUT/runs.jsonl`` as they finish; a second call with the same ``--out`` runs only what is
missing (same arm names must mean the same overrides: they are stored in
``OUT/arms.json`` and checked). A run that raises is reported and left out (exit status
1; the same command runs it again); the others go on. ``kill -USR1 PID`` finishes the
runs in flight and starts no new one, SIGTERM or Ctrl-C stops at once; either way the
report covers what ran (exit status 128 + the signal) and the same command continues.

Usage::

    .venv/bin/python bench/paired.py --out out/paired_seg --strategies paper \\
        --worlds house_cluttered,shared/house_cluttered --seeds 0-19 \\
        --arm new --arm old:explorer.segmentation.clutter_max_area_m2=0

prints, per world and strategy, runs complete, contacts, median time to 95 % per arm and
the median of the per-seed T95 ratios against the first arm (with wins / losses), then
the same over all worlds; ``--md FILE`` also writes that report.
"""

from __future__ import annotations

import argparse
import importlib
import dataclasses
import fcntl
import json
import math
import shlex
import signal
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
for _p in (ROOT, ROOT / "bench"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

import numpy as np  # noqa: E402

from bench.progress import Progress  # noqa: E402
from bench.store import code_version, read_csv  # noqa: E402
from bench.tasks import catch_stop_signals, restore_signals, run_drainable, \
    stop_signals_deferred  # noqa: E402
from bench.worlds import PAPER_CAMERA_MOUNT, load, sim_params_for, sim_time_limit  # noqa: E402
from sim_bridge.engine import SimParams  # noqa: E402
from sim_bridge.lockstep import STRATEGIES, ExplorerParams, LockstepParams, \
    load_explorer_params, run_exploration, strategy_spec  # noqa: E402

#: ExplorerParams sections an ``explorer.SECTION.FIELD`` override may name.
SECTIONS = tuple(f.name for f in dataclasses.fields(ExplorerParams))


@dataclasses.dataclass(frozen=True)
class Arm:
    """One setting of the comparison: a name and its overrides (key -> text value)."""

    name: str
    overrides: tuple[tuple[str, str], ...] = ()

    def spec(self) -> str:
        """The command-line form."""
        if not self.overrides:
            return self.name
        return self.name + ":" + ";".join(f"{k}={v}" for k, v in self.overrides)


def parse_arm(text: str) -> Arm:
    """``NAME`` or ``NAME:KEY=VALUE[;KEY=VALUE...]`` -> :class:`Arm` (keys checked by
    :func:`build_params`).

    Raises
    ------
    ValueError
        On an empty name or an override without ``=``.
    """
    name, _, rest = text.partition(":")
    name = name.strip()
    if not name:
        raise ValueError(f"arm {text!r}: empty name")
    ovs = []
    for part in filter(None, (p.strip() for p in rest.split(";"))):
        key, eq, val = part.partition("=")
        if not eq or not key.strip():
            raise ValueError(f"arm {name}: override {part!r} is not KEY=VALUE")
        ovs.append((key.strip(), val.strip()))
    return Arm(name, tuple(ovs))


def _value(cls: Any, field: str, text: str, key: str) -> Any:
    """``text`` converted to the type of ``cls``'s default for ``field``."""
    fields = {f.name: f for f in dataclasses.fields(cls)}
    if field not in fields:
        raise ValueError(f"{key}: {cls.__name__} has no field {field!r} "
                         f"(has {', '.join(sorted(fields))})")
    f = fields[field]
    default = (f.default if f.default is not dataclasses.MISSING
               else f.default_factory())  # type: ignore[misc]
    if isinstance(default, bool):
        low = text.lower()
        if low not in ("true", "false", "1", "0"):
            raise ValueError(f"{key}: expected true/false, got {text!r}")
        return low in ("true", "1")
    if isinstance(default, int):
        return int(text)
    if isinstance(default, float):
        return float(text)
    if isinstance(default, str):
        return text
    if isinstance(default, tuple):
        return tuple(type(default[0])(v) if default else float(v)
                     for v in text.split(",") if v)
    raise ValueError(f"{key}: fields of type {type(default).__name__} cannot be overridden")


def build_params(arm: Arm, base_explorer: ExplorerParams, base_sim: SimParams,
                 base_lockstep: LockstepParams) -> tuple[ExplorerParams, SimParams,
                                                         LockstepParams]:
    """The three parameter sets of ``arm``: the bases with its overrides applied (each
    dataclass validates its values).

    Raises
    ------
    ValueError
        On an unknown key or a rejected value.
    """
    ex, sim, ls = base_explorer, base_sim, base_lockstep
    for key, text in arm.overrides:
        parts = key.split(".")
        if parts[0] == "explorer" and len(parts) == 3:
            if parts[1] not in SECTIONS:
                raise ValueError(f"{key}: no explorer section {parts[1]!r} "
                                 f"(has {', '.join(SECTIONS)})")
            sec = getattr(ex, parts[1])
            sec = dataclasses.replace(sec, **{parts[2]: _value(type(sec), parts[2], text, key)})
            ex = dataclasses.replace(ex, **{parts[1]: sec})
        elif parts[0] == "sim" and len(parts) == 2:
            sim = dataclasses.replace(sim, **{parts[1]: _value(SimParams, parts[1], text, key)})
        elif parts[0] == "lockstep" and len(parts) == 2:
            ls = dataclasses.replace(ls, **{parts[1]: _value(LockstepParams, parts[1], text,
                                                             key)})
        else:
            raise ValueError(f"{key}: expected explorer.SECTION.FIELD, sim.FIELD or "
                             f"lockstep.FIELD")
    return ex, sim, ls


def parse_seeds(text: str) -> list[int]:
    """``0-19`` / ``1,5,7`` / ``0-4,10`` -> seeds in order, without repeats."""
    out: list[int] = []
    for part in filter(None, (p.strip() for p in text.split(","))):
        if "-" in part:
            lo, hi = (int(v) for v in part.split("-"))
            out += [s for s in range(lo, hi + 1) if s not in out]
        elif int(part) not in out:
            out.append(int(part))
    return out


# ------------------------------------------------------------------------------ runs

#: Set in the main process before the workers fork.
_ARMS: dict[str, tuple[ExplorerParams, SimParams, LockstepParams]] = {}
#: The code version the runs of this call are made with (read once, before forking).
_CODE = ["unknown"]


def _run(task: tuple[str, str, str, int, float]) -> dict[str, Any]:
    arm, world_spec, strategy, seed, limit = task
    ex, sim, ls = _ARMS[arm]
    world, gt = load(world_spec)
    t0 = time.process_time()
    res = run_exploration(world, strategy, seed,
                          params=dataclasses.replace(ls, max_sim_time_s=float(limit)),
                          sim_params=sim, explorer_params=ex, ground_truth=gt)
    row = res.summary_row()
    row.update(arm=arm, cpu_s=round(time.process_time() - t0, 2), code=_CODE[0],
               mapping_error=sim.mapping_error)
    return row


def _key(r: dict[str, Any]) -> tuple[str, str, str, int]:
    return (r["arm"], r["world"], r["strategy"], int(r["seed"]))


def _mark_s(r: dict[str, Any], key: str = "time_to_95_s") -> float:
    """The run's time to a coverage mark (``key``), NaN when it never got there."""
    v = r.get(key)
    return float(v) if v is not None and math.isfinite(float(v)) else math.nan


def report(rows: list[dict[str, Any]], arms: list[str]) -> str:
    """Markdown: per world x strategy and overall, per arm: complete / runs, contacts,
    median T95, and against the first arm the median per-seed T95 ratio with wins
    (ratio < 0.99) / losses (> 1.01). A seed whose run of either arm never reached 95 %
    counts in neither ratio."""
    by = {_key(r): r for r in rows}
    worlds = list(dict.fromkeys(r["world"] for r in rows))
    strats = list(dict.fromkeys(r["strategy"] for r in rows))
    ref = arms[0]
    lines = [f"Reference arm: `{ref}`; ratio = arm / reference T95, per seed (median; "
             "wins < 0.99, losses > 1.01).", "",
             "| world | strategy | arm | complete | contacts | median T95 [s] "
             "| T95 ratio (median) | wins/losses |", "|---|---|---|---|---|---|---|---|"]
    overall: dict[tuple[str, str], list[float]] = {}
    for w in worlds + ["(all)"]:
        for s in strats:
            for a in arms:
                rs = [r for r in rows if r["arm"] == a and r["strategy"] == s
                      and (w == "(all)" or r["world"] == w)]
                if not rs:
                    continue
                t95 = [_mark_s(r) for r in rs]
                ratios = []
                for r in rs:
                    b = by.get((ref, r["world"], s, int(r["seed"])))
                    if b is not None and math.isfinite(_mark_s(r)) and math.isfinite(_mark_s(b)):
                        ratios.append(_mark_s(r) / _mark_s(b))
                fin = [t for t in t95 if math.isfinite(t)]
                med = f"{np.median(fin):.1f}" if fin else "-"
                if a == ref:
                    rat, wl = "1", "-"
                elif ratios:
                    rat = f"{np.median(ratios):.3f}"
                    wl = f"{sum(x < 0.99 for x in ratios)}/{sum(x > 1.01 for x in ratios)}"
                else:
                    rat, wl = "-", "-"
                if w == "(all)":
                    overall[(s, a)] = ratios
                lines.append(f"| {w} | {s} | {a} | {sum(int(r['completed']) for r in rs)}/"
                             f"{len(rs)} | {sum(int(r['collisions']) for r in rs)} | {med} "
                             f"| {rat} | {wl} |")
    return "\n".join(lines) + "\n"


def _core_p95(rs: list[dict[str, Any]]) -> str:
    """'median / max' of the runs' decision-core p95 (ms); '-' when none recorded it."""
    v = [float(r["core_ms_p95"]) for r in rs
         if r.get("core_ms_p95") not in (None, "") and math.isfinite(float(r["core_ms_p95"]))]
    return f"{np.median(v):.0f} / {max(v):.0f}" if v else "-"


def against_report(rows: list[dict[str, Any]], arm: str, new: str,
                   tours: dict[str, float] | None = None) -> str:
    """Markdown: strategy ``new`` against every other strategy of the same arm, paired
    per seed: per world its median T95 and, per other strategy, the median per-seed T95
    ratio ``new`` / other with wins (< 0.99) / losses (> 1.01); whether ``new``'s median
    T95 is within 5 % of the best other strategy's median (the per-world target);
    then the median over all pairs per other strategy, and the same for the time to 99 %.
    A seed whose run of either never reached the mark counts in no ratio (its completion
    shows in the first table). With ``tours`` (world -> full-knowledge coverage tour, m)
    a last row gives each strategy's median over its runs of the path to 99 % divided by
    its world's tour (the path target), over the runs that reached 99 %."""
    mine = [r for r in rows if r["arm"] == arm]
    by = {(r["world"], r["strategy"], int(r["seed"])): r for r in mine}
    others = [s for s in dict.fromkeys(r["strategy"] for r in mine) if s != new]
    worlds = list(dict.fromkeys(r["world"] for r in mine))
    head = " | ".join(f"/ {s} (w/l)" for s in others)
    lines = [f"`{new}` against the other strategies of arm `{arm}`: T95 ratio = `{new}` / "
             "other, per seed (median; wins < 0.99, losses > 1.01); 'best +5 %' = "
             f"`{new}`'s median T95 <= 1.05 x the best other median; decision core = "
             f"`{new}`'s per-run p95 of frontier detection + selection per decision "
             "(median / max over its runs; wall time, so it depends on the machine's load).",
             "",
             f"| world | `{new}` median T95 [s] | {head} | best +5 % | decision core p95 "
             "[ms] |",
             "|---|---|" + "---|" * len(others) + "---|---|"]
    pooled: dict[str, list[float]] = {s: [] for s in others}
    for w in worlds:
        rs = [r for r in mine if r["world"] == w and r["strategy"] == new]
        if not rs:
            continue
        fin = [_mark_s(r) for r in rs if math.isfinite(_mark_s(r))]
        cells, best = [], math.inf
        for s in others:
            ratios = []
            fo = [_mark_s(r) for r in mine if r["world"] == w and r["strategy"] == s
                  and math.isfinite(_mark_s(r))]
            if fo:
                best = min(best, float(np.median(fo)))
            for r in rs:
                b = by.get((w, s, int(r["seed"])))
                if b is not None and math.isfinite(_mark_s(r)) and math.isfinite(_mark_s(b)):
                    ratios.append(_mark_s(r) / _mark_s(b))
            pooled[s] += ratios
            cells.append(f"{np.median(ratios):.3f} ({sum(x < 0.99 for x in ratios)}/"
                         f"{sum(x > 1.01 for x in ratios)})" if ratios else "-")
        med = float(np.median(fin)) if fin else math.nan
        ok = ("-" if not (math.isfinite(med) and math.isfinite(best))
              else ("yes" if med <= 1.05 * best else f"no ({med / best:.2f}x)"))
        lines.append(f"| {w} | {med:.1f} | " + " | ".join(cells) + f" | {ok} | "
                     f"{_core_p95(rs)} |")
    lines.append("| (all pairs) | | " + " | ".join(
        f"{np.median(v):.3f} ({sum(x < 0.99 for x in v)}/{sum(x > 1.01 for x in v)})"
        if v else "-" for v in pooled.values()) + " | | |")
    # The same pooled ratio for the time to 99 % (the completion mark): a strategy can
    # trade the first 95 % for a shorter whole run.
    cells = []
    for s in others:
        v = []
        for r in mine:
            b = by.get((r["world"], s, int(r["seed"]))) if r["strategy"] == new else None
            if b is not None:
                t_new, t_other = _mark_s(r, "time_to_99_s"), _mark_s(b, "time_to_99_s")
                if math.isfinite(t_new) and math.isfinite(t_other):
                    v.append(t_new / t_other)
        cells.append(f"{np.median(v):.3f} ({sum(x < 0.99 for x in v)}/"
                     f"{sum(x > 1.01 for x in v)})" if v else "-")
    lines.append("| (all pairs, time to 99 %) | | " + " | ".join(cells) + " | | |")
    if tours:
        def path_over_tour(strategy: str) -> str:
            v = [float(r["path_to_99_m"]) / tours[r["world"]] for r in mine
                 if r["strategy"] == strategy and r["world"] in tours
                 and math.isfinite(_mark_s(r, "path_to_99_m"))]
            return f"{np.median(v):.3f} (n={len(v)})" if v else "-"
        lines.append("| (path to 99 % / coverage tour, median) | " + path_over_tour(new)
                     + " | " + " | ".join(path_over_tour(s) for s in others) + " | | |")
    return "\n".join(lines) + "\n"


def load_tours(path: Path) -> dict[str, float]:
    """World -> full-knowledge coverage tour (m) from a benchmark's ``tours.csv``
    (empty when the file is absent)."""
    tours = {r["world"]: float(r["tour_m"] or "nan") for r in read_csv(path)}
    return {w: t for w, t in tours.items() if math.isfinite(t) and t > 0}


def _known_strategy(name: str) -> bool:
    """True when ``name`` is a benchmark arm or a registered strategy."""
    try:
        strategy_spec(name)
    except ValueError:
        return False
    return True


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="folder of runs.jsonl and arms.json")
    ap.add_argument("--worlds", required=True, help="comma-separated world specs")
    ap.add_argument("--strategies", default="paper",
                    help=f"comma-separated, from {','.join(STRATEGIES)} or a strategy that "
                         "a --plugin module registers")
    ap.add_argument("--plugin", action="append", default=[], metavar="MODULE",
                    help="import this module first (repeatable): a strategy it registers "
                         "(explore_seg.core.selection.register) runs with its default arm")
    ap.add_argument("--seeds", default="0-19", help="e.g. 0-19 or 1,5,7")
    ap.add_argument("--arm", action="append", default=[],
                    help="NAME or NAME:KEY=VALUE[;KEY=VALUE]; the first is the reference "
                         "(one arm: absolute figures only)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--max-sim-time", type=float, default=0.0,
                    help="sim time limit per run in s (0 = the benchmark's per-area limit)")
    ap.add_argument("--mapping-noise", default="none", metavar="PROFILE",
                    help="SLAM-like mapping error of every arm (SimParams.mapping_error: none, "
                         "realistic, harsh, custom); an arm's sim.mapping_error overrides it")
    ap.add_argument("--md", default="", help="also write the report to this file (with "
                    "--title, the command and the code version); keep a report that decides "
                    "something in bench/results/experiments/ (BENCHMARKS.md links it)")
    ap.add_argument("--title", default="", help="heading of the --md report")
    ap.add_argument("--against", default="", metavar="STRATEGY",
                    help="also compare this strategy with the others of each arm, paired "
                         "per seed (e.g. routed against explore_lite and nearest), and give "
                         "each one's path to 99 %% over the coverage tour of "
                         "bench/results/tours.csv")
    ap.add_argument("--no-runs", action="store_true",
                    help="run nothing: report the runs kept in --out that the other options "
                         "select (e.g. worlds compared on different seed ranges)")
    a = ap.parse_args(argv)
    try:
        arms = [parse_arm(t) for t in a.arm]
        if not arms or len({x.name for x in arms}) != len(arms):
            raise ValueError("give at least one --arm, with distinct names")
        for module in a.plugin:
            try:
                importlib.import_module(module)
            except ImportError as err:
                raise ValueError(f"--plugin {module}: {err}") from None
        strategies = [s for s in a.strategies.split(",") if s]
        bad = [s for s in strategies if not _known_strategy(s)]
        if bad:
            raise ValueError(f"unknown strategies {bad} (have {', '.join(STRATEGIES)} and "
                             "the strategies registered by --plugin modules)")
        seeds = parse_seeds(a.seeds)
        if a.against and a.against not in strategies:
            raise ValueError(f"--against {a.against} is not one of --strategies")
        base = (load_explorer_params(),
                sim_params_for(PAPER_CAMERA_MOUNT, None, a.mapping_noise), LockstepParams())
        for arm in arms:
            _ARMS[arm.name] = build_params(arm, *base)
    except ValueError as err:
        ap.error(str(err))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    lock = (out / ".lock").open("w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        ap.error(f"another bench/paired.py is running on {out}")
    spec_file = out / "arms.json"
    specs = {x.name: x.spec() for x in arms}
    if spec_file.exists():
        old = json.loads(spec_file.read_text())
        clash = {n: (old[n], s) for n, s in specs.items() if n in old and old[n] != s}
        if clash:
            ap.error(f"arm names reused with other overrides in {out}: {clash}")
        specs = {**old, **specs}
    spec_file.write_text(json.dumps(specs, indent=1) + "\n")
    runs_file = out / "runs.jsonl"
    rows = [json.loads(line) for line in runs_file.read_text().splitlines()
            ] if runs_file.exists() else []
    rows = list({_key(r): r for r in rows}.values())    # a run written twice counts once
    have = {_key(r) for r in rows}
    worlds = [w for w in a.worlds.split(",") if w]
    limits = {w: (0.0 if a.no_runs else
                  sim_time_limit(float(load(w)[1].explorable_area_m2), a.max_sim_time))
              for w in worlds}
    # seed-major so an interrupted comparison holds whole pairs
    tasks = [(x.name, w, s, seed, limits[w]) for seed in seeds for w in worlds
             for s in strategies for x in arms if (x.name, w, s, seed) not in have]
    if a.no_runs:
        tasks = []
    print(f"[paired] {len(tasks)} runs to do, {len(rows)} kept in {runs_file}", flush=True)
    interrupted = 0               # the signal that stopped the runs, 0 = none
    failed: list[str] = []        # "arm/world/strategy/seed: error"
    if tasks:
        _CODE[0] = code_version()
        interrupted = _run_tasks(tasks, a.jobs, runs_file, rows, failed)
    wanted = {x.name for x in arms}
    sel = [r for r in rows if r["arm"] in wanted and r["world"] in worlds
           and r["strategy"] in strategies and int(r["seed"]) in seeds]
    text = report(sel, [x.name for x in arms])
    if a.against:
        tours = load_tours(ROOT / "bench" / "results" / "tours.csv")
        for x in arms:
            text += "\n" + against_report(sel, x.name, a.against, tours)
    print(text)
    if a.md:
        head = f"### {a.title}\n\n" if a.title else ""
        # the command that makes these runs (--no-runs only reports them)
        cmd = " ".join(shlex.quote(x) for x in (argv if argv is not None else sys.argv[1:])
                       if x != "--no-runs")
        cpu = sum(float(r.get("cpu_s", 0.0)) for r in sel)
        Path(a.md).parent.mkdir(parents=True, exist_ok=True)
        codes: dict[str, int] = {}
        for r in sel:
            codes[r.get("code", "unrecorded")] = codes.get(r.get("code", "unrecorded"), 0) + 1
        made = ", ".join(f"{c} ({n} runs)" for c, n in sorted(codes.items()))
        Path(a.md).write_text(
            f"{head}Runs made with code {made}; {len(sel)} runs, {cpu / 3600:.1f} CPU hours; "
            f"reported {time.strftime('%Y-%m-%d')}. Command:\n\n```sh\n.venv/bin/python "
            f"bench/paired.py {cmd}\n```\n\n" + text)
    if failed:
        print(f"[paired] {len(failed)} runs failed (not in runs.jsonl; the same command "
              "runs them again): " + "; ".join(failed), file=sys.stderr)
    return 128 + interrupted if interrupted else (1 if failed else 0)


def _run_tasks(tasks: list[tuple[str, str, str, int, float]], jobs: int, runs_file: Path,
               rows: list[dict[str, Any]], failed: list[str]) -> int:
    """Run ``tasks`` on a pool of ``jobs`` processes, appending each row to
    ``runs_file`` and ``rows`` as it finishes (a failing run is reported and added to
    ``failed``, the others go on). SIGUSR1 finishes the runs in flight and starts no new
    one, SIGTERM / Ctrl-C stop at once (the rows written stay; the same command runs the
    rest). Returns the signal that stopped the runs, 0 when all ran."""
    import multiprocessing as mp
    bar = Progress(len(tasks), "paired")
    old = catch_stop_signals()
    try:
        with mp.get_context("fork").Pool(max(1, jobs), maxtasksperchild=10) as pool, \
                runs_file.open("a") as fh:
            try:
                for r in run_drainable(pool, jobs, tasks, failed, fn=_run, parts=4):
                    with stop_signals_deferred():     # a row is written whole or not at all
                        fh.write(json.dumps(r) + "\n")
                        fh.flush()
                        rows.append(r)
                    bar.update(f"{r['arm']} {r['world']} {r['strategy']} {r['seed']}: "
                               f"{r['stop_reason']} {r['coverage_pct']:.1f} %")
            except KeyboardInterrupt as err:
                pool.terminate()
                sig = int(err.args[0]) if err.args else int(signal.SIGINT)
                how = "stopped" if sig == signal.SIGUSR1 else "interrupted"
                print(f"\n[paired] {how} after {bar.done} of {len(tasks)} runs: reporting "
                      "what ran (the same command runs the rest)", file=sys.stderr)
                return sig
    finally:
        restore_signals(old)
    return 0


if __name__ == "__main__":
    sys.exit(main())
