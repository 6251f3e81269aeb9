"""Run metrics of the simulator: coverage, path length, collisions, goals.

Coverage is the share of the ground-truth explorable area (``GroundTruth.explorable``:
free cells reachable from the start in the lidar raster that a robot can observe from
some pose it can reach, see :mod:`sim_bridge.observable`) whose cell centre falls on a cell
the map knows (free or occupied): what the robot has observed. ``coverage_free_pct``
counts only map cells known free; it is lower by the inside cells the mapper marks
occupied (next to walls and thin legs the lidar's hit cells smear over the ground-truth
raster's free cells: 1-2 % in worlds full of chair and table legs), a mapping-accuracy
figure rather than an exploration one, so runs are judged on ``coverage_pct``. Grids are
compared through world coordinates, so the map may have any origin; when both grids
share the resolution lattice (the usual case) the comparison is a plain array slice.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import FREE_THRESHOLD, GridMap


@dataclass(frozen=True)
class CollisionEvent:
    """One contact: sim time, robot position (base_footprint) and what was hit; the
    commanded forward speed at the blocked step (negative: reversing) and whether the
    robot was backing off after an earlier contact."""

    t_s: float
    x_m: float
    y_m: float
    object: str
    cls: str
    part: str
    speed_mps: float = 0.0
    backing: bool = False


class CoverageReference:
    """The ground-truth explorable cells with their geometry, for fast comparisons.

    Parameters
    ----------
    inside : ndarray of bool, shape (H, W)
        Explorable cells, aligned with ``geometry``.
    geometry : GridMap
        Geometry of ``inside`` (its data is ignored).

    Raises
    ------
    ValueError
        When the shapes differ or no cell is inside.
    """

    def __init__(self, inside: npt.NDArray[np.bool_], geometry: GridMap) -> None:
        inside = np.asarray(inside, dtype=bool)
        if inside.shape != geometry.shape:
            raise ValueError(f"inside mask shape {inside.shape} differs from its grid "
                             f"{geometry.shape}")
        self.total_cells = int(inside.sum())
        if self.total_cells == 0:
            raise ValueError("ground truth has no explorable (inside) cell")
        self.inside = inside
        self.geometry = geometry
        rows, cols = np.nonzero(inside)
        self._xy = geometry.cells_to_world(rows, cols)

    @property
    def area_m2(self) -> float:
        """Explorable area in square metres."""
        return self.total_cells * self.geometry.resolution_m ** 2

    def _aligned_offset(self, grid: GridMap) -> tuple[int, int] | None:
        """(drow, dcol) with grid cell = ref cell + offset, when both share a lattice."""
        ref = self.geometry
        if (abs(grid.resolution_m - ref.resolution_m) > 1e-9 or grid.origin_yaw_rad != 0.0
                or ref.origin_yaw_rad != 0.0):
            return None
        dc = (ref.origin_xy_m[0] - grid.origin_xy_m[0]) / ref.resolution_m
        dr = (ref.origin_xy_m[1] - grid.origin_xy_m[1]) / ref.resolution_m
        if abs(dc - round(dc)) > 1e-4 or abs(dr - round(dr)) > 1e-4:
            return None
        return int(round(dr)), int(round(dc))

    def values_at_inside(self, grid: GridMap) -> npt.NDArray[np.int8]:
        """The map's value at every inside cell (``-1`` where the map does not reach).

        Returns
        -------
        ndarray of int8, shape (H, W)
            Aligned with ``inside``; cells that are not inside hold ``-1``.
        """
        out = np.full(self.inside.shape, -1, dtype=np.int8)
        off = self._aligned_offset(grid)
        if off is not None:
            dr, dc = off
            h, w = self.inside.shape
            r0, r1 = max(0, -dr), min(h, grid.height - dr)
            c0, c1 = max(0, -dc), min(w, grid.width - dc)
            if r0 < r1 and c0 < c1:
                out[r0:r1, c0:c1] = grid.data[r0 + dr:r1 + dr, c0 + dc:c1 + dc]
            out[~self.inside] = -1
            return out
        r, c = grid.world_to_cells(self._xy[0], self._xy[1])
        ok = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
        vals = np.full(r.shape, -1, dtype=np.int8)
        vals[ok] = grid.data[r[ok], c[ok]]
        out[self.inside] = vals
        return out

    def coverage(self, grid: GridMap, free_threshold: int = FREE_THRESHOLD
                 ) -> tuple[float, float]:
        """(known-free %, known %) of the inside cells in ``grid``."""
        vals = self.values_at_inside(grid)[self.inside]
        free = int(((vals >= 0) & (vals < free_threshold)).sum())
        known = int((vals >= 0).sum())
        return 100.0 * free / self.total_cells, 100.0 * known / self.total_cells


class SimMetrics:
    """Counters and histories of one run.

    Parameters
    ----------
    ground_truth : object with ``inside`` and ``lidar`` (GridMap), optional
        Coverage is measured over its ``explorable`` cells when it has them (see
        :mod:`sim_bridge.observable`), else over ``inside``. Without it coverage stays NaN.
    history_max : int
        Coverage history length bound: when full, every other sample is dropped and the
        sampling interval doubles (memory stays bounded for any run length).
    """

    def __init__(self, ground_truth: Any = None, history_max: int = 2048) -> None:
        if history_max < 4:
            raise ValueError(f"history_max must be >= 4, got {history_max}")
        if ground_truth is not None:
            ref = getattr(ground_truth, "explorable", None)
            ref = ground_truth.inside if ref is None else ref
            self.reference: CoverageReference | None = CoverageReference(ref, ground_truth.lidar)
        else:
            self.reference = None
        self.path_length_m = 0.0
        self.collisions: list[CollisionEvent] = []
        self.goals_received = 0
        self.goals_reached = 0
        self.goals_aborted = 0
        self.goals_rejected = 0
        self.abort_reasons: dict[str, int] = {}
        self.coverage_pct = math.nan
        self.coverage_free_pct = math.nan
        self.sim_time_s = 0.0
        self._history: list[tuple[float, float]] = []
        self._history_max = int(history_max)
        self._history_stride = 1
        self._history_skip = 0
        self._collisions_max = 10000
        self._collision_count = 0

    # --------------------------------------------------------------- updates
    def add_distance(self, d_m: float) -> None:
        """Add travelled distance (metres)."""
        self.path_length_m += float(d_m)

    def add_collision(self, event: CollisionEvent) -> None:
        """Record a contact event (the list is capped; the count never is)."""
        self._collision_count += 1
        if len(self.collisions) < self._collisions_max:
            self.collisions.append(event)

    def goal_received(self) -> None:
        """Count an accepted goal."""
        self.goals_received += 1

    def goal_reached(self) -> None:
        """Count a goal reached."""
        self.goals_reached += 1

    def goal_aborted(self, reason: str = "") -> None:
        """Count an aborted goal, grouped by the first words of its reason."""
        self.goals_aborted += 1
        key = " ".join(reason.split()[:2]) or "unknown"
        if key in self.abort_reasons or len(self.abort_reasons) < 32:
            self.abort_reasons[key] = self.abort_reasons.get(key, 0) + 1

    def goal_rejected(self) -> None:
        """Count a goal refused at the door (NaN, outside the map, ...)."""
        self.goals_rejected += 1

    def update_coverage(self, grid: GridMap, t_s: float) -> float:
        """Evaluate coverage of ``grid`` at sim time ``t_s``; returns the known %."""
        self.sim_time_s = max(self.sim_time_s, float(t_s))
        if self.reference is None:
            return math.nan
        self.coverage_free_pct, self.coverage_pct = self.reference.coverage(grid)
        if self._history_skip == 0:
            self._history.append((float(t_s), self.coverage_pct))
            if len(self._history) >= self._history_max:
                self._history = self._history[::2]
                self._history_stride *= 2
        self._history_skip = (self._history_skip + 1) % self._history_stride
        return self.coverage_pct

    def set_time(self, t_s: float) -> None:
        """Record the current sim time."""
        self.sim_time_s = float(t_s)

    # --------------------------------------------------------------- reading
    @property
    def coverage_history(self) -> list[tuple[float, float]]:
        """(t_s, coverage %) samples, oldest first."""
        return list(self._history)

    @property
    def n_collisions(self) -> int:
        """Number of contact events."""
        return self._collision_count

    def to_dict(self) -> dict[str, Any]:
        """Everything as plain JSON-able values."""
        ref = self.reference
        return {
            "sim_time_s": self.sim_time_s,
            "coverage_pct": _json_float(self.coverage_pct),
            "coverage_free_pct": _json_float(self.coverage_free_pct),
            "explorable_area_m2": ref.area_m2 if ref is not None else None,
            "path_length_m": self.path_length_m,
            "collisions": self.n_collisions,
            "collision_events": [asdict(e) for e in self.collisions],
            "goals_received": self.goals_received,
            "goals_reached": self.goals_reached,
            "goals_aborted": self.goals_aborted,
            "goals_rejected": self.goals_rejected,
            "abort_reasons": dict(self.abort_reasons),
            "coverage_history": [[t, c] for t, c in self._history],
        }

    def to_json(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` as JSON (parents created); returns the path."""
        out = Path(path)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(self.to_dict(), indent=1))
        return out

    def to_diagnostics(self) -> list[tuple[str, str]]:
        """Scalar metrics as (key, value) strings for a diagnostic_msgs/KeyValue list."""
        d = self.to_dict()
        keys = ("sim_time_s", "coverage_pct", "coverage_free_pct", "explorable_area_m2",
                "path_length_m", "collisions", "goals_received", "goals_reached",
                "goals_aborted", "goals_rejected")
        out = [(k, _fmt(d[k])) for k in keys]
        if self.collisions:
            e = self.collisions[-1]
            out.append(("last_collision",
                        f"t={e.t_s:.2f} x={e.x_m:.2f} y={e.y_m:.2f} {e.object or e.cls}/{e.part}"))
        return out


def _json_float(v: float) -> float | None:
    return None if not math.isfinite(v) else float(v)


def _fmt(v: Any) -> str:
    if v is None:
        return "nan"
    if isinstance(v, float):
        return f"{v:.3f}"
    return str(v)
