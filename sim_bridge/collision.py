"""Collision checking of the robot's disk against the world's solids."""

from __future__ import annotations

import math

import numpy as np

from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap
from sim_bridge.navigation.clearance import edge_distances
from sim_bridge.world import World


class Collider:
    """Disk-vs-world overlap tests for the robot body.

    Parameters
    ----------
    world : World
    radius_m : float
        Robot disk radius.
    height_m : float
        Primitives with ``zmin < height_m`` collide; a map-only world's occupied cells
        (``base_grid``) always do.
    """

    def __init__(self, world: World, radius_m: float, height_m: float) -> None:
        self.radius_m = float(radius_m)
        prims = [p for p in world.primitives if p.zmin < height_m]
        boxes = [p for p in prims if p.shape == "box"]
        cyls = [p for p in prims if p.shape == "cylinder"]
        self._boxes = boxes
        self._cyls = cyls
        self._bx = np.array([[p.x, p.y, math.cos(p.yaw), math.sin(p.yaw),
                              p.size[0] / 2.0, p.size[1] / 2.0] for p in boxes],
                            dtype=np.float64).reshape(-1, 6)
        self._cy = np.array([[p.x, p.y, p.size[0]] for p in cyls],
                            dtype=np.float64).reshape(-1, 3)
        # Map-only worlds carry their occupied cells as wall boxes too; the raster is
        # used only when a world has no primitives at all.
        self._grid: GridMap | None = None
        if world.base_grid is not None and not world.primitives:
            self._grid = world.base_grid  # type: ignore[assignment]

    def clearance(self, x: float, y: float) -> tuple[float, str, str, str]:
        """Distance from (x, y) to the nearest solid, and that solid's object/class/part.

        Returns ``(inf, "", "", "")`` in an empty world. Inside a solid the distance is 0.
        """
        best = (math.inf, "", "", "")
        if len(self._bx):
            b = self._bx
            dx, dy = x - b[:, 0], y - b[:, 1]
            u = np.abs(dx * b[:, 2] + dy * b[:, 3]) - b[:, 4]
            v = np.abs(-dx * b[:, 3] + dy * b[:, 2]) - b[:, 5]
            d = np.hypot(np.maximum(u, 0.0), np.maximum(v, 0.0))
            i = int(np.argmin(d))
            if d[i] < best[0]:
                p = self._boxes[i]
                best = (float(d[i]), p.object, p.cls, p.part)
        if len(self._cy):
            c = self._cy
            d = np.maximum(np.hypot(x - c[:, 0], y - c[:, 1]) - c[:, 2], 0.0)
            i = int(np.argmin(d))
            if d[i] < best[0]:
                p = self._cyls[i]
                best = (float(d[i]), p.object, p.cls, p.part)
        if self._grid is not None:
            d = self._grid_clearance(x, y)
            if d < best[0]:
                best = (d, "map", "wall", "cell")
        return best

    def nearest_point(self, x: float, y: float) -> tuple[float, float, str, str, str]:
        """The point of the nearest solid closest to (x, y), with that solid's
        object/class/part: ``(px, py, object, cls, part)`` (where a contact touched).

        ``(nan, nan, "", "", "")`` in an empty world; inside a solid the point is (x, y).
        """
        best_d, out = math.inf, (math.nan, math.nan, "", "", "")
        for p in self._boxes:
            c, s = math.cos(p.yaw), math.sin(p.yaw)
            dx, dy = x - p.x, y - p.y
            u = max(-p.size[0] / 2.0, min(p.size[0] / 2.0, dx * c + dy * s))
            v = max(-p.size[1] / 2.0, min(p.size[1] / 2.0, -dx * s + dy * c))
            px, py = p.x + u * c - v * s, p.y + u * s + v * c
            d = math.hypot(x - px, y - py)
            if d < best_d:
                best_d, out = d, (px, py, p.object, p.cls, p.part)
        for p in self._cyls:
            dc = math.hypot(x - p.x, y - p.y)
            k = min(1.0, p.size[0] / dc) if dc > 0 else 0.0
            px, py = p.x + (x - p.x) * k, p.y + (y - p.y) * k
            d = max(dc - p.size[0], 0.0)
            if d < best_d:
                best_d, out = d, (px, py, p.object, p.cls, p.part)
        if self._grid is not None:
            g = self._grid
            rr, cc = np.nonzero(g.data >= OCCUPIED_THRESHOLD)
            if rr.size:
                wx, wy = g.cells_to_world(rr, cc)
                d = np.hypot(wx - x, wy - y)
                i = int(np.argmin(d))
                if d[i] < best_d:
                    out = (float(wx[i]), float(wy[i]), "map", "wall", "cell")
        return out

    def _grid_clearance(self, x: float, y: float) -> float:
        """Distance to the nearest occupied cell square within the radius (inf if none)."""
        g = self._grid
        assert g is not None
        res = g.resolution_m
        rad = int(math.ceil(self.radius_m / res)) + 1
        r, c = g.world_to_cell(x, y)
        r0, r1 = max(0, r - rad), min(g.height, r + rad + 1)
        c0, c1 = max(0, c - rad), min(g.width, c + rad + 1)
        if r0 >= r1 or c0 >= c1:
            return math.inf
        fr, fc = g.world_to_cell_float(x, y)
        return float(edge_distances(g.data[r0:r1, c0:c1] >= OCCUPIED_THRESHOLD, r0, c0,
                                    np.atleast_1d(fr), np.atleast_1d(fc), res, math.inf)[0])

    def overlaps(self, x: float, y: float) -> bool:
        """True when the robot disk at (x, y) overlaps a solid."""
        return self.clearance(x, y)[0] < self.radius_m
