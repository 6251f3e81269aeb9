"""The part of a world's explorable area that a robot can actually observe.

``GroundTruth.inside`` (the free cells of the lidar raster flood-filled from the start) can
hold cells no run will ever see: the hollow inside of a wall block joined to a corridor
through a gap a few centimetres wide (the authors' maze has one, 1 % of its area), niches
behind such gaps. A completion criterion of "99 % of the reachable free area" is then
unreachable for every strategy.

:func:`observable_region` keeps the inside cells that the simulator's own lidar and mapper
mark observed from some pose the robot can reach: robot centres at least the robot radius
away from every footprint obstacle and connected to the start, sampled on a lattice, each
taking one noise-free scan. The coverage metrics use ``GroundTruth.explorable`` (inside and
observable) as their denominator when it is set.

The region is the same for every run of a world (it costs seconds: hundreds of scans), so
:func:`observable_region` keeps it: in this process, and on disk under
``$EXPLORE_SEG_CACHE_DIR`` (default ``~/.cache/explore_seg``)``/observable/``, keyed by a
hash of everything it depends on (the world's primitives, start and bounds, the ground-truth
rasters, the lidar, radius and spacing, and the source of the code that computes it), so a
changed world or changed code computes it afresh. ``EXPLORE_SEG_CACHE_DIR=""`` turns the
disk cache off; a cache that cannot be read or written is ignored.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
import tempfile
from collections import OrderedDict
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import OCCUPIED_THRESHOLD
from explore_seg.core.paths import inflate
from sim_bridge.mapping import MappingParams, ScanMapper
from sim_bridge.metrics import CoverageReference
from sim_bridge.sensors import Lidar, LidarParams
from sim_bridge.world import World

#: Default spacing (m) of the sampled robot positions.
SAMPLE_SPACING_M = 0.25

#: Regions kept in this process (most recently used last).
_MEMORY: OrderedDict[str, npt.NDArray[np.bool_]] = OrderedDict()
_MEMORY_SIZE = 16

#: Modules whose code decides the region: their source is part of the cache key.
_CODE_MODULES = ("sim_bridge/observable.py", "sim_bridge/mapping.py",
                 "sim_bridge/sensors/lidar.py", "sim_bridge/metrics.py",
                 "explore_seg/core/paths.py", "explore_seg/core/grid.py")
_ROOT = Path(__file__).resolve().parents[1]
_code_digest: list[str] = []


def reachable_centres(gt, robot_radius_m: float) -> npt.NDArray[np.bool_]:
    """Cells of ``gt``'s rasters where the robot's centre can be: farther than
    ``robot_radius_m`` from every obstacle of the footprint and lidar rasters, inside, and
    8-connected to the start (or, when the start itself is that close to an obstacle, to
    the nearest such cell).

    Parameters
    ----------
    gt : worlds.GroundTruth
    robot_radius_m : float
        >= 0.

    Returns
    -------
    ndarray of bool, shape of ``gt.inside``
        All False when no cell qualifies.
    """
    if not (math.isfinite(robot_radius_m) and robot_radius_m >= 0):
        raise ValueError(f"robot_radius_m must be finite and >= 0, got {robot_radius_m}")
    res = gt.lidar.resolution_m
    blocked = (gt.footprint.data >= OCCUPIED_THRESHOLD) | (gt.lidar.data >= OCCUPIED_THRESHOLD)
    ok = gt.inside & ~inflate(blocked, robot_radius_m, res)
    if not ok.any():
        return ok
    _, lab = cv2.connectedComponents(ok.view(np.uint8), connectivity=8)
    r, c = gt.start_cell
    k = int(lab[r, c])
    if k == 0:  # start within the radius of an obstacle: take the nearest clear cell
        rows, cols = np.nonzero(ok)
        j = int(np.argmin((rows - r) ** 2 + (cols - c) ** 2))
        k = int(lab[rows[j], cols[j]])
    return lab == k


def sample_cells(reach: npt.NDArray[np.bool_], step: int
                 ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Cells of ``reach`` on a lattice of ``step`` cells, plus enough cells of the strips
    the lattice misses (a corridor narrower than the spacing between two lattice lines)
    that every reachable cell has a sample within ``step - 1`` cells (Chebyshev)."""
    rows, cols = np.nonzero(reach)
    keep = (rows % step == 0) & (cols % step == 0)
    sr, sc = [rows[keep]], [cols[keep]]
    if step > 1:
        kernel = np.ones((2 * step - 1, 2 * step - 1), np.uint8)
        seeds = np.zeros(reach.shape, np.uint8)
        seeds[sr[0], sc[0]] = 1
        left = reach & (cv2.dilate(seeds, kernel) == 0)
        while left.any():   # greedy: the first uncovered cell in scan order, repeatedly
            r, c = (int(v) for v in np.argwhere(left)[0])
            sr.append(np.array([r]))
            sc.append(np.array([c]))
            left[max(0, r - step + 1):r + step, max(0, c - step + 1):c + step] = False
    return np.concatenate(sr), np.concatenate(sc)


def cache_dir() -> Path | None:
    """Directory of the on-disk region cache (see the module docstring), None when off."""
    env = os.environ.get("EXPLORE_SEG_CACHE_DIR")
    if env is not None:
        return Path(env) / "observable" if env else None
    return Path.home() / ".cache" / "explore_seg" / "observable"


def _code_hash() -> str:
    """Hash of the source of :data:`_CODE_MODULES` (read once per process); "" when a
    source file cannot be read (the disk cache is then not used)."""
    if not _code_digest:
        h = hashlib.sha256()
        try:
            for rel in _CODE_MODULES:
                h.update(rel.encode())
                h.update((_ROOT / rel).read_bytes())
            _code_digest.append(h.hexdigest())
        except OSError:
            _code_digest.append("")
    return _code_digest[0]


def region_key(world: World, gt, lidar_params: LidarParams, robot_radius_m: float,
               spacing_m: float) -> str:
    """Hex digest naming :func:`observable_region`'s result for these inputs: the
    world's primitives, start pose and bounds, ``gt``'s rasters, start cell and
    ``inside``, the lidar, radius, spacing and the code that computes it."""
    h = hashlib.sha256(_code_hash().encode())
    h.update(repr((world.primitives, tuple(float(v) for v in world.start_pose),
                   tuple(float(v) for v in world.bounds), lidar_params,
                   float(robot_radius_m), float(spacing_m), tuple(gt.start_cell))).encode())
    for g in (gt.lidar, gt.footprint):
        h.update(repr((g.data.shape, g.resolution_m, tuple(g.origin_xy_m),
                       g.origin_yaw_rad)).encode())
        h.update(np.ascontiguousarray(g.data).tobytes())
    h.update(repr(gt.inside.shape).encode())
    h.update(np.packbits(gt.inside).tobytes())
    return h.hexdigest()


def _disk_load(key: str, shape: tuple[int, ...]) -> npt.NDArray[np.bool_] | None:
    """The stored region of ``key``, None when absent, unreadable or of another shape."""
    d = cache_dir()
    if d is None or not _code_hash():
        return None
    try:
        with np.load(d / f"{key}.npz") as z:
            bits, n = z["bits"], tuple(int(v) for v in z["shape"])
        if n != shape:
            return None
        return np.unpackbits(bits, count=int(np.prod(n))).astype(bool).reshape(n)
    except (OSError, ValueError, KeyError):   # absent, partial or foreign: recompute
        return None


def _disk_store(key: str, region: npt.NDArray[np.bool_]) -> None:
    """Write atomically (a temporary file renamed into place), so parallel workers never
    read a partial file; failures leave the cache as it was."""
    d = cache_dir()
    if d is None or not _code_hash():
        return
    try:
        d.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=d, suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as f:
                np.savez(f, bits=np.packbits(region), shape=np.asarray(region.shape))
            os.replace(tmp, d / f"{key}.npz")
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    except OSError:
        pass


def observable_region(world: World, gt, lidar_params: LidarParams | None = None,
                      robot_radius_m: float = 0.2, spacing_m: float = SAMPLE_SPACING_M
                      ) -> npt.NDArray[np.bool_]:
    """Inside cells of ``gt`` observed by a noise-free scan from some reachable pose,
    from the cache when these inputs were computed before (see the module docstring).

    Parameters
    ----------
    world : World
        The world ``gt`` was rasterised from (the lidar casts against its primitives).
    gt : worlds.GroundTruth
    lidar_params : LidarParams, optional
        The runs' lidar (range, beams, mount); its noise is ignored.
    robot_radius_m : float
        Clearance of a reachable robot centre from obstacles.
    spacing_m : float
        Lattice spacing of the sampled positions (> 0); the start is always sampled.

    Returns
    -------
    ndarray of bool, shape of ``gt.inside``
        A subset of ``gt.inside``.

    Raises
    ------
    ValueError
        On a non-positive spacing or a negative radius.
    """
    if not (math.isfinite(spacing_m) and spacing_m > 0):
        raise ValueError(f"spacing_m must be finite and > 0, got {spacing_m}")
    if not (math.isfinite(robot_radius_m) and robot_radius_m >= 0):
        raise ValueError(f"robot_radius_m must be finite and >= 0, got {robot_radius_m}")
    lp = lidar_params if lidar_params is not None else LidarParams()
    key = region_key(world, gt, lp, robot_radius_m, spacing_m)
    region = _MEMORY.get(key)
    if region is None:
        region = _disk_load(key, gt.inside.shape)
        if region is None:
            region = compute_observable_region(world, gt, lp, robot_radius_m, spacing_m)
            _disk_store(key, region)
    _MEMORY[key] = region
    _MEMORY.move_to_end(key)
    while len(_MEMORY) > _MEMORY_SIZE:
        _MEMORY.popitem(last=False)
    return region.copy()


def compute_observable_region(world: World, gt, lp: LidarParams, robot_radius_m: float,
                              spacing_m: float) -> npt.NDArray[np.bool_]:
    """:func:`observable_region` without the cache."""
    lidar = Lidar(world, lp)
    res = gt.lidar.resolution_m
    reach = reachable_centres(gt, robot_radius_m)
    rows, cols = sample_cells(reach, max(1, int(round(spacing_m / res))))
    xs, ys = gt.lidar.cells_to_world(rows.astype(np.float64), cols.astype(np.float64))
    x0, y0 = (float(v) for v in world.start_pose[:2])
    xs, ys = np.append(xs, x0), np.append(ys, y0)
    xmin, ymin, xmax, ymax = world.bounds
    side = max(xmax - xmin, ymax - ymin) + 2.0 * lp.range_max_m + 1.0
    mapper = ScanMapper(((xmin + xmax) / 2.0, (ymin + ymax) / 2.0),
                        MappingParams(resolution_m=res, initial_size_m=side,
                                      max_size_m=max(side, MappingParams.max_size_m)))
    mx, my = lp.mount_xy_m
    for x, y in zip(xs.tolist(), ys.tolist()):
        pose = (x, y, 0.0)
        ranges = lidar.scan(pose)
        mapper.integrate_scan((x + mx, y + my, 0.0), ranges, lp.angle_min_rad,
                              lp.angle_increment_rad, lp.range_max_m, lp.range_min_m)
    known = CoverageReference(gt.inside, gt.lidar).values_at_inside(mapper.grid()) >= 0
    return known & gt.inside


def with_observable(world: World, gt, lidar_params: LidarParams | None = None,
                    robot_radius_m: float = 0.2, spacing_m: float = SAMPLE_SPACING_M):
    """``gt`` with its ``observable`` field set by :func:`observable_region` (``gt``
    itself when already set)."""
    if getattr(gt, "observable", None) is not None:
        return gt
    return dataclasses.replace(gt, observable=observable_region(
        world, gt, lidar_params, robot_radius_m, spacing_m))
