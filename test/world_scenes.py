"""Small worlds of a few primitives shared by the world tests."""

from __future__ import annotations

from sim_bridge.world import Primitive, World


def tiny_world(prims: list[Primitive], bounds=(0.0, 0.0, 0.5, 0.5), start=(0.05, 0.05, 0.0)):
    return World(name="t", bounds=bounds, start_pose=start, primitives=prims)


def prim_box(x, y, sx, sy, yaw=0.0, z=(0.0, 1.0), cls="wall", obj=""):
    return Primitive(obj, cls, "wall", "box", x, y, yaw, (sx, sy), z[0], z[1])
