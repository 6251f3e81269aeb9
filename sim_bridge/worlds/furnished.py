"""Seeded furnished floor-plan maps with room ground truth, for segmentation evaluation.

:func:`furnished_map` builds one floor plan from :func:`~sim_bridge.worlds.generate_house`
(walls and doors only) in one of three styles (:data:`MAP_KINDS`): ``office`` (cell
offices along a corridor), ``open_office`` (large open-plan rooms with desk islands) and
``home`` (a smaller flat: living room, bedrooms, kitchen, bath), or in the style of the
furnished plans of real buildings (:data:`REAL_KINDS`): ``real_office``, whose rooms are
filled as those are (:func:`~sim_bridge.worlds.raster_furniture.furnish_real_room`:
desks and cabinets along the walls closing niches, table blocks in rings of chairs, table
rows with ~1 m aisles, shelf combs). It returns

* the **plain** map: the walls, every inside cell free (what the unfurnished floor plan
  looks like), with its room labels;
* the **furnished** map: furniture footprints drawn into the raster as a 2D lidar sees
  them (:mod:`~sim_bridge.worlds.raster_furniture`), then *scanned*: rays cast from
  robot viewpoints spread over the free space mark what a lidar would have seen; cells
  never seen stay unknown (-1), so solid blobs show only their visible faces, space
  behind furniture is partly unknown (occlusion) and a few salt specks are added;
  its room labels are the plain ones restricted to the furnished map's free cells.

:func:`furnished_set` lists the seeded evaluation set (kinds cycling).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from explore_seg.core.grid import GridMap
from sim_bridge.world import World
from sim_bridge.worlds.house import generate_house
from sim_bridge.worlds.raster_furniture import furnish_raster_room, furnish_real_room
from sim_bridge.worlds.truth import ground_truth

#: Floor-plan styles of :func:`furnished_map` (the default evaluation set cycles them).
MAP_KINDS = ("office", "open_office", "home")
#: Floor-plan styles furnished like real buildings' plans (``--kinds`` of the evaluation).
REAL_KINDS = ("real_office",)
#: Lidar range of the scan simulation (m) and viewpoints per square metre of free space.
SCAN_RANGE_M = 8.0
VIEWPOINTS_PER_M2 = 1 / 6.0
#: Door approach kept free of furniture (m).
DOOR_KEEPOUT_M = 0.9


@dataclass(frozen=True)
class FurnishedMap:
    """One floor plan, plain and furnished, with room ground truth (grid layout)."""

    name: str
    kind: str
    plain: GridMap                       # walls only: 0 inside, 100 walls, -1 outside
    plain_rooms: npt.NDArray[np.int32]   # room ids on the plain free cells, 0 elsewhere
    furnished: GridMap                   # furniture drawn in, scanned (-1 unseen)
    furnished_rooms: npt.NDArray[np.int32]
    room_kinds: dict[int, str]
    start_cell: tuple[int, int]


def _layout(seed: int, kind: str) -> World:
    rng = np.random.default_rng(10_000 + seed)
    if kind == "office":
        size = float(rng.choice([18.0, 20.0, 22.0]))
        return generate_house(seed, (size, size), room_width_m=(3.0, 6.0))
    if kind == "open_office":
        size = float(rng.choice([20.0, 22.0, 24.0]))
        return generate_house(seed, (size, size * 0.9), room_width_m=(5.0, 10.0),
                              split_depth_m=30.0, extra_door_prob=0.5)
    if kind == "home":
        w, h = float(rng.uniform(10.0, 14.0)), float(rng.uniform(9.0, 12.0))
        return generate_house(seed, (round(w), round(h)), room_width_m=(2.5, 5.0),
                              corridor_width_m=(1.35, 1.6), split_depth_m=5.0,
                              start_clearance_m=0.55)
    if kind == "real_office":
        size = float(rng.choice([18.0, 20.0, 22.0, 24.0]))
        return generate_house(seed, (size, size * 0.8), room_width_m=(3.0, 7.5),
                              extra_door_prob=0.2)
    raise ValueError(f"kind must be one of {MAP_KINDS + REAL_KINDS}, got {kind!r}")


def _walls_only(world: World) -> World:
    return World(name=world.name, bounds=world.bounds, start_pose=world.start_pose,
                 primitives=[p for p in world.primitives if p.cls == "wall"])


def _fill_labels(labels: npt.NDArray[np.int32], free: npt.NDArray[np.bool_]
                 ) -> npt.NDArray[np.int32]:
    """Room ids on every free cell: unlabelled free cells (under the layout's own
    furniture) take the id of the geodesically nearest labelled free cell."""
    out = np.where(free, labels, 0).astype(np.int32)
    todo = free & (out == 0)
    k = ndimage.generate_binary_structure(2, 1)
    for _ in range(200):
        if not todo.any():
            break
        grown = ndimage.grey_dilation(out, footprint=k)
        put = todo & (grown > 0)
        out[put] = grown[put]
        todo &= ~put
    return out


def _room_rect(mask: npt.NDArray[np.bool_]) -> tuple[int, int, int, int] | None:
    """Interior rectangle of a (nearly rectangular) room mask: rows / columns filled
    over more than half of the widest one (door cells stick out and are left out)."""
    rows = mask.sum(axis=1)
    cols = mask.sum(axis=0)
    if rows.max(initial=0) == 0:
        return None
    rr = np.flatnonzero(rows > 0.5 * rows.max())
    cc = np.flatnonzero(cols > 0.5 * cols.max())
    return int(rr[0]), int(cc[0]), int(rr[-1]) + 1, int(cc[-1]) + 1


def _room_kind(rng: np.random.Generator, kind: str, area_m2: float, is_corridor: bool,
               used: dict[str, int]) -> str:
    if is_corridor:
        return "corridor"
    if kind == "office":
        return "meeting" if rng.random() < 0.2 else "office"
    if kind == "open_office":
        if area_m2 > 30:
            return "open_office"
        return str(rng.choice(["office", "meeting"]))
    if area_m2 > 18 and used.get("living", 0) == 0:
        return "living"
    if area_m2 < 7:
        return "bath"
    if used.get("kitchen", 0) == 0:
        return "kitchen"
    return str(rng.choice(["bedroom", "bedroom", "living"]))


def _real_room_kind(rng: np.random.Generator, area_m2: float, is_corridor: bool) -> str:
    if is_corridor:
        return "corridor"
    if area_m2 < 8:
        return str(rng.choice(["store", "office"]))
    if area_m2 > 25:
        return str(rng.choice(["lab", "meeting", "lab"]))
    return str(rng.choice(["office", "office", "meeting", "lab", "store"]))


def scan(occ: npt.NDArray[np.bool_], inside: npt.NDArray[np.bool_],
         viewpoints: npt.NDArray[np.int64], range_cells: float, n_rays: int = 1440,
         ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Cells seen free and cells seen occupied by rays from ``viewpoints`` (row, col).

    Every ray stops at its first occupied cell (which is seen); cells outside ``inside``
    and not occupied stop rays too (the outside of the building).
    """
    h, w = occ.shape
    seen_free = np.zeros((h, w), bool)
    seen_occ = np.zeros((h, w), bool)
    steps = np.arange(0.0, range_cells, 0.7)
    ang = np.linspace(0, 2 * math.pi, n_rays, endpoint=False)
    dr, dc = np.sin(ang)[:, None] * steps, np.cos(ang)[:, None] * steps
    block = occ | ~inside
    for r0, c0 in viewpoints:
        rr = np.rint(r0 + dr).astype(np.int64)
        cc = np.rint(c0 + dc).astype(np.int64)
        out = (rr < 0) | (rr >= h) | (cc < 0) | (cc >= w)
        rr = np.clip(rr, 0, h - 1)
        cc = np.clip(cc, 0, w - 1)
        hit = block[rr, cc] | out
        first = np.where(hit.any(axis=1), hit.argmax(axis=1), steps.size)
        upto = np.arange(steps.size)[None, :] < first[:, None]
        seen_free[rr[upto], cc[upto]] = True
        k = np.flatnonzero(first < steps.size)
        hr, hc = rr[k, first[k]], cc[k, first[k]]
        ok = occ[hr, hc]
        seen_occ[hr[ok], hc[ok]] = True
    return seen_free & ~occ, seen_occ


def furnished_map(seed: int, kind: str) -> FurnishedMap:
    """One seeded floor plan of style ``kind``, plain and furnished (see the module).

    Raises
    ------
    ValueError
        On an unknown kind.
    """
    world = _layout(seed, kind)
    real = kind in REAL_KINDS
    rng = np.random.default_rng(seed * 7919 + (MAP_KINDS + REAL_KINDS).index(kind))
    walls = _walls_only(world)
    gt = ground_truth(walls)
    res = gt.resolution_m
    plain = gt.as_map("lidar")
    free = plain.data == 0
    rooms = _fill_labels(world.room_labels, free)
    # door approaches: free cells near a cell of another room
    k = ndimage.generate_binary_structure(2, 1)
    hi = ndimage.grey_dilation(rooms, footprint=k)
    lo = -ndimage.grey_dilation(-np.where(free, rooms, 1 << 20), footprint=k)
    door = free & ((hi != rooms) | (lo != rooms))
    keepout = ndimage.binary_dilation(door, iterations=int(round(DOOR_KEEPOUT_M / res)))
    occ = plain.data == 100
    kinds: dict[int, str] = {}
    used: dict[str, int] = {}
    for rid in (int(v) for v in np.unique(rooms) if v > 0):
        rect = _room_rect(rooms == rid)
        if rect is None:
            continue
        area = (rect[2] - rect[0]) * (rect[3] - rect[1]) * res * res
        corridor = world.room_kinds.get(rid) == "corridor"
        if real:
            kinds[rid] = _real_room_kind(rng, area, corridor)
            furnish_real_room(rng, occ, rect, keepout, kinds[rid], res)
            continue
        rk = _room_kind(rng, kind, area, corridor, used)
        used[rk] = used.get(rk, 0) + 1
        kinds[rid] = rk
        furnish_raster_room(rng, occ, rect, keepout, rk, res)
    # scan: viewpoints with clearance, reachable from the start
    start = gt.start_cell
    reach_free = ndimage.label(free & ~occ, structure=k)[0]
    reach = reach_free == reach_free[start]
    clear = ndimage.distance_transform_edt(~occ) * res >= 0.35
    vps = []
    for rid in kinds:       # every room gets viewpoints (a robot that mapped it was there)
        cand = np.argwhere(reach & clear & (rooms == rid))
        n_vp = max(2, int(len(cand) * res * res * VIEWPOINTS_PER_M2))
        if len(cand):
            vps.append(cand[rng.choice(len(cand), size=min(n_vp, len(cand)), replace=False)])
    if real:
        # real plans are drawn: furniture and walls occupied, everything else free
        seen_free, seen_occ = free & ~occ, occ & (gt.inside | (plain.data == 100))
    else:
        seen_free, seen_occ = scan(occ, gt.inside, np.concatenate(vps), SCAN_RANGE_M / res)
    data = np.full(occ.shape, -1, np.int8)
    data[seen_free] = 0
    data[seen_occ] = 100
    salt = seen_free & (rng.random(occ.shape) < (0.0 if real else 2e-4))
    data[salt] = 100
    furnished = plain.with_data(data)
    return FurnishedMap(name=f"{kind}_s{seed}", kind=kind, plain=plain,
                        plain_rooms=np.where(free, rooms, 0).astype(np.int32),
                        furnished=furnished,
                        furnished_rooms=np.where(data == 0, rooms, 0).astype(np.int32),
                        room_kinds=kinds, start_cell=start)


def furnished_set(n: int = 30, first_seed: int = 0,
                  kinds: tuple[str, ...] = MAP_KINDS) -> list[tuple[int, str]]:
    """(seed, kind) of the evaluation set: ``n`` maps, kinds cycling through ``kinds``
    (default :data:`MAP_KINDS`).

    Raises
    ------
    ValueError
        On an empty or unknown kind.
    """
    bad = [k for k in kinds if k not in MAP_KINDS + REAL_KINDS]
    if not kinds or bad:
        raise ValueError(f"kinds must be some of {MAP_KINDS + REAL_KINDS}, got {kinds!r}")
    return [(first_seed + i, kinds[i % len(kinds)]) for i in range(n)]
