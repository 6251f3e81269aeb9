"""Blacklisted goals, and the map near each as it was when the goal was blacklisted.

A goal is blacklisted when it failed on the map of that moment: the navigator aborted, the
robot got no closer, or its frontier remained after the robot got there. On a SLAM map
that moment's map is often wrong near the goal: a doorway closed by a wall mapped twice,
speckle, a frontier in a blurred wall. Later scans (a look from elsewhere, a keyframe
from a turn) and loop-closure re-renders change the map there, and the goal may succeed.

:class:`Blacklist` keeps the goals (newest ``maxlen``) and, per goal, the map's **content
near it**: the numbers of occupied and of unknown cells within a radius, taken on the
first map :meth:`Blacklist.changed` sees after the goal was added. A count-based
signature ignores where in the window a cell lies, so a re-render that shifts the map a
few centimetres changes it little; a doorway that opens (occupied cells gone) or space
seen (unknown cells gone) changes it. :meth:`Blacklist.changed` returns the goals whose
content changed by at least a given number of cells (the goal manager then drops them,
so their frontiers are candidates again).

Examples
--------
>>> from explore_seg.core.grid import GridMap
>>> data = np.zeros((40, 40), np.int8); data[20, 10:30] = 100; data[25:, :] = -1
>>> g = GridMap(data, 0.05, (0.0, 0.0))
>>> bl = Blacklist(10)
>>> bl.add((1.0, 1.0))
>>> bl.changed(g, 0.5, 65, 10)           # the first map: the signature is taken
[]
>>> data2 = data.copy(); data2[20, 15:25] = 0   # a gap opens in the wall near the goal
>>> bl.changed(g.with_data(data2), 0.5, 65, 10)
[(1.0, 1.0)]
"""

from __future__ import annotations

from collections import deque
from typing import Iterator, Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap
from explore_seg.core.selection.areas import AreaCounts


def near_counts(grid: GridMap, xy_m: tuple[float, float], radius_m: float,
                occupied_threshold: int) -> tuple[int, int]:
    """(occupied, unknown) cells of ``grid`` within ``radius_m`` of ``xy_m`` (cells outside
    the map count as unknown)."""
    r0, c0 = grid.world_to_cell(*xy_m)
    k = int(np.ceil(radius_m / grid.resolution_m))
    rr, cc = np.mgrid[r0 - k:r0 + k + 1, c0 - k:c0 + k + 1]
    disc = (rr - r0) ** 2 + (cc - c0) ** 2 <= k * k
    rr, cc = rr[disc], cc[disc]
    inside = (rr >= 0) & (rr < grid.height) & (cc >= 0) & (cc < grid.width)
    vals = grid.data[rr[inside], cc[inside]]
    occupied = int(np.count_nonzero(vals >= occupied_threshold))
    unknown = int(np.count_nonzero(vals < 0)) + int(np.count_nonzero(~inside))
    return occupied, unknown


def near_any(points_xy_m: npt.ArrayLike, others_xy_m: npt.ArrayLike, radius_m: float
             ) -> npt.NDArray[np.bool_]:
    """For each point (shape (N, 2)): does one of ``others`` (shape (M, 2)) lie within
    ``radius_m``?

    >>> near_any([[0.0, 0.0], [2.0, 0.0]], [[0.3, 0.4]], 0.5).tolist()
    [True, False]
    """
    pts = np.asarray(points_xy_m, dtype=np.float64).reshape(-1, 2)
    others = np.asarray(others_xy_m, dtype=np.float64).reshape(-1, 2)
    if not len(pts) or not len(others):
        return np.zeros(len(pts), dtype=bool)
    d2 = ((pts[:, None, :] - others[None, :, :]) ** 2).sum(axis=2)
    return (d2 <= radius_m ** 2).any(axis=1)


class Blacklist:
    """Blacklisted goal points (newest ``maxlen``), with the map's content near each."""

    def __init__(self, maxlen: int) -> None:
        self._pts: deque[tuple[float, float]] = deque(maxlen=maxlen)
        self._content: dict[tuple[float, float], tuple[int, int]] = {}
        #: Points ever added (callers count new ones by difference).
        self.added = 0
        #: Changes with every addition, removal or clearing.
        self.version = 0
        self._checked: tuple[GridMap, int] | None = None   # the last call's map and version

    def __len__(self) -> int:
        return len(self._pts)

    def __iter__(self) -> Iterator[tuple[float, float]]:
        return iter(self._pts)

    def add(self, xy_m: tuple[float, float]) -> None:
        """Blacklist a point."""
        self._pts.append((float(xy_m[0]), float(xy_m[1])))
        self.added += 1
        self.version += 1

    def clear(self) -> None:
        """Forget every point."""
        self._pts.clear()
        self._content.clear()
        self.version += 1

    def resize(self, maxlen: int) -> None:
        """Keep the newest ``maxlen`` points."""
        self._pts = deque(self._pts, maxlen=maxlen)
        self.version += 1

    def remove(self, xy_m: tuple[float, float]) -> None:
        """Drop every entry at ``xy_m``."""
        self._pts = deque((p for p in self._pts if p != xy_m), maxlen=self._pts.maxlen)
        self._content.pop(xy_m, None)
        self.version += 1

    def excluded(self, points_xy_m: npt.NDArray[np.float64], radius_m: float
                 ) -> npt.NDArray[np.bool_]:
        """For each point (shape (N, 2)): is a blacklisted point within ``radius_m``?"""
        return near_any(points_xy_m, list(self._pts), radius_m)

    def changed(self, grid: GridMap, radius_m: float, occupied_threshold: int,
                min_cells: int) -> list[tuple[float, float]]:
        """The points whose occupied plus unknown cell counts within ``radius_m``
        (:func:`near_counts`) differ by at least ``min_cells`` from those of the first map
        this saw after the point was added (that map's counts are taken now for the
        points new since the last call). The points stay blacklisted. Call it with every
        decision's map: the same map object as the last call's, with no point added or
        removed since, returns [] at once."""
        if self._checked is not None and grid is self._checked[0] \
                and self.version == self._checked[1]:
            return []                   # nothing new since the last call
        self._checked = (grid, self.version)
        out = []
        content = {}
        for xy in dict.fromkeys(self._pts):
            now = near_counts(grid, xy, radius_m, occupied_threshold)
            then = content[xy] = self._content.get(xy, now)
            if abs(now[0] - then[0]) + abs(now[1] - then[1]) >= min_cells:
                out.append(xy)
        self._content = content         # points dropped from the deque are forgotten
        return out

    def drop_changed(self, grid: GridMap, near: tuple[float, int, int], areas: AreaCounts,
                     limit: int) -> int:
        """Drop the points that :meth:`changed` returns for ``near`` = (radius_m,
        occupied_threshold, min_cells), at most ``limit`` times per area of ``areas``
        (counted there). Returns how many were dropped."""
        radius_m = near[0]
        n = 0
        for xy in self.changed(grid, *near):
            if areas.count_near(xy, radius_m) < limit:
                areas.note(xy, radius_m)
                self.remove(xy)
                n += 1
        return n


class RevealWatch:
    """How much of the map near the goals of the last blacklist retry became known since.

    The blacklist retry (:meth:`.goals.GoalManager.step`) is free when it revealed space;
    counted over the whole map, a loop-closure re-render that shifts the map (walls
    redrawn a few centimetres over, blurred edges) would count as revealed space, and a
    retry whose goals stayed as they were would not be spent. :meth:`start` takes the
    unknown cells within ``radius_m`` of each retried goal (:func:`near_counts`; a cell
    near two goals counts twice, on both maps alike), :meth:`revealed_m2` how many of
    them are known now. ``radius_m`` 0: the cells that became known anywhere on the map.
    """

    def __init__(self, radius_m: float) -> None:
        self.radius_m = float(radius_m)
        self._points: tuple[tuple[float, float], ...] = ()
        self._unknown: int | None = None

    def _unknown_near(self, grid: GridMap) -> int:
        if self.radius_m <= 0:          # the whole map: minus its known cells
            return -int(np.count_nonzero(grid.data >= 0))
        return sum(near_counts(grid, xy, self.radius_m, 101)[1] for xy in self._points)

    def start(self, grid: GridMap, points: Sequence[tuple[float, float]]) -> None:
        """A retry of the goals ``points`` begins on ``grid``."""
        self._points = tuple(dict.fromkeys(points))
        self._unknown = self._unknown_near(grid)

    def revealed_m2(self, grid: GridMap) -> float:
        """Area near the last retry's goals known now and unknown when it began (0
        before any retry)."""
        if self._unknown is None:
            return 0.0
        return (self._unknown - self._unknown_near(grid)) * grid.resolution_m ** 2


__all__ = ["Blacklist", "RevealWatch", "near_any", "near_counts"]
