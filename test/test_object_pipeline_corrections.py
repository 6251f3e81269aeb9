"""The lock step's object pipeline after a SLAM correction: the depth voxels marked and the
boxes seen since the previous correction are forgotten when a loop closure re-rendered the
map."""

from __future__ import annotations

import dataclasses

import pytest

from explore_seg.core.objects import DepthFrame, Object3D, ObjectParams
from objects_scene import K, box_parts, camera_pose, render_depth
from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.lockstep import LockstepParams
from sim_bridge.object_pipeline import ObjectPipeline
from sim_bridge.slam_error import LoopClosure
from sim_bridge.worlds import default_world

POSE = camera_pose(z=0.894, pitch=0.1)
FRAME = DepthFrame(render_depth([box_parts((1.5, 0.1), (0.3, 0.3, 0.12))], POSE), K, POSE)


def _closure(rerendered: bool) -> LoopClosure:
    return LoopClosure(keyframe=5, matched=0, shift_m=0.3, shift_rad=0.0,
                       rerendered=rerendered)


@pytest.mark.parametrize("forget", [True, False])
def test_voxels_since_the_last_correction_are_forgotten(forget):
    eng = SimEngine(default_world("small_house"), SimParams(
        seed=3, enable_camera=True, compute_coverage=False, mapping_error="harsh"))
    params = dataclasses.replace(ObjectParams(), depth_forget_on_correction=forget)
    pipe = ObjectPipeline(eng, params, 3, LockstepParams())
    timings = {"detection": [], "objects": []}
    eng.step(0.1)
    pipe.update(timings)
    depth = pipe.map.depth
    assert depth is not None
    depth.update(FRAME, eng.time_s)                   # a box seen before any correction
    marked = len(depth)
    assert marked > 0
    slam = eng.slam_error
    assert slam is not None
    slam.closures.append(_closure(rerendered=False))  # a correction too small to re-render
    eng.step(0.1)
    pipe.update(timings)
    assert len(depth) == marked
    slam.closures.append(_closure(rerendered=True))   # the map was re-rendered
    eng.step(0.1)
    pipe.update(timings)
    assert (len(depth) == 0) is forget
    # voxels marked before this correction stay at the next one; newer ones go
    depth.update(FRAME, eng.time_s - 0.15)
    before = len(depth)
    eng.step(0.1)
    slam.closures.append(_closure(rerendered=True))
    pipe.update(timings)
    assert len(depth) == (before if forget else marked)


def _table(x: float) -> Object3D:
    return Object3D("dining table", 0.9, (x, 3.0, 0.37), (0.9, 0.75, 0.74), 0.0, 100)


@pytest.mark.parametrize("drop", [True, False])
def test_boxes_seen_since_the_last_correction_are_dropped(drop):
    """A tracked box last seen since the previous correction was placed at uncorrected
    poses: a re-rendering correction drops it (it is re-observed); one seen only before
    the previous correction stays."""
    eng = SimEngine(default_world("small_house"), SimParams(
        seed=3, enable_camera=True, compute_coverage=False, mapping_error="harsh"))
    # the default drops them
    params = dataclasses.replace(ObjectParams(), depth_obstacles=False, **(
        {} if drop else {"boxes_forget_on_correction": False}))
    pipe = ObjectPipeline(eng, params, 3, LockstepParams())
    timings = {"detection": [], "objects": []}
    slam = eng.slam_error
    assert slam is not None
    eng.step(0.1)
    pipe.update(timings)
    pipe.map.update([_table(-5.0)], stamp_ns=int(eng.time_s * 1e9))
    assert len(pipe.map) == 1
    slam.closures.append(_closure(rerendered=False))  # too small to re-render: kept
    eng.step(0.1)
    pipe.update(timings)
    assert len(pipe.map) == 1
    slam.closures.append(_closure(rerendered=True))
    eng.step(0.1)
    pipe.update(timings)
    assert (len(pipe.map) == 0) is drop
    # seen before this correction: kept at the next one; seen since: dropped
    old = len(pipe.map)
    pipe.map.update([_table(5.0)], stamp_ns=int((eng.time_s - 0.05) * 1e9))
    pipe.map.update([_table(9.0)], stamp_ns=int((eng.time_s + 0.05) * 1e9))
    eng.step(0.1)
    slam.closures.append(_closure(rerendered=True))
    pipe.update(timings)
    xs = sorted(round(o.center_xyz[0]) for o in pipe.map.objects())
    assert xs == ([5] if drop else sorted([-5] * old + [5, 9]))
