"""Procedural furniture: tables, chairs, desks, cabinets and sofas placed in rooms.

:func:`furnish_room` draws furniture groups (e.g. a desk and its chair) for one room and
places them at free spots of its interior, off the door keep-out zones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from sim_bridge.world import Primitive, WorldObject

_Part = tuple[str, str, float, float, float, tuple[float, ...], float, float]
# (part, shape, local x, local y, local yaw, size, zmin, zmax)


def _prim_aabb(p: Primitive) -> tuple[float, float, float, float]:
    if p.shape == "box":
        c, s = abs(math.cos(p.yaw)), abs(math.sin(p.yaw))
        ex = c * p.size[0] / 2 + s * p.size[1] / 2
        ey = s * p.size[0] / 2 + c * p.size[1] / 2
    else:
        ex = ey = p.size[0]
    return (p.x - ex, p.y - ey, p.x + ex, p.y + ey)


def _make_object(name: str, cls: str, pose: tuple[float, float, float],
                 parts: list[_Part]) -> tuple[list[Primitive], WorldObject]:
    """Primitives of an object from parts in its local frame, plus its summary."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    prims = []
    for part, shape, lx, ly, lyaw, size, z0, z1 in parts:
        py = yaw + lyaw if shape == "box" else 0.0
        py = math.atan2(math.sin(py), math.cos(py))
        prims.append(Primitive(name, cls, part, shape, x + c * lx - s * ly, y + s * lx + c * ly,
                               py, tuple(size), z0, z1))
    boxes = np.array([_prim_aabb(p) for p in prims])
    aabb = (float(boxes[:, 0].min()), float(boxes[:, 1].min()), min(p.zmin for p in prims),
            float(boxes[:, 2].max()), float(boxes[:, 3].max()), max(p.zmax for p in prims))
    return prims, WorldObject(name, cls, (x, y, yaw), aabb)


def _chair_parts(rng: np.random.Generator) -> list[_Part]:
    seat = float(rng.uniform(0.42, 0.48))
    z0 = float(rng.uniform(0.42, 0.44))
    z1 = z0 + 0.03
    leg = 0.04
    off = seat / 2 - leg / 2 - 0.01
    back_z = float(rng.uniform(0.82, 0.95))
    parts: list[_Part] = [("leg", "box", sx * off, sy * off, 0.0, (leg, leg), 0.0, z0)
                          for sx in (-1, 1) for sy in (-1, 1)]
    parts.append(("seat", "box", 0.0, 0.0, 0.0, (seat, seat), z0, z1))
    parts.append(("back", "box", -seat / 2 + 0.02, 0.0, 0.0, (0.04, seat), z1, back_z))
    return parts


def _office_chair_parts(rng: np.random.Generator) -> list[_Part]:
    seat = float(rng.uniform(0.46, 0.5))
    z0 = float(rng.uniform(0.42, 0.44))
    return [("base", "cylinder", 0.0, 0.0, 0.0, (float(rng.uniform(0.28, 0.32)),), 0.0, 0.07),
            ("post", "cylinder", 0.0, 0.0, 0.0, (0.025,), 0.07, z0),
            ("seat", "box", 0.0, 0.0, 0.0, (seat, seat), z0, z0 + 0.03),
            ("back", "box", -seat / 2 + 0.03, 0.0, 0.0, (0.05, seat), z0 + 0.1, 1.0)]


def _table_parts(rng: np.random.Generator, length: float, depth: float,
                 top_z: float) -> list[_Part]:
    thick = 0.03
    inset = 0.06
    cyl = bool(rng.random() < 0.5)
    parts: list[_Part] = []
    for sx in (-1, 1):
        for sy in (-1, 1):
            lx, ly = sx * (length / 2 - inset), sy * (depth / 2 - inset)
            if cyl:
                parts.append(("leg", "cylinder", lx, ly, 0.0, (0.025,), 0.0, top_z - thick))
            else:
                parts.append(("leg", "box", lx, ly, 0.0, (0.05, 0.05), 0.0, top_z - thick))
    parts.append(("top", "box", 0.0, 0.0, 0.0, (length, depth), top_z - thick, top_z))
    return parts


@dataclass
class _Group:
    """Furniture placed together (e.g. a desk and its chair), in a local frame.

    Local frame: +x points away from the wall a wall-standing group leans on; the
    group's local footprint is ``[0, depth] x [-width/2, width/2]`` (wall groups) or
    centred (free-standing groups).
    """

    items: list[tuple[str, str, tuple[float, float, float], list[_Part]]]
    lo: tuple[float, float]
    hi: tuple[float, float]
    against_wall: bool


def _desk_group(rng: np.random.Generator, office: bool) -> _Group:
    length = float(rng.uniform(1.0, 1.4))
    depth = float(rng.uniform(0.6, 0.7))
    top = float(rng.uniform(0.72, 0.75))
    # the desk's length runs along the wall (group local y)
    items = [("desk", "table", (depth / 2, 0.0, math.pi / 2),
              _table_parts(rng, length, depth, top))]
    chair_x = depth + float(rng.uniform(0.1, 0.3))
    jitter = float(rng.uniform(-0.3, 0.3))
    # chair faces the desk (local -x): yaw pi; its seat faces its local +x
    items.append(("chair", "chair", (chair_x, float(rng.uniform(-0.2, 0.2)), math.pi + jitter),
                  _office_chair_parts(rng) if office else _chair_parts(rng)))
    return _Group(items, (0.0, -length / 2), (chair_x + 0.35, length / 2), True)


def _table_group(rng: np.random.Generator, n_chairs: int) -> _Group:
    length = float(rng.uniform(1.2, 1.8))
    depth = float(rng.uniform(0.8, 1.0))
    top = float(rng.uniform(0.72, 0.75))
    items = [("table", "table", (0.0, 0.0, 0.0), _table_parts(rng, length, depth, top))]
    slots = [(0.0, -depth / 2 - 0.3, math.pi / 2), (0.0, depth / 2 + 0.3, -math.pi / 2),
             (-length / 2 - 0.3, 0.0, 0.0), (length / 2 + 0.3, 0.0, math.pi)]
    if length > 1.5:
        slots = [(-length / 4, -depth / 2 - 0.3, math.pi / 2),
                 (length / 4, -depth / 2 - 0.3, math.pi / 2),
                 (-length / 4, depth / 2 + 0.3, -math.pi / 2),
                 (length / 4, depth / 2 + 0.3, -math.pi / 2)] + slots[2:]
    for k in rng.permutation(len(slots))[:n_chairs]:
        sx, sy, syaw = slots[int(k)]
        items.append(("chair", "chair", (sx, sy, syaw + float(rng.uniform(-0.25, 0.25))),
                      _chair_parts(rng)))
    ex, ey = length / 2 + 0.6, depth / 2 + 0.6
    return _Group(items, (-ex, -ey), (ex, ey), False)


def _cabinet_group(rng: np.random.Generator) -> _Group:
    depth = float(rng.uniform(0.4, 0.5))
    width = float(rng.uniform(0.8, 1.4))
    height = float(rng.uniform(0.9, 2.0))
    parts: list[_Part] = [("body", "box", depth / 2, 0.0, 0.0, (depth, width), 0.0, height)]
    return _Group([("cabinet", "cabinet", (0.0, 0.0, 0.0), parts)],
                  (0.0, -width / 2), (depth, width / 2), True)


def _sofa_group(rng: np.random.Generator) -> _Group:
    depth = float(rng.uniform(0.8, 0.9))
    width = float(rng.uniform(1.6, 2.1))
    parts: list[_Part] = [("base", "box", depth / 2 + 0.1, 0.0, 0.0, (depth - 0.2, width),
                           0.0, 0.45),
                          ("back", "box", 0.1, 0.0, 0.0, (0.2, width), 0.0, 0.85)]
    return _Group([("sofa", "sofa", (0.0, 0.0, 0.0), parts)],
                  (0.0, -width / 2), (depth, width / 2), True)


def _loose_chair_group(rng: np.random.Generator) -> _Group:
    return _Group([("chair", "chair", (0.0, 0.0, float(rng.uniform(-math.pi, math.pi))),
                    _chair_parts(rng))], (-0.4, -0.4), (0.4, 0.4), False)


Rect = tuple[float, float, float, float]   # xmin, ymin, xmax, ymax


def _overlap(a: Rect, b: Rect, margin: float = 0.0) -> bool:
    return (a[0] < b[2] + margin and b[0] < a[2] + margin
            and a[1] < b[3] + margin and b[1] < a[3] + margin)


def _place_group(rng: np.random.Generator, group: _Group, interior: Rect,
                 blocked: list[Rect], clearance_m: float, tries: int
                 ) -> tuple[float, float, float] | None:
    """Pose (x, y, yaw) of the group frame, or None when no spot is free."""
    for _ in range(tries):
        if group.against_wall:
            side = int(rng.integers(4))           # 0: west wall, 1: south, 2: east, 3: north
            yaw = (0.0, math.pi / 2, math.pi, -math.pi / 2)[side]
            gap = 0.03
            half_w = (group.hi[1] - group.lo[1]) / 2
            if side in (0, 2):
                lo, hi = interior[1] + half_w, interior[3] - half_w
                if lo > hi:
                    continue
                along = float(rng.uniform(lo, hi))
                x = interior[0] + gap if side == 0 else interior[2] - gap
                pose = (x, along, yaw)
            else:
                lo, hi = interior[0] + half_w, interior[2] - half_w
                if lo > hi:
                    continue
                along = float(rng.uniform(lo, hi))
                y = interior[1] + gap if side == 1 else interior[3] - gap
                pose = (along, y, yaw)
        else:
            yaw = float(rng.choice([0.0, math.pi / 2]))
            ex = max(abs(group.lo[0]), abs(group.hi[0]))
            ey = max(abs(group.lo[1]), abs(group.hi[1]))
            if yaw != 0.0:
                ex, ey = ey, ex
            lox, hix = interior[0] + ex + clearance_m, interior[2] - ex - clearance_m
            loy, hiy = interior[1] + ey + clearance_m, interior[3] - ey - clearance_m
            if lox > hix or loy > hiy:
                continue
            pose = (float(rng.uniform(lox, hix)), float(rng.uniform(loy, hiy)), yaw)
        box = _group_box(group, pose)
        if box[0] < interior[0] - 1e-6 or box[2] > interior[2] + 1e-6 or \
                box[1] < interior[1] - 1e-6 or box[3] > interior[3] + 1e-6:
            continue
        if any(_overlap(box, b, clearance_m) for b in blocked):
            continue
        return pose
    return None


def _group_box(group: _Group, pose: tuple[float, float, float]) -> Rect:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    xs, ys = [], []
    for lx in (group.lo[0], group.hi[0]):
        for ly in (group.lo[1], group.hi[1]):
            xs.append(pose[0] + c * lx - s * ly)
            ys.append(pose[1] + s * lx + c * ly)
    return (min(xs), min(ys), max(xs), max(ys))


def _instantiate(group: _Group, pose: tuple[float, float, float], counters: dict[str, int]
                 ) -> tuple[list[Primitive], list[WorldObject]]:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    prims: list[Primitive] = []
    objs: list[WorldObject] = []
    for kind, cls, (lx, ly, lyaw), parts in group.items:
        k = counters.get(kind, 0)
        counters[kind] = k + 1
        wp = (pose[0] + c * lx - s * ly, pose[1] + s * lx + c * ly,
              math.atan2(math.sin(pose[2] + lyaw), math.cos(pose[2] + lyaw)))
        p, o = _make_object(f"{kind}_{k}", cls, wp, parts)
        prims.extend(p)
        objs.append(o)
    return prims, objs


def furnish_room(rng: np.random.Generator, interior: Rect, blocked: list[Rect], cluttered: bool,
                 clearance_m: float, tries: int, counters: dict[str, int]
                 ) -> tuple[list[Primitive], list[WorldObject]]:
    """Furniture of one room: groups drawn from ``rng`` and placed inside ``interior``.

    Parameters
    ----------
    rng : numpy.random.Generator
    interior : Rect
        The room's free rectangle (xmin, ymin, xmax, ymax) inside its walls (m).
    blocked : list of Rect
        Keep-out rectangles (door zones); those overlapping ``interior`` are honoured.
    cluttered : bool
        Dense variant: 2-4 desks, a table with chairs in large rooms, loose chairs,
        sometimes a cabinet; otherwise 1-3 of table / desk / cabinet / sofa.
    clearance_m : float
        Free gap kept between groups and to the keep-out zones (m).
    tries : int
        Placement attempts per group; a group without a free spot is dropped.
    counters : dict of str to int
        Per-kind name counters (updated), so object names stay unique over a house.

    Returns
    -------
    (primitives, objects)
    """
    area = (interior[2] - interior[0]) * (interior[3] - interior[1])
    groups: list[_Group] = []
    if cluttered:
        groups += [_desk_group(rng, office=bool(rng.random() < 0.5))
                   for _ in range(int(rng.integers(2, 5)))]
        if area > 12.0:
            groups.append(_table_group(rng, int(rng.integers(3, 5))))
        groups += [_loose_chair_group(rng) for _ in range(int(rng.integers(1, 3)))]
        if rng.random() < 0.4:
            groups.append(_cabinet_group(rng))
    else:
        makers: list[Callable[[], _Group]] = [
            lambda: _table_group(rng, int(rng.integers(0, 5))),
            lambda: _desk_group(rng, office=False),
            lambda: _cabinet_group(rng),
            lambda: _sofa_group(rng)]
        for k in rng.permutation(len(makers))[:int(rng.integers(1, 4))]:
            groups.append(makers[int(k)]())
    room_blocked = [b for b in blocked if _overlap(b, interior)]
    prims: list[Primitive] = []
    objects: list[WorldObject] = []
    for g in groups:
        pose = _place_group(rng, g, interior, room_blocked, clearance_m, tries)
        if pose is None:
            continue
        room_blocked.append(_group_box(g, pose))
        p, objs = _instantiate(g, pose, counters)
        prims.extend(p)
        objects.extend(objs)
    return prims, objects
