"""bench/records.py: compact run records (what the repository keeps of a benchmark), their
timing histograms, records rebuilt from runs.csv, and --resume / --merge reading them."""

from __future__ import annotations

import csv
import gzip
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import records, report, run_bench  # noqa: E402
from bench.rows import row_from_dict  # noqa: E402

ARGS = ["--worlds", "small_house", "--strategies", "nearest", "--jobs", "1",
        "--max-sim-time", "20", "--no-tour", "--yolo-frames", "0"]


def _full(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / records.FULL).read_text().splitlines()]


@pytest.fixture(scope="module")
def bench2(tmp_path_factory):
    """A benchmark folder with seeds 0 and 1 of small_house / nearest."""
    out = tmp_path_factory.mktemp("rec")
    assert run_bench.main(ARGS + ["--runs", "2", "--out", str(out), "--md", ""]) == 0
    return out


def _copy(src: Path, dst: Path, names=(records.FULL, records.COMPACT, "meta.json")) -> Path:
    dst.mkdir()
    for name in names:
        if (src / name).is_file():
            shutil.copyfile(src / name, dst / name)
    return dst


def test_histogram_percentiles_within_half_a_bin_and_exact_mean():
    rng = np.random.default_rng(3)
    v = np.exp(rng.normal(1.0, 0.8, 5000))            # ms, log-normal like update times
    h = records.histogram(v)
    assert h["n"] == 5000 and sum(h["counts"]) == 5000
    p50, mean, p95 = records.hist_stats(h)
    assert mean == pytest.approx(v.mean(), rel=1e-12)
    half = math.sqrt(records.BIN_RATIO) * 1.0005       # half a bin, and rank rounding
    for got, q in ((p50, 50), (p95, 95)):
        exact = float(np.percentile(v, q))
        assert exact / half <= got <= exact * half, (q, got, exact)
    # pooling two halves gives what the whole gives
    a, b = records.histogram(v[:1234]), records.histogram(v[1234:])
    assert records.hist_stats(records.merge_histograms([a, b])) == (p50, mean, p95)
    assert records.hist_stats(records.histogram([])) is None
    assert records.histogram([0.0, float("nan")])["counts"] == [1]


def test_compact_keeps_everything_but_the_per_update_lists(bench2):
    full = _full(bench2)
    comp = records.read_jsonl(bench2 / records.COMPACT)
    assert [records.key_of(d) for d in comp] == [records.key_of(d) for d in full]
    for f, c in zip(full, comp):
        assert "timings_ms" not in c and c["record"] == "compact"
        assert len(c["coverage_samples"]) == len(f["coverage_samples"])
        assert np.allclose(c["coverage_samples"], f["coverage_samples"], atol=0.005)
        for k in ("completed", "sim_time_s", "time_to_s", "path_to_m", "collisions"):
            assert c[k] == f[k], k
        for key, vals in f["timings_ms"].items():
            if vals:
                assert c["timing_p"][key][0] == round(float(np.percentile(vals, 50)), 3)
                assert c["timing_hist"][key]["n"] == len(vals)
        # the CSV row of the compact record is the full record's row
        assert row_from_dict(c) == row_from_dict(f)
    # a few hundred bytes to a few kB a run instead of the full record's size
    assert (bench2 / records.COMPACT).stat().st_size < (bench2 / records.FULL).stat().st_size


def test_resume_from_the_compact_file_alone(bench2, tmp_path):
    """A new checkout has runs.jsonl.gz (in git) but no runs.jsonl: nothing is run again."""
    res = _copy(bench2, tmp_path / "new", names=(records.COMPACT, "meta.json"))
    md = res / "B.md"
    assert run_bench.main(ARGS + ["--runs", "2", "--out", str(res), "--md", str(md),
                                  "--resume"]) == 0
    meta = json.loads((res / "meta.json").read_text())
    assert [p["runs_run"] for p in meta["parts"]] == [2, 0]
    assert "| nearest | 2 | " in md.read_text()
    # the report pools the compact records' histograms
    assert "| frontier detect + cluster | -" not in md.read_text()
    rows = report.read_csv(res / "runs.csv")
    assert rows == report.read_csv(bench2 / "runs.csv")


def test_full_record_is_used_only_when_it_is_the_same_run(bench2, tmp_path, capsys):
    res = _copy(bench2, tmp_path / "both")
    full = _full(res)
    got = {records.key_of(d): d for d in records.read(res)}
    assert all("timings_ms" in d for d in got.values())         # the same runs: full ones
    # a local runs.jsonl older than the committed runs.jsonl.gz (another part redid seed 0)
    full[0]["wall_time_s"] += 1.0
    full[0]["coverage_pct"] = 12.5
    (res / records.FULL).write_text("".join(json.dumps(d) + "\n" for d in full))
    got = {records.key_of(d): d for d in records.read(res)}
    assert len(got) == 2
    assert got[records.key_of(full[0])]["record"] == "compact"
    assert got[records.key_of(full[0])]["coverage_pct"] != 12.5
    assert "timings_ms" in got[records.key_of(full[1])]
    assert "differ from those of runs.jsonl.gz" in capsys.readouterr().err
    # a run only in runs.jsonl (a part that was not committed) is kept
    extra = dict(full[1], seed=5)
    (res / records.FULL).write_text(json.dumps(extra) + "\n")
    assert sorted(d["seed"] for d in records.read(res)) == [0, 1, 5]


def test_compact_records_stay_small():
    """A long run (a 5000 s maze: 1000 coverage samples, 5000 updates per timing) stays
    near 10 kB gzipped; its full record is ~50x that."""
    rng = np.random.default_rng(0)
    t = np.arange(1000) * 5.0
    full = {"world": "maze", "strategy": "paper", "seed": 0, "wall_time_s": 512.3456789,
            "coverage_samples": [[float(a), float(b), float(c)] for a, b, c in
                                 zip(t + 0.0123456, np.linspace(0, 99.0123456, 1000),
                                     np.linspace(0, 1200.98765, 1000))],
            "timings_ms": {k: list(np.exp(rng.normal(1.5, 0.6, 5000)))
                           for k in records.TIMING_KEYS}}
    line = records.compact_line(full)
    gz = len(gzip.compress(line))
    assert gz < 15_000, gz
    assert len(gzip.compress(json.dumps(full).encode())) > 10 * gz
    d = json.loads(line)
    assert all(isinstance(h["counts"], list) for h in d["timing_hist"].values())
    assert d["coverage_samples"][1] == [5.01, 0.1, 1.2]
    # an old sparse histogram is read and rewritten in today's form
    old = {"n": 3, "sum": 6.0, "bins": {"5": 2, "9": 1}}
    assert records.hist_stats(old) == records.hist_stats(records.merge_histograms([old]))
    again = records.compact({"world": "w", "strategy": "s", "seed": 0,
                             "timing_hist": {"frontier": old},
                             "coverage_samples": [[1.234567, 50.0, 0.123456]]})
    assert again["timing_hist"]["frontier"]["counts"] == [2, 0, 0, 0, 1]
    assert again["coverage_samples"] == [[1.23, 50.0, 0.12]]


def test_a_cut_gzip_member_loses_only_the_last_run(bench2, tmp_path):
    res = _copy(bench2, tmp_path / "cut", names=(records.COMPACT,))
    d = records.read_jsonl(res / records.COMPACT)[0]
    records.append_compact(res, dict(d, seed=7))
    data = (res / records.COMPACT).read_bytes()
    (res / records.COMPACT).write_bytes(data[:-12])            # killed while writing
    assert [r["seed"] for r in records.read_jsonl(res / records.COMPACT)] == [0, 1]
    records.write_compact(res, [d])
    assert gzip.decompress((res / records.COMPACT).read_bytes()).count(b"\n") == 1


def test_import_from_csv_rebuilds_the_rows_and_the_timing_table(bench2, tmp_path):
    res = _copy(bench2, tmp_path / "csv", names=("meta.json",))
    shutil.copyfile(bench2 / "runs.csv", res / "runs.csv")
    md = tmp_path / "old.md"
    report.write_all(bench2, md, command="x")
    assert records.import_csv(res, md) == 0
    assert records.import_csv(res, md) == 2                  # never over existing records
    recs = records.read(res)
    assert all(r["record"] == "csv" and r["coverage_samples"] == [] for r in recs)
    with open(bench2 / "runs.csv", newline="") as f:
        old = list(csv.DictReader(f))
    for r, o in zip(recs, old):
        row = row_from_dict(r)
        for k, v in o.items():
            got = row.get(k, "")
            assert (str(got) == v or (v == "" and (got == "" or (isinstance(got, float)
                                                                and math.isnan(got))))
                    or float(got) == pytest.approx(float(v))), (k, got, v)
    legacy = json.loads((res / records.LEGACY_TIMING).read_text())["worlds"]
    old_row = [ln for ln in md.read_text().splitlines() if ln.startswith("| small_house |")
               and " / " in ln][-1]
    p50, mean, p95 = legacy["small_house"]["frontier"]
    assert f"| small_house | {p50:.1f} / {mean:.1f} / {p95:.1f} |" in old_row
    new_md = tmp_path / "new.md"
    report.write_all(res, new_md, command="x")
    text = new_md.read_text()
    assert f"| small_house | {p50:.1f} / {mean:.1f} / {p95:.1f} † |" in text
    assert "rebuilt from `runs.csv`" in text
    assert "| nearest | 2 | " in text


def test_merge_adds_another_folders_runs_and_parts(bench2, tmp_path):
    a = tmp_path / "a"
    assert run_bench.main(ARGS + ["--runs", "1", "--out", str(a), "--md", ""]) == 0
    b = _copy(bench2, tmp_path / "b")
    with pytest.raises(SystemExit):
        run_bench.main(ARGS + ["--runs", "2", "--out", str(a), "--merge", str(b)])
    md = tmp_path / "M.md"
    assert run_bench.main(ARGS + ["--runs", "2", "--out", str(a), "--md", str(md), "--resume",
                                  "--merge", str(b)]) == 0
    meta = json.loads((a / "meta.json").read_text())
    # a's own part, b's part (merged), and this one, which ran nothing
    assert [p["runs_run"] for p in meta["parts"]] == [1, 2, 0]
    assert meta["parts"][1]["merged_from"] == str(b)
    assert sorted(r["seed"] for r in records.read(a)) == [0, 1]
    assert (a / (records.FULL + ".bak")).is_file()           # a's seed 0 was replaced: kept aside
    assert "added with `--merge`" in md.read_text()
    # a clone of b (its runs.jsonl.gz alone) merged again: its runs win, no part twice
    c = _copy(bench2, tmp_path / "c", names=(records.COMPACT, "meta.json"))
    assert run_bench.main(ARGS + ["--runs", "2", "--out", str(a), "--md", "", "--resume",
                                  "--merge", str(c)]) == 0
    meta = json.loads((a / "meta.json").read_text())
    assert [p["runs_run"] for p in meta["parts"]] == [1, 2, 0, 0]
    got = records.read(a)
    assert sorted(d["seed"] for d in got) == [0, 1]
    assert all(d["record"] == "compact" for d in got)
    # runs of a world this command does not name: refused
    assert run_bench.main([x if x != "small_house" else "small_cluttered" for x in ARGS]
                          + ["--runs", "2", "--out", str(a), "--md", "", "--resume",
                             "--merge", str(c)]) == 2
    other = tmp_path / "other"
    assert run_bench.main([x if x != "20" else "25" for x in ARGS]
                          + ["--runs", "1", "--out", str(other), "--md", ""]) == 0
    assert run_bench.main(ARGS + ["--runs", "2", "--out", str(a), "--md", "", "--resume",
                                  "--merge", str(other)]) == 2   # other settings: refused


def test_timing_table_marks_worlds_pooled_over_part_of_their_runs():
    full = {"world": "w", "strategy": "paper", "seed": 0,
            "timings_ms": {"frontier": [1.0, 2.0, 3.0]}}
    rebuilt = {"world": "w", "strategy": "paper", "seed": 1, "record": "csv",
               "timing_p": {"frontier": [9.0, 9.0]}}
    only_csv = {"world": "v", "strategy": "paper", "seed": 0, "record": "csv"}
    lines = report.timing_table([full, rebuilt, only_csv], None,
                                legacy={"strategy": "paper",
                                        "worlds": {"v": {"frontier": [4.0, 5.0, 6.0]}}})
    head = next(ln for ln in lines if ln.startswith("| world |"))
    col = [c.strip() for c in head.strip("|").split("|")].index("frontier")
    cell = {ln.split("|")[1].strip(): [c.strip() for c in ln.strip("|").split("|")][col]
            for ln in lines if ln.startswith(("| w |", "| v |"))}
    p50, mean, _ = records.hist_stats(records.histogram([1.0, 2.0, 3.0]))
    assert cell == {"w": f"{p50:.1f} / {mean:.1f} / 3.0 ‡1/2", "v": "4.0 / 5.0 / 6.0 †"}
    assert any(ln.startswith("‡k/n") for ln in lines) and any(ln.startswith("†") for ln in lines)


def test_timing_table_has_the_decision_core_column_outside_the_total():
    run = {"world": "w", "strategy": "paper", "seed": 0,
           "timings_ms": {"frontier": [1.0, 3.0], "selection": [2.0, 4.0],
                          "core": [3.0, 7.0]}}
    lines = report.timing_table([run], None)
    head = [c.strip() for c in next(ln for ln in lines if ln.startswith("| world |"))
            .strip("|").split("|")]
    row = [c.strip() for c in next(ln for ln in lines if ln.startswith("| w |"))
           .strip("|").split("|")]
    p50, mean, p95 = records.hist_stats(records.histogram([3.0, 7.0]))
    assert row[head.index("decision core")] == f"{p50:.1f} / {mean:.1f} / {p95:.1f}"
    f_mean = records.hist_stats(records.histogram([1.0, 3.0]))[1]
    s_mean = records.hist_stats(records.histogram([2.0, 4.0]))[1]
    assert row[head.index("total")] == f"{f_mean + s_mean:.1f}"   # the core is not added again
    old = {"world": "w", "strategy": "paper", "seed": 1, "timings_ms": {"frontier": [1.0]}}
    assert not any("decision core |" in ln for ln in report.timing_table([old], None))


def test_timing_is_read_back_from_either_layout_of_the_table():
    """The report's table (a row per world) and the one of the kept 2026-12-02 report (a
    row per module) give the same cells for bench/results."""
    root = Path(__file__).resolve().parents[1]
    old_md = (root / "bench" / "results" / "experiments"
              / "benchmarks_mixed_versions_2026-11-23_to_2026-12-02.md")
    runs = records.read(root / "bench" / "results")
    legacy = json.loads((root / "bench" / "results" / records.LEGACY_TIMING).read_text())
    new_md = "## Per-module timing\n\n" + "\n".join(report.timing_table(runs, None, legacy))
    s_old, s_new = [""], [""]
    old, new = records.timing_from_markdown(old_md.read_text(), s_old), \
        records.timing_from_markdown(new_md, s_new)
    assert s_old == s_new == ["paper"]
    assert len(old) >= 18 and all(new[w] == old[w] for w in old)
    assert all(old[w] == legacy["worlds"][w] for w in old)


def test_the_code_versions_of_bench_results_are_those_its_git_history_gives():
    root = Path(__file__).resolve().parents[1]
    res = root / "bench" / "results"
    try:
        code, log = records.codes_from_history(res)
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("no git history of bench/results here")
    if not log:
        pytest.skip("no git history of bench/results here (shallow clone?)")
    recs = records.read(res)
    old = [r for r in recs if r.get("record") == "csv" or "cpu_time_s" not in r]
    assert old, "bench/results holds no run from before versions were recorded"
    assert all(r["code"] == code[records.key_of(r)] for r in old)
    assert "unknown" not in {r["code"] for r in old}
