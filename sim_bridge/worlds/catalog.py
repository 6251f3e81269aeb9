"""The named embedded worlds (:data:`WORLD_NAMES`) the demo and the tests use."""

from __future__ import annotations

from sim_bridge.world import World
from sim_bridge.worlds.house import generate_house
from sim_bridge.worlds.maze import generate_maze
from sim_bridge.worlds.office import generate_office_floor

WORLD_NAMES: tuple[str, ...] = ("house", "house_cluttered", "maze", "small_house",
                                "small_cluttered", "office_floor")
#: Size of the small test houses (m).
SMALL_HOUSE_SIZE_M = (10.0, 8.0)
#: Room widths of the small houses (m): 2 rooms per side of the corridor.
SMALL_ROOM_WIDTH_M = (4.0, 6.0)


def default_world(name: str = "house_cluttered") -> World:
    """One of the embedded worlds (regenerated on each call, so callers may mutate it).

    ``house`` / ``house_cluttered``: :func:`generate_house` seed 1, 20 x 20 m;
    ``maze``: :func:`generate_maze` seed 1, 40 x 40 m; ``small_house`` /
    ``small_cluttered``: a 10 x 8 m house with 4 rooms and a corridor (seed 1);
    ``office_floor``: :func:`generate_office_floor` seed 1, 60 x 40 m (61 rooms, four
    corridors).

    Raises
    ------
    ValueError
        On a name not in :data:`WORLD_NAMES`.
    """
    if name == "house":
        w = generate_house(1)
    elif name == "house_cluttered":
        w = generate_house(1, cluttered=True)
    elif name == "maze":
        w = generate_maze(1)
    elif name in ("small_house", "small_cluttered"):
        w = generate_house(1, SMALL_HOUSE_SIZE_M, cluttered=name == "small_cluttered",
                           room_width_m=SMALL_ROOM_WIDTH_M)
    elif name == "office_floor":
        w = generate_office_floor(1)
    else:
        raise ValueError(f"world name must be one of {WORLD_NAMES}, got {name!r}")
    w.name = name
    return w
