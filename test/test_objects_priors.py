"""Size priors of the object costmap (explore_seg.core.objects.priors)."""

from __future__ import annotations

import pytest

from explore_seg.core.objects import UNKNOWN_CLASS, SizePrior, load_priors

PRIORS = load_priors()


def test_default_priors_hold_the_paper_values():
    assert PRIORS["chair"] == SizePrior(0.5, 1.5, 0.5, 2.0)
    assert PRIORS["dining table"] == SizePrior(0.75, 5.0, 0.5, 4.5)
    assert UNKNOWN_CLASS in PRIORS


@pytest.mark.parametrize("text, match", [
    ("- 1\n- 2\n", "'priors' mapping"),
    ("priors: {}\n", "empty"),
    ("priors:\n  chair: {min_xy_m: 0.5}\n", "must have keys"),
    ("priors:\n  chair: {min_xy_m: 2, max_xy_m: 1, min_z_m: 0, max_z_m: 1}\n", "min <= max"),
])
def test_load_priors_rejects_bad_files(tmp_path, text, match):
    path = tmp_path / "p.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=match):
        load_priors(path)
