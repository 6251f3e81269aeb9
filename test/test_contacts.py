"""Contact classification (sim_bridge.contacts), early-stop causes (sim_bridge.early_stop)
and the report's cause tables (bench.causes), old records included."""

from __future__ import annotations

import numpy as np
import pytest

from bench.causes import contacts_table, early_stop_table
from bench.rows import row_from_dict
from explore_seg.core.frontiers import FrontierParams, find_frontiers
from explore_seg.core.grid import GridMap
from sim_bridge.collision import Collider
from sim_bridge.contacts import cause_counts, classify_contact, marked_near
from sim_bridge.early_stop import FrontiersLeft, explain_stop
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.metrics import CollisionEvent, CoverageReference
from sim_bridge.run_result import RunResult
from sim_scenes import FAST, box, room_world


def _bin(x: float, y: float) -> list:
    """A 0.3 x 0.3 m bin of a class the detector does not know, 0.6 m tall."""
    return [box("bin_7", "other", "body", x, y, 0.3, 0.3, 0.0, 0.6)]


def _drive_into(world, layer=None, t_s=12.0):
    eng = SimEngine(world, SimParams(**FAST))
    got: list[dict] = []
    eng.on_collision(lambda ev: got.append(classify_contact(ev, eng.collider, eng.map, layer)))
    eng.step(0.1)
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(t_s)
    return eng, got


def test_a_contact_record_names_the_object_it_hit_and_the_map_had_it():
    eng, got = _drive_into(room_world(_bin(3.0, 2.0)))
    assert eng.metrics.n_collisions == 1 and len(got) == 1
    c = got[0]
    assert (c["object"], c["cls"], c["kind"]) == ("bin_7", "other", "object")
    # touched on the bin's near face, in front of the robot
    assert c["contact_xy_m"][0] == pytest.approx(2.85, abs=1e-3)
    assert c["speed_mps"] == pytest.approx(0.26) and not c["backing"]
    # the lidar mapped the bin; no object layer: "in map only"
    assert c["in_map"] and not c["in_layer"] and c["cause"] == "object, in map only"


def test_under_a_map_drift_the_touched_point_is_looked_up_where_the_map_has_it():
    # The map (and the layer) live in the map frame: a map 0.5 m off the world has the
    # bin 0.5 m further; looked up at the world point it would read "unseen".
    eng = SimEngine(room_world(_bin(3.0, 2.0)), SimParams(**FAST))
    got: list[tuple[dict, dict]] = []
    drift = (0.5, 0.0, 0.0)

    def record(ev):
        g = eng.map
        shifted = GridMap(g.data.copy(), g.resolution_m,
                          (g.origin_xy_m[0] + 0.5, g.origin_xy_m[1]))
        got.append((classify_contact(ev, eng.collider, shifted, None),
                    classify_contact(ev, eng.collider, shifted, None, map_from_world=drift)))

    eng.on_collision(record)
    eng.step(0.1)
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(12.0)
    world_frame, map_frame = got[0]
    assert world_frame["cause"] == "object, unseen"
    assert map_frame["cause"] == "object, in map only" and map_frame["in_map"]
    assert map_frame["contact_xy_m"] == world_frame["contact_xy_m"]   # reported in the world


def test_a_contact_with_an_object_the_layer_had_is_in_layer():
    world = room_world(_bin(3.0, 2.0))
    layer = GridMap(np.zeros((80, 120), np.int8), 0.05, (0.0, 0.0))
    r, c = layer.world_to_cell(2.9, 2.0)
    layer.data[r - 3:r + 4, c - 1:c + 5] = 100
    _, got = _drive_into(world, layer)
    assert got[0]["in_layer"] and got[0]["cause"] == "object, in layer"


def test_an_unseen_object_and_a_wall():
    # a table top above the lidar plane: the map does not have it
    top = [box("table_2", "table", "top", 3.0, 2.0, 0.8, 0.8, 0.70, 0.75)]
    _, got = _drive_into(room_world(top))
    assert got[0]["object"] == "table_2" and got[0]["cause"] == "object, unseen"
    _, got = _drive_into(room_world([]), t_s=20.0)
    assert got[0]["kind"] == "wall" and got[0]["cause"] == "wall, mapped"
    assert cause_counts(got) == {"wall, mapped": 1}


def test_marked_near_and_nearest_point():
    g = GridMap(np.zeros((20, 20), np.int8), 0.1, (0.0, 0.0))
    g.data[10, 10] = 100                 # centre (1.05, 1.05)
    assert marked_near(g, 1.1, 1.1, 0.1) and not marked_near(g, 1.3, 1.05, 0.1)
    assert not marked_near(None, 1.0, 1.0, 1.0) and not marked_near(g, 50.0, 50.0, 0.5)
    col = Collider(room_world([]), 0.22, 1.1)
    px, py, obj, cls, _ = col.nearest_point(5.9, 2.0)
    assert (px, py, obj, cls) == (pytest.approx(6.0), pytest.approx(2.0), "wall_e", "wall")
    ev = CollisionEvent(1.0, 5.78, 2.0, "wall_e", "wall", "wall", -0.1, True)
    assert classify_contact(ev, col, None, None)["cause"] == "wall, unmapped"


def _scene():
    """Known free room 0..2 m, unknown strip beyond x >= 2 m: one frontier."""
    data = np.full((40, 60), -1, np.int8)
    data[:, :40] = 0
    data[:, :1] = 100
    g = GridMap(data, 0.05, (0.0, 0.0))
    inside = np.ones(data.shape, bool)
    inside[:, :1] = False
    return g, CoverageReference(inside, g)


def test_explain_stop_names_the_frontier_reason_and_no_frontier_causes():
    g, ref = _scene()
    fp = FrontierParams(robot_radius_m=0.1)
    fr = find_frontiers(g, None, fp)
    assert len(fr) == 1
    out = explain_stop(g, ref, FrontiersLeft(fr, [np.inf], [True], [np.inf]), fp)
    assert out["cause"] == "blacklisted" and out["missing_m2"] == pytest.approx(2.0)
    assert out["frontiers"][0]["reason"] == "blacklisted"
    no_path = FrontiersLeft(fr, [np.inf], [False], [np.inf])
    assert explain_stop(g, ref, no_path, fp)["cause"] == "no path"
    not_selectable = FrontiersLeft(fr, [3.0], [False], [np.inf])
    assert explain_stop(g, ref, not_selectable, fp)["cause"] == "not selectable"
    # no frontier: the object layer closes the border
    extra = np.zeros(g.shape, bool)
    extra[:, 38:40] = True
    out = explain_stop(g, ref, FrontiersLeft([]), fp, extra)
    assert out["cause"] == "closed by object layer" and out["n_frontiers"] == 0
    assert explain_stop(g, ref, FrontiersLeft([]), fp)["cause"] == "frontier too small"
    g.data[:, 39] = 100                  # a mapped wall closes it
    assert explain_stop(g, ref, FrontiersLeft([]), fp)["cause"] == "behind mapped obstacles"


def _record(**kw):
    d = RunResult("w", "paper", 0).to_dict()
    d.update(kw)
    return d


def test_cause_tables_read_new_and_old_records():
    new = _record(collisions=2, completed=False, stop_reason="done",
                  contacts=[{"cause": "object, unseen", "cls": "other", "object": "bin_7",
                             "speed_mps": 0.2, "backing": False},
                            {"cause": "wall, mapped", "cls": "wall", "object": "w1",
                             "speed_mps": -0.1, "backing": True}],
                  early_stop={"cause": "closed by object layer", "missing_m2": 1.5,
                              "frontiers": [{"reason": "blacklisted"}]})
    old = _record(seed=1, collisions=3, completed=False, stop_reason="done",
                  collision_places=[[1.0, 2.0, "chair_3"]] * 3)
    for k in ("contacts", "early_stop"):
        old.pop(k)
    ct = contacts_table([new, old])
    assert "unclassified" in ct[0] and "object, unseen" in ct[0]
    cells = [x.strip() for x in ct[2].split("|")]
    assert cells[4] == "5" and "other: bin_7 ×1" in ct[2] and "chair_3 ×3" in ct[2]
    st = early_stop_table([new, old])
    assert "closed by object layer ×1" in st[2] and "unexplained ×1" in st[2]
    assert "blacklisted ×1" in st[2]
    # the CSV row of an old record still builds; a new one carries its causes
    assert row_from_dict(old)["contact_causes"] == ""
    assert row_from_dict(new)["stop_cause"] == "closed by object layer"


def test_a_run_stopped_below_target_says_why():
    from sim_bridge.lockstep import LockstepParams, run_exploration
    from sim_bridge.worlds import default_world, ground_truth
    w = default_world("small_house")
    r = run_exploration(w, "paper", 1, params=LockstepParams(max_sim_time_s=15.0),
                        ground_truth=ground_truth(w))
    assert r.stop_reason == "timeout" and not r.completed
    es = r.early_stop
    assert es is not None and es["missing_m2"] > 1.0 and es["n_gaps"] >= 1
    assert es["cause"] in ("selectable", "blacklisted", "no path", "not selectable",
                           "no passable cPoint", "frontier too small",
                           "closed by object layer", "behind mapped obstacles")
    assert es["frontiers"] and r.to_dict()["early_stop"] == es
    assert len(r.contacts) == r.collisions
