"""The occupancy grid as the floor-plan predictor's input, on a coarse lattice.

The map (0.05 m cells in the simulator) is cut into blocks of ``factor`` x ``factor``
cells (0.2 m with the default 4). Each coarse cell carries three fractions of its cells:
known free, occupied, unknown (they sum to 1; cells beyond the map's edge count as
unknown). The network sees these three channels over the map padded on every side by
``margin`` coarse cells of unknown space (so it predicts the building beyond the map's
current edge too) and up to a multiple of the network's stride.

:class:`CoarseFrame` maps the fine grid's cells to the padded coarse lattice.

Examples
--------
>>> d = np.full((8, 8), -1, dtype=np.int8); d[:4, :4] = 0; d[0, 0] = 100
>>> f = coarse_fractions(d, 4)
>>> f.shape, float(f[0, 0, 0]), float(f[1, 0, 0]), float(f[2, 1, 1])
((3, 2, 2), 0.9375, 0.0625, 1.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import OCCUPIED_THRESHOLD

#: Channels of the network's input, in order.
CHANNELS = ("free", "occupied", "unknown")


def coarse_fractions(data: npt.NDArray[np.integer], factor: int,
                     occupied_threshold: int = OCCUPIED_THRESHOLD) -> npt.NDArray[np.float32]:
    """Fractions of free, occupied and unknown cells per ``factor`` x ``factor`` block.

    Parameters
    ----------
    data : ndarray of int, shape (H, W)
        Occupancy: -1 unknown, 0..100 (>= ``occupied_threshold``: occupied).
    factor : int
        Block side in cells, >= 1; a partial last block counts its missing cells as
        unknown.
    occupied_threshold : int

    Returns
    -------
    ndarray of float32, shape (3, ceil(H / factor), ceil(W / factor))

    Raises
    ------
    ValueError
        On a non-2D ``data`` or ``factor`` < 1.
    """
    d = np.asarray(data)
    if d.ndim != 2:
        raise ValueError(f"data must be 2D (H, W), got shape {d.shape}")
    if int(factor) < 1:
        raise ValueError(f"factor must be >= 1, got {factor}")
    f = int(factor)
    h, w = d.shape
    hc, wc = -(-h // f), -(-w // f)
    pad = np.full((hc * f, wc * f), -1, dtype=np.int16)
    pad[:h, :w] = d
    blocks = pad.reshape(hc, f, wc, f)
    n = float(f * f)
    occ = (blocks >= occupied_threshold).sum(axis=(1, 3)) / n
    free = ((blocks >= 0) & (blocks < occupied_threshold)).sum(axis=(1, 3)) / n
    unk = 1.0 - occ - free
    return np.stack([free, occ, unk]).astype(np.float32)


@dataclass(frozen=True)
class CoarseFrame:
    """Where a fine grid lies in the padded coarse lattice.

    Attributes
    ----------
    factor : int
        Fine cells per coarse cell side.
    offset_rc : (int, int)
        Coarse cell of the fine cell (0, 0) (the padding above / left of the map).
    shape : (int, int)
        Padded coarse shape (a multiple of the stride).
    """

    factor: int
    offset_rc: tuple[int, int]
    shape: tuple[int, int]

    def coarse_of(self, cells_rc: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Coarse (row, col) of fine cells, shape (C, 2) (cells off the lattice clipped
        to its edge)."""
        rc = np.asarray(cells_rc, dtype=np.int64).reshape(-1, 2)
        out = np.floor_divide(rc, self.factor) + np.asarray(self.offset_rc, dtype=np.int64)
        out[:, 0] = np.clip(out[:, 0], 0, self.shape[0] - 1)
        out[:, 1] = np.clip(out[:, 1], 0, self.shape[1] - 1)
        return out


def padded_input(data: npt.NDArray[np.integer], factor: int, margin: int, stride: int,
                 occupied_threshold: int = OCCUPIED_THRESHOLD
                 ) -> tuple[npt.NDArray[np.float32], CoarseFrame]:
    """:func:`coarse_fractions` padded with unknown space: ``margin`` coarse cells on
    every side, then up to a multiple of ``stride`` (below and right).

    Returns
    -------
    features : ndarray of float32, shape (3, Hp, Wp)
    frame : CoarseFrame

    Raises
    ------
    ValueError
        On a bad ``data`` or ``factor``, ``margin`` < 0 or ``stride`` < 1.
    """
    if int(margin) < 0 or int(stride) < 1:
        raise ValueError(f"need margin >= 0 and stride >= 1, got margin={margin}, "
                         f"stride={stride}")
    frac = coarse_fractions(data, factor, occupied_threshold)
    _, hc, wc = frac.shape
    m, s = int(margin), int(stride)
    hp, wp = -(-(hc + 2 * m) // s) * s, -(-(wc + 2 * m) // s) * s
    out = np.zeros((3, hp, wp), dtype=np.float32)
    out[2] = 1.0
    out[:, m:m + hc, m:m + wc] = frac
    return out, CoarseFrame(int(factor), (m, m), (hp, wp))


__all__ = ["CHANNELS", "CoarseFrame", "coarse_fractions", "padded_input"]
