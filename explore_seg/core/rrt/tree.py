"""A rapidly-exploring random tree grown over an occupancy grid toward unknown space
(Umari & Mukhopadhyay, IROS 2017; rrt_exploration's detectors).

One extension: a random sample, its nearest vertex, a step of at most ``eta`` toward it
(``x_new``), then the straight edge nearest -> x_new is walked in steps of a fifth of a
cell:

* it meets an obstacle cell (before any unknown cell): rejected;
* it reaches an unknown cell first: the point where it does is a **frontier point** (the
  tree does not grow; the local tree is then re-rooted by its owner);
* otherwise x_new becomes a vertex.

Edges are checked on the raw map (occupied / unknown cells), not on inflated obstacles:
the trees only look for frontier points, the robot never drives along them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import GridMap

#: Cell classes of :class:`CellClasses`.
FREE, OBSTACLE, UNKNOWN = 0, 1, 2
#: Edge walk step as a share of the cell size (rrt_exploration: 0.2).
EDGE_STEP_CELLS = 0.2


@dataclass(frozen=True)
class CellClasses:
    """One map's cells as FREE / OBSTACLE / UNKNOWN (int8) and its geometry.

    Build with :meth:`from_grid`; cells outside the grid count as unknown.
    """

    classes: npt.NDArray[np.int8]
    grid: GridMap

    @classmethod
    def from_grid(cls, grid: GridMap, occupied_threshold: int,
                  extra_obstacles: npt.NDArray[np.bool_] | None = None) -> "CellClasses":
        """Obstacle: map value >= ``occupied_threshold`` or ``extra_obstacles``; unknown:
        map value < 0; everything else free."""
        out = np.full(grid.shape, FREE, dtype=np.int8)
        out[grid.data < 0] = UNKNOWN
        blocked = grid.data >= occupied_threshold
        if extra_obstacles is not None:
            blocked = blocked | extra_obstacles
        out[blocked] = OBSTACLE
        return cls(out, grid)

    def at(self, xy_m: npt.NDArray[np.float64]) -> npt.NDArray[np.int8]:
        """Classes of the cells holding the world points ``xy_m`` (N, 2)."""
        g = self.grid
        r, c = g.world_to_cells(xy_m[:, 0], xy_m[:, 1])
        h, w = self.classes.shape
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        if inside.all():
            return self.classes[r, c]
        out = np.full(len(r), UNKNOWN, dtype=np.int8)
        out[inside] = self.classes[r[inside], c[inside]]
        return out


def walk_edge(a: tuple[float, float], b: tuple[float, float], cells: CellClasses
              ) -> tuple[int, tuple[float, float]]:
    """Walk the edge a -> b: (FREE, b), (OBSTACLE, b) or (UNKNOWN, first unknown point).

    An obstacle on the way before the first unknown cell makes the edge OBSTACLE.
    """
    length = math.hypot(b[0] - a[0], b[1] - a[1])
    step = EDGE_STEP_CELLS * cells.grid.resolution_m
    n = max(1, int(math.ceil(length / step)))
    t = np.arange(1, n + 1, dtype=np.float64) / n
    pts = np.empty((n, 2))
    pts[:, 0] = a[0] + t * (b[0] - a[0])
    pts[:, 1] = a[1] + t * (b[1] - a[1])
    cls = cells.at(pts)
    unknown = np.flatnonzero(cls == UNKNOWN)
    end = int(unknown[0]) if unknown.size else n - 1
    if np.any(cls[:end + 1] == OBSTACLE):
        return OBSTACLE, b
    if unknown.size:
        return UNKNOWN, (float(pts[end, 0]), float(pts[end, 1]))
    return FREE, b


class RrtTree:
    """A tree of 2D vertices (world metres) grown by :meth:`extend`.

    Parameters
    ----------
    root_xy_m : (float, float)
    eta_m : float
        Longest edge.
    """

    def __init__(self, root_xy_m: tuple[float, float], eta_m: float) -> None:
        self.eta_m = float(eta_m)
        self._v = np.zeros((64, 2))
        self._n = 0
        self.reset(root_xy_m)

    @property
    def vertices(self) -> npt.NDArray[np.float64]:
        """The vertices, shape (N, 2) (a view: copy to keep)."""
        return self._v[:self._n]

    def reset(self, root_xy_m: tuple[float, float]) -> None:
        """Drop every vertex; ``root_xy_m`` is the new root."""
        self._n = 0
        self._add(root_xy_m)

    def _add(self, xy: tuple[float, float]) -> None:
        if self._n == len(self._v):
            self._v = np.concatenate([self._v, np.zeros_like(self._v)])
        self._v[self._n] = xy
        self._n += 1

    def extend(self, sample_xy_m: tuple[float, float], cells: CellClasses
               ) -> tuple[int, tuple[float, float]]:
        """One extension toward ``sample_xy_m`` (see the module docstring).

        Returns
        -------
        (FREE | OBSTACLE | UNKNOWN, point)
            FREE: the new vertex; UNKNOWN: the frontier point; OBSTACLE: x_new (rejected).
        """
        v = self.vertices
        d2 = (v[:, 0] - sample_xy_m[0]) ** 2 + (v[:, 1] - sample_xy_m[1]) ** 2
        i = int(np.argmin(d2))
        nx, ny = float(v[i, 0]), float(v[i, 1])
        d = math.sqrt(float(d2[i]))
        if d <= self.eta_m:
            new = (float(sample_xy_m[0]), float(sample_xy_m[1]))
        else:
            s = self.eta_m / d
            new = (nx + (sample_xy_m[0] - nx) * s, ny + (sample_xy_m[1] - ny) * s)
        status, point = walk_edge((nx, ny), new, cells)
        if status == FREE:
            self._add(new)
        return status, point
