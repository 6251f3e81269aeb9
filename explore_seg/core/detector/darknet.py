"""Darknet (``.cfg`` + ``.weights``) networks as torch modules: YOLOv3-tiny and kin.

Supported sections: ``[net]``, ``[convolutional]`` (optional ``batch_normalize``, ``leaky``/
``linear``/``relu``/``logistic`` activations, ``groups``), ``[maxpool]`` (including the
size-2 stride-1 layer of YOLOv3-tiny, padded like Darknet on the right/bottom only),
``[route]`` (with ``groups``/``group_id`` as in YOLOv4-tiny), ``[shortcut]`` (linear),
``[upsample]`` and ``[yolo]`` (``mask``, ``anchors``, ``classes``, ``scale_x_y``).

Batch normalisation is folded into the convolutions when the weights are loaded
(Darknet's ``(x - mean) / (sqrt(var) + 1e-6)``), so the module holds only convolutions.

The module takes ``(B, 3, H, W)`` float32 RGB in ``[0, 1]`` (``H`` and ``W`` multiples of
the network stride, 32 for YOLOv3-tiny) and returns one tensor per ``[yolo]`` layer,
shaped ``(B, H_i * W_i * A_i, 5 + classes)``; rows are ordered (grid row, grid column,
anchor) and columns are ``cx, cy, w, h`` in input pixels, the objectness and the class
scores already multiplied by the objectness. This is OpenCV's ``readNetFromDarknet``
layout, up to OpenCV's normalisation of the box by the input size.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt
import torch
from torch import nn
from torch.nn import functional as F

#: Darknet's leaky ReLU slope.
LEAKY_SLOPE = 0.1
#: Darknet adds this to sqrt(variance) when normalising.
BN_EPS = 1e-6
#: Header versions at or above this (major * 10 + minor) store ``seen`` as int64.
SEEN_INT64_MIN_VERSION = 2
#: Version fields above this mark a foreign/transposed format we do not read.
MAX_HEADER_VERSION = 1000

_SUPPORTED = ("net", "convolutional", "maxpool", "route", "shortcut", "upsample", "yolo")
_ACTIVATIONS = ("leaky", "linear", "relu", "logistic")


@dataclass(frozen=True)
class CfgSection:
    """One ``[kind]`` block of a Darknet cfg file.

    Parameters
    ----------
    kind : str
        Section name without brackets, lower case (``"convolutional"``).
    options : dict of str to str
        ``key=value`` pairs, keys lower case, values stripped.
    line : int
        1-based line of the ``[kind]`` header (for error messages).
    """

    kind: str
    options: dict[str, str] = field(default_factory=dict)
    line: int = 0

    def get_int(self, key: str, default: int | None = None) -> int:
        """Option ``key`` as an int (``default`` when absent, ValueError when required)."""
        return int(self._get(key, default))

    def get_float(self, key: str, default: float | None = None) -> float:
        """Option ``key`` as a float (``default`` when absent, ValueError when required)."""
        return float(self._get(key, default))

    def get_ints(self, key: str) -> list[int]:
        """Option ``key`` as a comma-separated list of ints (ValueError when absent)."""
        return [int(v) for v in str(self._get(key, None)).split(",") if v.strip()]

    def _get(self, key: str, default: object) -> object:
        if key in self.options:
            return self.options[key]
        if default is None:
            raise ValueError(f"[{self.kind}] at line {self.line} needs '{key}', "
                             f"got only {sorted(self.options)}")
        return default


def parse_cfg(text: str) -> list[CfgSection]:
    """Parse Darknet cfg text into sections.

    Parameters
    ----------
    text : str
        Content of a ``.cfg`` file. ``#`` and ``;`` start comments.

    Returns
    -------
    list of CfgSection
        In file order; the first one is ``[net]``.

    Raises
    ------
    ValueError
        If the text has no sections, an option appears before the first section, a line
        is neither a header nor ``key=value``, or the first section is not ``[net]``.

    Examples
    --------
    >>> [s.kind for s in parse_cfg("[net]\\nwidth=416\\n[maxpool]\\nsize=2")]
    ['net', 'maxpool']
    """
    sections: list[CfgSection] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].split(";", 1)[0].strip()
        if not line:
            continue
        if line.startswith("["):
            if not line.endswith("]"):
                raise ValueError(f"line {number}: expected '[section]', got {raw!r}")
            sections.append(CfgSection(line[1:-1].strip().lower(), {}, number))
            continue
        if "=" not in line:
            raise ValueError(f"line {number}: expected 'key=value', got {raw!r}")
        if not sections:
            raise ValueError(f"line {number}: option {raw!r} before the first [section]")
        key, value = line.split("=", 1)
        sections[-1].options[key.strip().lower()] = value.strip()
    if not sections:
        raise ValueError("cfg has no [section]")
    if sections[0].kind not in ("net", "network"):
        raise ValueError(f"cfg must start with [net], got [{sections[0].kind}]")
    return sections


class Conv(nn.Module):
    """Convolution (BN folded in at load time) followed by a Darknet activation."""

    def __init__(self, sec: CfgSection, in_channels: int) -> None:
        super().__init__()
        self.filters = sec.get_int("filters")
        self.size = sec.get_int("size", 1)
        stride = sec.get_int("stride", 1)
        self.groups = sec.get_int("groups", 1)
        pad = sec.get_int("padding", 0)
        if sec.get_int("pad", 0):
            pad = self.size // 2
        self.batch_normalize = bool(sec.get_int("batch_normalize", 0))
        self.activation = sec.options.get("activation", "logistic")
        if self.activation not in _ACTIVATIONS:
            raise ValueError(f"[convolutional] at line {sec.line}: activation must be one of "
                             f"{_ACTIVATIONS}, got {self.activation!r}")
        if in_channels % self.groups or self.filters % self.groups:
            raise ValueError(f"[convolutional] at line {sec.line}: groups={self.groups} must "
                             f"divide input {in_channels} and filters {self.filters}")
        self.in_channels = in_channels
        self.conv = nn.Conv2d(in_channels, self.filters, self.size, stride, pad,
                              groups=self.groups, bias=True)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = self.conv(x)
        if self.activation == "leaky":
            return F.leaky_relu(x, LEAKY_SLOPE)
        if self.activation == "relu":
            return F.relu(x)
        if self.activation == "logistic":
            return torch.sigmoid(x)
        return x


class MaxPool(nn.Module):
    """Darknet max pooling: padding ``size - 1`` split left/top ``p // 2``, rest right/bottom.

    Darknet ignores out-of-image samples, which for a max is the same as replicating the
    edge; the size-2 stride-1 layer of YOLOv3-tiny thus keeps the spatial size.
    """

    def __init__(self, sec: CfgSection) -> None:
        super().__init__()
        self.size = sec.get_int("size", 1)
        self.stride = sec.get_int("stride", 1)
        padding = sec.get_int("padding", self.size - 1)
        self.pads = (padding // 2, padding - padding // 2, padding // 2, padding - padding // 2)
        self.needs_pad = any(self.pads) and self.size != self.stride

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.needs_pad:
            x = F.pad(x, self.pads, mode="replicate")
            return F.max_pool2d(x, self.size, self.stride)
        return F.max_pool2d(x, self.size, self.stride, ceil_mode=True)


class Upsample(nn.Module):
    def __init__(self, sec: CfgSection) -> None:
        super().__init__()
        self.stride = sec.get_int("stride", 2)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.interpolate(x, scale_factor=float(self.stride), mode="nearest")


class Yolo(nn.Module):
    """Decodes one YOLO head: sigmoid xy + grid offset, exp wh * anchor, scores."""

    def __init__(self, sec: CfgSection, in_channels: int) -> None:
        super().__init__()
        anchors = sec.get_ints("anchors")
        if len(anchors) % 2:
            raise ValueError(f"[yolo] at line {sec.line}: anchors need w,h pairs, "
                             f"got {len(anchors)} numbers")
        pairs = [(anchors[i], anchors[i + 1]) for i in range(0, len(anchors), 2)]
        mask = sec.get_ints("mask") if "mask" in sec.options else list(range(len(pairs)))
        if any(not 0 <= m < len(pairs) for m in mask):
            raise ValueError(f"[yolo] at line {sec.line}: mask {mask} indexes outside the "
                             f"{len(pairs)} anchors")
        self.classes = sec.get_int("classes", 20)
        self.num_anchors = len(mask)
        self.scale_x_y = sec.get_float("scale_x_y", 1.0)
        expected = self.num_anchors * (5 + self.classes)
        if in_channels != expected:
            raise ValueError(f"[yolo] at line {sec.line}: input has {in_channels} channels, "
                             f"expected {self.num_anchors}*(5+{self.classes})={expected}")
        self.register_buffer(
            "anchors", torch.tensor([pairs[m] for m in mask], dtype=torch.float32))

    def forward(self, x: torch.Tensor, input_hw: tuple[int, int]) -> torch.Tensor:
        b, _, h, w = x.shape
        n = 5 + self.classes
        p = x.view(b, self.num_anchors, n, h, w).permute(0, 3, 4, 1, 2)  # B,H,W,A,N
        gy, gx = torch.meshgrid(torch.arange(h, dtype=x.dtype, device=x.device),
                                torch.arange(w, dtype=x.dtype, device=x.device),
                                indexing="ij")
        grid = torch.stack((gx, gy), dim=-1).view(1, h, w, 1, 2)
        stride = torch.tensor([input_hw[1] / w, input_hw[0] / h], dtype=x.dtype,
                              device=x.device)
        xy = torch.sigmoid(p[..., 0:2])
        if self.scale_x_y != 1.0:
            xy = xy * self.scale_x_y - 0.5 * (self.scale_x_y - 1.0)
        xy = (xy + grid) * stride
        wh = torch.exp(p[..., 2:4]) * self.anchors.view(1, 1, 1, self.num_anchors, 2)
        obj = torch.sigmoid(p[..., 4:5])
        cls = torch.sigmoid(p[..., 5:]) * obj
        out = torch.cat((xy, wh, obj, cls), dim=-1)
        return out.reshape(b, h * w * self.num_anchors, n)


class DarknetNet(nn.Module):
    """A Darknet network built from parsed cfg sections (weights not loaded).

    Parameters
    ----------
    sections : list of CfgSection
        From :func:`parse_cfg`; ``sections[0]`` is ``[net]``.

    Raises
    ------
    ValueError
        On unsupported sections or activations, bad route/shortcut indices, or a yolo
        layer whose input channel count does not match its anchors and classes.
    """

    def __init__(self, sections: list[CfgSection]) -> None:
        super().__init__()
        net = sections[0]
        self.input_channels = net.get_int("channels", 3)
        self.cfg_width = net.get_int("width", 416)
        self.cfg_height = net.get_int("height", 416)
        self.layers = nn.ModuleList()
        self.kinds: list[str] = []
        self.sources: list[list[int]] = []
        self.route_groups: list[tuple[int, int]] = []
        channels: list[int] = []
        downsample = 1
        scales: list[int] = []
        prev = self.input_channels
        for sec in sections[1:]:
            index = len(self.layers)
            src: list[int] = []
            groups = (1, 0)
            if sec.kind not in _SUPPORTED or sec.kind == "net":
                raise ValueError(f"line {sec.line}: unsupported section [{sec.kind}], "
                                 f"expected one of {_SUPPORTED[1:]}")
            if sec.kind == "convolutional":
                module: nn.Module = Conv(sec, prev)
                out = module.filters
                downsample *= sec.get_int("stride", 1)
            elif sec.kind == "maxpool":
                module = MaxPool(sec)
                out = prev
                downsample *= module.stride
            elif sec.kind == "upsample":
                module = Upsample(sec)
                out = prev
                downsample //= module.stride
            elif sec.kind == "route":
                src = [self._absolute(i, index, sec) for i in sec.get_ints("layers")]
                groups = (sec.get_int("groups", 1), sec.get_int("group_id", 0))
                if not 0 <= groups[1] < groups[0]:
                    raise ValueError(f"[route] at line {sec.line}: group_id {groups[1]} "
                                     f"outside 0..groups-1={groups[0] - 1}")
                out = sum(channels[i] // groups[0] for i in src)
                module = nn.Identity()
                downsample = scales[src[0]]
            elif sec.kind == "shortcut":
                src = [self._absolute(sec.get_int("from"), index, sec)]
                if channels[src[0]] != prev:
                    raise ValueError(f"[shortcut] at line {sec.line}: {channels[src[0]]} "
                                     f"channels cannot be added to {prev}")
                module = nn.Identity()
                out = prev
            else:  # yolo
                module = Yolo(sec, prev)
                out = prev
            self.layers.append(module)
            self.kinds.append(sec.kind)
            self.sources.append(src)
            self.route_groups.append(groups)
            channels.append(out)
            scales.append(downsample)
            prev = out
        self.stride = max(scales) if scales else 1

    def _absolute(self, i: int, index: int, sec: CfgSection) -> int:
        j = index + i if i < 0 else i
        if not 0 <= j < index:
            raise ValueError(f"[{sec.kind}] at line {sec.line}: layer {i} resolves to {j}, "
                             f"expected 0..{index - 1}")
        return j

    def conv_layers(self) -> list[Conv]:
        """The convolution modules, in file (= weights) order."""
        return [m for m in self.layers if isinstance(m, Conv)]

    def forward(self, x: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """Run the network; see the module docstring for the output layout."""
        input_hw = (int(x.shape[2]), int(x.shape[3]))
        outputs: list[torch.Tensor] = []
        heads: list[torch.Tensor] = []
        for kind, module, src, (groups, group_id) in zip(
                self.kinds, self.layers, self.sources, self.route_groups):
            if kind == "route":
                parts = [outputs[i] for i in src]
                if groups > 1:
                    parts = [p.chunk(groups, dim=1)[group_id] for p in parts]
                x = parts[0] if len(parts) == 1 else torch.cat(parts, dim=1)
            elif kind == "shortcut":
                x = x + outputs[src[0]]
            elif kind == "yolo":
                heads.append(module(x, input_hw))
            else:
                x = module(x)
            outputs.append(x)
        return tuple(heads)


def load_darknet_weights(net: DarknetNet, path: Path | str) -> dict[str, int]:
    """Load a Darknet ``.weights`` file into ``net``, folding batch norm into the convs.

    Layout: int32 ``major, minor, revision``; ``seen`` as int64 when
    ``major * 10 + minor >= 2`` else int32; then, per convolution in cfg order, float32
    ``bias`` (or BN beta), and when ``batch_normalize``: BN ``scale``, ``mean``,
    ``variance``; then the kernel ``(filters, in / groups, size, size)``.

    Parameters
    ----------
    net : DarknetNet
        Network built from the matching cfg; modified in place.
    path : Path or str
        The ``.weights`` file.

    Returns
    -------
    dict
        Header fields ``major``, ``minor``, ``revision``, ``seen``.

    Raises
    ------
    ValueError
        If the file is shorter or longer than the cfg requires, or its header is foreign.
    """
    raw = Path(path).read_bytes()
    header = np.frombuffer(raw, dtype=np.int32, count=3, offset=0)
    major, minor, revision = (int(v) for v in header)
    if major > MAX_HEADER_VERSION or minor > MAX_HEADER_VERSION:
        raise ValueError(f"{path}: unsupported weights header version {major}.{minor}")
    offset = 12
    if major * 10 + minor >= SEEN_INT64_MIN_VERSION:
        seen = int(np.frombuffer(raw, dtype=np.int64, count=1, offset=offset)[0])
        offset += 8
    else:
        seen = int(np.frombuffer(raw, dtype=np.int32, count=1, offset=offset)[0])
        offset += 4
    values: npt.NDArray[np.float32] = np.frombuffer(raw, dtype=np.float32, offset=offset)
    needed = sum(
        c.filters * (4 if c.batch_normalize else 1) + c.conv.weight.numel()
        for c in net.conv_layers())
    if values.size != needed:
        raise ValueError(f"{path}: has {values.size} float32 parameters, the cfg needs "
                         f"{needed}")
    pos = 0

    def take(n: int) -> npt.NDArray[np.float32]:
        nonlocal pos
        chunk = values[pos:pos + n]
        pos += n
        return chunk

    with torch.no_grad():
        for conv in net.conv_layers():
            n = conv.filters
            bias = take(n).astype(np.float64)
            if conv.batch_normalize:
                scale = take(n).astype(np.float64)
                mean = take(n).astype(np.float64)
                var = take(n).astype(np.float64)
            kernel = take(conv.conv.weight.numel()).astype(np.float64)
            kernel = kernel.reshape(tuple(conv.conv.weight.shape))
            if conv.batch_normalize:
                factor = scale / (np.sqrt(var) + BN_EPS)
                kernel = kernel * factor[:, None, None, None]
                bias = bias - mean * factor
            conv.conv.weight.copy_(torch.from_numpy(kernel.astype(np.float32)))
            conv.conv.bias.copy_(torch.from_numpy(bias.astype(np.float32)))
    return {"major": major, "minor": minor, "revision": revision, "seen": seen}


def load_darknet(cfg_path: Path | str, weights_path: Path | str) -> DarknetNet:
    """Build a network from a cfg file, load its weights and put it in eval mode.

    Parameters
    ----------
    cfg_path, weights_path : Path or str
        Darknet ``.cfg`` and ``.weights`` files.

    Returns
    -------
    DarknetNet
        Ready for inference (``eval()``, no gradients).

    Raises
    ------
    ValueError
        See :func:`parse_cfg`, :class:`DarknetNet` and :func:`load_darknet_weights`.
    FileNotFoundError
        If a file is missing.
    """
    net = DarknetNet(parse_cfg(Path(cfg_path).read_text(encoding="utf-8")))
    load_darknet_weights(net, weights_path)
    net.eval()
    for p in net.parameters():
        p.requires_grad_(False)
    return net
