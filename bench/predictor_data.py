"""Training and evaluation data of the floor-plan predictor, from generated plans only.

Each sample is one partial map of one generated floor plan, on the predictor's coarse
lattice (:mod:`explore_seg.core.prediction.features`):

* the plan: :func:`sim_bridge.worlds.generate_house` (plain or cluttered, a varied size,
  room and corridor widths, split depth, door probability) or
  :func:`sim_bridge.worlds.generate_office_floor` (a varied size), drawn by
  :func:`sample_world` from the generator seed ranges below, which leave out the
  benchmark's generated worlds (generator seed 1);
* the partial map: lidar scans (5 m, 360 rays, the simulator's lidar) ray-cast on the
  plan's lidar raster (:func:`sim_bridge.worlds.furnished.scan`) from a short simulated
  exploration: the start pose, then each next pose a random known free cell with 0.3 m
  of clearance next to unknown space (a frontier, as an explorer would go), between 1
  and ``max_poses`` poses;
* the target: per coarse cell, whether most of it is free space inside the building
  (``GroundTruth.inside``);
* the input: the free / occupied / unknown fractions of the partial map.

Everything is drawn from one ``numpy.random.Generator`` seeded by the caller, so a seed
gives the same samples (a test checks it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from explore_seg.core.prediction.features import coarse_fractions
from sim_bridge.world import World
from sim_bridge.worlds import generate_house, generate_office_floor, ground_truth
from sim_bridge.worlds.furnished import scan

#: Generator seeds of the training plans and of the held-back evaluation plans (the
#: benchmark's generated worlds use seed 1; the paired A/B runs use 1000..1999).
TRAIN_SEEDS = (100_000, 200_000)
EVAL_SEEDS = (900_000, 910_000)
#: Lidar of the scans (the simulator's defaults).
SCAN_RANGE_M = 5.0
SCAN_RAYS = 360
#: Clearance of a scan pose from occupied cells (m).
POSE_CLEARANCE_M = 0.3


def sample_world(rng: np.random.Generator, seed_range: tuple[int, int]) -> World:
    """A generated floor plan with randomly drawn generator parameters (module
    docstring); the generator seed is drawn from ``seed_range``. A draw the generator
    rejects (a room range that does not fit the size) is drawn again."""
    for _ in range(100):
        try:
            return _draw_world(rng, seed_range)
        except ValueError:
            continue
    raise ValueError("100 draws of generator parameters were all rejected")


def _draw_world(rng: np.random.Generator, seed_range: tuple[int, int]) -> World:
    seed = int(rng.integers(*seed_range))
    kind = rng.random()
    if kind < 0.12:
        size = (float(rng.uniform(40.0, 46.0)), float(rng.uniform(30.0, 34.0)))
        return generate_office_floor(seed, size, cluttered=bool(rng.random() < 0.5))
    lo = float(rng.uniform(2.5, 4.5))
    size = (float(np.round(rng.uniform(10.0, 26.0))), float(np.round(rng.uniform(10.0, 26.0))))
    return generate_house(
        seed, size, cluttered=bool(rng.random() < 0.4),
        room_width_m=(lo, lo + float(rng.uniform(0.5, 5.0))),
        corridor_width_m=(1.4, 1.4 + float(rng.uniform(0.0, 1.0))),
        split_depth_m=float(rng.uniform(4.5, 12.0)),
        extra_door_prob=float(rng.uniform(0.0, 0.6)))


@dataclass(frozen=True)
class PlanSamples:
    """Partial maps of one plan on the coarse lattice.

    Attributes
    ----------
    inputs : ndarray of float32, shape (K, 3, Hc, Wc)
    targets : ndarray of float32, shape (K, Hc, Wc)
        1 where most of the coarse cell is free inside the building.
    name : str
    """

    inputs: npt.NDArray[np.float32]
    targets: npt.NDArray[np.float32]
    name: str


def partial_maps(world: World, rng: np.random.Generator, count: int, max_poses: int,
                 factor: int) -> PlanSamples:
    """``count`` partial maps of ``world`` (module docstring)."""
    gt = ground_truth(world)
    res = gt.resolution_m
    occ = gt.lidar.data >= 65
    inside = gt.inside
    clear = ndimage.distance_transform_edt(~occ) * res >= POSE_CLEARANCE_M
    target = coarse_fractions(np.where(inside, 0, 100).astype(np.int8), factor)[0] > 0.5
    ins, tgs = [], []
    for _ in range(count):
        n_poses = int(rng.integers(1, max_poses + 1))
        seen_free, seen_occ = scan_walk(occ, inside, clear, gt.start_cell, n_poses, rng,
                                        SCAN_RANGE_M / res)
        data = np.full(occ.shape, -1, np.int8)
        data[seen_free] = 0
        data[seen_occ] = 100
        ins.append(coarse_fractions(data, factor))
        tgs.append(target.astype(np.float32))
    return PlanSamples(np.stack(ins), np.stack(tgs), world.name)


def scan_walk(occ: npt.NDArray[np.bool_], inside: npt.NDArray[np.bool_],
              clear: npt.NDArray[np.bool_], start_cell: Any, n_poses: int,
              rng: np.random.Generator, range_cells: float
              ) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Free and occupied cells seen by ``n_poses`` scans: the first from ``start_cell``,
    each next one from a random seen-free cell with clearance (``clear``) within 4 cells of
    unknown space. Stops early when there is no such cell."""
    seen_free = np.zeros(occ.shape, bool)
    seen_occ = np.zeros(occ.shape, bool)
    pose = np.asarray([start_cell])
    for k in range(n_poses):
        f, o = scan(occ, inside, pose, range_cells, SCAN_RAYS)
        seen_free |= f
        seen_occ |= o
        if k == n_poses - 1:
            break
        near_unknown = ndimage.binary_dilation(~(seen_free | seen_occ), iterations=4)
        cand = np.argwhere(seen_free & clear & near_unknown)
        if len(cand) == 0:
            break
        pose = cand[rng.integers(len(cand))][None]
    return seen_free, seen_occ


def crop(x: npt.NDArray[np.float32], y: npt.NDArray[np.float32], size: int,
         rng: np.random.Generator) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """A ``size`` x ``size`` window of one sample (padded with unknown space / not-inside
    where the plan is smaller), placed at random over the known part, randomly flipped and
    turned by a multiple of 90 degrees."""
    _, h, w = x.shape
    ph, pw = max(h, size) + size, max(w, size) + size
    xp = np.zeros((3, ph, pw), np.float32)
    xp[2] = 1.0
    yp = np.zeros((ph, pw), np.float32)
    r0, c0 = size // 2, size // 2
    xp[:, r0:r0 + h, c0:c0 + w] = x
    yp[r0:r0 + h, c0:c0 + w] = y
    known = np.argwhere(xp[2] < 1.0)
    centre = known[rng.integers(len(known))] if len(known) else np.asarray([ph // 2, pw // 2])
    jitter = rng.integers(-size // 4, size // 4 + 1, size=2)
    top = int(np.clip(centre[0] + jitter[0] - size // 2, 0, ph - size))
    left = int(np.clip(centre[1] + jitter[1] - size // 2, 0, pw - size))
    xs = xp[:, top:top + size, left:left + size]
    ys = yp[top:top + size, left:left + size]
    k = int(rng.integers(4))
    xs, ys = np.rot90(xs, k, axes=(1, 2)), np.rot90(ys, k)
    if rng.random() < 0.5:
        xs, ys = xs[:, :, ::-1], ys[:, ::-1]
    return np.ascontiguousarray(xs), np.ascontiguousarray(ys)


def make_samples(seed: int, plans: int, per_plan: int, max_poses: int, factor: int,
                 seed_range: tuple[int, int] = TRAIN_SEEDS) -> list[PlanSamples]:
    """``plans`` plans x ``per_plan`` partial maps, all drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    return [partial_maps(sample_world(rng, seed_range), rng, per_plan, max_poses, factor)
            for _ in range(plans)]


__all__ = ["EVAL_SEEDS", "PlanSamples", "TRAIN_SEEDS", "crop", "make_samples",
           "partial_maps", "sample_world"]
