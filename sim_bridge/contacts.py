"""Why a contact happened: what was hit and whether navigation could have known it.

:func:`classify_contact` turns a :class:`~sim_bridge.metrics.CollisionEvent` into a record
that names the solid that was hit (wall, or object id and class and part), the point it
was touched at, whether the occupancy map and the object layer marked that point at the
time of the contact, the robot's commanded speed and whether it was backing off after an
earlier contact. Its ``cause`` is one of :data:`CONTACT_CAUSES`:

* ``wall, mapped`` / ``wall, unmapped``: a wall (or a map-only world's occupied cell);
  mapped: the occupancy map had an occupied cell at the touched point;
* ``object, in layer``: the object layer (what the navigation stand-in plans around besides
  the map) had the touched point: planning or control came too close to a known obstacle;
* ``object, in map only``: the lidar map had it (legs, a low base), the object layer did not;
* ``object, unseen``: neither had it (an undetected object, a table top above the lidar).

"Had the point" means an occupied cell whose centre lies within ``tolerance_m`` (default
1.5 map cells) of the touched point. Under a mapping error model the map and the layer
live in the map frame, the touched point in the world: the point is looked up where the
map puts it now (``map_from_world``, the model's drift at the time of the contact).
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Any, Iterable

import numpy as np

from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap
from explore_seg.core.pose_fusion import Pose2D, compose
from sim_bridge.collision import Collider
from sim_bridge.metrics import CollisionEvent

#: Contact causes, in the order the report lists them.
CONTACT_CAUSES = ("wall, mapped", "wall, unmapped", "object, in layer", "object, in map only",
                  "object, unseen")


def marked_near(grid: GridMap | None, x: float, y: float, radius_m: float,
                threshold: int = OCCUPIED_THRESHOLD) -> bool:
    """True when ``grid`` has a cell ``>= threshold`` whose centre lies within
    ``radius_m`` of (x, y) (False for no grid or a point off the grid)."""
    if grid is None or not (math.isfinite(x) and math.isfinite(y)):
        return False
    res = grid.resolution_m
    r, c = grid.world_to_cell(x, y)
    k = int(math.ceil(radius_m / res)) + 1
    r0, r1 = max(0, r - k), min(grid.height, r + k + 1)
    c0, c1 = max(0, c - k), min(grid.width, c + k + 1)
    if r0 >= r1 or c0 >= c1:
        return False
    rr, cc = np.nonzero(grid.data[r0:r1, c0:c1] >= threshold)
    if rr.size == 0:
        return False
    wx, wy = grid.cells_to_world(rr + r0, cc + c0)
    return bool((np.hypot(wx - x, wy - y) <= radius_m).any())


def classify_contact(event: CollisionEvent, collider: Collider, grid: GridMap | None,
                     layer: GridMap | None, tolerance_m: float | None = None,
                     threshold: int = OCCUPIED_THRESHOLD,
                     map_from_world: Pose2D | None = None) -> dict[str, Any]:
    """The record of one contact (see the module docstring).

    Parameters
    ----------
    event : CollisionEvent
    collider : Collider
        The engine's collider (finds the touched point).
    grid : GridMap or None
        The occupancy map at the time of the contact.
    layer : GridMap or None
        The object layer the navigation had at that time (None: none).
    tolerance_m : float, optional
        Search radius around the touched point; default 1.5 cells of ``grid``.
    threshold : int
        Cells at or above this value are obstacles (map and layer).
    map_from_world : (x, y, yaw), optional
        The map <- world transform (a mapping error model's drift) at the time of the
        contact; None: the map frame is the world frame.

    Returns
    -------
    dict
        ``t_s, x_m, y_m, speed_mps, backing, object, cls, part, kind ("wall" | "object"),
        contact_xy_m, in_map, in_layer, cause`` (JSON-able).
    """
    px, py, obj, cls, part = collider.nearest_point(event.x_m, event.y_m)
    obj, cls, part = obj or event.object, cls or event.cls, part or event.part
    if tolerance_m is None:
        tolerance_m = 1.5 * (grid.resolution_m if grid is not None else 0.05)
    mx, my = px, py
    if map_from_world is not None and math.isfinite(px) and math.isfinite(py):
        mx, my, _ = compose(map_from_world, (px, py, 0.0))
    in_map = marked_near(grid, mx, my, tolerance_m, threshold)
    in_layer = marked_near(layer, mx, my, tolerance_m, threshold)
    kind = "wall" if cls == "wall" or obj == "map" else "object"
    if kind == "wall":
        cause = "wall, mapped" if in_map else "wall, unmapped"
    elif in_layer:
        cause = "object, in layer"
    elif in_map:
        cause = "object, in map only"
    else:
        cause = "object, unseen"
    return {"t_s": round(float(event.t_s), 3), "x_m": round(float(event.x_m), 3),
            "y_m": round(float(event.y_m), 3), "speed_mps": round(float(event.speed_mps), 3),
            "backing": bool(event.backing), "object": obj, "cls": cls, "part": part,
            "kind": kind,
            "contact_xy_m": [round(float(px), 3) if math.isfinite(px) else None,
                             round(float(py), 3) if math.isfinite(py) else None],
            "in_map": in_map, "in_layer": in_layer, "cause": cause}


def cause_counts(contacts: Iterable[dict[str, Any]]) -> dict[str, int]:
    """Contacts per cause, in :data:`CONTACT_CAUSES` order (causes with none left out)."""
    n = Counter(c.get("cause", "") for c in contacts)
    out = {k: n[k] for k in CONTACT_CAUSES if n[k]}
    out.update({k: v for k, v in sorted(n.items()) if k not in out and v})
    return out
