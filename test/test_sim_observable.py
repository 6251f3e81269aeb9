"""The observable part of the explorable area (sim_bridge.observable) and its use as the
coverage denominator."""

from __future__ import annotations

import numpy as np
import pytest

from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.observable import (observable_region, reachable_centres, sample_cells,
                                   with_observable)
from sim_bridge.sensors import LidarParams
from sim_bridge.world import Primitive, World
from sim_bridge.worlds import ground_truth

LIDAR = LidarParams(num_beams=360, range_max_m=5.0, noise_std_m=0.0)


def _box(x, y, sx, sy):
    return Primitive("", "wall", "wall", "box", x, y, 0.0, (sx, sy), 0.0, 1.0)


def _room(with_vault: bool) -> World:
    """A closed 4 x 3 m room (0.1 m walls). With ``with_vault``, a hollow 1 x 1 m block
    stands in it whose only opening is a 0.1 m slit through a 0.5 m deep wall: free
    cells joined to the room, but out of the robot's reach and mostly out of view."""
    prims = [_box(2.0, 0.05, 4.0, 0.1), _box(2.0, 2.95, 4.0, 0.1),
             _box(0.05, 1.5, 0.1, 3.0), _box(3.95, 1.5, 0.1, 3.0)]
    if with_vault:
        # vault walls around the interior x in [2.5, 3.3], y in [1.0, 1.8]
        prims += [_box(2.9, 0.95, 1.0, 0.1), _box(2.9, 1.85, 1.0, 0.1),
                  _box(3.35, 1.4, 0.1, 1.0),
                  # the west wall: 0.5 m deep, split by a 0.1 m slit at y = 1.4
                  _box(2.2, 1.125, 0.5, 0.45), _box(2.2, 1.675, 0.5, 0.45)]
    return World("vault" if with_vault else "room", (-0.5, -0.5, 4.5, 3.5),
                 (0.8, 1.5, 0.0), prims)


def _vault_interior(gt) -> np.ndarray:
    g = gt.lidar
    rows, cols = np.indices(g.shape)
    x, y = g.cells_to_world(rows.astype(float), cols.astype(float))
    return (x > 2.5) & (x < 3.3) & (y > 1.0) & (y < 1.8) & gt.inside


def test_open_room_is_fully_observable():
    w = _room(False)
    gt = ground_truth(w, 0.05)
    obs = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    assert obs.shape == gt.inside.shape
    assert not (obs & ~gt.inside).any()
    assert obs.sum() == gt.inside.sum()


def test_vault_behind_a_slit_is_inside_but_not_observable():
    w = _room(True)
    gt = ground_truth(w, 0.05)
    vault = _vault_interior(gt)
    assert vault.sum() > 150                       # the flood fill got in through the slit
    reach = reachable_centres(gt, 0.2)
    assert not (reach & vault).any()               # the robot cannot
    obs = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    assert not (obs & ~gt.inside).any()
    assert (obs & vault).sum() < 0.5 * vault.sum()  # seen only in the slit's fan
    rest = gt.inside & ~vault
    assert (obs & rest).sum() >= 0.995 * rest.sum()


def test_ground_truth_explorable_and_engine_reference():
    w = _room(True)
    gt = ground_truth(w, 0.05)
    assert gt.observable is None
    assert gt.explorable is gt.inside
    sp = SimParams(enable_camera=False)
    gt2 = with_observable(w, gt, sp.lidar_params(), sp.robot_radius_m)
    assert with_observable(w, gt2, LIDAR, 0.2) is gt2
    assert gt2.explorable.sum() < gt.inside.sum()
    assert gt2.explorable_area_m2 == pytest.approx(gt2.explorable.sum() * 0.0025)
    eng = SimEngine(w, sp)
    assert eng.metrics.reference is not None
    assert eng.metrics.reference.total_cells == int(gt2.explorable.sum())
    eng_all = SimEngine(w, SimParams(enable_camera=False, coverage_observable=False))
    assert eng_all.metrics.reference.total_cells == int(gt.inside.sum())
    eng_all = SimEngine(w, SimParams(enable_camera=False, coverage_observable=False),
                        ground_truth=gt2)
    assert eng_all.metrics.reference.total_cells == int(gt.inside.sum())


def test_bad_arguments():
    w = _room(False)
    gt = ground_truth(w, 0.05)
    with pytest.raises(ValueError, match="spacing_m"):
        observable_region(w, gt, LIDAR, spacing_m=0.0)
    with pytest.raises(ValueError, match="robot_radius_m"):
        reachable_centres(gt, -1.0)


def test_samples_cover_strips_between_lattice_lines():
    reach = np.zeros((40, 40), bool)
    reach[5:35, 12:14] = True            # a 2-cell strip between lattice columns 10 and 15
    reach[20, 0:40] = True               # and a 1-cell row across
    rows, cols = sample_cells(reach, 5)
    assert reach[rows, cols].all()
    for r, c in np.argwhere(reach):
        assert (np.maximum(abs(rows - r), abs(cols - c)) <= 4).any(), (r, c)


def _count_computes(monkeypatch) -> list[int]:
    """Counts calls of the uncached computation (and still runs it); the memory cache
    starts empty. The real computation stays at ``_REAL``."""
    from sim_bridge import observable as ob
    calls = [0]
    real = ob.compute_observable_region

    def counted(*a, **k):
        calls[0] += 1
        return real(*a, **k)

    monkeypatch.setattr(ob, "compute_observable_region", counted)
    monkeypatch.setitem(globals(), "_REAL", real)
    monkeypatch.setattr(ob, "_MEMORY", type(ob._MEMORY)())
    return calls


def test_region_is_cached_in_memory_and_on_disk(monkeypatch, tmp_path):
    from sim_bridge import observable as ob
    monkeypatch.setenv("EXPLORE_SEG_CACHE_DIR", str(tmp_path))
    calls = _count_computes(monkeypatch)
    w = _room(True)
    gt = ground_truth(w, 0.05)
    first = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    assert calls[0] == 1 and len(list((tmp_path / "observable").glob("*.npz"))) == 1
    first[:] = False                                   # the caller's copy, not the cache's
    again = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    assert calls[0] == 1
    ob._MEMORY.clear()                                 # a new process: read from disk
    from_disk = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    assert calls[0] == 1
    reference = _REAL(w, gt, LIDAR, 0.2, ob.SAMPLE_SPACING_M)
    assert np.array_equal(again, reference) and np.array_equal(from_disk, reference)
    assert reference.any()


def test_cache_recomputes_when_the_world_or_inputs_change(monkeypatch, tmp_path):
    from sim_bridge import observable as ob
    monkeypatch.setenv("EXPLORE_SEG_CACHE_DIR", str(tmp_path))
    calls = _count_computes(monkeypatch)
    closed, opened = _room(True), _room(True)
    # The vault's west wall without its lower half: the vault is open to the room.
    opened.primitives = [p for p in opened.primitives if not (p.x == 2.2 and p.y == 1.125)]
    gt_c, gt_o = ground_truth(closed, 0.05), ground_truth(opened, 0.05)
    a = observable_region(closed, gt_c, LIDAR, robot_radius_m=0.2)
    b = observable_region(opened, gt_o, LIDAR, robot_radius_m=0.2)
    assert calls[0] == 2
    vault = _vault_interior(gt_o)
    assert (b & vault).sum() > (a & vault).sum()       # now seen: not the cached region
    assert np.array_equal(b, _REAL(opened, gt_o, LIDAR, 0.2, ob.SAMPLE_SPACING_M))
    observable_region(closed, gt_c, LIDAR, robot_radius_m=0.25)
    observable_region(closed, gt_c, LidarParams(num_beams=180), robot_radius_m=0.2)
    observable_region(closed, gt_c, LIDAR, robot_radius_m=0.2, spacing_m=0.5)
    assert calls[0] == 5
    # The same inputs once more, in a fresh process (memory cleared): all from disk.
    ob._MEMORY.clear()
    observable_region(closed, gt_c, LIDAR, robot_radius_m=0.2)
    observable_region(opened, gt_o, LIDAR, robot_radius_m=0.2)
    assert calls[0] == 5


def test_a_damaged_or_disabled_disk_cache_is_recomputed(monkeypatch, tmp_path):
    from sim_bridge import observable as ob
    monkeypatch.setenv("EXPLORE_SEG_CACHE_DIR", str(tmp_path))
    calls = _count_computes(monkeypatch)
    w = _room(False)
    gt = ground_truth(w, 0.05)
    good = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    (f,) = (tmp_path / "observable").glob("*.npz")
    f.write_bytes(b"not a cache file")
    ob._MEMORY.clear()
    assert np.array_equal(observable_region(w, gt, LIDAR, robot_radius_m=0.2), good)
    assert calls[0] == 2
    monkeypatch.setenv("EXPLORE_SEG_CACHE_DIR", "")
    ob._MEMORY.clear()
    for p in (tmp_path / "observable").glob("*"):
        p.unlink()
    assert ob.cache_dir() is None
    assert np.array_equal(observable_region(w, gt, LIDAR, robot_radius_m=0.2), good)
    assert calls[0] == 3 and not list((tmp_path / "observable").glob("*"))


def test_unreadable_code_turns_the_disk_cache_off(monkeypatch, tmp_path):
    """Without the source to hash, a stored region could be stale: nothing is read or
    written on disk, the region is still right."""
    from sim_bridge import observable as ob
    monkeypatch.setenv("EXPLORE_SEG_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(ob, "_code_digest", [])
    monkeypatch.setattr(ob, "_CODE_MODULES", ("no/such/module.py",))
    calls = _count_computes(monkeypatch)
    w = _room(False)
    gt = ground_truth(w, 0.05)
    got = observable_region(w, gt, LIDAR, robot_radius_m=0.2)
    assert calls[0] == 1 and not (tmp_path / "observable").exists()
    assert np.array_equal(got, _REAL(w, gt, LIDAR, 0.2, ob.SAMPLE_SPACING_M))
