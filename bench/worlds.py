"""The benchmark's worlds and simulator settings: world specs, their loading, the sim
time limit of a run and the simulator parameters (camera mount, navigation margin).

World specs: the generated worlds (``house``, ``maze``, ``house_cluttered``,
``office_floor``, ``small_house``, ``small_cluttered``), ``shared/NAME`` for ``<shared>/worlds/NAME.world.yaml``
and ``eb/NAME`` for the Explore-Bench map ``<shared>/worlds/explore_bench/NAME.yaml``
(``<shared>`` = ``$EXPLORE_SEG_SHARED`` or ``../shared`` beside the repository), or a
path to a world file.
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

from sim_bridge import worlds as sim_worlds
from sim_bridge.engine import SimParams, load_world
from sim_bridge.observable import with_observable

ROOT = Path(__file__).resolve().parents[1]

GENERATED_WORLDS = ("house", "maze", "house_cluttered", "office_floor")
SHARED_WORLDS = ("house", "house_cluttered", "house_cluttered_plus", "maze")
#: Sim time limit per m^2 of explorable area, and its bounds (s).
TIME_PER_AREA_S = 5.0
MIN_SIM_TIME_S = 600.0
MAX_SIM_TIME_S = 7200.0


def shared_dir() -> Path | None:
    """``$EXPLORE_SEG_SHARED`` or ``../shared`` beside the repository, when present."""
    env = os.environ.get("EXPLORE_SEG_SHARED")
    cand = Path(env) if env else ROOT.parent / "shared"
    return cand if cand.is_dir() else None


def default_worlds() -> list[str]:
    """Generated worlds, plus the shared worlds and Explore-Bench maps when present."""
    names = list(GENERATED_WORLDS)
    sh = shared_dir()
    if sh is not None:
        names += [f"shared/{n}" for n in SHARED_WORLDS
                  if (sh / "worlds" / f"{n}.world.yaml").is_file()]
        eb = sh / "worlds" / "explore_bench"
        names += [f"eb/{p.stem}" for p in sorted(eb.glob("*.yaml")) if p.stem != "starts"]
    return names


def world_path(spec: str) -> str:
    """Resolve a world spec to what :func:`sim_bridge.engine.load_world` takes.

    Raises
    ------
    ValueError
        When a ``shared/`` or ``eb/`` world is asked for and the shared folder is absent.
    """
    for prefix, sub, suffix in (("shared/", "", ".world.yaml"), ("eb/", "explore_bench", ".yaml")):
        if spec.startswith(prefix):
            sh = shared_dir()
            if sh is None:
                raise ValueError(f"world {spec!r} needs the shared folder (../shared or "
                                 "$EXPLORE_SEG_SHARED), which is absent")
            return str(sh / "worlds" / sub / f"{spec[len(prefix):]}{suffix}")
    return spec


@functools.lru_cache(maxsize=64)
def load(spec: str):
    """(World, GroundTruth with its observable cells) of a spec, cached per process (the
    main process fills it before the workers fork)."""
    world = load_world(world_path(spec))
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
                   nav_margin_m: float | None = None) -> SimParams:
    """Simulator parameters of the runs: the defaults, with the camera at
    ``camera_mount`` = (height m, pitch rad) unless None, and the navigation stand-in's
    clearance beyond the robot radius (``nav_inflation_margin_m``) unless None."""
    kw: dict[str, float] = {}
    if camera_mount is not None:
        kw.update(camera_mount_z_m=camera_mount[0], camera_pitch_rad=camera_mount[1])
    if nav_margin_m is not None:
        kw["nav_inflation_margin_m"] = nav_margin_m
    return SimParams(**kw)
