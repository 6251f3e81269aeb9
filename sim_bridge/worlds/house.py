"""Procedural houses: a corridor with rooms on both sides, doors and furniture."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from explore_seg.core.fields import param_meta
from sim_bridge.world import World
from sim_bridge.worlds.furniture import Rect
from sim_bridge.worlds.floor import assemble_floor, snap, split_lengths
from sim_bridge.worlds.walls import Wall

@dataclass(frozen=True)
class HouseOptions:
    """Knobs of :func:`generate_house` (pass them as keyword ``opts``)."""

    wall_thickness_m: float = field(default=0.15, metadata=param_meta(
        "wall thickness", "m", range=(0.0, 1.0)))
    wall_height_m: float = field(default=2.5, metadata=param_meta(
        "wall height (above lintel_z_m)", "m", range=(0.0, math.inf)))
    door_width_m: tuple[float, float] = field(
        default=(0.8, 1.0), metadata=param_meta("door gap width range", "m"))
    lintels: bool = field(default=True, metadata=param_meta("door lintels from lintel_z_m"))
    lintel_z_m: float = field(default=2.0, metadata=param_meta(
        "lintel bottom height (below wall_height_m)", "m", range=(0.0, math.inf)))
    corridor_width_m: tuple[float, float] = field(
        default=(1.4, 1.8), metadata=param_meta("corridor width range", "m"))
    room_width_m: tuple[float, float] = field(
        default=(3.0, 6.0), metadata=param_meta("room width range along the corridor", "m"))
    split_depth_m: float = field(
        default=6.5, metadata=param_meta("rooms deeper than this may be split in two", "m"))
    extra_door_prob: float = field(
        default=0.3, metadata=param_meta("probability of a door between side-by-side rooms",
                                         range=(0.0, 1.0)))
    furniture_clearance_m: float = field(
        default=0.65, metadata=param_meta("free gap kept between furniture groups", "m"))
    door_keepout_m: float = field(
        default=1.0, metadata=param_meta("furniture-free depth in front of doors", "m"))
    place_tries: int = field(default=40, metadata=param_meta(
        "placement attempts per group", range=(1, 2**31 - 1)))
    start_clearance_m: float = field(
        default=0.6, metadata=param_meta("minimum start clearance to obstacles below 1.5 m",
                                         "m"))
    margin_m: float = field(default=0.5, metadata=param_meta("bounds margin", "m"))

    def __post_init__(self) -> None:
        if not 0 < self.wall_thickness_m < 1.0:
            raise ValueError(f"wall_thickness_m must be in (0, 1), got {self.wall_thickness_m}")
        if not self.wall_height_m > self.lintel_z_m > 0:
            raise ValueError(f"need wall_height_m > lintel_z_m > 0, got {self.wall_height_m}, "
                             f"{self.lintel_z_m}")
        for name in ("door_width_m", "corridor_width_m", "room_width_m"):
            lo, hi = getattr(self, name)
            if not 0 < lo <= hi:
                raise ValueError(f"{name} must be a range 0 < lo <= hi, got {(lo, hi)}")
        if self.corridor_width_m[0] < 2 * self.start_clearance_m + self.wall_thickness_m:
            raise ValueError(
                f"corridor_width_m {self.corridor_width_m} too narrow for start_clearance_m "
                f"{self.start_clearance_m}")
        if self.room_width_m[0] < self.door_width_m[1] + 4 * self.wall_thickness_m:
            raise ValueError(f"room_width_m {self.room_width_m} too small for doors")
        if not 0 <= self.extra_door_prob <= 1:
            raise ValueError(f"extra_door_prob must be in [0, 1], got {self.extra_door_prob}")
        if self.place_tries < 1:
            raise ValueError(f"place_tries must be >= 1, got {self.place_tries}")


def _house_layout(rng: np.random.Generator, width: float, height: float, o: HouseOptions
                  ) -> tuple[list[Wall], list[tuple[Rect, str]], list[tuple[int, int]],
                             tuple[float, float, float]]:
    """Canonical layout (corridor along x): walls, rooms (rect, kind), doors (room pairs)
    and the start pose. Rects are centre-line rectangles."""
    hw, hh = width / 2, height / 2
    cw = snap(float(rng.uniform(*o.corridor_width_m)))
    shift = snap(float(rng.uniform(-0.15, 0.15)) * height)
    cy0, cy1 = shift - cw / 2, shift + cw / 2
    rooms: list[tuple[Rect, str]] = [((-hw, cy0, hw, cy1), "corridor")]
    walls = [Wall(-hw, -hh, hw, -hh), Wall(-hw, hh, hw, hh), Wall(-hw, -hh, -hw, hh),
             Wall(hw, -hh, hw, hh), Wall(-hw, cy0, hw, cy0), Wall(-hw, cy1, hw, cy1)]
    links: list[tuple[int, int]] = []
    for side in (-1, 1):
        near, far = (cy0, -hh) if side < 0 else (cy1, hh)
        depth = abs(far - near)
        x = -hw
        columns = split_lengths(rng, width, *o.room_width_m)
        prev_front: int | None = None
        for k, cwid in enumerate(columns):
            x0, x1 = x, round(x + cwid, 6)
            x = x1
            if k > 0:
                walls.append(Wall(x0, min(near, far), x0, max(near, far)))
            split = depth > o.split_depth_m and rng.random() < 0.7
            if split:
                d = snap(depth * float(rng.uniform(0.4, 0.6)))
                mid = near + side * d
                walls.append(Wall(x0, mid, x1, mid))
                front = (x0, min(near, mid), x1, max(near, mid))
                back = (x0, min(mid, far), x1, max(mid, far))
                rooms.append((front, "room"))
                fi = len(rooms) - 1
                rooms.append((back, "room"))
                links.append((fi, fi + 1))
            else:
                rooms.append(((x0, min(near, far), x1, max(near, far)), "room"))
                fi = len(rooms) - 1
            links.append((0, fi))
            if prev_front is not None and rng.random() < o.extra_door_prob:
                links.append((prev_front, fi))
            prev_front = fi
    start = (snap(float(rng.uniform(-0.3, 0.3)) * width), shift, 0.0)
    return walls, rooms, links, start


def generate_house(seed: int, size_m: tuple[float, float] = (20.0, 20.0),
                   cluttered: bool = False, **opts: Any) -> World:
    """A seeded procedural house: a corridor with rooms on both sides, doors, furniture.

    The house is a rectangle of ``size_m`` centred at the origin. A corridor crosses it
    (along x or y, chosen by the seed); both sides are cut into rooms
    (:attr:`HouseOptions.room_width_m` wide, deep ones split into a front and a back
    room). Every front room has a door to the corridor, back rooms to their front room,
    neighbours sometimes to each other. Walls are ``wall_thickness_m`` boxes,
    ``wall_height_m`` high, with door gaps of ``door_width_m`` and lintels. Furniture:
    tables (4 legs + top at 0.72-0.75 m) with chairs (4 legs, seat at 0.42-0.47 m,
    backrest), desks with a chair, cabinets and sofas; the cluttered variant puts 2-4
    desks with (office) chairs, a table with chairs and loose chairs into every room.

    Parameters
    ----------
    seed : int
        Seed of the layout and furniture (same seed, same world).
    size_m : tuple of float
        Outer size (width along x, height along y) in metres; each >= 8 m.
    cluttered : bool
        Dense furniture variant.
    **opts
        Fields of :class:`HouseOptions`.

    Returns
    -------
    World
        With ``objects`` (one per furniture item), ``room_labels`` (int32 raster at
        0.05 m over the bounds, row = y; every inside free cell carries its room or
        corridor id, everything else 0), ``room_kinds`` and a start pose in the corridor.

    Raises
    ------
    ValueError
        On a bad size or option (unknown option names included).
    """
    try:
        o = HouseOptions(**opts)
    except TypeError as err:
        raise ValueError(f"unknown generate_house option: {err}") from None
    width, height = (float(v) for v in size_m)
    if not (width >= 8.0 and height >= 8.0):
        raise ValueError(f"size_m must be at least (8, 8) m, got {size_m}")
    rng = np.random.default_rng(seed)
    vertical = bool(rng.random() < 0.5)
    cw, ch = (height, width) if vertical else (width, height)
    return assemble_floor(rng, _house_layout(rng, cw, ch, o), o, (width, height), cluttered,
                          vertical, f"house{'_cluttered' if cluttered else ''}_s{seed}",
                          f"generated house seed={seed} size={width}x{height} m"
                          f"{' cluttered' if cluttered else ''}")
