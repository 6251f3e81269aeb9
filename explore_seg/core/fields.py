"""Metadata helper for the parameter dataclasses (read by ``explore_seg.params``).

Every parameter field of the package is declared one way::

    robot_radius_m: float = field(default=0.22, metadata=param_meta(
        "obstacles are inflated by this radius", "m", range=(0.0, math.inf)))

``doc`` and ``unit`` become the ROS parameter's description; ``range`` becomes its
``FloatingPointRange`` / ``IntegerRange`` (so ``ros2 param set`` rejects a value outside
it before the dataclass's own validation runs); ``read_only`` and ``ros=False`` are flags.
"""

from __future__ import annotations

import math
from dataclasses import field
from typing import Any

#: Upper end of an integer range that has none (ROS integer parameters are int64).
INT_MAX = 2 ** 31 - 1


def param_meta(doc: str, unit: str | None = None, *,
               range: tuple[float, float] | tuple[float, float, float] | None = None,
               **extra: Any) -> dict[str, Any]:
    """``field(metadata=...)`` of a parameter: its description, unit, range and flags.

    Parameters
    ----------
    doc : str
        What the parameter does.
    unit : str, optional
        Unit (``m``, ``s``, ``Hz``, ``cells``, ...).
    range : (low, high) or (low, high, step), optional
        Closed interval the value must lie in (``math.inf`` / :data:`INT_MAX` for an open
        end); ``step`` > 0 restricts the value to ``low + k * step`` (or ``high``).
    **extra
        Flags: ``read_only=True``, ``ros=False`` (not a ROS parameter).

    Raises
    ------
    ValueError
        When ``range`` is not (low <= high[, step >= 0]) of numbers.

    Examples
    --------
    >>> param_meta("robot radius", "m", read_only=True)
    {'doc': 'robot radius', 'unit': 'm', 'read_only': True}
    >>> param_meta("rate", "Hz", range=(0.0, 100.0))["range"]
    (0.0, 100.0)
    """
    meta: dict[str, Any] = {"doc": doc}
    if unit:
        meta["unit"] = unit
    if range is not None:
        if len(range) not in (2, 3) or any(math.isnan(float(v)) for v in range) \
                or not float(range[0]) <= float(range[1]) \
                or (len(range) == 3 and not float(range[2]) >= 0):
            raise ValueError(f"range must be (low, high[, step]) with low <= high and "
                             f"step >= 0, got {range!r}")
        meta["range"] = tuple(range)
    meta.update({k: v for k, v in extra.items() if v is not False or k != "read_only"})
    return meta


def non_negative(doc: str, unit: str | None = None, default: float = 0.0) -> Any:
    """A float parameter field whose range is [0, inf) (see :func:`param_meta`)."""
    return field(default=default, metadata=param_meta(doc, unit, range=(0.0, math.inf)))


def check_non_negative(params: Any, names: tuple[str, ...]) -> None:
    """Raise ``ValueError`` naming the first of ``names`` that is not finite and >= 0."""
    for name in names:
        value = getattr(params, name)
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be finite and >= 0, got {value}")
