"""The segmenter's labels, ids included, are those stored in segmentation_golden.json.

The digests were made by the code before the speed work of issue 23 (incremental DuDe
update p95 <= 25 ms), which had to keep the output as it was: batch labels and every
incremental update of exploration sequences on generated furnished and plain maps.
Regenerate only for an intended change of the output (``test/seg_golden.py --write``).
"""

from __future__ import annotations

import json

import pytest

from seg_golden import CASES, GOLDEN, QUICK, run_case


@pytest.mark.parametrize("name", QUICK)
def test_labels_match_golden(name: str) -> None:
    golden = json.loads(GOLDEN.read_text())[name]
    src, radius, step = next((s, r, st) for n, s, r, st in CASES if n == name)
    got = run_case(src, radius, step)
    assert got["batch"] == golden["batch"]
    assert len(got["steps"]) == len(golden["steps"])
    diff = [i for i, (a, b) in enumerate(zip(got["steps"], golden["steps"])) if a != b]
    assert not diff, f"labels differ from update {diff[0]} on ({len(diff)} updates)"
    assert got["next_id"] == golden["next_id"]
