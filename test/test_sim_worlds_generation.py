"""Procedural worlds: house and maze invariants, default worlds, save/load round trip."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage
from shapely.geometry import Point, Polygon

from sim_bridge.world import Primitive
from sim_bridge.worlds import (WORLD_NAMES, default_world, generate_house, generate_maze,
                               ground_truth, load_world, save_world)


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
    assert WORLD_NAMES == ("house", "house_cluttered", "maze", "small_house", "small_cluttered",
                           "office_floor")
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
