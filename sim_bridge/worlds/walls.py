"""Wall centre lines with door gaps, turned into wall boxes (shared by houses and mazes)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from explore_seg.core.grid import metres_to_cells
from sim_bridge.world import Primitive
from sim_bridge.worlds.truth import GT_RESOLUTION_M

@dataclass
class Wall:
    """A straight wall on a centre line from (x0, y0) to (x1, y1) with door gaps.

    ``doors`` holds (s0, s1) distances from (x0, y0) along the line.
    """

    x0: float
    y0: float
    x1: float
    y1: float
    doors: list[tuple[float, float]] = field(default_factory=list)

    @property
    def length(self) -> float:
        return math.hypot(self.x1 - self.x0, self.y1 - self.y0)

    def boxes(self, name: str, thickness: float, height: float, lintel_z: float | None
              ) -> list[Primitive]:
        """Solid wall pieces between the doors (extended by half a thickness at the two
        ends so corners close) and optional lintels over the doors."""
        length = self.length
        ux, uy = (self.x1 - self.x0) / length, (self.y1 - self.y0) / length
        yaw = math.atan2(uy, ux)
        if yaw > math.pi / 2 + 1e-9 or yaw < -math.pi / 2 - 1e-9:
            yaw = math.atan2(-uy, -ux)
        pieces: list[tuple[float, float, float, float]] = []
        start = -thickness / 2
        for d0, d1 in sorted(self.doors):
            pieces.append((start, d0, 0.0, height))
            if lintel_z is not None:
                pieces.append((d0, d1, lintel_z, height))
            start = d1
        pieces.append((start, length + thickness / 2, 0.0, height))
        out = []
        for s0, s1, z0, z1 in pieces:
            if s1 - s0 <= 1e-6:
                continue
            mid = 0.5 * (s0 + s1)
            out.append(Primitive(name, "wall", "wall", "box", self.x0 + ux * mid,
                                 self.y0 + uy * mid, yaw, (s1 - s0, thickness), z0, z1))
        return out


def add_door(walls: list[Wall], p0: tuple[float, float], p1: tuple[float, float]) -> bool:
    """Cut a door from p0 to p1 into the wall whose centre line holds both points."""
    for w in walls:
        length = w.length
        ux, uy = (w.x1 - w.x0) / length, (w.y1 - w.y0) / length
        ok = True
        ss = []
        for px, py in (p0, p1):
            dx, dy = px - w.x0, py - w.y0
            if abs(dx * uy - dy * ux) > 1e-6:
                ok = False
                break
            ss.append(dx * ux + dy * uy)
        if not ok or min(ss) < -1e-6 or max(ss) > length + 1e-6:
            continue
        w.doors.append((min(ss), max(ss)))
        return True
    return False


def bounds_around(xmin: float, ymin: float, xmax: float, ymax: float, margin: float
                  ) -> tuple[float, float, float, float]:
    """Bounds around a box, grown by ``margin`` and snapped outwards to the ground-truth
    raster (:data:`~sim_bridge.worlds.truth.GT_RESOLUTION_M`)."""
    step = GT_RESOLUTION_M
    return (round(metres_to_cells(xmin - margin, step) * step, 6),
            round(metres_to_cells(ymin - margin, step) * step, 6),
            round(math.ceil((xmax + margin) / step - 1e-9) * step, 6),
            round(math.ceil((ymax + margin) / step - 1e-9) * step, 6))
