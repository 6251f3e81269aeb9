"""Planar angles: the one wrapping convention of the package and the simulator."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt


def wrap_angle(a: float) -> float:
    """``a`` wrapped to the half-open range [-pi, pi).

    Both ends of a half turn map to ``-pi`` (``wrap_angle(pi) == wrap_angle(-pi) == -pi``),
    so a target straight behind always gives the same turn sign. The value is
    ``(a + pi) % 2pi - pi`` (an angle within rounding of ``pi`` therefore gives ``-pi``);
    where that rounds up to ``pi`` (``a`` a few ulps beyond an odd multiple of ``-pi``) it
    is ``-pi`` instead.

    Parameters
    ----------
    a : float
        Angle in radians (finite).

    Returns
    -------
    float
        In [-pi, pi), equal to ``a`` modulo 2 pi up to rounding.

    Examples
    --------
    >>> wrap_angle(math.pi), wrap_angle(-math.pi)
    (-3.141592653589793, -3.141592653589793)
    >>> round(wrap_angle(1.5 * math.pi), 12)
    -1.570796326795
    """
    w = (a + math.pi) % (2.0 * math.pi) - math.pi
    return w if w < math.pi else -math.pi


def wrap_angles(a: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """:func:`wrap_angle` of every element of ``a`` (same convention: [-pi, pi)).

    >>> wrap_angles([math.pi, -math.pi, 1.5 * math.pi]).round(6).tolist()
    [-3.141593, -3.141593, -1.570796]
    """
    w = (np.asarray(a, dtype=np.float64) + math.pi) % (2.0 * math.pi) - math.pi
    return np.where(w < math.pi, w, -math.pi)
