"""2.5D world model of the simulator: upright boxes and cylinders with a z-extent.

This module holds the data types every part of the simulator shares. Loading
(``explore_seg_world/1`` YAML, map_server YAML+PGM) and procedural generation live in
:mod:`sim_bridge.worlds`; sensors in :mod:`sim_bridge.sensors`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from explore_seg.core.grid import GridMap

SHAPES = ("box", "cylinder")


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
        :func:`sim_bridge.worlds.rasterize`).
        """
        from sim_bridge.worlds import rasterize   # local import: worlds imports this module
        return rasterize(self, resolution_m, z_low, z_high)
