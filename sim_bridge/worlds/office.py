"""Procedural office floors: two long corridors joined by cross corridors, cell offices
along the outer walls, blocks of offices and meeting rooms between the corridors.

Plan (canonical frame, x along the long side)::

    +------+------+-----+------+------+   outer band: offices (deep ones split front/back)
    |======== upper corridor ==========|
    | blk 0 rooms |XX| blk 1 rooms |XX|...   middle blocks: two rows of rooms, each row
    | blk 0 rooms |XX| blk 1 rooms |XX|      facing its corridor; XX = cross corridors
    |======== lower corridor ==========|
    +------+------+-----+------+------+   outer band

Every room has a door to the corridor it faces (back rooms to their front room), rooms
beside a cross corridor may have one to it and neighbours sometimes to each other. The
start is in the lower corridor. Furniture and room labels as in the generated houses
(:func:`~sim_bridge.worlds.floor.assemble_floor`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from sim_bridge.world import World
from sim_bridge.worlds.floor import assemble_floor, snap, split_lengths
from sim_bridge.worlds.furniture import Rect
from sim_bridge.worlds.house import HouseOptions
from sim_bridge.worlds.walls import Wall

#: Default outer size of an office floor (m) and its bounds.
OFFICE_SIZE_M = (60.0, 40.0)
MIN_OFFICE_SIZE_M = (40.0, 30.0)
#: Office defaults that differ from :class:`HouseOptions` (wider corridors).
OFFICE_OPTIONS: dict[str, Any] = {"corridor_width_m": (1.8, 2.2), "room_width_m": (3.0, 6.0)}
#: Width range of the middle blocks' rooms (m) and how many blocks the middle band has.
MIDDLE_ROOM_WIDTH_M = (4.0, 8.0)
MIDDLE_BLOCKS = 3
#: Probability of a door from a room beside a cross corridor into it.
CROSS_DOOR_PROB = 0.5

_Room = tuple[Rect, str]


def _band(rng: np.random.Generator, walls: list[Wall], rooms: list[_Room],
          links: list[tuple[int, int]], corridor: int,
          span: tuple[float, float, float, float], o: HouseOptions) -> None:
    """Offices along x in [x0, x1] between a corridor wall at y = ``near`` and the outer
    wall at y = ``far`` (``span`` = (x0, x1, near, far))."""
    x0, x1, near, far = span
    side = 1.0 if far > near else -1.0
    depth = abs(far - near)
    x = x0
    prev: int | None = None
    for k, width in enumerate(split_lengths(rng, x1 - x0, *o.room_width_m)):
        a, b = x, round(x + width, 6)
        x = b
        if k > 0:
            walls.append(Wall(a, min(near, far), a, max(near, far)))
        if depth > o.split_depth_m and rng.random() < 0.7:
            mid = near + side * snap(depth * float(rng.uniform(0.4, 0.6)))
            walls.append(Wall(a, mid, b, mid))
            rooms.append(((a, min(near, mid), b, max(near, mid)), "room"))
            front = len(rooms) - 1
            rooms.append(((a, min(mid, far), b, max(mid, far)), "room"))
            links.append((front, front + 1))
        else:
            rooms.append(((a, min(near, far), b, max(near, far)), "room"))
            front = len(rooms) - 1
        links.append((corridor, front))
        if prev is not None and rng.random() < o.extra_door_prob:
            links.append((prev, front))
        prev = front


def _block(rng: np.random.Generator, walls: list[Wall], rooms: list[_Room],
           links: list[tuple[int, int]], corridors: tuple[int, int],
           cross: tuple[int | None, int | None], rect: Rect, o: HouseOptions) -> None:
    """A middle block: a lower and an upper row of rooms facing the lower / upper
    corridor; the rooms at its ends may open into the cross corridors beside it."""
    bx0, y0, bx1, y1 = rect
    walls.extend([Wall(bx0, y0, bx1, y0), Wall(bx0, y1, bx1, y1)])
    if cross[0] is not None:
        walls.append(Wall(bx0, y0, bx0, y1))
    if cross[1] is not None:
        walls.append(Wall(bx1, y0, bx1, y1))
    ymid = snap(y0 + (y1 - y0) * float(rng.uniform(0.4, 0.6)))
    walls.append(Wall(bx0, ymid, bx1, ymid))
    for (ra, rb), corridor in zip(((y0, ymid), (ymid, y1)), corridors):
        widths = split_lengths(rng, bx1 - bx0, *MIDDLE_ROOM_WIDTH_M)
        x = bx0
        prev: int | None = None
        for k, width in enumerate(widths):
            a, b = x, round(x + width, 6)
            x = b
            if k > 0:
                walls.append(Wall(a, ra, a, rb))
            rooms.append(((a, ra, b, rb), "room"))
            i = len(rooms) - 1
            links.append((corridor, i))
            if prev is not None and rng.random() < o.extra_door_prob:
                links.append((prev, i))
            for end, cx in ((0, cross[0]), (len(widths) - 1, cross[1])):
                if k == end and cx is not None and rng.random() < CROSS_DOOR_PROB:
                    links.append((cx, i))
            prev = i


def _office_layout(rng: np.random.Generator, width: float, height: float, o: HouseOptions
                   ) -> tuple[list[Wall], list[_Room], list[tuple[int, int]],
                              tuple[float, float, float]]:
    """Canonical plan: walls, rooms (rect, kind), door links and the start pose."""
    hw, hh = width / 2, height / 2
    cw = snap(float(rng.uniform(*o.corridor_width_m)))
    depth_top = snap(float(rng.uniform(0.18, 0.22)) * height)
    depth_bottom = snap(float(rng.uniform(0.18, 0.22)) * height)
    yu1, yl0 = hh - depth_top, -hh + depth_bottom
    yu0, yl1 = round(yu1 - cw, 6), round(yl0 + cw, 6)
    rooms: list[_Room] = [((-hw, yl0, hw, yl1), "corridor"), ((-hw, yu0, hw, yu1), "corridor")]
    walls = [Wall(-hw, -hh, hw, -hh), Wall(-hw, hh, hw, hh), Wall(-hw, -hh, -hw, hh),
             Wall(hw, -hh, hw, hh), Wall(-hw, yl0, hw, yl0), Wall(-hw, yu1, hw, yu1)]
    links: list[tuple[int, int]] = []
    # cross corridors split the middle band into MIDDLE_BLOCKS blocks
    edges = [-hw]
    for k in range(1, MIDDLE_BLOCKS):
        c = snap(-hw + width * k / MIDDLE_BLOCKS + float(rng.uniform(-0.05, 0.05)) * width)
        edges += [round(c - cw / 2, 6), round(c + cw / 2, 6)]
    edges.append(hw)
    cross: list[int] = []
    for k in range(MIDDLE_BLOCKS - 1):
        rooms.append(((edges[2 * k + 1], yl1, edges[2 * k + 2], yu0), "corridor"))
        cross.append(len(rooms) - 1)
    _band(rng, walls, rooms, links, 0, (-hw, hw, yl0, -hh), o)
    _band(rng, walls, rooms, links, 1, (-hw, hw, yu1, hh), o)
    for k in range(MIDDLE_BLOCKS):
        left = cross[k - 1] if k > 0 else None
        right = cross[k] if k < MIDDLE_BLOCKS - 1 else None
        _block(rng, walls, rooms, links, (0, 1), (left, right),
               (edges[2 * k], yl1, edges[2 * k + 1], yu0), o)
    start = (snap(float(rng.uniform(-0.3, 0.3)) * width), round((yl0 + yl1) / 2, 6), 0.0)
    return walls, rooms, links, start


def generate_office_floor(seed: int, size_m: tuple[float, float] = OFFICE_SIZE_M,
                          cluttered: bool = False, **opts: Any) -> World:
    """A seeded office floor (see the module docstring), centred at the origin.

    Parameters
    ----------
    seed : int
        Seed of the plan and the furniture (same seed, same world).
    size_m : (float, float)
        Outer size (x, y) in metres, at least :data:`MIN_OFFICE_SIZE_M`.
    cluttered : bool
        Dense furniture (desks, tables, loose chairs in every room).
    **opts
        Fields of :class:`~sim_bridge.worlds.house.HouseOptions` (defaults:
        :data:`OFFICE_OPTIONS` over the house defaults).

    Returns
    -------
    World
        With ``objects``, ``room_labels`` (rooms and corridors), ``room_kinds``
        (``room`` / ``corridor``) and a start pose in the lower corridor.

    Raises
    ------
    ValueError
        On a bad size or option.
    """
    try:
        o = HouseOptions(**{**OFFICE_OPTIONS, **opts})
    except TypeError as err:
        raise ValueError(f"unknown generate_office_floor option: {err}") from None
    width, height = (float(v) for v in size_m)
    if not (width >= MIN_OFFICE_SIZE_M[0] and height >= MIN_OFFICE_SIZE_M[1]):
        raise ValueError(f"size_m must be at least {MIN_OFFICE_SIZE_M} m, got {size_m}")
    rng = np.random.default_rng([int(seed), 0x0FF1CE])
    return assemble_floor(rng, _office_layout(rng, width, height, o), o, (width, height),
                          cluttered,
                          False, f"office_floor{'_cluttered' if cluttered else ''}_s{seed}",
                          f"generated office floor seed={seed} size={width}x{height} m"
                          f"{' cluttered' if cluttered else ''}")
