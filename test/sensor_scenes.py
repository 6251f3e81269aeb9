"""Small rooms and tables shared by the lidar and camera tests."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from sim_bridge.world import Primitive, World, WorldObject
from sim_bridge.worlds import ground_truth


def wall_box(x, y, sx, sy, z=(0.0, 2.5)):
    return Primitive("", "wall", "wall", "box", x, y, 0.0, (sx, sy), z[0], z[1])


def room_4x4(extra=(), objects=()):
    """4 x 4 m room: inner wall faces at x, y = +-2 (walls 0.15 m thick)."""
    walls = [wall_box(0.0, 2.075, 4.3, 0.15), wall_box(0.0, -2.075, 4.3, 0.15),
             wall_box(2.075, 0.0, 0.15, 4.3), wall_box(-2.075, 0.0, 0.15, 4.3)]
    return World("room", (-2.5, -2.5, 2.5, 2.5), (0.0, 0.0, 0.0), walls + list(extra),
                 list(objects))


def table_with_legs(x, y, length=1.2, depth=0.8, top=(0.72, 0.75), leg_r=0.025):
    parts = [Primitive("table", "table", "leg", "cylinder", x + sx * (length / 2 - 0.05),
                       y + sy * (depth / 2 - 0.05), 0.0, (leg_r,), 0.0, top[0])
             for sx in (-1, 1) for sy in (-1, 1)]
    parts.append(Primitive("table", "table", "top", "box", x, y, 0.0, (length, depth),
                           top[0], top[1]))
    obj = WorldObject("table", "table", (x, y, 0.0),
                      (x - length / 2, y - depth / 2, 0.0, x + length / 2, y + depth / 2, top[1]))
    return parts, obj


def random_free_poses(world, n, seed, clearance_m=0.25):
    gt = ground_truth(world)
    dist = ndimage.distance_transform_edt(gt.footprint.data < 65) * gt.resolution_m
    rr, cc = np.nonzero(gt.inside & (dist >= clearance_m))
    rng = np.random.default_rng(seed)
    pick = rng.choice(rr.size, n, replace=False)
    xs, ys = gt.lidar.cells_to_world(rr[pick], cc[pick])
    return [(float(x), float(y), float(a)) for x, y, a in zip(xs, ys, rng.uniform(-4, 4, n))]
