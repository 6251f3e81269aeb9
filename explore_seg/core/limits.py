"""Limits on what one input message may make a node do, and its time-fault settings.

Every node binds :class:`InputLimits` under ``input.``. The map and label converters
(:mod:`explore_seg.convert`) check a message's sizes against the data it carries and against
these limits *before* they allocate anything, so a hostile ``width x height`` or a tiny
resolution costs a warning instead of gigabytes or minutes; poses and map origins farther
than ``max_coordinate_m`` from the frame's origin are rejected before any cell arithmetic.
``clock_jump_s`` and ``stall_periods`` drive :mod:`explore_seg.time_guard`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from typing import TYPE_CHECKING

import numpy as np  # noqa: F401 - used by the doctest

from explore_seg.core.fields import INT_MAX, param_meta

if TYPE_CHECKING:
    from explore_seg.core.grid import GridMap


@dataclass(frozen=True)
class InputLimits:
    """Input limits and time-fault settings shared by every node (``input.*``).

    Raises
    ------
    ValueError
        From ``__post_init__`` on a non-positive or non-finite limit.

    Examples
    --------
    >>> InputLimits().check_map_size(100, 50, 0.05)
    >>> InputLimits(max_map_cells=100).check_map_size(100, 50, 0.05)
    Traceback (most recent call last):
    ...
    ValueError: map claims 100x50 = 5000 cells, more than input.max_map_cells = 100
    """

    max_map_cells: int = field(default=16_000_000, metadata=param_meta(
        "largest width*height accepted in a map, object layer or region labels (checked "
        "before any array is made); 4000 x 4000 cells is 200 x 200 m at 0.05 m, sized so "
        "that the map nodes of one robot fit a 4-8 GB Jetson even when all of it is known",
        "cells", range=(1, INT_MAX)))
    min_resolution_m: float = field(default=0.005, metadata=param_meta(
        "finer maps are rejected (kernels sized from the resolution, e.g. the robot-radius "
        "inflation, would grow without bound)", "m", range=(0.0, math.inf)))
    max_coordinate_m: float = field(default=100_000.0, metadata=param_meta(
        "poses and map origins farther than this from their frame's origin are rejected",
        "m", range=(0.0, math.inf)))
    pose_map_margin_m: float = field(default=5.0, metadata=param_meta(
        "robot poses farther than this outside the current map's bounds are dropped (a pose "
        "of another frame or a wild estimate); checked once a map has been received", "m",
        range=(0.0, math.inf)))
    clock_jump_s: float = field(default=5.0, metadata=param_meta(
        "a stamp or the node clock going back (sim reset) or ahead (future-stamped input) by "
        "more than this is a clock jump (a stamp's step ahead counts beyond the time the "
        "node clock advanced since that stream's previous stamp: a slow map publisher is "
        "none): time-keyed state is reset and it is logged once; "
        "streams whose newest stamps differ by more than this are reported as clock sources "
        "that disagree", "s", range=(0.0, math.inf)))
    stall_periods: int = field(default=10, metadata=param_meta(
        "when inputs arrive but nothing has been produced for this many periods, the node "
        "logs why it waits", "", range=(1, INT_MAX)))

    def __post_init__(self) -> None:
        if not (math.isfinite(self.pose_map_margin_m) and self.pose_map_margin_m >= 0):
            raise ValueError(f"pose_map_margin_m must be finite and >= 0, "
                             f"got {self.pose_map_margin_m}")
        for name in ("min_resolution_m", "max_coordinate_m", "clock_jump_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        for name in ("max_map_cells", "stall_periods"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")

    def check_map_size(self, width: int, height: int, resolution_m: float) -> None:
        """Raise ``ValueError`` when a claimed map geometry is empty or exceeds the limits
        (allocates nothing)."""
        w, h = int(width), int(height)
        if w < 1 or h < 1:
            # an empty map (e.g. width=0, data=[]) would replace the last good one
            raise ValueError(f"map size must be at least 1x1 cells, got {w}x{h}")
        if w * h > self.max_map_cells:
            raise ValueError(f"map claims {w}x{h} = {w * h} cells, more than "
                             f"input.max_map_cells = {self.max_map_cells}")
        res = float(resolution_m)
        if not (math.isfinite(res) and res >= self.min_resolution_m):
            raise ValueError(f"map resolution {res} m is below input.min_resolution_m = "
                             f"{self.min_resolution_m} m (or not finite)")
        extent = max(w, h) * res
        if extent > 2 * self.max_coordinate_m:
            # e.g. resolution 1e300: cell centres overflow to inf and NaN downstream
            raise ValueError(f"map spans {extent:.6g} m ({w}x{h} cells at {res:.6g} m), more "
                             f"than 2 * input.max_coordinate_m = "
                             f"{2 * self.max_coordinate_m:g} m")

    def check_xy(self, x_m: float, y_m: float, what: str) -> None:
        """Raise ``ValueError`` when (x, y) is non-finite or beyond ``max_coordinate_m``."""
        lim = self.max_coordinate_m
        if not (math.isfinite(x_m) and math.isfinite(y_m)):
            raise ValueError(f"{what}: position must be finite, got ({x_m}, {y_m})")
        if abs(x_m) > lim or abs(y_m) > lim:
            raise ValueError(f"{what}: position ({x_m:.6g}, {y_m:.6g}) is beyond "
                             f"input.max_coordinate_m = {lim:g} m")

    def check_near_map(self, x_m: float, y_m: float, grid: GridMap) -> None:
        """Raise ``ValueError`` when (x, y) lies more than ``pose_map_margin_m`` outside
        ``grid``'s bounds (its rotated rectangle); the message names pose, map and margin.

        >>> from explore_seg.core.grid import GridMap
        >>> g = GridMap(np.zeros((20, 10), np.int8), 0.5)           # 5 m x 10 m
        >>> InputLimits().check_near_map(9.0, 3.0, g)               # 4 m out: fine
        >>> InputLimits(pose_map_margin_m=1.0).check_near_map(9.0, 3.0, g)
        Traceback (most recent call last):
        ...
        ValueError: pose (9.000, 3.000) lies 4.00 m outside the map (x 0.00..5.00, y 0.00..10.00 m), more than input.pose_map_margin_m = 1 m
        """
        r, c = grid.world_to_cell_float(x_m, y_m)
        out_r = max(0.0, -float(r), float(r) - grid.height)
        out_c = max(0.0, -float(c), float(c) - grid.width)
        out_m = math.hypot(out_r, out_c) * grid.resolution_m
        if out_m > self.pose_map_margin_m:
            h, w = grid.height - 0.5, grid.width - 0.5          # corner (edge) cells
            xs, ys = grid.cells_to_world([-0.5, -0.5, h, h], [-0.5, w, -0.5, w])
            x0, x1, y0, y1 = xs.min(), xs.max(), ys.min(), ys.max()
            raise ValueError(f"pose ({x_m:.3f}, {y_m:.3f}) lies {out_m:.2f} m outside the map "
                             f"(x {x0:.2f}..{x1:.2f}, y {y0:.2f}..{y1:.2f} m), more than "
                             f"input.pose_map_margin_m = {self.pose_map_margin_m:g} m")


def normalize_frame(frame_id: str, default: str = "") -> str:
    """A frame id without its leading ``/`` (tf2 names have none); ``default`` if empty.

    >>> normalize_frame("/map"), normalize_frame("", "map")
    ('map', 'map')
    """
    return frame_id.lstrip("/") or default


def check_frame(frame_id: str, expected: str, what: str) -> None:
    """Raise ``ValueError`` unless ``frame_id`` is ``expected`` (leading ``/`` ignored; an
    empty frame id is taken to be ``expected``)."""
    got = normalize_frame(frame_id, normalize_frame(expected))
    if got != normalize_frame(expected):
        raise ValueError(f"{what} frame must be {normalize_frame(expected)!r} (the map's), "
                         f"got {frame_id!r}")
