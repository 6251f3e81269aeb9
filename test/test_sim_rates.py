"""The real stack's rates in the simulator: slam_toolbox's keyframes and map publishing
interval, Nav2's controller rate and replanning, and the explorer's reuse of its map
products while the map is unchanged."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import GridMap
from explore_seg.core.selection import SelectionParams
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.slam_error import is_keyframe
from sim_bridge.worlds import default_world
from sim_scenes import FAST, room_world

#: Every rate back to the behaviour before they were modelled.
OLD_RATES = dict(map_update_interval_s=0.0, mapping_keyframe_travel_m=0.0,
                 mapping_keyframe_turn_rad=0.0, nav_controller_rate_hz=0.0, scan_rate_hz=10.0)


def _publications(eng: SimEngine, duration_s: float) -> list[tuple[float, GridMap]]:
    """(sim time, map) at every publication during ``duration_s`` of 20 ms steps."""
    out = []
    seen = eng.map_publishes
    end = eng.time_s + duration_s
    while eng.time_s < end - 1e-9:
        t = eng.time_s
        eng.step(0.02)
        if eng.map_publishes != seen:
            out.append((t, eng.map))
            seen = eng.map_publishes
    return out


def test_the_map_is_republished_every_interval_stamped_then():
    eng = SimEngine(room_world([]), SimParams(**FAST, map_update_interval_s=1.0))
    eng.set_cmd_vel(0.0, 0.3)                          # turn: the map keeps changing
    pubs = _publications(eng, 4.5)
    assert [t for t, _ in pubs] == pytest.approx([0.0, 1.0, 2.0, 3.0, 4.0])
    assert [g.stamp_ns for _, g in pubs] == [0, 10**9, 2 * 10**9, 3 * 10**9, 4 * 10**9]
    # between publications the explorer sees one object; the live map moves on
    before = eng.map
    eng.step(0.3)
    assert eng.map is before and eng.live_map.stamp_ns > before.stamp_ns


def test_an_unchanged_map_is_republished_with_the_same_content_and_version():
    eng = SimEngine(room_world([]), SimParams(**FAST, map_update_interval_s=0.5))
    pubs = _publications(eng, 2.2)                      # standing still: one keyframe
    versions = set()
    for _, g in pubs:
        assert np.array_equal(g.data, pubs[0][1].data)
    for _ in range(3):
        eng.step(0.5)
        versions.add(eng.map_version)
    assert len(pubs) == 5 and len(versions) == 1


def test_only_keyframe_scans_enter_the_published_map():
    eng = SimEngine(room_world([]), SimParams(**FAST, map_update_interval_s=0.0,
                                              mapping_keyframe_travel_m=0.5,
                                              mapping_keyframe_turn_rad=0.5))
    eng.set_cmd_vel(0.0, 0.3)
    changed_at, live_changes = [], 0
    version, live = eng.map_version, eng.live_map_version
    scans = []
    while eng.time_s < 6.0 - 1e-9:
        eng.step(0.02)
        scans += eng.drain_scans()
        if eng.map_version != version:
            version = eng.map_version
            changed_at.append(scans[-1].stamp_s)
        if eng.live_map_version != live:
            live, live_changes = eng.live_map_version, live_changes + 1
    expected, last = [], None
    for s in scans:
        if is_keyframe(last, s.pose, 0.5, 0.5):
            last = s.pose
            expected.append(s.stamp_s)
    assert len(expected) == 4 and changed_at == expected
    assert abs(len(scans) - 6.0 * eng.params.scan_rate_hz) <= 1
    assert live_changes >= len(scans) - 1               # navigation's map: every scan
    known = (eng.map.data >= 0).sum()
    assert 0 < known <= (eng.true_map.data >= 0).sum()  # coverage: every scan


def test_without_keyframes_and_interval_every_scan_is_published():
    eng = SimEngine(room_world([]), SimParams(**FAST, **OLD_RATES))
    eng.set_cmd_vel(0.0, 0.3)
    n0 = eng.map_publishes
    eng.step(2.0)
    assert eng.map_publishes - n0 == 20                 # 10 Hz scans
    assert eng.map is eng.live_map and eng.map_version == eng.live_map_version


@pytest.mark.parametrize("rate_hz, calls", [(20.0, 40), (10.0, 20), (0.0, 100)])
def test_the_path_follower_runs_at_the_controller_rate(rate_hz, calls):
    eng = SimEngine(room_world([]), SimParams(**FAST, nav_controller_rate_hz=rate_hz))
    eng.step(0.1)
    nav = eng.navigator
    times: list[float] = []
    update = nav.update

    def counted(pose, now_s):
        times.append(now_s)
        return update(pose, now_s)

    nav.update = counted                                  # type: ignore[method-assign]
    eng.set_goal(5.0, 2.0, 0.0)
    eng.step(2.0)
    assert eng.nav_status.state.value == "active"
    assert len(times) == calls
    if rate_hz:                                          # evenly spread: no bursts
        gaps = np.diff(times)
        assert gaps.max() <= 1.0 / rate_hz + 0.02 + 1e-9
        assert gaps.min() >= 1.0 / rate_hz - 0.02 - 1e-9


def test_replans_at_one_hz_while_the_map_changes_and_at_once_for_a_new_obstacle():
    eng = SimEngine(room_world([], size=(10.0, 4.0)), SimParams(**FAST))
    eng.step(0.1)
    nav = eng.navigator
    eng.set_goal(6.5, 2.0, 0.0)
    eng.step(0.1)
    n0 = nav.plan_count
    eng.step(4.0)                                         # the live map changes every scan
    assert eng.nav_status.state.value == "active"
    assert 3 <= nav.plan_count - n0 <= 4                  # Nav2's RateController hz=1.0
    n1, v1 = nav.plan_count, eng.plan_version
    layer = replace(eng.live_map, data=np.zeros_like(eng.live_map.data))
    r, c = layer.world_to_cell(eng.pose[0] + 1.0, 2.0)
    layer.data[max(0, r - 3):r + 4, c] = 100             # a box across the way
    eng.add_costmap_layer("object_costmap", layer)
    eng.step(0.1)                                         # the next controller call
    assert nav.plan_count == n1 + 1 and eng.plan_version != v1


def _same_step(a, b) -> None:
    assert (a.action, a.reason, a.robot_rc) == (b.action, b.reason, b.robot_rc)
    assert (a.goal is None) == (b.goal is None)
    if a.goal is not None:
        assert (a.goal.xy_m, a.goal.yaw_rad) == (b.goal.xy_m, b.goal.yaw_rad)
    assert len(a.frontiers) == len(b.frontiers)
    for fa, fb in zip(a.frontiers, b.frontiers):
        assert np.array_equal(fa.cells, fb.cells)
    if a.dist_m is None:
        assert b.dist_m is None
    else:
        assert np.array_equal(a.dist_m, b.dist_m, equal_nan=True)
    if a.selection is not None:
        assert np.array_equal(a.selection.costs, b.selection.costs, equal_nan=True)


@pytest.mark.parametrize("strategy", ["nearest", "routed", "explore_lite"])
def test_reusing_the_map_products_gives_what_recomputing_gives(strategy):
    eng = SimEngine(default_world("small_house"), SimParams(**FAST, map_update_interval_s=1.0))
    eng.set_cmd_vel(0.15, 0.25)
    fp = FrontierParams()
    reuse = Explorer(fp, SelectionParams(strategy=strategy))
    fresh = Explorer(fp, SelectionParams(strategy=strategy))
    reused = 0
    for k in range(24):                                   # 4 decisions per map
        eng.step(0.25)
        grid = eng.map
        if k % 2:                                         # an equal map, another object
            grid = grid.with_data(grid.data.copy())
        fresh._key = None                                 # recompute everything
        a = reuse.step(eng.time_s, grid, eng.slam_pose)
        b = fresh.step(eng.time_s, grid, eng.slam_pose)
        assert b.detected
        reused += not a.detected
        _same_step(a, b)
    assert reused >= 12
