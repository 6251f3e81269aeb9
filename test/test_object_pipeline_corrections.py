"""The lock step's object pipeline after a SLAM correction: the depth voxels marked and the
boxes seen since the previous correction are forgotten when a loop closure re-rendered the
map, except those of the last ``correction_move_recent_s``, which move with the SLAM pose's
jump."""

from __future__ import annotations

import dataclasses

import numpy as np
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


def _closure(rerendered: bool, jump: tuple[float, float, float] = (0.3, 0.0, 0.0)
             ) -> LoopClosure:
    return LoopClosure(keyframe=5, matched=0, shift_m=0.3, shift_rad=0.0,
                       rerendered=rerendered, jump=jump)


@pytest.mark.parametrize("forget", [True, False])
def test_voxels_since_the_last_correction_are_forgotten(forget):
    eng = SimEngine(default_world("small_house"), SimParams(
        seed=3, enable_camera=True, compute_coverage=False, mapping_error="harsh"))
    params = dataclasses.replace(ObjectParams(), depth_forget_on_correction=forget,
                                 correction_move_recent_s=0.0)
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
    params = dataclasses.replace(ObjectParams(), depth_obstacles=False,
                                 correction_move_recent_s=0.0, **(
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


def test_what_was_seen_just_before_a_correction_moves_with_the_pose_jump():
    """A box and voxels seen within correction_move_recent_s before a re-rendering
    correction are moved by the SLAM pose's jump (two closures since the last update: their
    jumps composed), not forgotten: an obstacle beside the robot, outside the camera's
    view, would not be seen again before the robot meets it. What was seen since the
    previous correction but earlier is forgotten as before."""
    eng = SimEngine(default_world("small_house"), SimParams(
        seed=3, enable_camera=True, compute_coverage=False, mapping_error="harsh"))
    pipe = ObjectPipeline(eng, ObjectParams(correction_move_recent_s=0.05), 3,
                          LockstepParams())
    timings = {"detection": [], "objects": []}
    slam = eng.slam_error
    assert slam is not None
    eng.step(0.1)
    pipe.update(timings)
    depth = pipe.map.depth
    assert depth is not None
    t_next = eng.time_s + 0.1                                   # the correction's time
    pipe.map.update([_table(-5.0)], stamp_ns=int((t_next - 0.08) * 1e9))   # before that
    pipe.map.update([_table(5.0)], stamp_ns=int((t_next - 0.02) * 1e9))    # just before
    depth.update(FRAME, t_next - 0.02)
    v = pipe.map.params.depth_voxel_m
    c = depth.centres()
    want = {(int(np.floor((x + 0.1) / v)), int(np.floor((y + 0.2) / v)), round(z, 6))
            for x, y, z in c}
    eng.step(0.1)
    slam.closures.append(_closure(True, (0.1, 0.0, 0.0)))
    slam.closures.append(_closure(True, (0.0, 0.2, 0.0)))
    pipe.update(timings)
    objs = pipe.map.objects()
    assert [(round(o.center_xyz[0], 6), round(o.center_xyz[1], 6)) for o in objs] == [
        (5.1, 3.2)]
    got = {(int(np.floor(x / v)), int(np.floor(y / v)), round(z, 6))
           for x, y, z in depth.centres()}
    assert got == want and len(got) > 0
