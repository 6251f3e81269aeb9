"""Tests of sim_bridge.worlds: loading, rasters, generation, default worlds."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from scipy import ndimage
from shapely.geometry import Point, Polygon

from explore_seg.core.grid import grid_from_ascii
from sim_bridge.world import Primitive, World
from sim_bridge.worlds import (WORLD_NAMES, default_world, flood_inside, generate_house,
                               generate_maze, ground_truth, load_world, rasterize, save_world)

SHARED_WORLDS = ("house", "house_cluttered", "house_cluttered_plus", "maze")
EXPLORE_BENCH = ("corner", "corridor", "corridor_asym", "corridor_sym", "loop",
                 "loop_with_corridor", "room", "room_1", "room_2", "room_3", "room_with_corner",
                 "room_with_corridor")


def _world(prims: list[Primitive], bounds=(0.0, 0.0, 0.5, 0.5), start=(0.05, 0.05, 0.0)):
    return World(name="t", bounds=bounds, start_pose=start, primitives=prims)


def _box(x, y, sx, sy, yaw=0.0, z=(0.0, 1.0), cls="wall", obj=""):
    return Primitive(obj, cls, "wall", "box", x, y, yaw, (sx, sy), z[0], z[1])


def _cyl(x, y, r, z=(0.0, 1.0)):
    return Primitive("o", "table", "leg", "cylinder", x, y, 0.0, (r,), z[0], z[1])


def _pgm(path: Path) -> np.ndarray:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)[::-1]
    return np.where(img == 0, 100, np.where(img == 254, 0, -1)).astype(np.int8)


# ------------------------------------------------------------------ rasterisation
@pytest.mark.parametrize("prim, expected", [
    # box edges exactly on cell borders: touching neighbours are not occupied
    (_box(0.2, 0.2, 0.2, 0.2), """
.....
.....
.##..
.##..
.....
"""),
    # box overlapping its neighbours by 0.5 mm: below the 1 mm rule
    (_box(0.2, 0.2, 0.201, 0.201), """
.....
.....
.##..
.##..
.....
"""),
    # overlap of 2 mm marks the neighbours
    (_box(0.2, 0.2, 0.204, 0.204), """
.....
####.
####.
####.
####.
"""),
    # thin leg at a cell centre: one cell
    (_cyl(0.25, 0.25, 0.02), """
.....
.....
..#..
.....
.....
"""),
    # box turned by 45 deg: a diamond
    (_box(0.25, 0.25, 0.12, 0.12, yaw=math.pi / 4), """
.....
..#..
.###.
..#..
.....
"""),
])
def test_rasterize_cell_rule(prim, expected):
    grid, _ = grid_from_ascii(expected, resolution_m=0.1)
    got = rasterize(_world([prim]), 0.1, 0.17, 0.17)
    assert got.data.tolist() == grid.data.tolist()


@pytest.mark.parametrize("z, z_low, z_high, occupied", [
    ((0.0, 0.17), 0.17, 0.17, True),      # plane test is closed at zmax
    ((0.17, 1.0), 0.17, 0.17, True),      # ... and at zmin
    ((0.18, 1.0), 0.17, 0.17, False),
    ((0.5, 1.0), 0.0, 0.5, False),        # band test is open: a seat from 0.5 m is not in it
    ((0.45, 1.0), 0.0, 0.5, True),
    ((2.0, 2.5), 0.0, 1.5, False),        # lintel
])
def test_rasterize_height_filter(z, z_low, z_high, occupied):
    got = rasterize(_world([_box(0.25, 0.25, 0.2, 0.2, z=z)]), 0.1, z_low, z_high)
    assert bool(got.data.any()) is occupied


def test_world_occupancy_method_matches_rasterize():
    w = _world([_box(0.25, 0.25, 0.2, 0.2), _cyl(0.05, 0.45, 0.03)])
    assert np.array_equal(w.occupancy(0.05, 0.0, 0.5).data, rasterize(w, 0.05, 0.0, 0.5).data)


def test_rasterize_rejects_bad_band():
    with pytest.raises(ValueError, match="z_low <= z_high"):
        rasterize(_world([]), 0.1, 0.5, 0.2)


def test_ground_truth_inside_is_flood_fill_from_start():
    # a closed 1 x 1 m room (walls 0.1 m) inside 2 x 2 m bounds, start in it
    walls = [_box(0.5, 0.05, 1.0, 0.1), _box(0.5, 0.95, 1.0, 0.1),
             _box(0.05, 0.5, 0.1, 1.0), _box(0.95, 0.5, 0.1, 1.0)]
    w = World("room", (-0.5, -0.5, 1.5, 1.5), (0.5, 0.5, 0.0), walls)
    gt = ground_truth(w, 0.1)
    assert gt.inside.sum() == 64                    # 8 x 8 interior cells
    assert gt.free_area_m2 == pytest.approx(0.64)
    m = gt.as_map("lidar").data
    assert (m == 0).sum() == 64 and (m == 100).sum() == 100 - 64
    assert (m == -1).sum() == 400 - 100


def test_flood_inside_is_4_connected():
    grid, marks = grid_from_ascii("""
    ..#..
    .S#..
    ##.#.
    ...#.
    """)
    inside = flood_inside(grid.free_mask(), marks["S"][0])
    want, _ = grid_from_ascii("""
    ##...
    ##...
    .....
    .....
    """)
    assert inside.tolist() == (want.data == 100).tolist()


def test_flood_inside_rejects_blocked_start():
    with pytest.raises(ValueError, match="occupied"):
        flood_inside(np.zeros((3, 3), bool), (1, 1))


def test_flood_inside_rejects_start_outside():
    with pytest.raises(ValueError, match="outside"):
        flood_inside(np.ones((3, 3), bool), (5, 1))


def test_as_map_rejects_unknown_raster():
    gt = ground_truth(_world([_box(0.35, 0.35, 0.1, 0.1)]), 0.1)
    with pytest.raises(ValueError, match="which must be one of"):
        gt.as_map("ceiling")


# ------------------------------------------------------------------ shared worlds
@pytest.mark.parametrize("name", SHARED_WORLDS)
def test_shared_world_loads(shared, name):
    path = shared / "worlds" / f"{name}.world.yaml"
    w = load_world(path)
    doc = yaml.safe_load(path.read_text())
    assert w.name == name
    assert len(w.primitives) == len(doc["obstacles"])
    assert len(w.objects) == len(doc["objects"])
    assert w.bounds == tuple(doc["bounds"]) and w.start_pose == tuple(doc["start_pose"])


@pytest.mark.parametrize("name", ["house_cluttered_plus", "maze", "house"])
@pytest.mark.parametrize("which, suffix", [("lidar", ""), ("footprint", "_footprint"),
                                           ("footprint_tall", "_footprint_tall")])
def test_shared_rasters_match_pgm(shared, name, which, suffix):
    w = load_world(shared / "worlds" / f"{name}.world.yaml")
    gt = ground_truth(w)
    ref = _pgm(shared / "worlds" / f"{name}{suffix}.pgm")
    mine = gt.as_map(which).data
    assert mine.shape == ref.shape
    assert (mine == ref).mean() >= 0.995
    occ_ref, occ_me = ref == 100, mine == 100
    # occupied cells agree to a few cells (rotated maze walls differ by a hair)
    assert (occ_ref ^ occ_me).sum() <= 0.001 * occ_ref.size


@pytest.mark.parametrize("name", EXPLORE_BENCH)
def test_explore_bench_map_loads_with_start(shared, name):
    folder = shared / "worlds" / "explore_bench"
    w = load_world(folder / f"{name}.yaml")
    starts = yaml.safe_load((folder / "starts.yaml").read_text())["maps"][name]
    assert w.start_pose == tuple(starts["start_pose"])
    grid = w.base_grid
    assert grid.resolution_m == 0.1 and grid.origin_xy_m == (-12.5, -12.5)
    assert np.array_equal(grid.data, _pgm(folder / f"{name}.pgm"))
    assert int((grid.data == 0).sum()) == starts["free_cells"]
    # the wall boxes reproduce the map exactly at its own resolution
    gt = ground_truth(w, 0.1)
    assert np.array_equal(gt.as_map("lidar").data, grid.data)


def test_explore_bench_start_override_and_fallback(shared, tmp_path):
    src = shared / "worlds" / "explore_bench"
    w = load_world(src / "room.yaml", start_pose=(1.0, 2.0, 0.5))
    assert w.start_pose == (1.0, 2.0, 0.5)
    # without starts.yaml: the free cell farthest from non-free cells
    (tmp_path / "room.pgm").write_bytes((src / "room.pgm").read_bytes())
    (tmp_path / "room.yaml").write_text((src / "room.yaml").read_text())
    w = load_world(tmp_path / "room.yaml")
    grid = w.base_grid
    dist = ndimage.distance_transform_edt(grid.data == 0)
    r, c = grid.world_to_cell(w.start_pose[0], w.start_pose[1])
    assert dist[r, c] == dist.max()


# ------------------------------------------------------------------ loader errors
_GOOD = {"format": "explore_seg_world/1", "name": "t", "bounds": [0, 0, 2, 2],
         "start_pose": [1, 1, 0], "objects": [],
         "obstacles": [{"name": "w/a", "object": "w", "class": "wall", "part": "wall",
                        "shape": "box", "pose": [0.5, 0.5, 0], "size": [0.2, 0.2],
                        "z": [0, 1]}]}


def _with(path: list, value):
    doc = yaml.safe_load(yaml.safe_dump(_GOOD))
    node = doc
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return doc


def test_good_world_file_loads(tmp_path):
    p = tmp_path / "t.world.yaml"
    p.write_text(yaml.safe_dump(_GOOD))
    w = load_world(p)
    assert w.primitives[0] == Primitive("w", "wall", "wall", "box", 0.5, 0.5, 0.0, (0.2, 0.2),
                                        0.0, 1.0)


@pytest.mark.parametrize("doc, match", [
    (_with(["colour"], "red"), "unknown key 'colour'"),
    (_with(["bounds"], KeyError), "missing key 'bounds'"),
    (_with(["format"], "explore_seg_world/2"), "key 'format'"),
    (_with(["bounds"], [0, 0, 2]), "key 'bounds'"),
    (_with(["bounds"], [2, 0, 0, 2]), "key 'bounds' needs"),
    (_with(["start_pose"], [5, 5, 0]), "key 'start_pose'.*outside"),
    (_with(["start_pose"], [1, "a", 0]), "key 'start_pose'"),
    (_with(["obstacles"], {"a": 1}), "key 'obstacles' must be a list"),
    (_with(["obstacles", 0, "radius"], 1), r"obstacles\[0\].*unknown key 'radius'"),
    (_with(["obstacles", 0, "shape"], "cone"), "key 'shape'"),
    (_with(["obstacles", 0, "class"], "robot"), "key 'class'"),
    (_with(["obstacles", 0, "size"], [0.2]), "key 'size'"),
    (_with(["obstacles", 0, "size"], [0.2, -1]), "key 'size' or 'z' invalid"),
    (_with(["obstacles", 0, "z"], [1, 0]), "key 'size' or 'z' invalid"),
    (_with(["obstacles", 0, "pose"], [0, 0, float("nan")]), "key 'pose'.*finite"),
    (_with(["obstacles", 0, "z"], KeyError), "missing key 'z'"),
    (_with(["objects"], [{"name": "a", "class": "chair", "pose": [0, 0, 0]}]),
     "missing key 'aabb'"),
    (_with(["name"], 3), "key 'name' must be a string"),
])
def test_world_file_errors_name_the_key(tmp_path, doc, match):
    p = tmp_path / "bad.world.yaml"
    p.write_text(yaml.safe_dump(doc))
    with pytest.raises(ValueError, match=match):
        load_world(p)


_MAP = {"image": "m.pgm", "mode": "trinary", "resolution": 0.1, "origin": [0, 0, 0],
        "negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196}


@pytest.mark.parametrize("change, match", [
    ({"color": 1}, "unknown key 'color'"),
    ({"image": KeyError}, "key 'format'.*key 'image'"),
    ({"resolution": KeyError}, "missing key 'resolution'"),
    ({"resolution": -0.1}, "key 'resolution'"),
    ({"origin": [0, 0]}, "key 'origin'"),
    ({"origin": [0, 0, 0.3]}, "key 'origin' yaw"),
    ({"mode": "fancy"}, "key 'mode'"),
    ({"negate": 2}, "key 'negate'"),
    ({"occupied_thresh": 1.5}, "key 'occupied_thresh'"),
    ({"free_thresh": 0.9}, "key 'free_thresh'"),
    ({"image": "missing.pgm"}, "key 'image' names a missing file"),
    ({"image": "m.txt"}, "key 'image': cannot read"),
])
def test_map_yaml_errors_name_the_key(tmp_path, change, match):
    img = np.full((10, 12), 254, np.uint8)
    img[0, :] = 0
    cv2.imwrite(str(tmp_path / "m.pgm"), img)
    (tmp_path / "m.txt").write_text("not an image")
    doc = dict(_MAP)
    for k, v in change.items():
        if v is KeyError:
            del doc[k]
        else:
            doc[k] = v
    p = tmp_path / "m.yaml"
    p.write_text(yaml.safe_dump(doc))
    with pytest.raises(ValueError, match=match):
        load_world(p)


def test_map_yaml_trinary_negate_and_rows(tmp_path):
    img = np.full((4, 5), 254, np.uint8)
    img[0, :] = 0          # top image row = largest y
    img[3, 0] = 205
    cv2.imwrite(str(tmp_path / "m.pgm"), img)
    (tmp_path / "m.yaml").write_text(yaml.safe_dump(dict(_MAP, origin=[1.0, 2.0, 0.0])))
    w = load_world(tmp_path / "m.yaml", start_pose=(1.25, 2.15, 0.0))
    assert w.base_grid.data.tolist() == [[-1, 0, 0, 0, 0], [0] * 5, [0] * 5, [100] * 5]
    assert w.bounds == (1.0, 2.0, 1.5, 2.4)
    (tmp_path / "n.yaml").write_text(yaml.safe_dump(dict(_MAP, negate=1)))
    w = load_world(tmp_path / "n.yaml", start_pose=(0.05, 0.35, 0.0))
    assert w.base_grid.data[3].tolist() == [0] * 5 and w.base_grid.data[1, 1] == 100


@pytest.mark.parametrize("content, match", [
    ("a: [1, 2", "not valid YAML"),
    ("just: text", "neither key 'format'"),
])
def test_unreadable_files(tmp_path, content, match):
    p = tmp_path / "x.yaml"
    p.write_text(content)
    with pytest.raises(ValueError, match=match):
        load_world(p)


def test_missing_file(tmp_path):
    with pytest.raises(ValueError, match="no such world file"):
        load_world(tmp_path / "nope.world.yaml")


# ------------------------------------------------------------------ generator
def _dist_m(gt):
    return ndimage.distance_transform_edt(gt.footprint_tall.data < 65) * gt.resolution_m


def _closed(gt) -> bool:
    ins = gt.inside
    return not (ins[0].any() or ins[-1].any() or ins[:, 0].any() or ins[:, -1].any())


@pytest.mark.parametrize("seed, size, cluttered", [
    (1, (20.0, 20.0), False), (2, (20.0, 20.0), True), (3, (20.0, 14.0), True),
    (4, (10.0, 8.0), False), (5, (12.0, 9.0), True)])
def test_house_invariants(seed, size, cluttered):
    w = generate_house(seed, size, cluttered=cluttered)
    gt = ground_truth(w)
    assert _closed(gt)
    r, c = gt.start_cell
    assert _dist_m(gt)[r, c] >= 0.6
    free = gt.inside & (gt.lidar.data < 65)
    # labels cover exactly the inside free cells, and every room is reachable
    assert np.array_equal(w.room_labels > 0, free)
    assert set(np.unique(w.room_labels[free]).tolist()) == set(w.room_kinds)
    assert list(w.room_kinds.values()).count("corridor") == 1
    # a disk robot of radius 0.2 m (footprint raster) reaches every room from the start
    roomy = ndimage.distance_transform_edt(gt.footprint.data < 65) * gt.resolution_m >= 0.2
    comp, _ = ndimage.label(roomy)
    reach = comp == comp[r, c]
    assert set(np.unique(w.room_labels[reach]).tolist()) - {0} == set(w.room_kinds)
    assert w.room_labels.shape == gt.inside.shape
    # the house fills its size: outer walls at +-size/2
    walls = [p for p in w.primitives if p.cls == "wall"]
    xs = [p.x for p in walls]
    ys = [p.y for p in walls]
    assert max(xs) - min(xs) == pytest.approx(size[0], abs=0.2)
    assert max(ys) - min(ys) == pytest.approx(size[1], abs=0.2)
    # walls: 0.15 m thick, 2.5 m high (lintels from 2.0 m)
    assert all(p.size[1] == pytest.approx(0.15) for p in walls)
    assert {p.zmax for p in walls} == {2.5} and {p.zmin for p in walls} <= {0.0, 2.0}


def test_house_furniture_structure_and_no_wall_overlap():
    w = generate_house(7, cluttered=True)
    walls = [p for p in w.primitives if p.cls == "wall" and p.zmin == 0.0]

    def poly(p):
        if p.shape == "cylinder":
            return Point(p.x, p.y).buffer(p.size[0], 32)
        c, s = math.cos(p.yaw), math.sin(p.yaw)
        hx, hy = p.size[0] / 2, p.size[1] / 2
        return Polygon([(p.x + c * u - s * v, p.y + s * u + c * v)
                        for u, v in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))])

    wall_polys = [poly(p) for p in walls]
    by_obj: dict[str, list[Primitive]] = {}
    for p in w.primitives:
        if p.cls != "wall":
            by_obj.setdefault(p.object, []).append(p)
            assert not any(poly(p).intersection(q).area > 1e-9 for q in wall_polys), p
    assert set(by_obj) == {o.name for o in w.objects}
    n_chairs = n_tables = 0
    for o in w.objects:
        parts = by_obj[o.name]
        kinds = sorted(p.part for p in parts)
        for p in parts:     # the aabb holds every part
            b = poly(p).bounds
            assert o.aabb[0] <= b[0] + 1e-9 and b[2] <= o.aabb[3] + 1e-9
            assert o.aabb[1] <= b[1] + 1e-9 and b[3] <= o.aabb[4] + 1e-9
        if o.cls == "table":
            n_tables += 1
            assert kinds == ["leg"] * 4 + ["top"]
            top = next(p for p in parts if p.part == "top")
            assert 0.72 <= top.zmax <= 0.75
            assert all(p.zmax <= top.zmin + 1e-9 for p in parts if p.part == "leg")
        if o.cls == "chair":
            n_chairs += 1
            seat = next(p for p in parts if p.part == "seat")
            assert 0.42 <= seat.zmin and seat.zmax <= 0.47 + 1e-9
            assert "back" in kinds and (kinds.count("leg") == 4 or "post" in kinds)
    rooms = sum(1 for k in w.room_kinds.values() if k == "room")
    assert n_chairs >= 2 * rooms and n_tables >= 2 * rooms


def test_house_deterministic_per_seed_and_varies():
    a, b, c = generate_house(11), generate_house(11), generate_house(12)
    assert a.primitives == b.primitives and a.objects == b.objects
    assert np.array_equal(a.room_labels, b.room_labels) and a.start_pose == b.start_pose
    assert a.primitives != c.primitives


@pytest.mark.parametrize("kwargs, match", [
    ({"size_m": (5.0, 20.0)}, "size_m"),
    ({"colour": "red"}, "unknown generate_house option"),
    ({"wall_thickness_m": 0.0}, "wall_thickness_m"),
    ({"door_width_m": (1.0, 0.8)}, "door_width_m"),
    ({"corridor_width_m": (0.8, 1.0)}, "corridor_width_m"),
    ({"room_width_m": (1.0, 2.0)}, "room_width_m"),
    ({"extra_door_prob": 2.0}, "extra_door_prob"),
    ({"place_tries": 0}, "place_tries"),
    ({"lintel_z_m": 3.0}, "lintel_z_m"),
])
def test_house_rejects_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        generate_house(1, **kwargs)


@pytest.mark.parametrize("seed, size, cell", [(1, (40.0, 40.0), 2.0), (2, (12.0, 9.0), 1.5)])
def test_maze_invariants(seed, size, cell):
    w = generate_maze(seed, size, cell)
    assert w.room_labels is None
    gt = ground_truth(w)
    assert _closed(gt)
    nx, ny = int(size[0] // cell), int(size[1] // cell)
    # every cell centre is reachable from the start
    xs = (np.arange(nx) + 0.5) * cell - nx * cell / 2
    ys = (np.arange(ny) + 0.5) * cell - ny * cell / 2
    gx, gy = np.meshgrid(xs, ys)
    r, c = gt.lidar.world_to_cells(gx.ravel(), gy.ravel())
    assert gt.inside[r, c].all()
    # corridors about a cell wide: free area near nx*ny*(cell - 0.15)^2 plus openings
    assert nx * ny * (cell - 0.2) ** 2 < gt.free_area_m2 < nx * ny * cell ** 2
    assert generate_maze(seed, size, cell).primitives == w.primitives
    assert generate_maze(seed + 1, size, cell).primitives != w.primitives


@pytest.mark.parametrize("kwargs, match", [
    ({"size_m": (3.0, 40.0)}, "fewer than 2x2"),
    ({"cell_m": 0.5}, "wall_thickness_m"),
    ({"loop_prob": -0.1}, "loop_prob"),
    ({"doors": 3}, "unknown generate_maze option 'doors'"),
])
def test_maze_rejects_bad_options(kwargs, match):
    with pytest.raises(ValueError, match=match):
        generate_maze(1, **kwargs)


def test_default_worlds():
    assert WORLD_NAMES == ("house", "house_cluttered", "maze", "small_house", "small_cluttered")
    small = default_world("small_house")
    assert 3 <= sum(k == "room" for k in small.room_kinds.values()) <= 4
    xs = [p.x for p in small.primitives]
    assert max(xs) - min(xs) == pytest.approx(10.0, abs=0.2)
    clut = default_world("small_cluttered")
    assert {o.cls for o in clut.objects} >= {"chair", "table"}
    assert default_world("house").name == "house"
    assert default_world("house_cluttered").primitives == generate_house(
        1, cluttered=True).primitives
    with pytest.raises(ValueError, match="world name must be one of"):
        default_world("castle")


def test_save_load_round_trip(tmp_path):
    w = default_world("small_cluttered")
    save_world(w, tmp_path / "s.world.yaml")
    back = load_world(tmp_path / "s.world.yaml")
    assert len(back.primitives) == len(w.primitives) and back.objects[0].name == w.objects[0].name
    assert np.array_equal(ground_truth(back).lidar.data, ground_truth(w).lidar.data)
    assert np.array_equal(ground_truth(back).footprint.data, ground_truth(w).footprint.data)
