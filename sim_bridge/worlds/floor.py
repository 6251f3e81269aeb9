"""A floor plan (wall centre lines, room rectangles, door links) turned into a furnished
:class:`~sim_bridge.world.World` with room ground truth; shared by the generated houses
(:mod:`~sim_bridge.worlds.house`) and office floors (:mod:`~sim_bridge.worlds.office`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from explore_seg.core.grid import OCCUPIED_THRESHOLD
from sim_bridge.world import Primitive, World, WorldObject, raster_geometry
from sim_bridge.worlds.furniture import Rect, furnish_room
from sim_bridge.worlds.truth import GT_RESOLUTION_M, ground_truth
from sim_bridge.worlds.walls import Wall, add_door, bounds_around

#: Room kinds that get furniture (corridors and halls stay empty).
FURNISHED_KINDS = frozenset({"room"})


def snap(v: float, step: float = 0.05) -> float:
    """``v`` rounded to a multiple of ``step`` (0.05 m: the ground-truth raster)."""
    return round(round(v / step) * step, 6)


def split_lengths(rng: np.random.Generator, total: float, lo: float, hi: float) -> list[float]:
    """Widths in [lo, hi] (snapped to 0.05 m) that sum to ``total`` (> lo)."""
    out: list[float] = []
    left = total
    while left > hi:
        w = snap(float(rng.uniform(lo, min(hi, left - lo))))
        out.append(w)
        left = round(left - w, 6)
    out.append(left)
    return out


def shared_edge(a: Rect, b: Rect) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """Common boundary segment of two touching rectangles (None when they do not share one)."""
    eps = 1e-6
    for ax, bx in ((a[2], b[0]), (a[0], b[2])):
        if abs(ax - bx) < eps:
            lo, hi = max(a[1], b[1]), min(a[3], b[3])
            if hi - lo > eps:
                return (ax, lo), (ax, hi)
    for ay, by in ((a[3], b[1]), (a[1], b[3])):
        if abs(ay - by) < eps:
            lo, hi = max(a[0], b[0]), min(a[2], b[2])
            if hi - lo > eps:
                return (lo, ay), (hi, ay)
    return None


def _rotate90(x: float, y: float) -> tuple[float, float]:
    return -y, x


def paint_rooms(rooms: list[tuple[Rect, str]], bounds: tuple[float, float, float, float],
                res: float) -> npt.NDArray[np.int32]:
    """Room ids (1-based, in list order; later rooms paint over earlier) on a raster of
    ``bounds`` at ``res``."""
    h, w = raster_geometry(bounds, res)
    labels = np.zeros((h, w), np.int32)
    xs = bounds[0] + (np.arange(w) + 0.5) * res
    ys = bounds[1] + (np.arange(h) + 0.5) * res
    for k, (r, _) in enumerate(rooms, start=1):
        cols = (xs >= r[0]) & (xs < r[2])
        rows = (ys >= r[1]) & (ys < r[3])
        labels[np.ix_(rows, cols)] = k
    return labels


def cut_doors(rng: np.random.Generator, walls: list[Wall], rooms: list[tuple[Rect, str]],
              links: list[tuple[int, int]], o: Any) -> None:
    """A door of ``o.door_width_m`` (drawn per link) at a random place of the wall two
    linked rooms share (links of rooms without a long enough common wall are skipped)."""
    for a, b in links:
        edge = shared_edge(rooms[a][0], rooms[b][0])
        if edge is None:
            continue
        (ex0, ey0), (ex1, ey1) = edge
        length = math.hypot(ex1 - ex0, ey1 - ey0)
        dw = snap(float(rng.uniform(*o.door_width_m)))
        margin = o.wall_thickness_m / 2 + 0.2
        if length < dw + 2 * margin:
            continue
        s0 = float(rng.uniform(margin, length - margin - dw))
        ux, uy = (ex1 - ex0) / length, (ey1 - ey0) / length
        add_door(walls, (ex0 + ux * s0, ey0 + uy * s0),
                 (ex0 + ux * (s0 + dw), ey0 + uy * (s0 + dw)))


#: A floor plan in its canonical frame: wall centre lines, (rect, kind) per room, pairs of
#: room indices to join by a door, the start pose.
FloorPlan = tuple[list[Wall], list[tuple[Rect, str]], list[tuple[int, int]],
                  tuple[float, float, float]]


def assemble_floor(rng: np.random.Generator, plan: FloorPlan, o: Any,
                   size_m: tuple[float, float], cluttered: bool, vertical: bool, name: str,
                   description: str) -> World:
    """The world of a floor plan centred at the origin: doors cut for ``links``, the
    plan turned by 90 degrees when ``vertical``, wall boxes with lintels, furniture in
    every room of a :data:`FURNISHED_KINDS` kind (door approaches kept free), a start
    with ``o.start_clearance_m`` and the room labels.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws the doors and the furniture (in that order).
    plan : FloorPlan
        (walls, rooms, links, start) in the plan's canonical frame.
    o : HouseOptions (or an object with its fields)
    size_m : (float, float)
        Outer size (width along x, height along y) after the turn.
    cluttered : bool
        Dense furniture.
    vertical : bool
        Turn the plan by +90 degrees (x -> y).
    name, description : str

    Returns
    -------
    World
        With ``objects``, ``room_labels`` / ``room_resolution_m`` / ``room_kinds``.

    Raises
    ------
    ValueError
        When no start cell keeps ``o.start_clearance_m``.
    """
    walls, rooms, links, start = plan
    cut_doors(rng, walls, rooms, links, o)
    if vertical:
        for w in walls:
            w.x0, w.y0 = _rotate90(w.x0, w.y0)
            w.x1, w.y1 = _rotate90(w.x1, w.y1)
        rooms = [((-r[3], r[0], -r[1], r[2]), kind) for r, kind in rooms]
        sx, sy = _rotate90(start[0], start[1])
        start = (sx, sy, math.pi / 2)
    prims: list[Primitive] = []
    lintel = o.lintel_z_m if o.lintels else None
    for k, w in enumerate(walls):
        prims.extend(w.boxes(f"wall_{k}", o.wall_thickness_m, o.wall_height_m, lintel))
    # door keep-out zones
    blocked: list[Rect] = []
    for w in walls:
        ux, uy = (w.x1 - w.x0) / w.length, (w.y1 - w.y0) / w.length
        for d0, d1 in w.doors:
            pts = [(w.x0 + ux * s + uy * n, w.y0 + uy * s - ux * n)
                   for s in (d0 - 0.2, d1 + 0.2) for n in (-o.door_keepout_m, o.door_keepout_m)]
            blocked.append((min(p[0] for p in pts), min(p[1] for p in pts),
                            max(p[0] for p in pts), max(p[1] for p in pts)))
    objects: list[WorldObject] = []
    counters: dict[str, int] = {}
    t2 = o.wall_thickness_m / 2
    for rect, kind in rooms:
        if kind not in FURNISHED_KINDS:
            continue
        interior = (rect[0] + t2, rect[1] + t2, rect[2] - t2, rect[3] - t2)
        p, objs = furnish_room(rng, interior, blocked, cluttered, o.furniture_clearance_m,
                               o.place_tries, counters)
        prims.extend(p)
        objects.extend(objs)
    hw, hh = size_m[0] / 2, size_m[1] / 2
    bounds = bounds_around(-hw - t2, -hh - t2, hw + t2, hh + t2, o.margin_m)
    world = World(name=name, bounds=bounds, start_pose=start, primitives=prims,
                  objects=objects, description=description)
    gt = ground_truth(world)
    dist = ndimage.distance_transform_edt(gt.footprint_tall.data < OCCUPIED_THRESHOLD) \
        * GT_RESOLUTION_M
    r, c = gt.start_cell
    if dist[r, c] < o.start_clearance_m:     # never expected: corridors hold no furniture
        ok = gt.inside & (dist >= o.start_clearance_m)
        if not ok.any():
            raise ValueError(f"no start cell with clearance {o.start_clearance_m} m ({name})")
        rr, cc = np.nonzero(ok)
        k = int(np.argmax(dist[rr, cc]))
        x, y = gt.lidar.cell_to_world(rr[k], cc[k])
        world.start_pose = (x, y, start[2])
        gt = ground_truth(world)
    labels = paint_rooms(rooms, bounds, GT_RESOLUTION_M)
    free = gt.inside & (gt.lidar.data < OCCUPIED_THRESHOLD)
    world.room_labels = np.where(free, labels, 0).astype(np.int32)
    world.room_resolution_m = GT_RESOLUTION_M
    world.room_kinds = {k: kind for k, (_, kind) in enumerate(rooms, start=1)}
    return world
