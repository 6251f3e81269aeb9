"""Furniture footprints drawn straight into an occupancy raster, as a 2D lidar sees them.

At the scan plane (~0.17 m) a lidar sees cupboards, shelves, beds, sofas and kitchen
counters as solid blobs, desks and tables as leg specks, drawer pedestals or side
panels, office chairs as a ring of five castor specks. :func:`furnish_raster_room`
fills one rectangular room of a raster with such items (offices, open-plan desk islands,
meeting rooms, homes), off the door keep-out cells.

Items are small uint8 stamps (1 = occupied) in cell units; items that stand against a
wall have their back on row 0 and are turned so that the back touches the wall.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Stamp = npt.NDArray[np.uint8]
#: Room kinds :func:`furnish_raster_room` knows.
ROOM_KINDS = ("office", "open_office", "meeting", "living", "bedroom", "kitchen", "bath",
              "corridor")
#: Room kinds of the ``real`` furnishing (:func:`furnish_real_room`), after the furnished
#: maps of real buildings: offices with desks and cabinets along the walls, meeting rooms
#: with a table block in a ring of chairs, labs with table rows and ~1 m aisles, store
#: rooms with shelves standing out from a wall.
REAL_ROOM_KINDS = ("office", "meeting", "lab", "store", "corridor")


def _cells(m: float, res: float) -> int:
    return max(1, int(round(m / res)))


def _speck(st: Stamp, r: int, c: int, t: int = 1) -> None:
    h, w = st.shape
    st[max(0, min(h - t, r)):max(0, min(h - t, r)) + t,
       max(0, min(w - t, c)):max(0, min(w - t, c)) + t] = 1


def _disc(st: Stamp, rc: float, cc: float, rad: float) -> None:
    rr, cc_ = np.ogrid[:st.shape[0], :st.shape[1]]
    st[(rr - rc) ** 2 + (cc_ - cc) ** 2 <= rad * rad] = 1


def _chair(rng: np.random.Generator, res: float) -> Stamp:
    """Office chair (five castor specks on a ring) or a four-legged chair."""
    n = _cells(0.62, res)
    st = np.zeros((n, n), np.uint8)
    c = (n - 1) / 2
    if rng.random() < 0.65:
        r = _cells(0.28, res)
        a0 = float(rng.uniform(0, 2 * math.pi))
        for k in range(5):
            a = a0 + 2 * math.pi * k / 5
            _speck(st, int(round(c + r * math.sin(a))), int(round(c + r * math.cos(a))))
    else:
        d = _cells(0.42, res)
        lo = int(round(c - d / 2))
        for r_ in (lo, lo + d - 1):
            for c_ in (lo, lo + d - 1):
                _speck(st, r_, c_)
    return st


def _desk(rng: np.random.Generator, depth: int, width: int, style: str) -> Stamp:
    """One desk seen from the scan plane, back on row 0."""
    st = np.zeros((depth, width), np.uint8)
    if style == "legs":
        for r in (0, depth - 1):
            for c in (0, width - 1):
                _speck(st, r, c, 2 if rng.random() < 0.5 else 1)
    elif style == "pedestal":          # drawer unit at one end, two legs at the other
        pw = min(width // 3, 9)
        left = rng.random() < 0.5
        c0 = 0 if left else width - pw
        st[1:depth - 1, c0:c0 + pw] = 1
        other = width - 1 if left else 0
        _speck(st, 0, other)
        _speck(st, depth - 1, other)
    else:                              # side panels (sled frames)
        st[:, :1] = 1
        st[:, -1:] = 1
    return st


def desk_row(rng: np.random.Generator, res: float, n: int, back_to_back: bool) -> Stamp:
    """``n`` desks side by side with chairs in front (both sides when back to back)."""
    depth = _cells(float(rng.uniform(0.6, 0.8)), res)
    width = _cells(float(rng.uniform(1.2, 1.6)), res)
    style = str(rng.choice(["legs", "pedestal", "panels"]))
    chair_zone = _cells(0.75, res)
    one = np.zeros((depth + chair_zone, n * width), np.uint8)
    for k in range(n):
        one[:depth, k * width:(k + 1) * width] |= _desk(rng, depth, width, style)
        if rng.random() < 0.85:
            ch = _chair(rng, res)
            r0 = depth + int(rng.integers(0, max(1, chair_zone - ch.shape[0])))
            c0 = k * width + (width - ch.shape[1]) // 2 + int(rng.integers(-3, 4))
            c0 = max(0, min(one.shape[1] - ch.shape[1], c0))
            one[r0:r0 + ch.shape[0], c0:c0 + ch.shape[1]] |= ch
        if rng.random() < 0.3:                           # a bin under the desk
            _disc(one, depth - 4, k * width + width // 2, _cells(0.13, res))
    if not back_to_back:
        return one
    other = desk_row(rng, res, n, False)[::-1]
    h = min(other.shape[1], one.shape[1])
    return np.vstack([other[:, :h], one[:, :h]])


def solid(rng: np.random.Generator, res: float, depth_m: tuple[float, float],
          length_m: tuple[float, float]) -> Stamp:
    """A solid blob (cupboard, shelf, counter, sofa, bed): depth x length."""
    return np.ones((_cells(float(rng.uniform(*depth_m)), res),
                    _cells(float(rng.uniform(*length_m)), res)), np.uint8)


def l_sofa(rng: np.random.Generator, res: float) -> Stamp:
    d = _cells(0.85, res)
    a, b = _cells(float(rng.uniform(1.8, 2.6)), res), _cells(float(rng.uniform(1.4, 2.0)), res)
    st = np.zeros((b, a), np.uint8)
    st[:d, :] = 1
    st[:, :d] = 1
    return st


def table(rng: np.random.Generator, res: float, chairs: int) -> Stamp:
    """A table (legs or a central pedestal) with chairs around it."""
    tl = _cells(float(rng.uniform(1.2, 2.4)), res)
    tw = _cells(float(rng.uniform(0.8, 1.1)), res)
    m = _cells(0.6, res)
    st = np.zeros((tw + 2 * m, tl + 2 * m), np.uint8)
    if rng.random() < 0.7:
        for r in (m, m + tw - 1):
            for c in (m, m + tl - 1):
                _speck(st, r, c, 2)
    else:
        _disc(st, m + tw / 2, m + tl / 2, _cells(0.2, res))
    for k in range(chairs):
        ch = _chair(rng, res)
        side = k % 2
        c0 = m + int(rng.integers(0, max(1, tl - ch.shape[1])))
        r0 = 0 if side == 0 else st.shape[0] - ch.shape[0]
        st[r0:r0 + ch.shape[0], c0:c0 + ch.shape[1]] |= ch
    return st


def small_disc(res: float, radius_m: float) -> Stamp:
    n = 2 * _cells(radius_m, res) + 1
    st = np.zeros((n, n), np.uint8)
    _disc(st, (n - 1) / 2, (n - 1) / 2, _cells(radius_m, res))
    return st


def _plan(rng: np.random.Generator, kind: str, res: float, area_m2: float
          ) -> list[tuple[Stamp, bool]]:
    """(stamp, against wall) items of a room kind, biggest first."""
    items: list[tuple[Stamp, bool]] = []
    cup = lambda: solid(rng, res, (0.35, 0.6), (0.8, 2.4))   # noqa: E731
    if kind == "office":
        for _ in range(int(rng.integers(1, 3))):
            items.append((desk_row(rng, res, int(rng.integers(1, 4)), False), True))
        items += [(cup(), True) for _ in range(int(rng.integers(1, 4)))]
        items += [(small_disc(res, 0.15), False) for _ in range(int(rng.integers(0, 3)))]
    elif kind == "open_office":
        n_isl = max(1, int(area_m2 / 22))
        for _ in range(n_isl):
            items.append((desk_row(rng, res, int(rng.integers(2, 5)), True), False))
        items += [(desk_row(rng, res, int(rng.integers(2, 4)), False), True)
                  for _ in range(int(rng.integers(0, 3)))]
        items += [(cup(), True) for _ in range(int(rng.integers(2, 6)))]
        items += [(solid(rng, res, (0.5, 0.6), (0.5, 0.7)), False)]      # printer
        items += [(small_disc(res, 0.2), False) for _ in range(int(rng.integers(1, 4)))]
    elif kind == "meeting":
        items.append((table(rng, res, int(rng.integers(2, 9))), False))
        items += [(cup(), True) for _ in range(int(rng.integers(0, 3)))]
    elif kind == "living":
        items.append((l_sofa(rng, res) if rng.random() < 0.4 else
                      solid(rng, res, (0.8, 0.95), (1.6, 2.3)), bool(rng.random() < 0.6)))
        items.append((solid(rng, res, (0.35, 0.5), (1.2, 2.0)), True))   # TV unit
        items.append((table(rng, res, 0), False))                         # coffee table
        items += [(solid(rng, res, (0.75, 0.85), (0.75, 0.85)), False)
                  for _ in range(int(rng.integers(0, 3)))]                # armchairs
        items += [(cup(), True) for _ in range(int(rng.integers(1, 3)))]
    elif kind == "bedroom":
        items.append((solid(rng, res, (1.95, 2.1), (0.9, 1.8)), True))   # bed, head to wall
        items.append((solid(rng, res, (0.55, 0.65), (1.0, 2.4)), True))  # wardrobe
        items += [(solid(rng, res, (0.35, 0.45), (0.4, 0.5)), True)
                  for _ in range(int(rng.integers(0, 3)))]                # nightstands
        items.append((desk_row(rng, res, 1, False), True))
    elif kind == "kitchen":
        items += [(solid(rng, res, (0.6, 0.65), (1.8, 3.4)), True) for _ in range(2)]
        items.append((table(rng, res, int(rng.integers(2, 5))), False))
        items.append((solid(rng, res, (0.6, 0.7), (0.6, 0.7)), True))    # fridge
    elif kind == "bath":
        items.append((solid(rng, res, (0.7, 0.8), (1.6, 1.8)), True))    # bath tub
        items.append((solid(rng, res, (0.45, 0.55), (0.6, 1.0)), True))  # basin unit
    elif kind == "corridor":
        if rng.random() < 0.5:
            items.append((solid(rng, res, (0.3, 0.4), (0.8, 1.6)), True))
        items += [(small_disc(res, 0.2), True) for _ in range(int(rng.integers(0, 2)))]
    else:
        raise ValueError(f"room kind must be one of {ROOM_KINDS}, got {kind!r}")
    return items


def _fits(taken: npt.NDArray[np.bool_], r: int, c: int, h: int, w: int, pad: int) -> bool:
    H, W = taken.shape
    if r < 0 or c < 0 or r + h > H or c + w > W:
        return False
    return not taken[max(0, r - pad):r + h + pad, max(0, c - pad):c + w + pad].any()


def furnish_raster_room(rng: np.random.Generator, occ: npt.NDArray[np.bool_],
                        rect: tuple[int, int, int, int], keepout: npt.NDArray[np.bool_],
                        kind: str, res: float, clearance_m: float = 0.7,
                        tries: int = 30) -> int:
    """Draw the furniture of one room into ``occ`` (in place); returns items placed.

    Parameters
    ----------
    rng : numpy.random.Generator
    occ : ndarray of bool, shape (H, W)
        Occupancy raster (True = occupied at the scan plane), modified in place.
    rect : (r0, c0, r1, c1)
        The room's free interior in cells (end exclusive).
    keepout : ndarray of bool, shape (H, W)
        Cells no furniture may cover (door approaches).
    kind : str
        One of :data:`ROOM_KINDS`.
    res : float
        Metres per cell.
    clearance_m : float
        Free gap kept between items (a free-standing item keeps it to the walls too).
    tries : int
        Placement attempts per item; an item without a free spot is dropped.
    """
    r0, c0, r1, c1 = rect
    if r1 - r0 < 4 or c1 - c0 < 4:
        return 0
    area = (r1 - r0) * (c1 - c0) * res * res
    taken = keepout[r0:r1, c0:c1].copy()
    sub = occ[r0:r1, c0:c1]
    pad = _cells(clearance_m, res)
    H, W = taken.shape
    placed = 0
    for stamp, wall in _plan(rng, kind, res, area):
        for _ in range(tries):
            k = int(rng.integers(4))
            st = np.rot90(stamp, k)
            h, w = st.shape
            if wall:     # k=0: back on row 0 (north... low rows), 1: left, 2: bottom, 3: right
                if k == 0:
                    r, c = 0, int(rng.integers(0, max(1, W - w + 1)))
                elif k == 1:
                    r, c = int(rng.integers(0, max(1, H - h + 1))), 0
                elif k == 2:
                    r, c = H - h, int(rng.integers(0, max(1, W - w + 1)))
                else:
                    r, c = int(rng.integers(0, max(1, H - h + 1))), W - w
                # along the wall, neighbours may touch (rows of cupboards); keep the pad
                # in front only through the taken-mask check with a small pad
                ok = _fits(taken, r, c, h, w, pad // 3)
            else:
                r = int(rng.integers(pad, max(pad + 1, H - h - pad + 1)))
                c = int(rng.integers(pad, max(pad + 1, W - w - pad + 1)))
                ok = r + h + pad <= H and c + w + pad <= W and _fits(taken, r, c, h, w, pad)
            if not ok:
                continue
            sub[r:r + h, c:c + w] |= st.astype(bool)
            taken[r:r + h, c:c + w] = True
            placed += 1
            break
    return placed


def _disc_chair(res: float) -> Stamp:
    """A chair drawn as one solid disc (0.35 to 0.45 m), as on real furnished plans."""
    return small_disc(res, 0.2)


def _ring_chair(rng: np.random.Generator, res: float) -> Stamp:
    return _disc_chair(res) if rng.random() < 0.5 else _chair(rng, res)


def table_block(rng: np.random.Generator, res: float, length_m: float, width_m: float
                ) -> Stamp:
    """A block of tables (legs, or solid as drawn on plans) in a ring of chairs 0.1 to
    0.2 m off its edges, 0.55 to 0.8 m apart: the free space round it is a ring."""
    tl, tw = _cells(length_m, res), _cells(width_m, res)
    m = _cells(0.6, res)
    st = np.zeros((tw + 2 * m, tl + 2 * m), np.uint8)
    if rng.random() < 0.5:
        for r in (m, m + tw - 1):
            for c in range(m, m + tl, _cells(1.2, res)):
                _speck(st, r, c, 2)
            _speck(st, r, m + tl - 1, 2)
    else:
        st[m:m + tw, m:m + tl] = 1
    gap = float(rng.uniform(0.55, 0.8))
    for horizontal, span in ((True, tl), (False, tw)):
        n = max(1, int(span * res / gap))
        for k in range(n):
            off = m + int(round((k + 0.5) * span / n))
            for far in (False, True):
                ch = _ring_chair(rng, res)
                h, w = ch.shape
                if horizontal:
                    r0 = st.shape[0] - h if far else 0
                    c0 = max(0, min(st.shape[1] - w, off - w // 2))
                else:
                    r0 = max(0, min(st.shape[0] - h, off - h // 2))
                    c0 = st.shape[1] - w if far else 0
                st[r0:r0 + h, c0:c0 + w] |= ch
    return st


@dataclass(frozen=True)
class WallRun:
    """Furniture along a wall: item depth range (m), gap range between items (m), the
    share of the slots that hold an item, and whether chairs stand in front."""

    depth_m: tuple[float, float]
    gap_m: tuple[float, float]
    fill: float
    chairs: bool = False


def _wall_run(rng: np.random.Generator, res: float, length: int, run: WallRun) -> Stamp:
    """Cabinets, desks and shelves along one wall (back on row 0), ``run.fill`` of the
    slots taken, with gaps between them: the niches that furniture against walls closes."""
    depth = _cells(float(rng.uniform(*run.depth_m)), res)
    st = np.zeros((depth, length), np.uint8)
    c = int(rng.integers(0, max(1, _cells(1.0, res))))
    while c < length:
        w = _cells(float(rng.uniform(0.8, 2.0)), res)
        if rng.random() < run.fill:
            d = min(depth, _cells(float(rng.uniform(*run.depth_m)), res))
            st[:d, c:min(length, c + w)] = 1
        c += w + _cells(float(rng.uniform(*run.gap_m)), res)
    return st


def _put(sub: npt.NDArray[np.bool_], taken: npt.NDArray[np.bool_], st: Stamp, r: int, c: int
         ) -> None:
    """Draw ``st`` at (r, c) (clamped into the room), less the ``taken`` cells (door
    approaches): a row of tables is shortened where it would block a door."""
    h, w = st.shape
    H, W = sub.shape
    st = st[:H, :W]
    h, w = st.shape
    r, c = max(0, min(H - h, r)), max(0, min(W - w, c))
    sub[r:r + h, c:c + w] |= (st > 0) & ~taken[r:r + h, c:c + w]


def _along_walls(rng: np.random.Generator, sub: npt.NDArray[np.bool_],
                 taken: npt.NDArray[np.bool_], res: float, walls: int, spec: WallRun
                 ) -> None:
    """Runs of furniture along ``walls`` of the room's four walls (chairs in front)."""
    H, W = sub.shape
    for side in rng.permutation(4)[:walls]:
        length = W if side in (0, 2) else H
        run = _wall_run(rng, res, length, spec)
        st = np.rot90(run, int(side))
        r = H - st.shape[0] if side == 2 else 0
        c = W - st.shape[1] if side == 3 else 0
        mask = st & ~taken[r:r + st.shape[0], c:c + st.shape[1]].astype(np.uint8)
        sub[r:r + st.shape[0], c:c + st.shape[1]] |= mask.astype(bool)
        if not spec.chairs:
            continue
        d = run.shape[0]
        for k in range(int(length * res / 1.5)):
            ch = _ring_chair(rng, res)
            along = int(rng.integers(0, max(1, length - ch.shape[1])))
            out = d + int(rng.integers(1, _cells(0.3, res) + 1))
            if side == 0:
                _put(sub, taken, ch, out, along)
            elif side == 2:
                _put(sub, taken, ch, H - out - ch.shape[0], along)
            elif side == 1:
                _put(sub, taken, ch, along, out)
            else:
                _put(sub, taken, ch, along, W - out - ch.shape[1])


def furnish_real_room(rng: np.random.Generator, occ: npt.NDArray[np.bool_],
                      rect: tuple[int, int, int, int], keepout: npt.NDArray[np.bool_],
                      kind: str, res: float) -> None:
    """Draw the furniture of one room of kind ``kind`` (:data:`REAL_ROOM_KINDS`) into
    ``occ`` (in place), after the furnished plans of real buildings: the room is filled
    with it, not dotted.

    * ``office``: desks, cabinets and shelves along two or three walls with gaps (niches)
      between them, chairs in front, a few free chairs;
    * ``meeting``: a table block in a ring of chairs, 0.8 to 1.2 m off the walls (the
      free space is a ring round it), cabinets along a wall;
    * ``lab``: rows of tables across the room with ~1 m aisles, one end of every row
      against a wall, a walkway at the other end, chairs in the aisles;
    * ``store``: shelves standing out 1 to 1.6 m from a wall, ~1 m apart (a comb);
    * ``corridor``: a cabinet now and then.

    Parameters are those of :func:`furnish_raster_room`.

    Raises
    ------
    ValueError
        On an unknown kind.
    """
    if kind not in REAL_ROOM_KINDS:
        raise ValueError(f"real room kind must be one of {REAL_ROOM_KINDS}, got {kind!r}")
    r0, c0, r1, c1 = rect
    if r1 - r0 < 8 or c1 - c0 < 8:
        return
    sub = occ[r0:r1, c0:c1]
    taken = keepout[r0:r1, c0:c1]
    H, W = sub.shape
    before = sub.copy()
    if kind == "office":
        _along_walls(rng, sub, taken, res, int(rng.integers(2, 4)),
                     WallRun((0.4, 0.8), (0.2, 1.0), 0.8, chairs=True))
        for _ in range(int(rng.integers(0, 3))):
            ch = _ring_chair(rng, res)
            _put(sub, taken, ch, int(rng.integers(0, H)), int(rng.integers(0, W)))
    elif kind == "meeting":
        clear = _cells(float(rng.uniform(0.8, 1.2)), res) + _cells(0.6, res)
        tl = max(_cells(1.2, res), W - 2 * clear - 2 * _cells(0.6, res))
        tw = max(_cells(0.9, res), H - 2 * clear - 2 * _cells(0.6, res))
        if rng.random() < 0.5:
            _along_walls(rng, sub, taken, res, 1, WallRun((0.4, 0.5), (0.3, 1.0), 0.7))
        st = table_block(rng, res, tl * res, tw * res)
        _put(sub, taken, st, (H - st.shape[0]) // 2, (W - st.shape[1]) // 2)
    elif kind == "lab":
        across = W >= H                     # rows run along the longer side
        n_len, n_cross = (W, H) if across else (H, W)
        walk = _cells(float(rng.uniform(0.9, 1.3)), res)
        pos = _cells(float(rng.uniform(0.3, 0.9)), res)
        end_wall = bool(rng.random() < 0.5)
        while pos < n_cross - _cells(0.6, res):
            depth = _cells(float(rng.uniform(0.6, 0.8)), res)
            zone = _cells(0.5, res)
            row = np.zeros((depth + zone, n_len - walk), np.uint8)
            if rng.random() < 0.5:
                row[:depth] = 1
            else:
                for c in [*range(0, row.shape[1], _cells(1.4, res)), row.shape[1] - 1]:
                    _speck(row, 0, c, 2)
                    _speck(row, depth - 1, c, 2)
            for c in range(_cells(0.3, res), row.shape[1] - _cells(0.6, res), _cells(1.2, res)):
                if rng.random() < 0.6:
                    ch = _ring_chair(rng, res)[:zone, :row.shape[1] - c]
                    row[depth:depth + ch.shape[0], c:c + ch.shape[1]] |= ch
            if not end_wall:
                row = row[:, ::-1]
            st = row if across else row.T
            if across:
                _put(sub, taken, st, pos, 0 if end_wall else walk)
            else:
                _put(sub, taken, st, 0 if end_wall else walk, pos)
            pos += row.shape[0] + _cells(float(rng.uniform(0.9, 1.2)), res)
    elif kind == "store":
        along_w = W >= H
        n_len = W if along_w else H
        depth_in = _cells(float(rng.uniform(1.0, 1.6)), res)
        thick = _cells(float(rng.uniform(0.2, 0.4)), res)
        c = _cells(float(rng.uniform(0.8, 1.2)), res)
        while c < n_len - _cells(0.8, res):
            st = np.ones((depth_in, thick), np.uint8)
            if along_w:
                _put(sub, taken, st, 0, c)
            else:
                _put(sub, taken, st.T, c, 0)
            c += thick + _cells(float(rng.uniform(0.9, 1.2)), res)
    elif kind == "corridor":
        if rng.random() < 0.5:
            _along_walls(rng, sub, taken, res, 1, WallRun((0.3, 0.4), (2.0, 5.0), 0.4))
    # the door approaches stay free
    sub &= ~(taken & ~before)
