"""Checks of the ``range`` metadata of parameter dataclasses, shared by their tests."""

from __future__ import annotations

import dataclasses
import math

import pytest


def ranged_fields(cls: type) -> dict[str, tuple[float, float]]:
    """``{field name: (lo, hi)}`` of the fields of ``cls`` that declare a range."""
    return {f.name: tuple(f.metadata["range"][:2]) for f in dataclasses.fields(cls)
            if "range" in f.metadata}


def assert_range_enforced(cls: type, name: str, match: str | None = "") -> None:
    """The default of ``name`` is in its range and ``__post_init__`` rejects values just
    outside either end (the upper end when it is finite and below the int32 maximum); the
    error names the field unless ``match`` says otherwise (None: any message)."""
    lo, hi = ranged_fields(cls)[name]
    assert lo <= getattr(cls(), name) <= hi
    step = 1 if isinstance(lo, int) else 0.5
    pattern = name if match == "" else match
    with pytest.raises(ValueError, match=pattern):
        cls(**{name: lo - step})
    if math.isfinite(hi) and hi < 2**31 - 1:
        with pytest.raises(ValueError, match=pattern):
            cls(**{name: hi + step})
