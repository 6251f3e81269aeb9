"""World loading, procedural generation and ground-truth rasters of the 2.5D simulator.

* :mod:`~sim_bridge.worlds.catalog`: :func:`load_world`, the one loader of a world spec
  (a generated world's name, ``shared/NAME`` or ``eb/NAME`` from the package's ``worlds/``
  folder, or a file path); :func:`default_world` builds the generated worlds
  (:data:`WORLD_NAMES`).
* :mod:`~sim_bridge.worlds.files`: :func:`read_world_file` / :func:`save_world`
  (``explore_seg_world/1`` YAML, map_server YAML + PGM/PNG, Explore-Bench layout).
* :mod:`~sim_bridge.worlds.house`, :mod:`~sim_bridge.worlds.maze`: seeded worlds sized like
  the paper's (20 x 20 m house, 40 x 40 m maze); :mod:`~sim_bridge.worlds.office`: a
  60 x 40 m office floor; :mod:`~sim_bridge.worlds.floor` (plan -> world),
  :mod:`~sim_bridge.worlds.furniture` and :mod:`~sim_bridge.worlds.walls` build their parts.
* :mod:`~sim_bridge.worlds.truth`: :func:`ground_truth` rasters and the explorable region;
  :func:`rasterize` itself lives with the world model in :mod:`sim_bridge.world`.

Everything here is ROS-free numpy. Coordinates: metres, radians, world x/y on the floor,
rasters in grid layout (row = y). This package re-exports the public names of its modules.
"""

from sim_bridge.world import CELL_OVERLAP_M, raster_geometry, rasterize
from sim_bridge.worlds.catalog import (EXPLORE_BENCH_MAPS, FILE_WORLDS, SMALL_HOUSE_SIZE_M,
                                       SMALL_ROOM_WIDTH_M, WORLD_NAMES, default_world,
                                       load_world, resolve_world, world_file, worlds_dir)
from sim_bridge.worlds.files import (KNOWN_CLASSES, MAP_WALL_HEIGHT_M, WORLD_FORMAT,
                                     read_world_file, save_world, world_to_dict)
from sim_bridge.worlds.furniture import Rect
from sim_bridge.worlds.house import HouseOptions, generate_house
from sim_bridge.worlds.maze import generate_maze
from sim_bridge.worlds.office import OFFICE_SIZE_M, generate_office_floor
from sim_bridge.worlds.truth import (FOOTPRINT_TALL_Z_M, FOOTPRINT_Z_M, GT_RESOLUTION_M,
                                     LIDAR_PLANE_Z_M, GroundTruth, flood_inside, ground_truth)

__all__ = [
    "CELL_OVERLAP_M", "EXPLORE_BENCH_MAPS", "FILE_WORLDS", "FOOTPRINT_TALL_Z_M", "FOOTPRINT_Z_M", "GT_RESOLUTION_M", "KNOWN_CLASSES",
    "LIDAR_PLANE_Z_M", "MAP_WALL_HEIGHT_M", "OFFICE_SIZE_M", "SMALL_HOUSE_SIZE_M", "SMALL_ROOM_WIDTH_M",
    "WORLD_FORMAT", "WORLD_NAMES", "GroundTruth", "HouseOptions", "Rect", "default_world",
    "flood_inside", "generate_house", "generate_maze", "generate_office_floor", "ground_truth", "load_world",
    "raster_geometry", "rasterize", "read_world_file", "resolve_world", "save_world", "world_file",
    "world_to_dict", "worlds_dir",
]
