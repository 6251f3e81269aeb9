"""World files: ``explore_seg_world/1`` YAML and map_server YAML + PGM/PNG.

* :func:`read_world_file` reads an ``explore_seg_world/1`` file (``*.world.yaml``) or a
  map_server YAML (+ PGM/PNG; an Explore-Bench map, with its start from a sibling
  ``starts.yaml``) into a :class:`~sim_bridge.world.World`. Loading by spec (names,
  shipped worlds, paths) is :func:`sim_bridge.worlds.catalog.load_world`.
* :func:`save_world` / :func:`world_to_dict` write the ``explore_seg_world/1`` format.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import yaml
from scipy import ndimage

from explore_seg.core.grid import MAP_IMAGE_MODES, GridMap, occupancy_from_map_image
from sim_bridge.world import SHAPES, Primitive, World, WorldObject

WORLD_FORMAT = "explore_seg_world/1"
#: Classes a primitive or object may have (``table`` also covers desks in the shipped worlds).
KNOWN_CLASSES = ("wall", "chair", "table", "desk", "cabinet", "sofa", "other")
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


def read_world_file(path: str | Path,
                    start_pose: tuple[float, float, float] | None = None) -> World:
    """Read a world file.

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
    >>> from sim_bridge.worlds import worlds_dir
    >>> w = read_world_file(worlds_dir() / "maze.world.yaml")
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
