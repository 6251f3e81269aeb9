"""Floor-plan prediction per map: :class:`FloorPlanPredictor` and its optional loading.

:meth:`FloorPlanPredictor.predict` turns a :class:`~explore_seg.core.grid.GridMap` into a
:class:`PredictedMap`: the probability that each coarse cell (``factor`` map cells a
side) is free space inside the building, over the map padded by ``margin_m`` of unknown
space on every side. Known coarse cells keep what the map says (a fully known free cell
is 1, a cell holding an occupied cell 0); the network's guess fills the rest.

:func:`load_predictor` returns ``(None, reason)`` instead of raising when torch or the
weight file is missing, so a caller explores on without prediction and logs the reason.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap
from explore_seg.core.prediction.features import CoarseFrame, padded_input
from explore_seg.core.prediction.model import WEIGHTS_PATH, load_unet, stride


@dataclass(frozen=True)
class PredictedMap:
    """The predicted floor plan of one map version.

    Attributes
    ----------
    p_free : ndarray of float32, shape (Hp, Wp)
        Probability that the coarse cell is free space inside the building.
    fractions : ndarray of float32, shape (3, Hp, Wp)
        The input: known free, occupied and unknown fractions per coarse cell.
    frame : CoarseFrame
        Where the map's cells lie on the coarse lattice.
    cell_m : float
        Coarse cell side (m).
    """

    p_free: npt.NDArray[np.float32] = field(repr=False)
    fractions: npt.NDArray[np.float32] = field(repr=False)
    frame: CoarseFrame
    cell_m: float


class FloorPlanPredictor:
    """A loaded U-Net (:mod:`.model`) and how the map is fed to it.

    Parameters
    ----------
    net : torch.nn.Module
        In eval mode (:func:`~explore_seg.core.prediction.model.load_unet`).
    widths : tuple of int
        Its level widths (the input stride).
    factor : int
        Map cells per coarse cell side it was trained with.
    margin_m : float
        Unknown space added around the map (m), >= 0.
    occupied_threshold : int
    """

    def __init__(self, net: Any, widths: tuple[int, ...], factor: int, margin_m: float = 5.0,
                 occupied_threshold: int = OCCUPIED_THRESHOLD) -> None:
        if not (math.isfinite(margin_m) and margin_m >= 0):
            raise ValueError(f"margin_m must be finite and >= 0, got {margin_m}")
        self._net, self._stride, self.factor = net, stride(widths), int(factor)
        self._margin_m, self._thr = float(margin_m), int(occupied_threshold)
        #: CPU seconds of the last :meth:`predict` (``time.process_time``).
        self.last_cpu_s = 0.0

    def predict(self, grid: GridMap) -> PredictedMap:
        """The predicted floor plan of ``grid`` (module docstring)."""
        import torch

        t0 = time.process_time()
        cell_m = grid.resolution_m * self.factor
        margin = int(math.ceil(self._margin_m / cell_m))
        x, frame = padded_input(grid.data, self.factor, margin, self._stride, self._thr)
        with torch.inference_mode():
            logit = self._net(torch.from_numpy(x)[None])[0].numpy()
        p = 1.0 / (1.0 + np.exp(-logit.astype(np.float32)))
        free, occ, unk = x
        # Known parts as mapped; the guess weighs in by the unknown share.
        p = np.where(occ > 0, 0.0, free + unk * p).astype(np.float32)
        self.last_cpu_s = time.process_time() - t0
        return PredictedMap(p, x, frame, cell_m)


def load_predictor(path: str | Path | None = None, margin_m: float = 5.0,
                   occupied_threshold: int = OCCUPIED_THRESHOLD, threads: int = 0
                   ) -> tuple[FloorPlanPredictor | None, str]:
    """``(predictor, "")``, or ``(None, why)`` when torch or the weights are missing or
    unusable (module docstring).

    Parameters
    ----------
    path : str or Path, optional
        Weight file; default :data:`~explore_seg.core.prediction.model.WEIGHTS_PATH`.
    margin_m, occupied_threshold : see :class:`FloorPlanPredictor`
    threads : int
        > 0: ``torch.set_num_threads(threads)`` (process-wide); 0 leaves it.
    """
    p = Path(path) if path is not None else WEIGHTS_PATH
    try:
        net, widths, factor, _meta = load_unet(p)
    except ImportError as err:
        return None, f"torch is not installed ({err})"
    except ValueError as err:
        return None, str(err)
    if threads > 0:
        import torch

        torch.set_num_threads(int(threads))
    return FloorPlanPredictor(net, widths, factor, margin_m, occupied_threshold), ""


__all__ = ["FloorPlanPredictor", "PredictedMap", "load_predictor"]
