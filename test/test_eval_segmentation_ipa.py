"""``bench/eval_segmentation.py --set ipa_dev``: the real furnished development maps, read from
``../shared/data/ipa_dev`` (never from the repository)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import eval_segmentation  # noqa: E402


def _ipa_dev() -> Path:
    """``<shared>/data/ipa_dev`` (academic, non-commercial licence: never in the repository),
    or skip the test naming where it was looked for."""
    folder = eval_segmentation.ipa_dev_dir()
    if not folder.is_dir():
        pytest.skip(f"the IPA development maps are not present at {folder} "
                    "($EXPLORE_SEG_SHARED/data/ipa_dev or ../shared/data/ipa_dev)")
    return folder


def test_ipa_dev_cases_are_binarised_and_flipped_like_the_ipa_evaluation():
    folder = _ipa_dev()
    import cv2

    name, grid, rooms = next(eval_segmentation.ipa_dev_cases(folder, furnished=True))
    assert name == "office_a_furnitures"
    img = cv2.imread(str(folder / "maps" / "office_a_furnitures.pgm"), cv2.IMREAD_UNCHANGED)
    assert grid.data.shape == img.shape == rooms.shape
    # row 0 of the image is the top (largest y): the grid's last row
    np.testing.assert_array_equal(grid.data[-1] == 0, img[0] == 254)
    assert set(np.unique(grid.data)) <= {0, 100}
    assert grid.resolution_m == 0.05


def test_ipa_dev_prints_plain_and_furnished_scores(capsys):
    folder = _ipa_dev()
    assert eval_segmentation.main(["--set", "ipa_dev", "--ipa-dir", str(folder)]) == 0
    out = capsys.readouterr().out
    for name in eval_segmentation.IPA_DEV_MAPS:
        assert re.search(rf"^  {name} ", out, re.M), name
        assert re.search(rf"^  {name}_furnitures ", out, re.M), name
    scores = {}
    for key in ("plain", "furnished"):
        m = re.search(rf"^{key}\s*: recall\s+([\d.]+) .* precision\s+([\d.]+) .* segments per "
                      rf"room\s+([\d.]+)", out, re.M)
        assert m, out
        scores[key] = tuple(float(v) for v in m.groups())
    for recall, precision, per_room in scores.values():
        assert 50 < recall <= 100 and 50 < precision <= 100 and per_room > 0.5


def test_ipa_dev_names_a_missing_file(tmp_path, capsys):
    (tmp_path / "maps").mkdir()
    assert eval_segmentation.main(["--set", "ipa_dev", "--ipa-dir", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "office_a.pgm is missing" in err


def test_seg_overrides_set_segmentation_fields_and_name_a_bad_one():
    out = eval_segmentation.parse_overrides(["passage_merge_ratio=0.7", "corridor_merge=true",
                                             "max_rounds=3"])
    assert out == {"passage_merge_ratio": 0.7, "corridor_merge": True, "max_rounds": 3}
    with pytest.raises(ValueError, match="'tau=1'"):
        eval_segmentation.parse_overrides(["tau=1"])
    with pytest.raises(SystemExit):
        eval_segmentation.main(["--seg", "passage_merge_ratio=-1"])
