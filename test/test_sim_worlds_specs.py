"""World specs: the one loader (:func:`sim_bridge.worlds.load_world`), the worlds shipped in
``worlds/`` and the benchmark's world list. A world asked for and not found is an error
naming it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bench import run_bench
from bench.worlds import default_worlds, load, world_path
from sim_bridge import engine
from sim_bridge.worlds import (EXPLORE_BENCH_MAPS, FILE_WORLDS, WORLD_NAMES, default_world,
                               load_world, read_world_file, resolve_world, world_file,
                               worlds_dir)
from world_digest import world_digest

ROOT = Path(__file__).resolve().parents[1]
#: Digests of the shipped worlds as loaded from the copies they were taken from.
DIGESTS = json.loads((ROOT / "test" / "data" / "world_digests.json").read_text())
SHIPPED = [f"shared/{n}" for n in FILE_WORLDS] + [f"eb/{n}" for n in EXPLORE_BENCH_MAPS]


def test_worlds_dir_is_the_repository_folder():
    assert worlds_dir() == ROOT / "worlds"


def test_the_shipped_lists_name_every_world_file():
    assert sorted(FILE_WORLDS) == sorted(p.name[:-len(".world.yaml")]
                                         for p in worlds_dir().glob("*.world.yaml"))
    assert sorted(EXPLORE_BENCH_MAPS) == sorted(
        p.stem for p in (worlds_dir() / "explore_bench").glob("*.yaml") if p.stem != "starts")
    assert sorted(DIGESTS) == sorted(SHIPPED)


@pytest.mark.parametrize("spec", SHIPPED)
def test_a_shipped_world_loads_to_the_same_arrays_as_its_source_copy(spec):
    assert world_digest(load_world(spec)) == DIGESTS[spec]


def test_the_benchmark_loads_a_spec_like_the_simulator():
    world, gt = load("eb/corner")
    assert world.name == "eb/corner"
    assert world_digest(world) == DIGESTS["eb/corner"]
    assert gt.observable is not None


@pytest.mark.parametrize("spec, rel", [("shared/maze", "maze.world.yaml"),
                                       ("eb/room_2", "explore_bench/room_2.yaml")])
def test_a_spec_and_its_path_load_the_same_world(spec, rel):
    path = worlds_dir() / rel
    assert world_file(spec) == path and world_path(spec) == str(path)
    assert world_digest(load_world(spec)) == world_digest(load_world(str(path)))
    assert world_digest(load_world(path)) == world_digest(read_world_file(path))


def test_names_and_paths_resolve_as_before(tmp_path):
    assert resolve_world("small_house") == "small_house"
    assert world_file("small_house") is None
    w = load_world("small_house")
    assert w.name == "small_house" and w.primitives == default_world("small_house").primitives
    moved = load_world("small_house", start_pose=(1.0, 1.5, 0.3))
    assert moved.start_pose == (1.0, 1.5, 0.3)
    with pytest.raises(ValueError, match="outside bounds"):
        load_world("small_house", start_pose=(100.0, 0.0, 0.0))
    # a path whose text starts like a spec, given with its suffix, is a path
    (tmp_path / "eb").mkdir()
    src = worlds_dir() / "explore_bench"
    for f in ("room.yaml", "room.pgm"):
        (tmp_path / "eb" / f).write_bytes((src / f).read_bytes())
    w = load_world(str(tmp_path / "eb" / "room.yaml"), start_pose=(1.0, 2.0, 0.5))
    assert w.start_pose == (1.0, 2.0, 0.5)


@pytest.mark.parametrize("spec, match", [
    ("eb/nope", r"world 'eb/nope': no file .*explore_bench/nope\.yaml; eb/NAME takes NAME from "
                r"corner, "),
    ("shared/houses", r"world 'shared/houses': no file .*houses\.world\.yaml; shared/NAME takes"),
    ("eb/", r"world 'eb/': no file"),
    ("shared/explore_bench/room", r"world 'shared/explore_bench/room': no file"),
    ("hosue", r"world 'hosue' is not a world name \(house, .*eb/NAME"),
    ("missing/dir/x.world.yaml", r"world 'missing/dir/x.world.yaml': no such world file"),
    ("", r"non-empty"),
])
def test_a_world_not_found_is_an_error_naming_it(spec, match):
    with pytest.raises(ValueError, match=match):
        resolve_world(spec)
    with pytest.raises(ValueError, match=match):
        load_world(spec)


def test_the_engine_loads_through_the_one_loader():
    assert not hasattr(engine, "load_world")
    eng = engine.engine_from_params(engine.SimParams(world="eb/corridor_asym"))
    assert world_digest(eng.world) == DIGESTS["eb/corridor_asym"]


def test_the_full_benchmark_lists_all_twenty_worlds():
    specs = default_worlds()
    assert len(specs) == len(set(specs)) == 20
    assert specs[:4] == ["house", "maze", "house_cluttered", "office_floor"]
    assert specs[4:] == SHIPPED
    assert all(s in WORLD_NAMES or Path(world_path(s)).is_file() for s in specs)


def test_bench_list_prints_the_resolved_worlds_and_runs_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    assert run_bench.main(["--list", "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("[bench] 20 worlds x ")
    listed = dict(line.split("\t") for line in lines[1:])
    assert list(listed) == default_worlds()
    assert listed["house"] == "(generated)"
    assert listed["eb/room_3"] == str(worlds_dir() / "explore_bench" / "room_3.yaml")
    assert not out.exists()


def test_bench_stops_on_a_missing_world_naming_every_one(tmp_path, capsys):
    out = tmp_path / "out"
    rc = run_bench.main(["--worlds", "eb/room,eb/nope,shared/nope", "--runs", "1",
                         "--out", str(out)])
    assert rc == 2
    err = capsys.readouterr().err
    assert "world 'eb/nope'" in err and "world 'shared/nope'" in err and "eb/room'" not in err
    assert not out.exists()
