"""The generated office floor: size, rooms, corridors, doors, reachability, determinism."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from explore_seg.core.grid import OCCUPIED_THRESHOLD
from explore_seg.core.paths import inflate
from sim_bridge.engine import SimParams
from sim_bridge.worlds import generate_office_floor, ground_truth, load_world, world_to_dict


@pytest.fixture(scope="module", params=[1, 7])
def office(request):
    world = generate_office_floor(request.param)
    return world, ground_truth(world)


def test_size_rooms_and_corridors(office):
    world, _ = office
    walls = [p for p in world.primitives if p.cls == "wall"]
    xs = [p.x for p in walls]
    ys = [p.y for p in walls]
    assert max(xs) - min(xs) == pytest.approx(60.0, abs=0.2)
    assert max(ys) - min(ys) == pytest.approx(40.0, abs=0.2)
    kinds = list(world.room_kinds.values())
    assert kinds.count("room") >= 30
    assert kinds.count("corridor") == 4          # two long ones, two cross corridors
    assert len(world.objects) >= kinds.count("room")   # furnished like the houses
    assert {o.cls for o in world.objects} >= {"chair", "table"}


def test_every_room_is_reachable_for_the_robot(office):
    """Flood fill over the robot's footprint raster grown by its radius, from the start:
    every room and corridor holds reachable cells (its doors are wide enough)."""
    world, gt = office
    res = gt.resolution_m
    blocked = gt.footprint.data >= OCCUPIED_THRESHOLD
    passable = ~inflate(blocked, SimParams().robot_radius_m, res)
    lab, _ = ndimage.label(passable, structure=np.ones((3, 3)))
    reach = lab == lab[gt.start_cell]
    assert reach[gt.start_cell]
    labels = world.room_labels
    for room in world.room_kinds:
        cells = labels == room
        assert cells.any(), f"room {room} has no free cell"
        share = (reach & cells).sum() / cells.sum()
        assert share > 0.5, f"room {room} ({world.room_kinds[room]}): {share:.2f} reachable"


def test_same_seed_same_world_other_seed_other_world():
    a, b = generate_office_floor(3), generate_office_floor(3)
    assert world_to_dict(a) == world_to_dict(b)
    assert np.array_equal(a.room_labels, b.room_labels)
    assert world_to_dict(generate_office_floor(4)) != world_to_dict(a)


def test_named_world_and_bad_size():
    w = load_world("office_floor")
    assert w.name == "office_floor"
    assert w.primitives == generate_office_floor(1).primitives
    with pytest.raises(ValueError, match="size_m must be at least"):
        generate_office_floor(1, size_m=(20.0, 20.0))
    with pytest.raises(ValueError, match="unknown generate_office_floor option"):
        generate_office_floor(1, hallways=2)
