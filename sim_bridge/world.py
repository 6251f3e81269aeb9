"""2.5D world model of the simulator: upright boxes and cylinders with a z-extent.

This module holds the data types every part of the simulator shares and
:func:`rasterize`, which turns primitives into occupancy rasters with the rules of
``worlds/README.md`` (section 3): a cell is occupied when a primitive's cross-section
overlaps the cell square by more than 1 mm. Loading (``explore_seg_world/1`` YAML,
map_server YAML+PGM), procedural generation and ground truth live in
:mod:`sim_bridge.worlds`; sensors in :mod:`sim_bridge.sensors`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap

SHAPES = ("box", "cylinder")
#: A primitive marks a cell when its cross-section overlaps the cell by more than this (m).
CELL_OVERLAP_M = 0.001


@dataclass(frozen=True)
class Primitive:
    """One collision solid.

    box: the upright prism ``|u| <= sx/2, |v| <= sy/2, zmin <= z <= zmax`` in the frame at
    (x, y) turned by ``yaw``; cylinder: ``(x'-x)^2 + (y'-y)^2 <= radius^2``.
    """

    object: str                       # name of the object it belongs to ("" for walls)
    cls: str                          # class: wall, chair, table, desk, cabinet, ...
    part: str                         # wall, leg, top, seat, back, base, ...
    shape: str                        # "box" | "cylinder"
    x: float
    y: float
    yaw: float
    size: tuple[float, ...]           # box: (sx, sy); cylinder: (radius,)
    zmin: float
    zmax: float

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise ValueError(f"shape must be one of {SHAPES}, got {self.shape!r}")
        want = 2 if self.shape == "box" else 1
        if len(self.size) != want:
            raise ValueError(f"{self.shape} size needs {want} values, got {self.size}")
        if not all(s > 0 for s in self.size):
            raise ValueError(f"size values must be > 0, got {self.size}")
        if not (0.0 <= self.zmin < self.zmax):
            raise ValueError(f"need 0 <= zmin < zmax, got [{self.zmin}, {self.zmax}]")

    def spans(self, z_low: float, z_high: float) -> bool:
        """True when the solid occupies some height in the open band (z_low, z_high)."""
        return self.zmin < z_high and self.zmax > z_low


@dataclass(frozen=True)
class WorldObject:
    """A non-wall object (summary for oracle detection and evaluation)."""

    name: str
    cls: str
    pose: tuple[float, float, float]                       # x, y, yaw
    aabb: tuple[float, float, float, float, float, float]  # xmin, ymin, zmin, xmax, ymax, zmax


@dataclass
class World:
    """A world: obstacles, start pose, bounds and optional ground truth rooms.

    ``room_labels`` (when known, e.g. for generated houses) is an int32 raster at
    ``room_resolution_m`` over ``bounds`` in grid layout (row = y), 0 = no room,
    k > 0 room id; ``room_kinds`` maps ids to "room"/"corridor".
    ``base_grid`` holds the occupancy of a map-only world (Explore-Bench maps), whose
    occupied cells act as walls of unlimited height.
    """

    name: str
    bounds: tuple[float, float, float, float]              # xmin, ymin, xmax, ymax
    start_pose: tuple[float, float, float]
    primitives: list[Primitive] = field(default_factory=list)
    objects: list[WorldObject] = field(default_factory=list)
    room_labels: npt.NDArray[np.int32] | None = None
    room_resolution_m: float = 0.05
    room_kinds: dict[int, str] = field(default_factory=dict)
    base_grid: object | None = None                         # explore_seg.core.grid.GridMap
    description: str = ""

    def occupancy(self, resolution_m: float, z_low: float, z_high: float) -> "GridMap":
        """Occupancy GridMap (0 / 100 int8) over ``bounds`` of the primitives in a height band.

        ``z_low == z_high`` selects primitives cut by that plane (``zmin <= z <= zmax``),
        otherwise those occupying some height in ``(z_low, z_high)``; a cell is occupied
        when a cross-section overlaps it by more than 1 mm (see
        :func:`rasterize`).
        """
        return rasterize(self, resolution_m, z_low, z_high)


def _height_filter(prims: list[Primitive], z_low: float, z_high: float) -> list[Primitive]:
    if z_low == z_high:   # a plane: closed test as for the lidar raster
        return [p for p in prims if p.zmin <= z_low <= p.zmax]
    return [p for p in prims if p.spans(z_low, z_high)]


def raster_geometry(bounds: tuple[float, float, float, float], resolution_m: float
                    ) -> tuple[int, int]:
    """(height, width) in cells of a raster covering ``bounds`` at ``resolution_m``.

    Raises
    ------
    ValueError
        On a non-positive resolution or empty bounds.
    """
    if not resolution_m > 0:
        raise ValueError(f"resolution_m must be > 0, got {resolution_m}")
    xmin, ymin, xmax, ymax = bounds
    if not (xmax > xmin and ymax > ymin):
        raise ValueError(f"bounds must have xmax > xmin and ymax > ymin, got {bounds}")
    width = int(round((xmax - xmin) / resolution_m))
    height = int(round((ymax - ymin) / resolution_m))
    return height, width


def rasterize(world: World, resolution_m: float, z_low: float, z_high: float,
              overlap_m: float = CELL_OVERLAP_M) -> GridMap:
    """Occupancy (0 / 100 int8) of the primitives in a height band over ``world.bounds``.

    Parameters
    ----------
    world : World
    resolution_m : float
        Metres per cell, > 0.
    z_low, z_high : float
        Height band (m). ``z_low == z_high`` selects primitives with
        ``zmin <= z <= zmax`` (a scan plane); otherwise those occupying some height in
        the open band ``(z_low, z_high)``.
    overlap_m : float
        A cell is occupied when the cross-section overlaps the cell square by more than
        this: every separating axis of box and square overlaps by more than ``overlap_m``,
        or a circle's radius exceeds its distance to the square by more than it.

    Returns
    -------
    GridMap
        Origin at ``(xmin, ymin)`` of the bounds, frame ``map``, data 0 or 100.

    Raises
    ------
    ValueError
        On ``z_high < z_low``, bad resolution or bounds.
    """
    if z_high < z_low:
        raise ValueError(f"need z_low <= z_high, got [{z_low}, {z_high}]")
    height, width = raster_geometry(world.bounds, resolution_m)
    xmin, ymin = world.bounds[0], world.bounds[1]
    occ = np.zeros((height, width), dtype=bool)
    res = float(resolution_m)
    half = 0.5 * res
    for p in _height_filter(world.primitives, z_low, z_high):
        if p.shape == "box":
            c, s = math.cos(p.yaw), math.sin(p.yaw)
            hx, hy = 0.5 * p.size[0], 0.5 * p.size[1]
            ex = abs(c) * hx + abs(s) * hy
            ey = abs(s) * hx + abs(c) * hy
        else:
            ex = ey = p.size[0]
        c0 = max(int(math.floor((p.x - ex - xmin) / res)) - 1, 0)
        c1 = min(int(math.floor((p.x + ex - xmin) / res)) + 2, width)
        r0 = max(int(math.floor((p.y - ey - ymin) / res)) - 1, 0)
        r1 = min(int(math.floor((p.y + ey - ymin) / res)) + 2, height)
        if c0 >= c1 or r0 >= r1:
            continue
        xs = xmin + (np.arange(c0, c1) + 0.5) * res - p.x      # (w,)
        ys = ymin + (np.arange(r0, r1) + 0.5) * res - p.y      # (h,)
        if p.shape == "box":
            dx = xs[None, :]
            dy = ys[:, None]
            hit = ((ex + half - np.abs(dx)) > overlap_m) & ((ey + half - np.abs(dy)) > overlap_m)
            u = dx * c + dy * s
            v = -dx * s + dy * c
            proj = half * (abs(c) + abs(s))
            hit &= (hx + proj - np.abs(u)) > overlap_m
            hit &= (hy + proj - np.abs(v)) > overlap_m
        else:
            qx = np.maximum(np.abs(xs) - half, 0.0)[None, :]
            qy = np.maximum(np.abs(ys) - half, 0.0)[:, None]
            hit = (p.size[0] - np.sqrt(qx * qx + qy * qy)) > overlap_m
        occ[r0:r1, c0:c1] |= hit
    data = np.where(occ, np.int8(100), np.int8(0)).astype(np.int8)
    return GridMap(data, res, (float(xmin), float(ymin)))
