"""A tiny sweep through a local Ray gives the process pool's runs.csv rows.

Runs only where Ray is installed (the optional ``ray`` extra, requirements-ray.txt).
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

pytest.importorskip("ray")

from bench import run_bench  # noqa: E402

ARGS = ["--worlds", "small_house", "--strategies", "nearest,paper_noseg", "--runs", "2",
        "--jobs", "2", "--max-sim-time", "15", "--no-tour", "--yolo-frames", "0", "--md", ""]


def _rows(out: Path) -> list[dict[str, str]]:
    """runs.csv without the columns that time the machine (wall and CPU time, per-update
    ms)."""
    with open(out / "runs.csv", newline="") as fh:
        rows = [{k: v for k, v in r.items()
                 if k not in ("wall_time_s", "cpu_time_s") and "_ms_" not in k}
                for r in csv.DictReader(fh)]
    return sorted(rows, key=lambda r: (r["world"], r["strategy"], int(r["seed"])))


def test_local_ray_sweep_gives_the_process_pools_rows(tmp_path):
    pool, ray_out = tmp_path / "pool", tmp_path / "ray"
    assert run_bench.main(ARGS + ["--out", str(pool)]) == 0
    assert run_bench.main(ARGS + ["--out", str(ray_out), "--executor", "ray"]) == 0
    a, b = _rows(pool), _rows(ray_out)
    assert len(a) == 4
    assert a == b
    parts = json.loads((ray_out / "meta.json").read_text()).get("parts")
    assert parts[-1]["executor"] == "ray"
