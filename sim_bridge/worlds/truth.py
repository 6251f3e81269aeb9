"""Ground-truth rasters of a world: lidar plane, robot footprints, explorable region.

The lidar raster holds the primitives with ``zmin <= 0.17 <= zmax``, the footprints
those that occupy some height in (0, 0.5) and (0, 1.5) m (:func:`~sim_bridge.world.rasterize`);
``inside`` is the 4-connected flood fill from the start cell over cells free in the
lidar raster. Rasters are in grid layout (row = y).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap
from sim_bridge.world import World, rasterize

#: Height of the 2D lidar scan plane used for the ``lidar`` raster (m).
LIDAR_PLANE_Z_M = 0.17
#: Height band of the robot footprint raster (m).
FOOTPRINT_Z_M = (0.0, 0.5)
#: Height band of the tall footprint raster (m).
FOOTPRINT_TALL_Z_M = (0.0, 1.5)
#: Raster resolution of ground truth and room labels (m).
GT_RESOLUTION_M = 0.05


@dataclass(frozen=True)
class GroundTruth:
    """Ground-truth rasters of a world over its bounds (grid layout, row = y).

    Attributes
    ----------
    lidar, footprint, footprint_tall : GridMap
        Occupancy 0 / 100 (int8) of the primitives cut by the lidar plane, occupying
        height in the footprint band and in the tall footprint band.
    inside : ndarray of bool, shape (H, W)
        Explorable region: 4-connected flood fill from the start cell over cells that
        are free in ``lidar`` (the free cells of the shipped PGMs).
    free_area_m2 : float
        ``inside.sum() * resolution**2``.
    start_cell : tuple of int
        (row, col) of the start pose.
    observable : ndarray of bool, shape (H, W), or None
        Inside cells a robot can observe (:func:`sim_bridge.observable.observable_region`);
        None when not computed.
    """

    lidar: GridMap
    footprint: GridMap
    footprint_tall: GridMap
    inside: npt.NDArray[np.bool_]
    free_area_m2: float
    start_cell: tuple[int, int]
    observable: npt.NDArray[np.bool_] | None = None

    @property
    def explorable(self) -> npt.NDArray[np.bool_]:
        """The coverage denominator: ``inside & observable`` (``inside`` when
        ``observable`` is None)."""
        return self.inside if self.observable is None else self.inside & self.observable

    @property
    def explorable_area_m2(self) -> float:
        """Area of :attr:`explorable` in square metres."""
        return float(self.explorable.sum()) * self.lidar.resolution_m ** 2

    @property
    def resolution_m(self) -> float:
        """Metres per cell."""
        return self.lidar.resolution_m

    def as_map(self, which: str = "lidar") -> GridMap:
        """Trinary map as in the shipped PGMs: 100 occupied, 0 inside free, -1 elsewhere.

        Parameters
        ----------
        which : {"lidar", "footprint", "footprint_tall"}

        Raises
        ------
        ValueError
            On another name.
        """
        grids = {"lidar": self.lidar, "footprint": self.footprint,
                 "footprint_tall": self.footprint_tall}
        if which not in grids:
            raise ValueError(f"which must be one of {sorted(grids)}, got {which!r}")
        occ = grids[which].data >= OCCUPIED_THRESHOLD
        data = np.full(occ.shape, -1, np.int8)
        data[self.inside] = 0
        data[occ] = 100
        return grids[which].with_data(data)


def flood_inside(passable: npt.NDArray[np.bool_], start_cell: tuple[int, int]
                 ) -> npt.NDArray[np.bool_]:
    """4-connected component of ``passable`` holding ``start_cell``.

    Raises
    ------
    ValueError
        If the start cell lies outside the raster or is not passable.
    """
    r, c = start_cell
    if not (0 <= r < passable.shape[0] and 0 <= c < passable.shape[1]):
        raise ValueError(f"start cell {start_cell} outside raster of shape {passable.shape}")
    if not passable[r, c]:
        raise ValueError(f"start cell {start_cell} is occupied at the lidar plane")
    labels, _ = ndimage.label(passable, structure=ndimage.generate_binary_structure(2, 1))
    return labels == labels[r, c]


def ground_truth(world: World, resolution_m: float = GT_RESOLUTION_M,
                 lidar_z_m: float = LIDAR_PLANE_Z_M,
                 footprint_z_m: tuple[float, float] = FOOTPRINT_Z_M,
                 footprint_tall_z_m: tuple[float, float] = FOOTPRINT_TALL_Z_M) -> GroundTruth:
    """Lidar / footprint / tall footprint rasters and the explorable ``inside`` region.

    Parameters
    ----------
    world : World
    resolution_m : float
        Raster resolution (m), > 0; the rasters cover ``world.bounds``.
    lidar_z_m : float
        Scan plane height (m).
    footprint_z_m, footprint_tall_z_m : tuple of float
        Height bands (m) of the two footprint rasters.

    Returns
    -------
    GroundTruth

    Raises
    ------
    ValueError
        If the start pose is outside the bounds or inside an obstacle at the scan plane.
    """
    lidar = rasterize(world, resolution_m, lidar_z_m, lidar_z_m)
    foot = rasterize(world, resolution_m, *footprint_z_m)
    tall = rasterize(world, resolution_m, *footprint_tall_z_m)
    start = lidar.world_to_cell(world.start_pose[0], world.start_pose[1])
    inside = flood_inside(lidar.data < OCCUPIED_THRESHOLD, start)
    return GroundTruth(lidar, foot, tall, inside,
                       float(inside.sum()) * resolution_m * resolution_m, start)
