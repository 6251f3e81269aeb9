"""SHA-256 digest of a loaded world and its ground truth, for checking that the worlds
shipped in ``worlds/`` load to the same arrays as the copies they were taken from
(``test/data/world_digests.json``)."""

from __future__ import annotations

import hashlib

import numpy as np

from sim_bridge.worlds import ground_truth


def world_digest(world) -> dict[str, str]:
    """{part: hex digest} of a :class:`~sim_bridge.world.World`: its bounds and start,
    its primitives and objects, its base grid (map-only worlds) and the three
    ground-truth rasters with the explorable region."""
    def h(*arrays) -> str:
        m = hashlib.sha256()
        for a in arrays:
            a = np.ascontiguousarray(a)
            m.update(str((a.dtype.str, a.shape)).encode())
            m.update(a.tobytes())
        return m.hexdigest()

    prims = np.array([(p.x, p.y, p.yaw, *p.size, *([0.0] * (2 - len(p.size))), p.zmin, p.zmax)
                      for p in world.primitives], dtype=np.float64)
    labels = "\n".join(f"{p.object}|{p.cls}|{p.part}|{p.shape}" for p in world.primitives)
    objects = "\n".join(f"{o.name}|{o.cls}|{tuple(o.pose)}|{tuple(o.aabb)}"
                        for o in world.objects)
    gt = ground_truth(world)
    out = {
        "frame": h(np.array(world.bounds + world.start_pose, dtype=np.float64)),
        "primitives": h(prims, np.frombuffer(labels.encode(), np.uint8)),
        "objects": h(np.frombuffer(objects.encode(), np.uint8)),
        "truth": h(gt.lidar.data, gt.footprint.data, gt.footprint_tall.data, gt.inside),
    }
    if world.base_grid is not None:
        out["base_grid"] = h(world.base_grid.data)
    return out
