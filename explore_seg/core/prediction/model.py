"""The floor-plan U-Net and its weight file.

The network maps the three input channels of :mod:`.features` (free, occupied, unknown
fractions per coarse cell) to one logit per coarse cell: free space inside the building
(1) against walls, furniture and the outside (0). It is a U-Net with ``len(widths)``
levels (a max-pool between levels, so inputs are padded to a multiple of
:func:`stride`): two 3x3 convolutions with ReLU per level, two dilated (2, 4) 3x3
convolutions at the bottom for a receptive field of several rooms, bilinear upsampling
and skip concatenation on the way up, and a 1x1 output convolution. No normalisation
layers: inference is the same function as training.

The weight file is an ``.npz`` of float32 arrays named as the module's ``state_dict``
plus ``meta.widths`` (int64) and ``meta.factor`` (the coarse cell side in fine cells), so
reading it needs numpy only and runs no pickled code. ``torch`` is imported inside the
functions that build a network (:func:`build_unet`, :func:`load_unet`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

#: Channel widths of the default network, one per level.
DEFAULT_WIDTHS = (8, 16, 32, 64)
#: The package's weights (written by ``make train-predictor``; absent until then).
WEIGHTS_PATH = Path(__file__).resolve().parent / "weights" / "floorplan_unet.npz"
_META = "meta."


def stride(widths: tuple[int, ...]) -> int:
    """Input sides must be multiples of this (one 2x pool per level below the first)."""
    return 2 ** len(widths)


def build_unet(widths: tuple[int, ...] = DEFAULT_WIDTHS, in_channels: int = 3) -> Any:
    """A fresh (randomly initialised, torch's default seed state) U-Net.

    Raises
    ------
    ImportError
        When torch is not installed.
    ValueError
        On fewer than 2 levels or a width < 1.
    """
    if len(widths) < 2 or any(int(w) < 1 for w in widths):
        raise ValueError(f"widths must hold >= 2 positive channel counts, got {widths}")
    import torch
    from torch import nn

    def block(cin: int, cout: int, dil: tuple[int, int] = (1, 1)) -> nn.Sequential:
        return nn.Sequential(
            nn.Conv2d(cin, cout, 3, padding=dil[0], dilation=dil[0]), nn.ReLU(inplace=True),
            nn.Conv2d(cout, cout, 3, padding=dil[1], dilation=dil[1]), nn.ReLU(inplace=True))

    class UNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            ws = [int(w) for w in widths]
            self.down = nn.ModuleList(
                [block(in_channels if i == 0 else ws[i - 1], w) for i, w in enumerate(ws)])
            self.bottom = block(ws[-1], ws[-1], (2, 4))
            self.up = nn.ModuleList(
                [block(ws[i] + (ws[i + 1] if i + 1 < len(ws) else ws[-1]), ws[i])
                 for i in range(len(ws))])
            self.head = nn.Conv2d(ws[0], 1, 1)

        def forward(self, x: torch.Tensor) -> torch.Tensor:
            skips = []
            for layer in self.down:
                x = layer(x)
                skips.append(x)
                x = nn.functional.max_pool2d(x, 2)
            x = self.bottom(x)
            for i in range(len(self.up) - 1, -1, -1):
                x = nn.functional.interpolate(x, scale_factor=2.0, mode="bilinear",
                                              align_corners=False)
                x = self.up[i](torch.cat([skips[i], x], dim=1))
            return self.head(x)[:, 0]

    return UNet()


def save_unet(net: Any, path: str | Path, widths: tuple[int, ...], factor: int,
              extra: dict[str, Any] | None = None) -> None:
    """Write ``net``'s weights and its shape to ``path`` (``.npz``; module docstring);
    ``extra``: more ``meta.*`` entries (training seed, command, quality figures)."""
    arrays = {k: v.detach().cpu().numpy().astype(np.float32)
              for k, v in net.state_dict().items()}
    arrays[_META + "widths"] = np.asarray(widths, dtype=np.int64)
    arrays[_META + "factor"] = np.asarray(int(factor), dtype=np.int64)
    for k, v in (extra or {}).items():
        arrays[_META + k] = np.asarray(v)
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **arrays)


def read_weights(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """(weights, meta) of a weight file.

    Raises
    ------
    ValueError
        When the file is missing, unreadable or lacks ``meta.widths`` / ``meta.factor``
        (the message names the file).
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"predictor weights {p} not found (make train-predictor writes them)")
    try:
        with np.load(p, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (OSError, ValueError) as err:
        raise ValueError(f"predictor weights {p} unreadable: {err}") from None
    meta = {k[len(_META):]: v for k, v in data.items() if k.startswith(_META)}
    weights = {k: v for k, v in data.items() if not k.startswith(_META)}
    for key in ("widths", "factor"):
        if key not in meta:
            raise ValueError(f"predictor weights {p} lack meta.{key}")
    return weights, meta


def load_unet(path: str | Path) -> tuple[Any, tuple[int, ...], int, dict[str, np.ndarray]]:
    """(network in eval mode, widths, factor, meta) from a weight file.

    Raises
    ------
    ImportError
        When torch is not installed.
    ValueError
        On a missing or unreadable file, or weights that do not fit the network its
        ``meta.widths`` describe.
    """
    weights, meta = read_weights(path)
    widths = tuple(int(w) for w in np.atleast_1d(meta["widths"]))
    import torch

    net = build_unet(widths)
    try:
        net.load_state_dict({k: torch.from_numpy(v) for k, v in weights.items()})
    except RuntimeError as err:
        raise ValueError(f"predictor weights {path} do not fit widths {widths}: {err}") \
            from None
    net.eval()
    return net, widths, int(meta["factor"]), meta


__all__ = ["DEFAULT_WIDTHS", "WEIGHTS_PATH", "build_unet", "load_unet", "read_weights",
           "save_unet", "stride"]
