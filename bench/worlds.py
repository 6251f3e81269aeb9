"""The benchmark's worlds and simulator settings: world specs, their loading, the sim
time limit of a run and the simulator parameters (camera mount, navigation margin).

World specs (:mod:`sim_bridge.worlds.catalog`): the generated worlds (``house``, ``maze``,
``house_cluttered``, ``office_floor``, ``small_house``, ``small_cluttered``),
``shared/NAME`` for the package's ``worlds/NAME.world.yaml``, ``eb/NAME`` for the
Explore-Bench map ``worlds/explore_bench/NAME.yaml``, or a path to a world file.
"""

from __future__ import annotations

import functools
from pathlib import Path

from sim_bridge import worlds as sim_worlds
from sim_bridge.engine import SimParams
from sim_bridge.observable import with_observable
from sim_bridge.worlds import EXPLORE_BENCH_MAPS, FILE_WORLDS, load_world, resolve_world

ROOT = Path(__file__).resolve().parents[1]

GENERATED_WORLDS = ("house", "maze", "house_cluttered", "office_floor")
#: Sim time limit per m^2 of explorable area, and its bounds (s).
TIME_PER_AREA_S = 5.0
MIN_SIM_TIME_S = 600.0
MAX_SIM_TIME_S = 7200.0
#: Seeded runs per world x strategy of the full matrix (``run_bench.py --runs``'s default).
FULL_RUNS = 20
#: Runs per world x strategy of the long generated worlds in the full matrix (the others
#: get ``--runs``): a maze or office floor run takes 10-40 min of CPU.
WORLD_RUNS = {"maze": 10, "office_floor": 10}


def default_worlds() -> list[str]:
    """The full benchmark's worlds: the generated ones, the four world files and the
    twelve Explore-Bench maps shipped in ``worlds/`` (20 specs)."""
    return (list(GENERATED_WORLDS) + [f"shared/{n}" for n in FILE_WORLDS]
            + [f"eb/{n}" for n in EXPLORE_BENCH_MAPS])


def world_path(spec: str) -> str:
    """What the simulator's ``world`` parameter takes for a spec: the file of a shipped
    or file world, or the name of a generated one.

    Raises
    ------
    ValueError
        When the spec names no world (a ``shared/`` or ``eb/`` name that is not shipped,
        a missing file, an unknown name); the message names it.
    """
    return resolve_world(spec)


@functools.lru_cache(maxsize=64)
def load(spec: str):
    """(World, GroundTruth with its observable cells) of a spec, cached per process (the
    main process fills it before the workers fork)."""
    world = load_world(spec)
    world.name = spec
    sp = SimParams()
    return world, with_observable(world, sim_worlds.ground_truth(world), sp.lidar_params(),
                                  sp.robot_radius_m)


def sim_time_limit(area_m2: float, override: float | None) -> float:
    """``override`` or ``TIME_PER_AREA_S`` per m^2 within [MIN_SIM_TIME_S, MAX_SIM_TIME_S]."""
    if override:
        return float(override)
    return float(min(MAX_SIM_TIME_S, max(MIN_SIM_TIME_S, TIME_PER_AREA_S * area_m2)))


#: RGB-D camera mount of the paper's robot (height above the floor m, pitch rad down).
PAPER_CAMERA_MOUNT = (0.894, 0.1)


def sim_params_for(camera_mount: tuple[float, float] | None,
                   nav_margin_m: float | None = None,
                   mapping_error: str = "none") -> SimParams:
    """Simulator parameters of the runs: the defaults, with the camera at
    ``camera_mount`` = (height m, pitch rad) unless None, the navigation stand-in's
    clearance beyond the robot radius (``nav_inflation_margin_m``) unless None, and the
    SLAM-like mapping error profile ``mapping_error`` (``SimParams.mapping_error``).

    Raises
    ------
    ValueError
        On a value SimParams rejects (e.g. an unknown mapping error profile).
    """
    kw: dict[str, float | str] = {"mapping_error": mapping_error}
    if camera_mount is not None:
        kw.update(camera_mount_z_m=camera_mount[0], camera_pitch_rad=camera_mount[1])
    if nav_margin_m is not None:
        kw["nav_inflation_margin_m"] = nav_margin_m
    return SimParams(**kw)
