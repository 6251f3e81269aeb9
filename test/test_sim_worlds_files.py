"""World files: the worlds shipped in ``worlds/`` (houses, maze, Explore-Bench maps), world
specs, loader errors naming file and key."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
from scipy import ndimage
import yaml

from sim_bridge.world import Primitive
from sim_bridge.worlds import ground_truth, load_world, worlds_dir

SHARED_WORLDS = ("house", "house_cluttered", "house_cluttered_plus", "maze")
EXPLORE_BENCH = ("corner", "corridor", "corridor_asym", "corridor_sym", "loop",
                 "loop_with_corridor", "room", "room_1", "room_2", "room_3", "room_with_corner",
                 "room_with_corridor")
WORLDS = worlds_dir()


def _pgm(path: Path) -> np.ndarray:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)[::-1]
    return np.where(img == 0, 100, np.where(img == 254, 0, -1)).astype(np.int8)


@pytest.mark.parametrize("name", SHARED_WORLDS)
def test_shared_world_loads(name):
    path = WORLDS / f"{name}.world.yaml"
    w = load_world(path)
    doc = yaml.safe_load(path.read_text())
    assert w.name == name
    assert len(w.primitives) == len(doc["obstacles"])
    assert len(w.objects) == len(doc["objects"])
    assert w.bounds == tuple(doc["bounds"]) and w.start_pose == tuple(doc["start_pose"])


@pytest.mark.parametrize("name", ["house_cluttered_plus", "maze", "house"])
@pytest.mark.parametrize("which, suffix", [("lidar", ""), ("footprint", "_footprint"),
                                           ("footprint_tall", "_footprint_tall")])
def test_shared_rasters_match_pgm(name, which, suffix):
    w = load_world(WORLDS / f"{name}.world.yaml")
    gt = ground_truth(w)
    ref = _pgm(WORLDS / f"{name}{suffix}.pgm")
    mine = gt.as_map(which).data
    assert mine.shape == ref.shape
    assert (mine == ref).mean() >= 0.995
    occ_ref, occ_me = ref == 100, mine == 100
    # occupied cells agree to a few cells (rotated maze walls differ by a hair)
    assert (occ_ref ^ occ_me).sum() <= 0.001 * occ_ref.size


@pytest.mark.parametrize("name", EXPLORE_BENCH)
def test_explore_bench_map_loads_with_start(name):
    folder = WORLDS / "explore_bench"
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


def test_explore_bench_start_override_and_fallback(tmp_path):
    src = WORLDS / "explore_bench"
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
