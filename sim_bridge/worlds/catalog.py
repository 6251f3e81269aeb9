"""Every world the simulator loads, by spec: :func:`load_world` is the one loader.

A world spec is one of

* a generated world's name (:data:`WORLD_NAMES`, :func:`default_world`);
* ``shared/NAME``: the world file ``worlds/NAME.world.yaml`` shipped with the package
  (:data:`FILE_WORLDS`; the prefix keeps the name of the data folder the files came from,
  so results keyed by it stay valid);
* ``eb/NAME``: the Explore-Bench map ``worlds/explore_bench/NAME.yaml`` shipped with the
  package (:data:`EXPLORE_BENCH_MAPS`);
* a path to a ``*.world.yaml`` or map_server ``*.yaml`` file.

``worlds/`` is the package's data folder (:func:`worlds_dir`): beside ``sim_bridge/`` in a
source checkout, ``share/explore_seg/worlds`` once installed.
"""

from __future__ import annotations

from pathlib import Path

from sim_bridge.world import World
from sim_bridge.worlds.files import read_world_file
from sim_bridge.worlds.house import generate_house
from sim_bridge.worlds.maze import generate_maze
from sim_bridge.worlds.office import generate_office_floor

WORLD_NAMES: tuple[str, ...] = ("house", "house_cluttered", "maze", "small_house",
                                "small_cluttered", "office_floor")
#: Size of the small test houses (m).
SMALL_HOUSE_SIZE_M = (10.0, 8.0)
#: Room widths of the small houses (m): 2 rooms per side of the corridor.
SMALL_ROOM_WIDTH_M = (4.0, 6.0)
#: The ``explore_seg_world/1`` files in ``worlds/`` (spec ``shared/NAME``).
FILE_WORLDS: tuple[str, ...] = ("house", "house_cluttered", "house_cluttered_plus", "maze")
#: The Explore-Bench maps in ``worlds/explore_bench/`` (spec ``eb/NAME``).
EXPLORE_BENCH_MAPS: tuple[str, ...] = (
    "corner", "corridor", "corridor_asym", "corridor_sym", "loop", "loop_with_corridor",
    "room", "room_1", "room_2", "room_3", "room_with_corner", "room_with_corridor")
#: Spec prefix -> (subfolder of ``worlds/``, file suffix, the names shipped).
SPEC_PREFIXES: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "shared/": ("", ".world.yaml", FILE_WORLDS),
    "eb/": ("explore_bench", ".yaml", EXPLORE_BENCH_MAPS)}
#: A file every complete ``worlds/`` folder holds (tells it from ``sim_bridge/worlds/``).
_WORLDS_MARKER = Path("explore_bench") / "starts.yaml"


def worlds_dir() -> Path:
    """The package's ``worlds/`` folder.

    The first of ``P/worlds`` and ``P/share/explore_seg/worlds`` that holds
    ``explore_bench/starts.yaml``, for P = the folders above this file: the source
    checkout's folder, or the install prefix of a colcon or pip install.

    Raises
    ------
    ValueError
        When no such folder exists (the message names where it was looked for).
    """
    here = Path(__file__).resolve()
    tried = []
    for parent in here.parents:
        for cand in (parent / "worlds", parent / "share" / "explore_seg" / "worlds"):
            if (cand / _WORLDS_MARKER).is_file():
                return cand
            tried.append(str(cand))
    raise ValueError(f"the package's worlds folder (with {_WORLDS_MARKER}) is missing; "
                     f"looked in {', '.join(tried[:4])} and above")


def world_file(spec: str) -> Path | None:
    """The shipped file of a ``shared/NAME`` or ``eb/NAME`` spec; None for any other spec.

    Raises
    ------
    ValueError
        When the spec has one of the prefixes but no such file is shipped (the message
        names the spec, the file and the names that exist).
    """
    for prefix, (sub, suffix, known) in SPEC_PREFIXES.items():
        if spec.startswith(prefix) and not spec.endswith((".yaml", ".yml")):
            name = spec[len(prefix):]
            folder = worlds_dir() / sub
            path = folder / f"{name}{suffix}"
            if not name or "/" in name or not path.is_file():
                raise ValueError(f"world {spec!r}: no file {path}; {prefix}NAME takes NAME "
                                 f"from {', '.join(known)}")
            return path
    return None


def resolve_world(spec: str | Path) -> str:
    """What ``spec`` loads from: a generated world's name, or the path of a world file.

    Raises
    ------
    ValueError
        When ``spec`` is none of the specs of the module docstring, or names a file
        that does not exist; the message names the spec.
    """
    if isinstance(spec, Path):
        spec = str(spec)
    if not isinstance(spec, str) or not spec:
        raise ValueError(f"world spec must be a non-empty string or path, got {spec!r}")
    shipped = world_file(spec)
    if shipped is not None:
        return str(shipped)
    if spec in WORLD_NAMES:
        return spec
    if spec.endswith((".yaml", ".yml")) or "/" in spec:
        if not Path(spec).is_file():
            raise ValueError(f"world {spec!r}: no such world file")
        return spec
    raise ValueError(f"world {spec!r} is not a world name ({', '.join(WORLD_NAMES)}), "
                     f"shared/NAME ({', '.join(FILE_WORLDS)}), eb/NAME "
                     f"({', '.join(EXPLORE_BENCH_MAPS)}) or a path to a *.yaml world file")


def load_world(spec: str | Path, start_pose: tuple[float, float, float] | None = None
               ) -> World:
    """The world of a spec (module docstring): generated, shipped or read from a file.

    Parameters
    ----------
    spec : str or Path
        A generated world's name, ``shared/NAME``, ``eb/NAME`` or a path to a
        ``*.world.yaml`` / map_server ``*.yaml`` file (see
        :func:`~sim_bridge.worlds.files.read_world_file`).
    start_pose : tuple of float, optional
        (x, y, yaw) replacing the world's start pose; it must lie within the bounds.

    Returns
    -------
    World
        A new object on each call (callers may mutate it).

    Raises
    ------
    ValueError
        On a spec that names no world (:func:`resolve_world`), an unreadable or invalid
        file (the message names the file and the key) or a start outside the bounds.

    Examples
    --------
    >>> load_world("shared/maze").start_pose
    (0.0, 0.0, 0.0)
    >>> load_world("eb/room_2").bounds
    (-12.5, -12.5, 12.5, 12.5)
    """
    what = resolve_world(spec)
    if what not in WORLD_NAMES:
        return read_world_file(Path(what), start_pose)
    world = default_world(what)
    if start_pose is not None:
        x, y, yaw = (float(v) for v in start_pose)
        b = world.bounds
        if not (b[0] < x < b[2] and b[1] < y < b[3]):
            raise ValueError(f"world {what!r}: start_pose {[x, y, yaw]} lies outside bounds "
                             f"{list(b)}")
        world.start_pose = (x, y, yaw)
    return world


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
