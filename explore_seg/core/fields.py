"""Metadata helper for the parameter dataclasses (read by ``explore_seg.params``)."""

from __future__ import annotations

from typing import Any


def param_meta(doc: str, unit: str | None = None, **extra: Any) -> dict[str, Any]:
    """``field(metadata=...)`` of a parameter: its description, unit and flags.

    Examples
    --------
    >>> param_meta("robot radius", "m", read_only=True)
    {'doc': 'robot radius', 'unit': 'm', 'read_only': True}
    """
    meta: dict[str, Any] = {"doc": doc}
    if unit:
        meta["unit"] = unit
    meta.update({k: v for k, v in extra.items() if v is not False or k != "read_only"})
    return meta
