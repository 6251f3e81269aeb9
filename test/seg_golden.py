"""Label digests of the DuDe segmenter on seeded maps (support of test_segmentation_golden).

Speed work on :mod:`explore_seg.core.segmentation` must not change its output: the same
labels, ids included, for the same inputs. This module runs a fixed set of cases (batch
segmentations and incremental exploration sequences on generated furnished and plain
maps) and reduces every label image to a SHA-1 digest. The digests of the code before a
speed change are stored in ``segmentation_golden.json`` next to this file; regenerate
them only for an intended change of the output::

    .venv/bin/python test/seg_golden.py --write
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for _p in (ROOT, ROOT / "bench"):
    if str(_p) not in sys.path:
        sys.path.insert(0, str(_p))

from bench_segmentation import exploration_maps  # noqa: E402

from explore_seg.core.grid import GridMap  # noqa: E402
from explore_seg.core.segmentation import (IncrementalSegmenter,  # noqa: E402
                                           SegmentationParams, segment)

GOLDEN = Path(__file__).resolve().parent / "segmentation_golden.json"

#: (name, map source, reveal disc radius m, raster step m); sources: "furnished:KIND:SEED",
#: "plain:KIND:SEED" (the unfurnished floor plan), "house:SEED[:cluttered]" (a generated
#: 20 m house as the lidar sees it).
CASES = [
    ("office_s3", "furnished:office:3", 5.0, 2.5),
    ("open_office_s1", "furnished:open_office:1", 5.0, 2.5),
    ("home_s2", "furnished:home:2", 3.5, 2.0),
    ("plain_office_s4", "plain:office:4", 5.0, 2.5),
    ("house_s0_cluttered", "house:0:cluttered", 5.0, 2.5),
]
#: The cases of the test (a subset, seconds); ``--all`` runs every case.
QUICK = ("office_s3", "home_s2", "house_s0_cluttered")


def load_map(source: str) -> tuple[GridMap, tuple[int, int]]:
    """The grid and start cell of a case's map source."""
    kind, *rest = source.split(":")
    if kind in ("furnished", "plain"):
        from sim_bridge.worlds.furnished import furnished_map
        fm = furnished_map(int(rest[1]), rest[0])
        return (fm.furnished if kind == "furnished" else fm.plain), fm.start_cell
    from sim_bridge.worlds import generate_house, ground_truth
    gt = ground_truth(generate_house(int(rest[0]), cluttered="cluttered" in rest))
    return gt.as_map("lidar"), gt.start_cell


def digest(labels: np.ndarray) -> str:
    """SHA-1 of a label image (shape and int32 values)."""
    a = np.ascontiguousarray(labels, dtype=np.int32)
    return hashlib.sha1(repr(a.shape).encode() + a.tobytes()).hexdigest()[:16]


def run_case(source: str, radius_m: float, step_m: float) -> dict[str, object]:
    """Digests of the batch labels and of every incremental update of one case."""
    grid, start = load_map(source)
    params = SegmentationParams()
    seg = IncrementalSegmenter(params)
    steps = [digest(seg.update(g)) for g, _off in exploration_maps(grid, start, radius_m,
                                                                    step_m)]
    return {"batch": digest(segment(grid, params)), "steps": steps,
            "next_id": seg.next_id}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="store the digests")
    ap.add_argument("--out", type=Path, default=GOLDEN)
    args = ap.parse_args(argv)
    res = {name: run_case(src, r, s) for name, src, r, s in CASES}
    if args.write:
        args.out.write_text(json.dumps(res, indent=1) + "\n")
        print(f"wrote {args.out}")
        return 0
    old = json.loads(GOLDEN.read_text())
    bad = 0
    for name, r in res.items():
        o = old.get(name)
        same = o == r
        bad += not same
        diff = "" if same or o is None else " first differing step " + str(next(
            (i for i, (a, b) in enumerate(zip(o["steps"], r["steps"])) if a != b), None))
        print(f"{name}: {'same' if same else 'DIFFERENT'}{diff}")
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
