"""bench/report.py: one code version per report (refusal, --allow-mixed, certificates of
bench/same_results.py), the paired T95 ratio's bootstrap interval, the line budget of
BENCHMARKS.md on a full matrix, and the matrix machinery of bench/run_bench.py (seeds per
world, shards, --resume, --merge, the closing wall / CPU line)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import noise_table, records, report, run_bench, same_results, store  # noqa: E402
from bench.worlds import default_worlds  # noqa: E402
from sim_bridge.strategy_specs import MATRIX_STRATEGIES as STRATEGIES  # noqa: E402

A, B = "aaaaaaa11111", "bbbbbbb22222"


def _rec(world: str, strategy: str, seed: int, code: str | None, t95: float | None = 100.0,
         **kw) -> dict:
    d = {"world": world, "strategy": strategy, "seed": seed, "completed": t95 is not None,
         "stop_reason": "coverage" if t95 is not None else "timeout",
         "sim_time_s": (t95 or 600.0) + 20.0, "wall_time_s": 1.0, "coverage_pct": 99.2,
         "explorable_area_m2": 50.0, "path_length_m": 40.0 + seed, "collisions": 0,
         "goals_sent": 5, "goal_switches": 0, "goals_blacklisted": 0, "nav_aborts": 0,
         "n_objects": 0, "time_to_s": {"95": t95, "99": None if t95 is None else t95 + 10},
         "path_to_m": {"95": 30.0, "99": 35.0 if t95 is not None else None},
         "coverage_samples": [], "cpu_time_s": 2.5}
    if code is not None:
        d["code"] = code
    d.update(kw)
    return d


def _folder(path: Path, recs: list[dict], worlds: list[str] | None = None,
            strategies: list[str] | None = None) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    records.write_compact(path, recs)
    worlds = worlds or list(dict.fromkeys(r["world"] for r in recs))
    strategies = strategies or list(dict.fromkeys(r["strategy"] for r in recs))
    (path / "meta.json").write_text(json.dumps({
        "command": "bench/run_bench.py --out X", "worlds": worlds, "strategies": strategies,
        "settings": {}, "wall_s": 10.0,
        "parts": [{"command": "bench/run_bench.py --out X", "started": "2026-12-06 10:00:00",
                   "code": A, "runs_run": len(recs), "wall_s": 10.0}]}))
    store.write_csv(path / "tours.csv", [{"world": w, "tour_m": 30.0, "explorable_area_m2": 50.0}
                                         for w in worlds])
    return path


def _two_versions(tmp_path: Path) -> Path:
    recs = [_rec("w", s, k, A if k < 2 else B) for s in ("routed", "nearest") for k in range(3)]
    return _folder(tmp_path / "res", recs)


# ------------------------------------------------------------------ versions


def test_mixed_versions_are_refused_naming_each_version_and_its_runs(tmp_path):
    out = _two_versions(tmp_path)
    with pytest.raises(report.MixedVersions) as err:
        report.write_all(out, tmp_path / "B.md", command="x")
    msg = str(err.value)
    assert f"{A}: 4 runs" in msg and f"{B}: 2 runs" in msg and "--allow-mixed" in msg
    assert not (tmp_path / "B.md").exists()
    assert report.main([str(out), "--md", str(tmp_path / "B.md")]) == 2
    assert run_bench.main(["--report-only", "--out", str(out), "--md", str(tmp_path / "B.md")]) == 3
    assert not (tmp_path / "B.md").exists()
    assert run_bench.main(["--report-only", "--out", str(out), "--md", str(tmp_path / "B.md"),
                           "--allow-mixed"]) == 0
    # a run that records no version is not one version either
    no_code = _folder(tmp_path / "old", [_rec("w", "routed", 0, None)])
    with pytest.raises(report.MixedVersions, match="unknown: 1 runs"):
        report.write_all(no_code, tmp_path / "C.md", command="x")


def test_allow_mixed_marks_every_row_with_its_versions(tmp_path):
    out = _two_versions(tmp_path)
    md = report.write_all(out, tmp_path / "B.md", command="x", allow_mixed=True)
    text = md.read_text()
    assert "Mixed code versions: 2" in text
    assert f"| v1 | `{A}` | 4 |" in text and f"| v2 | `{B}` | 2 |" in text
    rows = [ln for ln in text.splitlines() if ln.startswith(("| routed |", "| nearest |"))]
    summary, per_world = rows[:2], rows[2:]
    assert len(per_world) == 2 and all(ln.endswith("| v1×2, v2×1 |") for ln in per_world)
    assert all(ln.endswith("| 2 versions, v1–v2 |") for ln in summary)
    # one version: no version column, the version in the heading
    one = _folder(tmp_path / "one", [_rec("w", "routed", k, A) for k in range(2)])
    text = report.write_all(one, tmp_path / "O.md", command="x").read_text()
    assert f"**Code version: `{A}`**" in text and "| code |" not in text


def _certificate(runs: list[dict], before: str, after: str) -> dict:
    return {"certificate": same_results.CERTIFICATE, "format": same_results.CERTIFICATE_FORMAT,
            "before": before, "after": after,
            "runs": {f"{r['world']}/{r['strategy']}/{r['seed']}":
                     {k: r.get(k) for k in same_results.FINGERPRINT} for r in runs}}


def test_a_certificate_makes_the_runs_it_lists_count_as_its_after_commit(tmp_path):
    out = _two_versions(tmp_path)
    b_runs = [r for r in records.read(out) if r["code"] == B]
    cert = tmp_path / "cert.json"
    cert.write_text(json.dumps(_certificate(b_runs, B, A)))
    text = report.write_all(out, tmp_path / "B.md", command="x",
                            certificates=[cert]).read_text()
    assert f"**Code version: `{A}`** (every run; 2 of them certified identical" in text
    # in the folder's certificates/ it applies without being named
    (out / report.CERT_DIR).mkdir()
    (out / report.CERT_DIR / "b-a.json").write_text(cert.read_text())
    assert report.write_all(out, tmp_path / "C.md", command="x").is_file()
    (out / report.CERT_DIR / "b-a.json").unlink()
    # a listed run whose figures differ is another run: not certified
    wrong = _certificate(b_runs, B, A)
    next(iter(wrong["runs"].values()))["sim_time_s"] += 1.0
    cert.write_text(json.dumps(wrong))
    with pytest.raises(report.MixedVersions, match=f"{B}: 1 runs"):
        report.write_all(out, tmp_path / "D.md", command="x", certificates=[cert])
    # the wrong direction certifies nothing; chains A -> C, B -> A make one version C
    cert.write_text(json.dumps(_certificate(b_runs, A, B)))
    with pytest.raises(report.MixedVersions):
        report.write_all(out, tmp_path / "E.md", command="x", certificates=[cert])
    a_runs = [r for r in records.read(out) if r["code"] == A]
    c = "ccccccc33333"
    (tmp_path / "c1.json").write_text(json.dumps(_certificate(a_runs + b_runs, A, c)))
    (tmp_path / "c2.json").write_text(json.dumps(_certificate(b_runs, B, A)))
    text = report.write_all(out, tmp_path / "F.md", command="x",
                            certificates=[tmp_path / "c1.json", tmp_path / "c2.json"]).read_text()
    assert f"**Code version: `{c}`**" in text


@pytest.mark.parametrize("change, what", [
    ({"certificate": "other"}, "same-results"),
    ({"format": 99}, "format"),
    ({"after": A + "+modified"}, "clean commit"),
    ({"before": "unknown"}, "clean commit"),
    ({"runs": {}}, "runs"),
])
def test_a_malformed_certificate_is_refused_naming_the_file(tmp_path, change, what):
    out = _two_versions(tmp_path)
    cert = tmp_path / "bad.json"
    cert.write_text(json.dumps({**_certificate(records.read(out), B, A), **change}))
    with pytest.raises(ValueError, match=what) as err:
        report.write_all(out, tmp_path / "B.md", command="x", certificates=[cert])
    assert "bad.json" in str(err.value)


def _same_results_file(code: str, results: dict[str, dict]) -> dict[str, dict]:
    return {k: {"key": k, "code": code, "wall_s": 1.0, "cpu_s": 1.0, "result": r}
            for k, r in results.items()}


def test_same_results_writes_a_certificate_only_for_identical_runs_on_clean_commits(tmp_path):
    res = {"w/routed/0": dict(_rec("w", "routed", 0, None), time_to_s={"95": 1.0})}
    before, after = _same_results_file(B, res), _same_results_file(A, res)
    cert, why = same_results.certificate(before, after)
    assert why == "" and cert["before"] == B and cert["after"] == A
    assert cert["runs"]["w/routed/0"]["sim_time_s"] == res["w/routed/0"]["sim_time_s"]
    assert set(cert["runs"]["w/routed/0"]) == set(same_results.FINGERPRINT)
    differ = {"w/routed/0": dict(res["w/routed/0"], collisions=1)}
    assert same_results.certificate(before, _same_results_file(A, differ))[0] is None
    dirty = _same_results_file(A + "+modified", res)
    assert "committed code" in same_results.certificate(before, dirty)[1]
    assert same_results.certificate(before, _same_results_file(B, res))[0] is None
    overridden = {k: dict(r, set="sim.map_update_interval_s=0") for k, r in after.items()}
    assert "--set" in same_results.certificate(before, overridden)[1]
    # compare writes it; the report reads it back
    for name, runs in (("b.json", before), ("a.json", after)):
        (tmp_path / name).write_text(json.dumps({"runs": list(runs.values())}))
    path = tmp_path / "certs" / "b-a.json"
    assert same_results.main(["compare", str(tmp_path / "b.json"), str(tmp_path / "a.json"),
                              "--certificate", str(path)]) == 0
    assert report.read_certificates([path.parent])[0]["runs"] == cert["runs"]


# ------------------------------------------------------------------ statistics


def test_bootstrap_interval_of_known_inputs():
    assert report.bootstrap_ci([2.0, 2.0, 2.0]) == (2.0, 2.0)
    # two values: resampled medians are 1, 1.5, 2 with chances 1/4, 1/2, 1/4, so the
    # 2.5 % and 97.5 % quantiles are the two values themselves
    assert report.bootstrap_ci([1.0, 2.0]) == (1.0, 2.0)
    v = list(np.linspace(0.8, 1.2, 20))
    lo, hi = report.bootstrap_ci(v)
    assert (lo, hi) == report.bootstrap_ci(v)                     # seeded: reproducible
    assert lo < float(np.median(v)) < hi and 0.8 < lo and hi < 1.2
    assert report.bootstrap_ci(v, level=0.5) != (lo, hi)
    with pytest.raises(ValueError, match="none"):
        report.bootstrap_ci([])
    with pytest.raises(ValueError, match="level"):
        report.bootstrap_ci([1.0], level=1.0)


def test_paired_ratio_pairs_by_seed_and_counts_a_missed_95_with_its_end_time():
    ref = [_rec("w", "routed", k, A, t95=100.0) for k in range(4)]
    rs = [_rec("w", "nearest", k, A, t95=t) for k, t in enumerate((50.0, 100.0, 200.0))]
    rs.append(_rec("w", "nearest", 3, A, t95=None))     # never reached 95 %: ends at 620 s
    med, lo, hi, n, cens = report.paired_ratio(rs, ref)
    assert n == 4 and cens == 1
    assert med == pytest.approx(float(np.median([0.5, 1.0, 2.0, 6.2])))
    assert (lo, hi) == report.bootstrap_ci([0.5, 1.0, 2.0, 6.2])
    assert report.paired_ratio(rs, [_rec("w", "routed", 9, A)]) is None
    row = next(ln for ln in report.world_table("w", {("w", "routed"): ref, ("w", "nearest"): rs},
                                               ["routed", "nearest"], 30.0, None, {})
               if ln.startswith("| nearest"))
    assert f"| {med:.2f} [{lo:.2f}, {hi:.2f}] † |" in row


# ------------------------------------------------------------------ the line budget


def _full_matrix(codes: tuple[str, ...] = (A,)) -> list[dict]:
    rng = np.random.default_rng(1)
    recs = []
    for w in default_worlds():
        n = run_bench.runs_of(w, 20, run_bench.WORLD_RUNS)
        for i, s in enumerate(STRATEGIES):
            for k in range(n):
                t = float(rng.uniform(100, 900)) if rng.random() > 0.05 else None
                recs.append(_rec(w, s, k, codes[(i + k) % len(codes)], t95=t,
                                 collisions=int(rng.integers(0, 3))))
    return recs


@pytest.mark.parametrize("codes", [(A,), (A, B, "ccccccc33333")], ids=["one", "mixed"])
def test_full_matrix_report_fits_in_400_lines(tmp_path, codes):
    recs = _full_matrix(codes)
    assert len({r["world"] for r in recs}) == 20 and len({r["strategy"] for r in recs}) == 7
    assert sum(1 for r in recs if r["world"] == "maze") == 7 * 10
    out = _folder(tmp_path / "full", recs, default_worlds(), list(STRATEGIES))
    md = report.write_all(out, tmp_path / "B.md", command="bench/run_bench.py",
                          allow_mixed=len(codes) > 1)
    lines = md.read_text().splitlines()
    assert len(lines) <= 400, len(lines)
    assert sum(1 for ln in lines if ln.startswith("### ")) == 20
    assert sum(1 for ln in lines if ln.startswith("| nearest |")) == 20 + 1   # + summary
    assert "no runs in these results" not in md.read_text()
    assert "Part of the full matrix" not in md.read_text()


def test_a_partial_matrix_names_the_worlds_and_seeds_it_lacks(tmp_path):
    full = _full_matrix()
    part = [r for r in full if r["world"] not in ("maze", "office_floor") and r["seed"] < 15
            and not (r["world"] == "eb/loop" and r["strategy"] == "nearest" and r["seed"] == 3)]
    line = report.full_matrix_lines(part)[0]
    assert line.startswith(f"**Part of the full matrix: {len(part)} of its {len(full)} runs**")
    assert "worlds without runs: `maze`, `office_floor`" in line
    assert "seeds 15-19 in 17 worlds" in line
    assert "seeds 3, 15-19 in 1 world (`eb/loop`)" in line
    out = _folder(tmp_path / "part", part)
    assert line in report.write_all(out, tmp_path / "B.md", command="x").read_text()
    assert report.full_matrix_lines(full) == []


def test_a_matrix_folder_links_the_experiment_reports_beside_it(tmp_path):
    results = tmp_path / "results"
    (results / "experiments").mkdir(parents=True)
    (results / "experiments" / "benchmarks_old.md").write_text("old\n")
    out = _folder(results / "matrix", [_rec("w", "routed", 0, A)])
    text = report.write_all(out, tmp_path / "B.md", command="x").read_text()
    assert "are files in [results/experiments/](results/experiments/)" in text
    assert "[benchmarks_old](results/experiments/benchmarks_old.md)" in text


def test_the_command_shown_reruns_the_matrix_without_the_options_of_one_part(tmp_path):
    cmd = ("bench/run_bench.py --out /elsewhere/matrix --worlds a,b --runs 15 --md '' "
           "--resume --merge out/part --no-runs --redo=paper --prune --jobs 2")
    inside = ROOT / "bench" / "results" / "matrix"
    assert report.rerun_command(cmd, inside) == (
        "bench/run_bench.py --out bench/results/matrix --worlds a,b --runs 15 --md '' "
        "--resume --jobs 2")
    assert report.rerun_command("bench/run_bench.py --out=x --runs 2", tmp_path / "m") == \
        f"bench/run_bench.py --out {tmp_path / 'm'} --runs 2"
    out = _folder(tmp_path / "m", [_rec("w", "routed", 0, A)])
    text = report.write_all(out, tmp_path / "B.md", command=cmd).read_text()
    assert f"bench/run_bench.py --out {out} --worlds a,b" in text and "--merge" not in text


def test_benchmarks_md_in_the_repository_fits_in_400_lines():
    assert len((ROOT / "BENCHMARKS.md").read_text().splitlines()) <= 400


# ------------------------------------------------------------------ the matrix machinery


def test_matrix_tasks_cap_the_long_worlds_and_shards_partition_the_matrix():
    specs = ["house", "maze", "office_floor"]
    keys = run_bench.matrix_tasks(specs, ["routed", "nearest"], 20, 0, run_bench.WORLD_RUNS, None)
    per = {w: sum(1 for k in keys if k[0] == w) for w in specs}
    assert per == {"house": 40, "maze": 20, "office_floor": 20}
    shards = [run_bench.matrix_tasks(specs, ["routed", "nearest"], 20, 0, run_bench.WORLD_RUNS,
                                     (k, 3)) for k in (1, 2, 3)]
    assert sorted(sum(shards, [])) == sorted(keys)                  # each run in one shard
    assert max(map(len, shards)) - min(map(len, shards)) <= 1
    assert run_bench.parse_world_runs("maze=10, eb/room=3") == {"maze": 10, "eb/room": 3}
    for bad in ("maze", "maze=0", "=3"):
        with pytest.raises(ValueError, match="WORLD=N"):
            run_bench.parse_world_runs(bad)
    assert run_bench.parse_shard("2/3") == (2, 3) and run_bench.parse_shard("") is None
    for bad in ("0/3", "4/3", "x"):
        with pytest.raises(ValueError, match="K/N"):
            run_bench.parse_shard(bad)


def test_list_counts_the_full_matrix(tmp_path, capsys):
    assert run_bench.main(["--list", "--out", str(tmp_path / "x")]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert head.startswith(f"[bench] 20 worlds x {len(STRATEGIES)} strategies")
    n = len(STRATEGIES) * (18 * 20 + 2 * 10)
    assert head.endswith(f"(at most maze: 10, office_floor: 10; {n} runs in all):")
    assert not (tmp_path / "x").exists()


TINY = ["--worlds", "small_house,eb/room", "--strategies", "nearest,explore_lite",
        "--runs", "2", "--jobs", "1", "--max-sim-time", "12", "--no-tour",
        "--yolo-frames", "0", "--world-runs", "eb/room=1"]


def test_tiny_matrix_in_shards_merged_and_resumed(tmp_path, capsys):
    a, b, c = tmp_path / "a", tmp_path / "b", tmp_path / "c"
    for k, out in enumerate((a, b, c), 1):
        assert run_bench.main(TINY + ["--out", str(out), "--md", "", "--shard", f"{k}/3"]) == 0
    runs = [records.read(out) for out in (a, b, c)]
    assert [len(r) for r in runs] == [2, 2, 2]        # small_house 2 seeds, eb/room 1
    assert all(r["code"] == store.code_version() and r["cpu_time_s"] > 0 for rs in runs
               for r in rs)
    err = capsys.readouterr().err
    assert "[bench] matrix: 2 runs in 1 parts" in err and "CPU s" in err and "in the runs" in err
    # merging one slice runs nothing of the slice still missing (--no-runs)
    assert run_bench.main(TINY + ["--out", str(a), "--md", "", "--resume", "--no-runs",
                                  "--merge", str(b)]) == 0
    assert len(records.read(a)) == 4
    md = tmp_path / "B.md"
    assert run_bench.main(TINY + ["--out", str(a), "--md", str(md), "--resume", "--no-runs",
                                  "--merge", str(c)]) == 0
    meta = json.loads((a / "meta.json").read_text())
    assert [p["runs_run"] for p in meta["parts"]] == [2, 2, 0, 2, 0]   # nothing run again
    assert "[bench] matrix: 6 runs in 5 parts" in capsys.readouterr().err
    keys = {records.key_of(r) for r in records.read(a)}
    assert keys == {("small_house", s, k) for s in ("nearest", "explore_lite") for k in (0, 1)} \
        | {("eb/room", s, 0) for s in ("nearest", "explore_lite")}
    text = md.read_text()
    assert "### small_house" in text and "### eb/room" in text and "Run in 5 parts" in text
    # --resume alone runs only what is missing: here one seed more
    more = [x if x != "2" else "3" for x in TINY]
    assert run_bench.main(more + ["--out", str(a), "--md", "", "--resume"]) == 0
    assert json.loads((a / "meta.json").read_text())["parts"][-1]["runs_run"] == 2
    assert len(records.read(a)) == 8


# ------------------------------------------------------------------ mapping error table


def test_the_table_under_mapping_error_pairs_each_run_with_its_noise_free_one(tmp_path):
    base = [_rec("w", s, k, A, t95=100.0 + 10 * k) for s in ("routed", "nearest")
            for k in range(3)]
    real = [_rec("w", "routed", k, A, t95=(100.0 + 10 * k) * 1.1) for k in range(3)]
    real += [_rec("w", "nearest", 0, A, t95=None, stop_reason="done", coverage_pct=90.0),
             _rec("w", "nearest", 1, A, t95=None, stop_reason="done", coverage_pct=98.0),
             _rec("w", "nearest", 2, A, t95=120.0, collisions=2)]
    real += [_rec("w", "paper", 1, A, t95=130.0)]    # a strategy with fewer seeds
    base += [_rec("w", "paper", k, A, t95=100.0) for k in range(3)]
    out = _folder(tmp_path / "none", base)
    noisy = _folder(tmp_path / "realistic", real)
    md = report.write_all(out, tmp_path / "B.md", command="x",
                          noise_dirs=[("realistic", noisy)]).read_text()
    assert "## Under mapping error" in md
    assert "| routed | none | 1 | 3 | 0-2 | 3/3 | 0 | 0 | 110 | 1 (reference) |" in md
    assert "| routed | realistic | 1 | 3 | 0-2 | 3/3 | 0 | 0 | 121 | 1.10 [1.10, 1.10] |" in md
    # the seeds each row ran, paired with the noise-free run of the same seed
    assert "| paper | realistic | 1 | 1 | 1 | 1/1 | 0 | 0 | 130 | 1.30 [1.30, 1.30] |" in md
    row = next(ln for ln in md.splitlines() if ln.startswith("| nearest | realistic |"))
    # one "done" below 97 %, one at 98 % (not early), contacts 2, the seeds without a
    # T95 count with their end time (†)
    assert row.startswith("| nearest | realistic | 1 | 3 | 0-2 | 1/3 | 1 | 2 |") and "†" in row
    assert "`realistic` on `aaaaaaa11111`" in md


def test_a_noise_folder_of_mixed_versions_is_refused(tmp_path):
    out = _folder(tmp_path / "none", [_rec("w", "routed", k, A) for k in range(2)])
    noisy = _folder(tmp_path / "harsh", [_rec("w", "routed", k, (A, B)[k]) for k in range(2)])
    with pytest.raises(report.MixedVersions):
        report.write_all(out, tmp_path / "B.md", command="x", noise_dirs=[("harsh", noisy)])


@pytest.mark.parametrize("items, what", [
    (["realistic"], "PROFILE=DIR"), (["none={d}"], "own folder"),
    (["harsh={d}", "harsh={d}"], "twice"), (["harsh={d}/missing"], "no folder")])
def test_mapping_noise_dirs_are_checked(tmp_path, items, what):
    with pytest.raises(ValueError, match=what):
        noise_table.parse_dirs([i.format(d=tmp_path) for i in items])


def test_full_matrix_report_with_two_noise_profiles_fits_in_400_lines(tmp_path):
    recs = _full_matrix((A,))
    out = _folder(tmp_path / "full", recs, default_worlds(), list(STRATEGIES))
    dirs = [(p, _folder(tmp_path / p, recs, default_worlds(), list(STRATEGIES)))
            for p in ("realistic", "harsh")]
    md = report.write_all(out, tmp_path / "B.md", command="bench/run_bench.py", noise_dirs=dirs)
    lines = md.read_text().splitlines()
    assert len(lines) <= 400, len(lines)
    assert sum(1 for ln in lines if ln.startswith("| routed | harsh |")) == 1


def test_a_run_outside_the_matrix_folder_never_overwrites_the_committed_report(tmp_path):
    assert store.default_report_path(ROOT / "out" / "bench") == ROOT / "BENCHMARKS.md"
    assert store.default_report_path(tmp_path / "x") == tmp_path / "x" / "BENCHMARKS.md"
    assert run_bench._parse(["--out", str(tmp_path / "x")]).md == str(tmp_path / "x" /
                                                                       "BENCHMARKS.md")
    assert run_bench._parse(["--out", str(tmp_path / "x"), "--md", ""]).md == ""
