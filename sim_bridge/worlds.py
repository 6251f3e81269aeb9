"""World loading, procedural generation and ground-truth rasters of the 2.5D simulator.

* :func:`load_world` reads an ``explore_seg_world/1`` file (``*.world.yaml``) or a
  map_server YAML (+ PGM/PNG; an Explore-Bench map) into a :class:`~sim_bridge.world.World`.
* :func:`generate_house` / :func:`generate_maze` build seeded worlds sized like the
  paper's (20 x 20 m house, 40 x 40 m maze); :func:`default_world` names the ones the
  demo and the tests use (:data:`WORLD_NAMES`).
* :func:`rasterize` / :func:`ground_truth` turn primitives into occupancy rasters with the
  rules of the shared worlds' README (section 3): a cell is occupied when a primitive's
  cross-section overlaps the cell square by more than 1 mm; the lidar raster holds the
  primitives with ``zmin <= 0.17 <= zmax``, the footprints those that occupy some height
  in (0, 0.5) and (0, 1.5) m; ``inside`` is the 4-connected flood fill from the start
  cell over cells free in the lidar raster.

Everything here is ROS-free numpy. Coordinates: metres, radians, world x/y on the floor,
rasters in grid layout (row = y).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import cv2
import numpy as np
import numpy.typing as npt
import yaml
from scipy import ndimage

from explore_seg.core.grid import MAP_IMAGE_MODES, OCCUPIED_THRESHOLD, GridMap, occupancy_from_map_image
from sim_bridge.world import SHAPES, Primitive, World, WorldObject

WORLD_FORMAT = "explore_seg_world/1"
#: Classes a primitive or object may have (``table`` also covers desks in the shared worlds).
KNOWN_CLASSES = ("wall", "chair", "table", "desk", "cabinet", "sofa", "other")
#: Height of the 2D lidar scan plane used for the ``lidar`` raster (m).
LIDAR_PLANE_Z_M = 0.17
#: Height band of the robot footprint raster (m).
FOOTPRINT_Z_M = (0.0, 0.5)
#: Height band of the tall footprint raster (m).
FOOTPRINT_TALL_Z_M = (0.0, 1.5)
#: A primitive marks a cell when its cross-section overlaps the cell by more than this (m).
CELL_OVERLAP_M = 0.001
#: Raster resolution of ground truth and room labels (m).
GT_RESOLUTION_M = 0.05
#: Height given to the occupied cells of a map-only world (they act as unlimited walls).
MAP_WALL_HEIGHT_M = 10.0

_TOP_KEYS = {"format", "name", "description", "source", "bounds", "start_pose", "rasters",
             "notes", "objects", "obstacles"}
_TOP_REQUIRED = {"format", "bounds", "start_pose", "obstacles"}
_OBST_KEYS = {"name", "object", "class", "part", "shape", "pose", "size", "z", "approx", "added"}
_OBST_REQUIRED = {"class", "shape", "pose", "size", "z"}
_OBJ_KEYS = {"name", "class", "pose", "aabb", "parts", "approx", "added"}
_OBJ_REQUIRED = {"name", "class", "pose", "aabb"}
_MAP_KEYS = {"image", "mode", "resolution", "origin", "negate", "occupied_thresh",
             "free_thresh"}
_MAP_REQUIRED = {"image", "resolution", "origin"}


# ============================================================ ground truth rasters
@dataclass(frozen=True)
class GroundTruth:
    """Ground-truth rasters of a world over its bounds (grid layout, row = y).

    Attributes
    ----------
    lidar, footprint, footprint_tall : GridMap
        Occupancy 0 / 100 (int8) of the primitives cut by the lidar plane, occupying
        height in the footprint band and in the tall footprint band.
    inside : ndarray of bool, shape (H, W)
        Explorable region: 4-connected flood fill from the start cell over cells that
        are free in ``lidar`` (the free cells of the shipped PGMs).
    free_area_m2 : float
        ``inside.sum() * resolution**2``.
    start_cell : tuple of int
        (row, col) of the start pose.
    observable : ndarray of bool, shape (H, W), or None
        Inside cells a robot can observe (:func:`sim_bridge.observable.observable_region`);
        None when not computed.
    """

    lidar: GridMap
    footprint: GridMap
    footprint_tall: GridMap
    inside: npt.NDArray[np.bool_]
    free_area_m2: float
    start_cell: tuple[int, int]
    observable: npt.NDArray[np.bool_] | None = None

    @property
    def explorable(self) -> npt.NDArray[np.bool_]:
        """The coverage denominator: ``inside & observable`` (``inside`` when
        ``observable`` is None)."""
        return self.inside if self.observable is None else self.inside & self.observable

    @property
    def explorable_area_m2(self) -> float:
        """Area of :attr:`explorable` in square metres."""
        return float(self.explorable.sum()) * self.lidar.resolution_m ** 2

    @property
    def resolution_m(self) -> float:
        """Metres per cell."""
        return self.lidar.resolution_m

    def as_map(self, which: str = "lidar") -> GridMap:
        """Trinary map as in the shipped PGMs: 100 occupied, 0 inside free, -1 elsewhere.

        Parameters
        ----------
        which : {"lidar", "footprint", "footprint_tall"}

        Raises
        ------
        ValueError
            On another name.
        """
        grids = {"lidar": self.lidar, "footprint": self.footprint,
                 "footprint_tall": self.footprint_tall}
        if which not in grids:
            raise ValueError(f"which must be one of {sorted(grids)}, got {which!r}")
        occ = grids[which].data >= OCCUPIED_THRESHOLD
        data = np.full(occ.shape, -1, np.int8)
        data[self.inside] = 0
        data[occ] = 100
        return grids[which].with_data(data)


def _height_filter(prims: list[Primitive], z_low: float, z_high: float) -> list[Primitive]:
    if z_low == z_high:   # a plane: closed test as for the lidar raster
        return [p for p in prims if p.zmin <= z_low <= p.zmax]
    return [p for p in prims if p.spans(z_low, z_high)]


def raster_geometry(bounds: tuple[float, float, float, float], resolution_m: float
                    ) -> tuple[int, int]:
    """(height, width) in cells of a raster covering ``bounds`` at ``resolution_m``.

    Raises
    ------
    ValueError
        On a non-positive resolution or empty bounds.
    """
    if not resolution_m > 0:
        raise ValueError(f"resolution_m must be > 0, got {resolution_m}")
    xmin, ymin, xmax, ymax = bounds
    if not (xmax > xmin and ymax > ymin):
        raise ValueError(f"bounds must have xmax > xmin and ymax > ymin, got {bounds}")
    width = int(round((xmax - xmin) / resolution_m))
    height = int(round((ymax - ymin) / resolution_m))
    return height, width


def rasterize(world: World, resolution_m: float, z_low: float, z_high: float,
              overlap_m: float = CELL_OVERLAP_M) -> GridMap:
    """Occupancy (0 / 100 int8) of the primitives in a height band over ``world.bounds``.

    Parameters
    ----------
    world : World
    resolution_m : float
        Metres per cell, > 0.
    z_low, z_high : float
        Height band (m). ``z_low == z_high`` selects primitives with
        ``zmin <= z <= zmax`` (a scan plane); otherwise those occupying some height in
        the open band ``(z_low, z_high)``.
    overlap_m : float
        A cell is occupied when the cross-section overlaps the cell square by more than
        this: every separating axis of box and square overlaps by more than ``overlap_m``,
        or a circle's radius exceeds its distance to the square by more than it.

    Returns
    -------
    GridMap
        Origin at ``(xmin, ymin)`` of the bounds, frame ``map``, data 0 or 100.

    Raises
    ------
    ValueError
        On ``z_high < z_low``, bad resolution or bounds.
    """
    if z_high < z_low:
        raise ValueError(f"need z_low <= z_high, got [{z_low}, {z_high}]")
    height, width = raster_geometry(world.bounds, resolution_m)
    xmin, ymin = world.bounds[0], world.bounds[1]
    occ = np.zeros((height, width), dtype=bool)
    res = float(resolution_m)
    half = 0.5 * res
    for p in _height_filter(world.primitives, z_low, z_high):
        if p.shape == "box":
            c, s = math.cos(p.yaw), math.sin(p.yaw)
            hx, hy = 0.5 * p.size[0], 0.5 * p.size[1]
            ex = abs(c) * hx + abs(s) * hy
            ey = abs(s) * hx + abs(c) * hy
        else:
            ex = ey = p.size[0]
        c0 = max(int(math.floor((p.x - ex - xmin) / res)) - 1, 0)
        c1 = min(int(math.floor((p.x + ex - xmin) / res)) + 2, width)
        r0 = max(int(math.floor((p.y - ey - ymin) / res)) - 1, 0)
        r1 = min(int(math.floor((p.y + ey - ymin) / res)) + 2, height)
        if c0 >= c1 or r0 >= r1:
            continue
        xs = xmin + (np.arange(c0, c1) + 0.5) * res - p.x      # (w,)
        ys = ymin + (np.arange(r0, r1) + 0.5) * res - p.y      # (h,)
        if p.shape == "box":
            dx = xs[None, :]
            dy = ys[:, None]
            hit = ((ex + half - np.abs(dx)) > overlap_m) & ((ey + half - np.abs(dy)) > overlap_m)
            u = dx * c + dy * s
            v = -dx * s + dy * c
            proj = half * (abs(c) + abs(s))
            hit &= (hx + proj - np.abs(u)) > overlap_m
            hit &= (hy + proj - np.abs(v)) > overlap_m
        else:
            qx = np.maximum(np.abs(xs) - half, 0.0)[None, :]
            qy = np.maximum(np.abs(ys) - half, 0.0)[:, None]
            hit = (p.size[0] - np.sqrt(qx * qx + qy * qy)) > overlap_m
        occ[r0:r1, c0:c1] |= hit
    data = np.where(occ, np.int8(100), np.int8(0)).astype(np.int8)
    return GridMap(data, res, (float(xmin), float(ymin)))


def flood_inside(passable: npt.NDArray[np.bool_], start_cell: tuple[int, int]
                 ) -> npt.NDArray[np.bool_]:
    """4-connected component of ``passable`` holding ``start_cell``.

    Raises
    ------
    ValueError
        If the start cell lies outside the raster or is not passable.
    """
    r, c = start_cell
    if not (0 <= r < passable.shape[0] and 0 <= c < passable.shape[1]):
        raise ValueError(f"start cell {start_cell} outside raster of shape {passable.shape}")
    if not passable[r, c]:
        raise ValueError(f"start cell {start_cell} is occupied at the lidar plane")
    labels, _ = ndimage.label(passable, structure=ndimage.generate_binary_structure(2, 1))
    return labels == labels[r, c]


def ground_truth(world: World, resolution_m: float = GT_RESOLUTION_M,
                 lidar_z_m: float = LIDAR_PLANE_Z_M,
                 footprint_z_m: tuple[float, float] = FOOTPRINT_Z_M,
                 footprint_tall_z_m: tuple[float, float] = FOOTPRINT_TALL_Z_M) -> GroundTruth:
    """Lidar / footprint / tall footprint rasters and the explorable ``inside`` region.

    Parameters
    ----------
    world : World
    resolution_m : float
        Raster resolution (m), > 0; the rasters cover ``world.bounds``.
    lidar_z_m : float
        Scan plane height (m).
    footprint_z_m, footprint_tall_z_m : tuple of float
        Height bands (m) of the two footprint rasters.

    Returns
    -------
    GroundTruth

    Raises
    ------
    ValueError
        If the start pose is outside the bounds or inside an obstacle at the scan plane.
    """
    lidar = rasterize(world, resolution_m, lidar_z_m, lidar_z_m)
    foot = rasterize(world, resolution_m, *footprint_z_m)
    tall = rasterize(world, resolution_m, *footprint_tall_z_m)
    start = lidar.world_to_cell(world.start_pose[0], world.start_pose[1])
    inside = flood_inside(lidar.data < OCCUPIED_THRESHOLD, start)
    return GroundTruth(lidar, foot, tall, inside,
                       float(inside.sum()) * resolution_m * resolution_m, start)


# ============================================================ loading
def _err(where: str, msg: str) -> ValueError:
    return ValueError(f"{where}: {msg}")


def _floats(value: Any, n: int, key: str, where: str) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise _err(where, f"key '{key}' must be a list of {n} numbers, got {value!r}")
    try:
        out = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise _err(where, f"key '{key}' must hold numbers, got {value!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise _err(where, f"key '{key}' must be finite, got {value!r}")
    if any(isinstance(v, bool) for v in value):
        raise _err(where, f"key '{key}' must hold numbers, got {value!r}")
    return out


def _check_keys(entry: Any, allowed: set[str], required: set[str], where: str) -> None:
    if not isinstance(entry, dict):
        raise _err(where, f"expected a mapping, got {type(entry).__name__}")
    unknown = sorted(set(entry) - allowed)
    if unknown:
        raise _err(where, f"unknown key '{unknown[0]}' (allowed: {sorted(allowed)})")
    missing = sorted(required - set(entry))
    if missing:
        raise _err(where, f"missing key '{missing[0]}'")


def _str(entry: dict, key: str, where: str, default: str | None = None) -> str:
    value = entry.get(key, default)
    if not isinstance(value, str):
        raise _err(where, f"key '{key}' must be a string, got {value!r}")
    return value


def _bounds(value: Any, where: str) -> tuple[float, float, float, float]:
    b = _floats(value, 4, "bounds", where)
    if not (b[2] > b[0] and b[3] > b[1]):
        raise _err(where, f"key 'bounds' needs xmax > xmin and ymax > ymin, got {list(b)}")
    return b  # type: ignore[return-value]


def _parse_world_yaml(doc: Any, path: Path) -> World:
    where = str(path)
    _check_keys(doc, _TOP_KEYS, _TOP_REQUIRED, where)
    if doc["format"] != WORLD_FORMAT:
        raise _err(where, f"key 'format' must be {WORLD_FORMAT!r}, got {doc['format']!r}")
    name = _str(doc, "name", where, path.name.split(".")[0])
    description = _str(doc, "description", where, "")
    bounds = _bounds(doc["bounds"], where)
    start = _floats(doc["start_pose"], 3, "start_pose", where)
    if not (bounds[0] < start[0] < bounds[2] and bounds[1] < start[1] < bounds[3]):
        raise _err(where, f"key 'start_pose' {list(start)} lies outside bounds {list(bounds)}")
    obstacles = doc["obstacles"]
    if not isinstance(obstacles, list):
        raise _err(where, f"key 'obstacles' must be a list, got {type(obstacles).__name__}")
    prims = []
    for i, ob in enumerate(obstacles):
        w = f"{where}: obstacles[{i}]"
        _check_keys(ob, _OBST_KEYS, _OBST_REQUIRED, w)
        cls = _str(ob, "class", w)
        if cls not in KNOWN_CLASSES:
            raise _err(w, f"key 'class' must be one of {KNOWN_CLASSES}, got {cls!r}")
        shape = _str(ob, "shape", w)
        if shape not in SHAPES:
            raise _err(w, f"key 'shape' must be one of {SHAPES}, got {shape!r}")
        pose = _floats(ob["pose"], 3, "pose", w)
        size = _floats(ob["size"], 2 if shape == "box" else 1, "size", w)
        z = _floats(ob["z"], 2, "z", w)
        try:
            prims.append(Primitive(object=_str(ob, "object", w, ""), cls=cls,
                                   part=_str(ob, "part", w, ""), shape=shape,
                                   x=pose[0], y=pose[1], yaw=pose[2], size=size,
                                   zmin=z[0], zmax=z[1]))
        except ValueError as err:
            raise _err(w, f"key 'size' or 'z' invalid: {err}") from None
    objects_doc = doc.get("objects", [])
    if not isinstance(objects_doc, list):
        raise _err(where, f"key 'objects' must be a list, got {type(objects_doc).__name__}")
    objects = []
    for i, ob in enumerate(objects_doc):
        w = f"{where}: objects[{i}]"
        _check_keys(ob, _OBJ_KEYS, _OBJ_REQUIRED, w)
        cls = _str(ob, "class", w)
        if cls not in KNOWN_CLASSES:
            raise _err(w, f"key 'class' must be one of {KNOWN_CLASSES}, got {cls!r}")
        objects.append(WorldObject(_str(ob, "name", w), cls,
                                   _floats(ob["pose"], 3, "pose", w),  # type: ignore[arg-type]
                                   _floats(ob["aabb"], 6, "aabb", w)))  # type: ignore[arg-type]
    return World(name=name, bounds=bounds, start_pose=start,  # type: ignore[arg-type]
                 primitives=prims, objects=objects, description=description)


def _read_map_image(path: Path, where: str) -> npt.NDArray[np.uint8]:
    if not path.is_file():
        raise _err(where, f"key 'image' names a missing file {path}")
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise _err(where, f"key 'image': cannot read {path} as PGM/PNG")
    if img.ndim == 3:   # colour PNG (BGR[A]): map_server averages the colour channels
        img = img[:, :, :3].astype(np.float64).mean(axis=2)
    if img.dtype == np.uint16:
        img = img / 257.0
    return np.asarray(np.round(img), dtype=np.uint8)




def _merge_cells_to_rects(mask: npt.NDArray[np.bool_]) -> list[tuple[int, int, int, int]]:
    """Cover ``mask`` by disjoint cell rectangles (row0, col0, row1, col1), exclusive ends.

    Row runs are found per row with numpy; identical runs in consecutive rows merge.
    """
    rects: list[tuple[int, int, int, int]] = []
    open_runs: dict[tuple[int, int], int] = {}    # (c0, c1) -> start row
    h = mask.shape[0]
    for r in range(h + 1):
        runs: set[tuple[int, int]] = set()
        if r < h:
            padded = np.concatenate(([False], mask[r], [False])).astype(np.int8)
            edges = np.flatnonzero(np.diff(padded))
            runs = {(int(a), int(b)) for a, b in zip(edges[0::2], edges[1::2])}
        for key in [k for k in open_runs if k not in runs]:
            rects.append((open_runs.pop(key), key[0], r, key[1]))
        for key in runs:
            open_runs.setdefault(key, r)
    return rects


def _clearance_start(free: npt.NDArray[np.bool_], grid: GridMap) -> tuple[float, float, float]:
    if not free.any():
        raise ValueError("map has no free cell for a start pose")
    dist = ndimage.distance_transform_edt(free)
    r, c = np.unravel_index(int(np.argmax(dist)), dist.shape)
    x, y = grid.cell_to_world(r, c)
    return (x, y, 0.0)


def _starts_pose(yaml_path: Path) -> tuple[float, float, float] | None:
    starts = yaml_path.parent / "starts.yaml"
    if not starts.is_file():
        return None
    with open(starts, encoding="utf-8") as fh:
        doc = yaml.safe_load(fh)
    maps = doc.get("maps") if isinstance(doc, dict) else None
    if not isinstance(maps, dict):
        raise _err(str(starts), "missing key 'maps'")
    for key, entry in maps.items():
        if not isinstance(entry, dict):
            continue
        if key == yaml_path.stem or entry.get("map") == yaml_path.name:
            if "start_pose" not in entry:
                raise _err(str(starts), f"maps.{key}: missing key 'start_pose'")
            return _floats(entry["start_pose"], 3, "start_pose",  # type: ignore[return-value]
                           f"{starts}: maps.{key}")
    return None


def _parse_map_yaml(doc: Any, path: Path,
                    start_pose: tuple[float, float, float] | None) -> World:
    where = str(path)
    if not isinstance(doc, dict):
        raise _err(where, f"expected a mapping, got {type(doc).__name__}")
    unknown = sorted(set(doc) - _MAP_KEYS)
    if unknown:
        raise _err(where, f"unknown key '{unknown[0]}' (allowed: {sorted(_MAP_KEYS)})")
    missing = sorted(_MAP_REQUIRED - set(doc))
    if missing:
        raise _err(where, f"missing key '{missing[0]}'")
    res = doc["resolution"]
    if isinstance(res, bool) or not isinstance(res, (int, float)) or not res > 0:
        raise _err(where, f"key 'resolution' must be a number > 0, got {res!r}")
    origin = _floats(doc["origin"], 3, "origin", where)
    if origin[2] != 0.0:
        raise _err(where, f"key 'origin' yaw must be 0 (turned maps unsupported), got {origin[2]}")
    mode = doc.get("mode", "trinary")
    if mode not in MAP_IMAGE_MODES:
        raise _err(where, f"key 'mode' must be one of {MAP_IMAGE_MODES}, got {mode!r}")
    negate = doc.get("negate", 0)
    if negate not in (0, 1, True, False):
        raise _err(where, f"key 'negate' must be 0 or 1, got {negate!r}")
    thr = {}
    for key, default in (("occupied_thresh", 0.65), ("free_thresh", 0.196)):
        value = doc.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= 1:
            raise _err(where, f"key '{key}' must be a number in [0, 1], got {value!r}")
        thr[key] = float(value)
    if not thr["free_thresh"] < thr["occupied_thresh"]:
        raise _err(where, f"key 'free_thresh' {thr['free_thresh']} must be < "
                          f"occupied_thresh {thr['occupied_thresh']}")
    image = doc["image"]
    if not isinstance(image, str):
        raise _err(where, f"key 'image' must be a string, got {image!r}")
    img = _read_map_image(path.parent / image, where)
    values = occupancy_from_map_image(img, mode, bool(negate), thr["occupied_thresh"],
                                   thr["free_thresh"])[::-1].copy()   # row = y
    grid = GridMap(values, float(res), (origin[0], origin[1]))
    occ = grid.occupied_mask()
    prims = []
    for r0, c0, r1, c1 in _merge_cells_to_rects(occ):
        x0, y0 = origin[0] + c0 * res, origin[1] + r0 * res
        prims.append(Primitive(object="map", cls="wall", part="wall", shape="box",
                               x=x0 + 0.5 * (c1 - c0) * res, y=y0 + 0.5 * (r1 - r0) * res,
                               yaw=0.0, size=((c1 - c0) * res, (r1 - r0) * res),
                               zmin=0.0, zmax=MAP_WALL_HEIGHT_M))
    bounds = (origin[0], origin[1], origin[0] + grid.width * res, origin[1] + grid.height * res)
    if start_pose is None:
        start_pose = _starts_pose(path)
    if start_pose is None:
        start_pose = _clearance_start(grid.free_mask(), grid)
    start = _floats(list(start_pose), 3, "start_pose", where)
    r, c = grid.world_to_cell(start[0], start[1])
    if not grid.in_bounds(r, c) or occ[r, c]:
        raise _err(where, f"start_pose {list(start)} is outside the map or on an occupied cell")
    stem = path.name[:-len(".yaml")] if path.name.endswith(".yaml") else path.stem
    return World(name=stem, bounds=bounds, start_pose=start,  # type: ignore[arg-type]
                 primitives=prims, objects=[], base_grid=grid,
                 description=f"map-only world from {path.name}")


def load_world(path: str | Path, start_pose: tuple[float, float, float] | None = None
               ) -> World:
    """Load a world file.

    Parameters
    ----------
    path : str or Path
        ``*.world.yaml`` (format ``explore_seg_world/1``) or a map_server YAML whose
        ``image`` (PGM/PNG) sits next to it.
    start_pose : tuple of float, optional
        (x, y, yaw) overriding the start of a map-only world. Without it the pose comes
        from a sibling ``starts.yaml`` (Explore-Bench layout: ``maps.<stem>.start_pose``)
        or, failing that, the free cell farthest from any non-free cell.

    Returns
    -------
    World
        For map-only worlds ``base_grid`` holds the map (row = y) and ``primitives`` one
        wall box (``object="map"``, 0..``MAP_WALL_HEIGHT_M``) per merged rectangle of
        occupied cells, so every sensor and raster treats both kinds alike.

    Raises
    ------
    ValueError
        On a missing/unreadable file, unknown or missing keys, or invalid values; the
        message names the file and the key.

    Examples
    --------
    >>> w = load_world("/work/shared/worlds/maze.world.yaml")  # doctest: +SKIP
    >>> w.start_pose
    (0.0, 0.0, 0.0)
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"{p}: no such world file")
    try:
        with open(p, encoding="utf-8") as fh:
            doc = yaml.safe_load(fh)
    except yaml.YAMLError as err:
        raise ValueError(f"{p}: not valid YAML: {err}") from None
    if isinstance(doc, dict) and "format" in doc:
        if start_pose is not None:
            doc = dict(doc, start_pose=list(start_pose))
        return _parse_world_yaml(doc, p)
    if isinstance(doc, dict) and "image" in doc:
        return _parse_map_yaml(doc, p, start_pose)
    raise ValueError(f"{p}: neither key 'format' ({WORLD_FORMAT}) nor key 'image' "
                     f"(map_server YAML) found")


def world_to_dict(world: World) -> dict[str, Any]:
    """``explore_seg_world/1`` mapping of a world (primitives and objects; no rasters).

    Room labels and base grids are not part of the format and are dropped.
    """
    def r(v: float) -> float:
        return round(float(v), 6)
    names: dict[str, int] = {}
    obstacles = []
    for p in world.primitives:
        base = f"{p.object or p.cls}/{p.part or p.shape}"
        k = names.get(base, 0)
        names[base] = k + 1
        obstacles.append({"name": f"{base}_{k}", "object": p.object, "class": p.cls,
                          "part": p.part, "shape": p.shape,
                          "pose": [r(p.x), r(p.y), r(p.yaw)],
                          "size": [r(s) for s in p.size], "z": [r(p.zmin), r(p.zmax)]})
    objects = [{"name": o.name, "class": o.cls, "pose": [r(v) for v in o.pose],
                "aabb": [r(v) for v in o.aabb]} for o in world.objects]
    return {"format": WORLD_FORMAT, "name": world.name, "description": world.description,
            "bounds": [r(v) for v in world.bounds],
            "start_pose": [r(v) for v in world.start_pose],
            "objects": objects, "obstacles": obstacles}


def save_world(world: World, path: str | Path) -> None:
    """Write ``world`` as an ``explore_seg_world/1`` YAML file (see :func:`world_to_dict`)."""
    with open(path, "w", encoding="utf-8") as fh:
        yaml.safe_dump(world_to_dict(world), fh, sort_keys=False, default_flow_style=None,
                       width=200)


# ============================================================ generation helpers
_Part = tuple[str, str, float, float, float, tuple[float, ...], float, float]
# (part, shape, local x, local y, local yaw, size, zmin, zmax)


def _snap(v: float, step: float = 0.05) -> float:
    return round(round(v / step) * step, 6)


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


@dataclass
class _Wall:
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


def _add_door(walls: list[_Wall], p0: tuple[float, float], p1: tuple[float, float]) -> bool:
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


def _bounds_around(xmin: float, ymin: float, xmax: float, ymax: float, margin: float
                   ) -> tuple[float, float, float, float]:
    step = GT_RESOLUTION_M
    return (round(math.floor((xmin - margin) / step + 1e-9) * step, 6),
            round(math.floor((ymin - margin) / step + 1e-9) * step, 6),
            round(math.ceil((xmax + margin) / step - 1e-9) * step, 6),
            round(math.ceil((ymax + margin) / step - 1e-9) * step, 6))


def _split_lengths(rng: np.random.Generator, total: float, lo: float, hi: float) -> list[float]:
    """Widths in [lo, hi] (snapped to 0.05 m) that sum to ``total`` (> lo)."""
    out: list[float] = []
    left = total
    while left > hi:
        w = _snap(float(rng.uniform(lo, min(hi, left - lo))))
        out.append(w)
        left = round(left - w, 6)
    out.append(left)
    return out


# ============================================================ house
@dataclass(frozen=True)
class HouseOptions:
    """Knobs of :func:`generate_house` (pass them as keyword ``opts``)."""

    wall_thickness_m: float = field(default=0.15, metadata={"doc": "wall thickness", "unit": "m"})
    wall_height_m: float = field(default=2.5, metadata={"doc": "wall height", "unit": "m"})
    door_width_m: tuple[float, float] = field(
        default=(0.8, 1.0), metadata={"doc": "door gap width range", "unit": "m"})
    lintels: bool = field(default=True, metadata={"doc": "door lintels from lintel_z_m"})
    lintel_z_m: float = field(default=2.0, metadata={"doc": "lintel bottom height", "unit": "m"})
    corridor_width_m: tuple[float, float] = field(
        default=(1.4, 1.8), metadata={"doc": "corridor width range", "unit": "m"})
    room_width_m: tuple[float, float] = field(
        default=(3.0, 6.0), metadata={"doc": "room width range along the corridor", "unit": "m"})
    split_depth_m: float = field(
        default=6.5, metadata={"doc": "rooms deeper than this may be split in two", "unit": "m"})
    extra_door_prob: float = field(
        default=0.3, metadata={"doc": "probability of a door between side-by-side rooms"})
    furniture_clearance_m: float = field(
        default=0.65, metadata={"doc": "free gap kept between furniture groups", "unit": "m"})
    door_keepout_m: float = field(
        default=1.0, metadata={"doc": "furniture-free depth in front of doors", "unit": "m"})
    place_tries: int = field(default=40, metadata={"doc": "placement attempts per group"})
    start_clearance_m: float = field(
        default=0.6, metadata={"doc": "minimum start clearance to obstacles below 1.5 m",
                               "unit": "m"})
    margin_m: float = field(default=0.5, metadata={"doc": "bounds margin", "unit": "m"})

    def __post_init__(self) -> None:
        if not 0 < self.wall_thickness_m < 1.0:
            raise ValueError(f"wall_thickness_m must be in (0, 1), got {self.wall_thickness_m}")
        if not self.wall_height_m > self.lintel_z_m > 0:
            raise ValueError(f"need wall_height_m > lintel_z_m > 0, got {self.wall_height_m}, "
                             f"{self.lintel_z_m}")
        for name in ("door_width_m", "corridor_width_m", "room_width_m"):
            lo, hi = getattr(self, name)
            if not 0 < lo <= hi:
                raise ValueError(f"{name} must be a range 0 < lo <= hi, got {(lo, hi)}")
        if self.corridor_width_m[0] < 2 * self.start_clearance_m + self.wall_thickness_m:
            raise ValueError(
                f"corridor_width_m {self.corridor_width_m} too narrow for start_clearance_m "
                f"{self.start_clearance_m}")
        if self.room_width_m[0] < self.door_width_m[1] + 4 * self.wall_thickness_m:
            raise ValueError(f"room_width_m {self.room_width_m} too small for doors")
        if not 0 <= self.extra_door_prob <= 1:
            raise ValueError(f"extra_door_prob must be in [0, 1], got {self.extra_door_prob}")
        if self.place_tries < 1:
            raise ValueError(f"place_tries must be >= 1, got {self.place_tries}")


def _house_layout(rng: np.random.Generator, width: float, height: float, o: HouseOptions
                  ) -> tuple[list[_Wall], list[tuple[Rect, str]], list[tuple[int, int]],
                             tuple[float, float, float]]:
    """Canonical layout (corridor along x): walls, rooms (rect, kind), doors (room pairs)
    and the start pose. Rects are centre-line rectangles."""
    hw, hh = width / 2, height / 2
    cw = _snap(float(rng.uniform(*o.corridor_width_m)))
    shift = _snap(float(rng.uniform(-0.15, 0.15)) * height)
    cy0, cy1 = shift - cw / 2, shift + cw / 2
    rooms: list[tuple[Rect, str]] = [((-hw, cy0, hw, cy1), "corridor")]
    walls = [_Wall(-hw, -hh, hw, -hh), _Wall(-hw, hh, hw, hh), _Wall(-hw, -hh, -hw, hh),
             _Wall(hw, -hh, hw, hh), _Wall(-hw, cy0, hw, cy0), _Wall(-hw, cy1, hw, cy1)]
    links: list[tuple[int, int]] = []
    for side in (-1, 1):
        near, far = (cy0, -hh) if side < 0 else (cy1, hh)
        depth = abs(far - near)
        x = -hw
        columns = _split_lengths(rng, width, *o.room_width_m)
        prev_front: int | None = None
        for k, cwid in enumerate(columns):
            x0, x1 = x, round(x + cwid, 6)
            x = x1
            if k > 0:
                walls.append(_Wall(x0, min(near, far), x0, max(near, far)))
            split = depth > o.split_depth_m and rng.random() < 0.7
            if split:
                d = _snap(depth * float(rng.uniform(0.4, 0.6)))
                mid = near + side * d
                walls.append(_Wall(x0, mid, x1, mid))
                front = (x0, min(near, mid), x1, max(near, mid))
                back = (x0, min(mid, far), x1, max(mid, far))
                rooms.append((front, "room"))
                fi = len(rooms) - 1
                rooms.append((back, "room"))
                links.append((fi, fi + 1))
            else:
                rooms.append(((x0, min(near, far), x1, max(near, far)), "room"))
                fi = len(rooms) - 1
            links.append((0, fi))
            if prev_front is not None and rng.random() < o.extra_door_prob:
                links.append((prev_front, fi))
            prev_front = fi
    start = (_snap(float(rng.uniform(-0.3, 0.3)) * width), shift, 0.0)
    return walls, rooms, links, start


def _shared_edge(a: Rect, b: Rect) -> tuple[tuple[float, float], tuple[float, float]] | None:
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


def _paint_rooms(rooms: list[tuple[Rect, str]], bounds: tuple[float, float, float, float],
                 res: float) -> npt.NDArray[np.int32]:
    h, w = raster_geometry(bounds, res)
    labels = np.zeros((h, w), np.int32)
    xs = bounds[0] + (np.arange(w) + 0.5) * res
    ys = bounds[1] + (np.arange(h) + 0.5) * res
    for k, (r, _) in enumerate(rooms, start=1):
        cols = (xs >= r[0]) & (xs < r[2])
        rows = (ys >= r[1]) & (ys < r[3])
        labels[np.ix_(rows, cols)] = k
    return labels


def generate_house(seed: int, size_m: tuple[float, float] = (20.0, 20.0),
                   cluttered: bool = False, **opts: Any) -> World:
    """A seeded procedural house: a corridor with rooms on both sides, doors, furniture.

    The house is a rectangle of ``size_m`` centred at the origin. A corridor crosses it
    (along x or y, chosen by the seed); both sides are cut into rooms
    (:attr:`HouseOptions.room_width_m` wide, deep ones split into a front and a back
    room). Every front room has a door to the corridor, back rooms to their front room,
    neighbours sometimes to each other. Walls are ``wall_thickness_m`` boxes,
    ``wall_height_m`` high, with door gaps of ``door_width_m`` and lintels. Furniture:
    tables (4 legs + top at 0.72-0.75 m) with chairs (4 legs, seat at 0.42-0.47 m,
    backrest), desks with a chair, cabinets and sofas; the cluttered variant puts 2-4
    desks with (office) chairs, a table with chairs and loose chairs into every room.

    Parameters
    ----------
    seed : int
        Seed of the layout and furniture (same seed, same world).
    size_m : tuple of float
        Outer size (width along x, height along y) in metres; each >= 8 m.
    cluttered : bool
        Dense furniture variant.
    **opts
        Fields of :class:`HouseOptions`.

    Returns
    -------
    World
        With ``objects`` (one per furniture item), ``room_labels`` (int32 raster at
        0.05 m over the bounds, row = y; every inside free cell carries its room or
        corridor id, everything else 0), ``room_kinds`` and a start pose in the corridor.

    Raises
    ------
    ValueError
        On a bad size or option (unknown option names included).
    """
    try:
        o = HouseOptions(**opts)
    except TypeError as err:
        raise ValueError(f"unknown generate_house option: {err}") from None
    width, height = (float(v) for v in size_m)
    if not (width >= 8.0 and height >= 8.0):
        raise ValueError(f"size_m must be at least (8, 8) m, got {size_m}")
    rng = np.random.default_rng(seed)
    vertical = bool(rng.random() < 0.5)
    cw, ch = (height, width) if vertical else (width, height)
    walls, rooms, links, start = _house_layout(rng, cw, ch, o)
    # doors between linked rooms (canonical frame)
    for a, b in links:
        edge = _shared_edge(rooms[a][0], rooms[b][0])
        if edge is None:
            continue
        (ex0, ey0), (ex1, ey1) = edge
        length = math.hypot(ex1 - ex0, ey1 - ey0)
        dw = _snap(float(rng.uniform(*o.door_width_m)))
        margin = o.wall_thickness_m / 2 + 0.2
        if length < dw + 2 * margin:
            continue
        s0 = float(rng.uniform(margin, length - margin - dw))
        ux, uy = (ex1 - ex0) / length, (ey1 - ey0) / length
        _add_door(walls, (ex0 + ux * s0, ey0 + uy * s0),
                  (ex0 + ux * (s0 + dw), ey0 + uy * (s0 + dw)))
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
        if kind != "room":
            continue
        interior = (rect[0] + t2, rect[1] + t2, rect[2] - t2, rect[3] - t2)
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
        for g in groups:
            pose = _place_group(rng, g, interior, room_blocked, o.furniture_clearance_m,
                                o.place_tries)
            if pose is None:
                continue
            room_blocked.append(_group_box(g, pose))
            p, objs = _instantiate(g, pose, counters)
            prims.extend(p)
            objects.extend(objs)
    hw, hh = width / 2, height / 2
    bounds = _bounds_around(-hw - t2, -hh - t2, hw + t2, hh + t2, o.margin_m)
    world = World(name=f"house{'_cluttered' if cluttered else ''}_s{seed}", bounds=bounds,
                  start_pose=start, primitives=prims, objects=objects,
                  description=f"generated house seed={seed} size={width}x{height} m"
                              f"{' cluttered' if cluttered else ''}")
    gt = ground_truth(world)
    dist = ndimage.distance_transform_edt(gt.footprint_tall.data < OCCUPIED_THRESHOLD) \
        * GT_RESOLUTION_M
    r, c = gt.start_cell
    if dist[r, c] < o.start_clearance_m:     # never expected: the corridor holds no furniture
        ok = gt.inside & (dist >= o.start_clearance_m)
        if not ok.any():
            raise ValueError(f"no start cell with clearance {o.start_clearance_m} m (seed {seed})")
        rr, cc = np.nonzero(ok)
        k = int(np.argmax(dist[rr, cc]))
        x, y = gt.lidar.cell_to_world(rr[k], cc[k])
        world.start_pose = (x, y, start[2])
        gt = ground_truth(world)
    labels = _paint_rooms(rooms, bounds, GT_RESOLUTION_M)
    free = gt.inside & (gt.lidar.data < OCCUPIED_THRESHOLD)
    world.room_labels = np.where(free, labels, 0).astype(np.int32)
    world.room_resolution_m = GT_RESOLUTION_M
    world.room_kinds = {k: kind for k, (_, kind) in enumerate(rooms, start=1)}
    return world


# ============================================================ maze
def generate_maze(seed: int, size_m: tuple[float, float] = (40.0, 40.0), cell_m: float = 2.0,
                  **opts: Any) -> World:
    """A seeded maze of wall boxes on a grid of ``cell_m`` cells.

    A perfect maze (depth-first backtracker) whose interior walls are then removed with
    probability ``loop_prob`` to make a few loops. Walls are ``wall_thickness_m`` thick
    and ``wall_height_m`` high; collinear wall pieces are merged into one box. The start
    is the centre of the middle cell.

    Parameters
    ----------
    seed : int
    size_m : tuple of float
        Outer size (m); the maze has ``floor(size / cell_m)`` cells per axis (>= 2).
    cell_m : float
        Cell pitch (m): corridors are ``cell_m - wall_thickness_m`` wide.
    **opts
        ``wall_thickness_m`` (0.15), ``wall_height_m`` (2.5), ``loop_prob`` (0.05),
        ``margin_m`` (0.5).

    Returns
    -------
    World
        ``room_labels`` is None.

    Raises
    ------
    ValueError
        On a bad size, cell, option name or value.
    """
    known = {"wall_thickness_m": 0.15, "wall_height_m": 2.5, "loop_prob": 0.05, "margin_m": 0.5}
    unknown = sorted(set(opts) - set(known))
    if unknown:
        raise ValueError(f"unknown generate_maze option '{unknown[0]}' (known: {sorted(known)})")
    o = dict(known, **opts)
    t = float(o["wall_thickness_m"])
    if not 0 < t < cell_m - 0.5:
        raise ValueError(f"need 0 < wall_thickness_m < cell_m - 0.5, got {t} for cell {cell_m}")
    if not 0 <= float(o["loop_prob"]) <= 1:
        raise ValueError(f"loop_prob must be in [0, 1], got {o['loop_prob']}")
    nx, ny = (int(math.floor(float(v) / cell_m + 1e-9)) for v in size_m)
    if nx < 2 or ny < 2:
        raise ValueError(f"size_m {size_m} holds fewer than 2x2 cells of {cell_m} m")
    rng = np.random.default_rng(seed)
    # walls: east[i, j] between cell (i, j) and (i+1, j); north[i, j] between (i, j), (i, j+1)
    east = np.ones((nx, ny), bool)
    north = np.ones((nx, ny), bool)
    seen = np.zeros((nx, ny), bool)
    stack = [(int(rng.integers(nx)), int(rng.integers(ny)))]
    seen[stack[0]] = True
    while stack:
        i, j = stack[-1]
        nbrs = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                if 0 <= i + di < nx and 0 <= j + dj < ny and not seen[i + di, j + dj]]
        if not nbrs:
            stack.pop()
            continue
        a, b = nbrs[int(rng.integers(len(nbrs)))]
        if a != i:
            east[min(a, i), j] = False
        else:
            north[i, min(b, j)] = False
        seen[a, b] = True
        stack.append((a, b))
    loops = rng.random((2, nx, ny)) < float(o["loop_prob"])
    east[:-1] &= ~loops[0][:-1]
    north[:, :-1] &= ~loops[1][:, :-1]
    x0, y0 = -nx * cell_m / 2, -ny * cell_m / 2
    walls: list[_Wall] = [_Wall(x0, y0, -x0, y0), _Wall(x0, y0, x0, -y0)]
    # vertical lines x = x0 + (i+1) cell: runs of east[i, :]
    for i in range(nx):
        edges = np.flatnonzero(np.diff(np.concatenate(([0], east[i].astype(np.int8), [0]))))
        for a, b in zip(edges[0::2], edges[1::2]):
            xl = x0 + (i + 1) * cell_m
            walls.append(_Wall(xl, y0 + a * cell_m, xl, y0 + b * cell_m))
    for j in range(ny):
        edges = np.flatnonzero(np.diff(np.concatenate(([0], north[:, j].astype(np.int8), [0]))))
        for a, b in zip(edges[0::2], edges[1::2]):
            yl = y0 + (j + 1) * cell_m
            walls.append(_Wall(x0 + a * cell_m, yl, x0 + b * cell_m, yl))
    prims: list[Primitive] = []
    for k, w in enumerate(walls):
        prims.extend(w.boxes(f"wall_{k}", t, float(o["wall_height_m"]), None))
    start = (x0 + (nx // 2 + 0.5) * cell_m, y0 + (ny // 2 + 0.5) * cell_m, 0.0)
    bounds = _bounds_around(x0 - t / 2, y0 - t / 2, -x0 + t / 2, -y0 + t / 2,
                            float(o["margin_m"]))
    return World(name=f"maze_s{seed}", bounds=bounds, start_pose=start, primitives=prims,
                 description=f"generated maze seed={seed} {nx}x{ny} cells of {cell_m} m")


# ============================================================ defaults
WORLD_NAMES: tuple[str, ...] = ("house", "house_cluttered", "maze", "small_house",
                                "small_cluttered")
#: Size of the small test houses (m).
SMALL_HOUSE_SIZE_M = (10.0, 8.0)
#: Room widths of the small houses (m): 2 rooms per side of the corridor.
SMALL_ROOM_WIDTH_M = (4.0, 6.0)


def default_world(name: str = "house_cluttered") -> World:
    """One of the embedded worlds (regenerated on each call, so callers may mutate it).

    ``house`` / ``house_cluttered``: :func:`generate_house` seed 1, 20 x 20 m;
    ``maze``: :func:`generate_maze` seed 1, 40 x 40 m; ``small_house`` /
    ``small_cluttered``: a 10 x 8 m house with 4 rooms and a corridor (seed 1).

    Raises
    ------
    ValueError
        On a name not in :data:`WORLD_NAMES`.
    """
    if name == "house":
        w = generate_house(1)
    elif name == "house_cluttered":
        w = generate_house(1, cluttered=True)
    elif name == "maze":
        w = generate_maze(1)
    elif name in ("small_house", "small_cluttered"):
        w = generate_house(1, SMALL_HOUSE_SIZE_M, cluttered=name == "small_cluttered",
                           room_width_m=SMALL_ROOM_WIDTH_M)
    else:
        raise ValueError(f"world name must be one of {WORLD_NAMES}, got {name!r}")
    w.name = name
    return w
