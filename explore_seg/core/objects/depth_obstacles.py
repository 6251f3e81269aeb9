"""Generic obstacles from depth: every depth point in a height band marks the object layer,
whatever its class (the idea of Nav2's voxel / obstacle layer).

The YOLO boxes give the full extent of furniture the detector knows, including the parts
the camera does not see; an object of a class it does not know and the lidar does not
cut (a box lower than the scan plane, a bin's rim, a shelf overhang above the scan
plane) would be missed. :class:`DepthObstacles` keeps voxels in
the map frame:

* **marking**: the depth image is sampled every ``depth_pixel_stride``-th pixel up to
  ``depth_max_range_m``; points between ``depth_min_height_m`` (the floor margin) and
  ``depth_max_height_m`` (the robot's height), not in a voxel column that also holds a
  point at the lidar's height (``depth_lidar_height_m`` within ``depth_lidar_band_m``)
  in this frame or in a frame of the evidence window, or next to one (the lidar sees what
  stands there, so the 2D map has it, and this holds however far the SLAM pose has
  drifted from the map's walls; the window because the camera loses that row of a wall or
  leg in some frames, below its view from close by or between the sampled rows from
  afar, while the drifting pose moves the points from frame to frame; the neighbours
  because a pitched camera places a wall's points of one pixel column a few centimetres
  apart sideways at different heights), not over a
  wall of the 2D map (``drop_wall_points``), are binned into voxels of ``depth_voxel_m`` (x, y) by
  ``depth_voxel_height_m`` (z); a voxel with at least ``depth_min_points`` points in a
  frame gains one point of score (up to ``depth_max_score``);
* **evidence over frames**: a voxel with fewer points in a frame is pending: its points
  add up over the frames of ``depth_evidence_window_s`` (from its first point), and it is
  marked in the frame that brings the sum to ``depth_min_points``. An object seen only at
  long range or only along a thin strip (an overhang above a wall, seen over it from across
  the room) gives one point per voxel per frame: it is marked before the robot is close,
  when it may already be outside the camera's narrow field of view. A pending voxel the
  camera sees through is dropped, as is one whose window ends first;
* **clearing**: a stored voxel that lies in the camera's view, in front of the measured
  surface by more than ``depth_clear_margin_m`` at its pixel (the ray passed through it),
  loses one point; at zero it is forgotten. Voxels out of view (behind the robot, below
  the camera's field of view when the robot is close) are kept;
* **decay**: a voxel not marked for ``depth_decay_s`` is forgotten (0: never).

The layer cell of a voxel column is an obstacle when any voxel of the column is stored:
:meth:`DepthObstacles.mask` on any grid geometry.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from explore_seg.core.camera import apply_transform, invert_transform
from explore_seg.core.grid import GridMap
from explore_seg.core.objects.frame import DepthFrame
from explore_seg.core.objects.params import ObjectParams
from explore_seg.core.objects.walls import WallMask

_XY_BITS = 21
_Z_BITS = 10
_XY_OFF = 1 << (_XY_BITS - 1)


def _pack(ix: npt.NDArray[np.int64], iy: npt.NDArray[np.int64], iz: npt.NDArray[np.int64]
          ) -> npt.NDArray[np.int64]:
    return (((ix + _XY_OFF) << (_XY_BITS + _Z_BITS)) | ((iy + _XY_OFF) << _Z_BITS)
            | iz).astype(np.int64)


def _with_neighbours(columns: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """Column keys (``key >> _Z_BITS``) of ``columns`` and of their 8 neighbours."""
    steps = np.array([(dx << _XY_BITS) + dy for dx in (-1, 0, 1) for dy in (-1, 0, 1)],
                     np.int64)
    return np.unique((columns[:, None] + steps[None, :]).ravel())


def _unpack(keys: npt.NDArray[np.int64]) -> tuple[npt.NDArray[np.int64], ...]:
    ix = (keys >> (_XY_BITS + _Z_BITS)) - _XY_OFF
    iy = ((keys >> _Z_BITS) & ((1 << _XY_BITS) - 1)) - _XY_OFF
    iz = keys & ((1 << _Z_BITS) - 1)
    return ix, iy, iz


def _merge(keys: npt.NDArray[np.int64], score: npt.NDArray[np.int16],
           stamp: npt.NDArray[np.float64], keys2: npt.NDArray[np.int64],
           score2: npt.NDArray[np.int16], stamp2: npt.NDArray[np.float64]
           ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int16], npt.NDArray[np.float64]]:
    """Two sets of voxels as one, sorted by key; a key in both (or twice) keeps its
    highest score and latest stamp."""
    all_keys = np.concatenate([keys, keys2])
    out, inv = np.unique(all_keys, return_inverse=True)
    sc = np.zeros(out.size, np.int16)
    st = np.full(out.size, -math.inf)
    np.maximum.at(sc, inv, np.concatenate([score, score2]).astype(np.int16))
    np.maximum.at(st, inv, np.concatenate([stamp, stamp2]))
    return out, sc, st


class DepthObstacles:
    """Voxels of depth points in the robot's height band (see the module docstring).

    Parameters
    ----------
    params : ObjectParams
        The ``depth_*`` fields (and ``drop_wall_points``).
    """

    def __init__(self, params: ObjectParams) -> None:
        self.params = params
        self._keys = np.zeros(0, np.int64)       # sorted
        self._score = np.zeros(0, np.int16)
        self._stamp = np.zeros(0, np.float64)
        self._columns = np.zeros(0, np.int64)    # sorted (ix, iy) keys of stored voxels
        # pending voxels (fewer than depth_min_points so far): sorted keys, points, the
        # stamp of their first point
        self._pend_keys = np.zeros(0, np.int64)
        self._pend_count = np.zeros(0, np.int32)
        self._pend_stamp = np.zeros(0, np.float64)
        # columns (``key >> _Z_BITS``) that held a point at the lidar's height in a frame of
        # the evidence window: sorted keys, the stamp of their last such frame
        self._lidar_cols = np.zeros(0, np.int64)
        self._lidar_stamp = np.zeros(0, np.float64)
        #: Changes whenever the set of obstacle columns changes.
        self.version = 0

    def __len__(self) -> int:
        return int(self._keys.size)

    def clear(self) -> None:
        """Forget every voxel."""
        self.__init__(self.params)  # type: ignore[misc]

    # ------------------------------------------------------------------ update
    def band_points(self, frame: DepthFrame, walls: WallMask | None = None
                    ) -> npt.NDArray[np.float64]:
        """Map-frame depth points in the height band that this frame alone lets mark (not
        in or next to a column with a point at the lidar's height), shape (N, 3)."""
        pts, cols, lidar_cols = self._band(frame, walls)
        return pts[~np.isin(cols, _with_neighbours(lidar_cols))]

    def _band(self, frame: DepthFrame, walls: WallMask | None
              ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], npt.NDArray[np.int64]]:
        """The frame's map-frame points in the height band and not on a wall of the 2D map,
        shape (N, 3); their column keys (``key >> _Z_BITS``), shape (N,); and the sorted
        columns holding a point at the lidar's height (empty when ``depth_lidar_band_m``
        is 0)."""
        p = self.params
        s = p.depth_pixel_stride
        d = frame.depth_m[::s, ::s]
        rows, cols = np.mgrid[0:frame.depth_m.shape[0]:s, 0:frame.depth_m.shape[1]:s]
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(d) & (d > 0) & (d <= p.depth_max_range_m)
        z = d[ok].astype(np.float64)
        k = frame.intrinsics
        pts = np.stack([(cols[ok] - k.cx) * z / k.fx, (rows[ok] - k.cy) * z / k.fy, z], axis=1)
        pts = apply_transform(frame.map_from_optical, pts)
        keys = self._column_keys(pts)
        lidar_cols = (np.unique(keys[np.abs(pts[:, 2] - p.depth_lidar_height_m)
                                     <= p.depth_lidar_band_m])
                      if p.depth_lidar_band_m > 0 else np.zeros(0, np.int64))
        band = (pts[:, 2] > p.depth_min_height_m) & (pts[:, 2] < p.depth_max_height_m)
        if walls is not None and p.drop_wall_points and band.any():
            band[band] = ~walls.on(pts[band, :2])
        return pts[band], keys[band], lidar_cols

    def _column_keys(self, pts: npt.NDArray[np.float64]) -> npt.NDArray[np.int64]:
        """The (ix, iy) voxel column key of each point (the stored voxels' ``key >> z
        bits``), shape (N,)."""
        v = self.params.depth_voxel_m
        ix = np.floor(pts[:, 0] / v).astype(np.int64)
        iy = np.floor(pts[:, 1] / v).astype(np.int64)
        return _pack(ix, iy, np.zeros_like(ix)) >> _Z_BITS

    def update(self, frame: DepthFrame, stamp_s: float, walls: WallMask | None = None
               ) -> bool:
        """Mark, clear and decay with one depth frame; True when the obstacle columns
        changed.

        Parameters
        ----------
        frame : DepthFrame
        stamp_s : float
            Frame time (seconds, monotonic; used by the decay).
        walls : WallMask, optional
            Depth points on the 2D map's walls do not mark (the map has them).
        """
        p = self.params
        pts, cols, lidar_cols = self._band(frame, walls)
        lidar_near = self._lidar_near(lidar_cols, stamp_s)
        pts = pts[~np.isin(cols, lidar_near)]
        v, vz = p.depth_voxel_m, p.depth_voxel_height_m
        ix = np.floor(pts[:, 0] / v).astype(np.int64)
        iy = np.floor(pts[:, 1] / v).astype(np.int64)
        iz = np.floor((pts[:, 2] - p.depth_min_height_m) / vz).astype(np.int64)
        seen, counts = np.unique(_pack(ix, iy, iz), return_counts=True)
        new = self._with_pending(frame, seen, counts, stamp_s, lidar_near)
        keys, score, stamp = self._keys, self._score.astype(np.int32), self._stamp
        # clearing: stored voxels the camera sees through (not marked in this frame)
        if keys.size:
            through = self._seen_through(frame, keys) & ~np.isin(keys, new)
            score = score - through.astype(np.int32)
        # marking
        if new.size:
            if keys.size:
                idx_c = np.minimum(np.searchsorted(keys, new), keys.size - 1)
                found = keys[idx_c] == new
            else:
                idx_c, found = np.zeros(new.size, np.int64), np.zeros(new.size, bool)
            score[idx_c[found]] = np.minimum(score[idx_c[found]] + 1, p.depth_max_score)
            stamp = stamp.copy()
            stamp[idx_c[found]] = stamp_s
            add = new[~found]
            keys = np.concatenate([keys, add])
            score = np.concatenate([score, np.ones(add.size, np.int32)])
            stamp = np.concatenate([stamp, np.full(add.size, float(stamp_s))])
            order = np.argsort(keys, kind="stable")
            keys, score, stamp = keys[order], score[order], stamp[order]
        keep = score > 0
        if p.depth_decay_s > 0:
            keep &= stamp >= stamp_s - p.depth_decay_s
        if keep.sum() > p.depth_max_voxels:       # bounded: the oldest go first
            old = np.argsort(stamp[keep], kind="stable")[:int(keep.sum()) - p.depth_max_voxels]
            keep[np.flatnonzero(keep)[old]] = False
        return self._store(keys[keep], score[keep].astype(np.int16), stamp[keep])

    def _with_pending(self, frame: DepthFrame, seen: npt.NDArray[np.int64],
                      counts: npt.NDArray[np.int64], stamp_s: float,
                      lidar_near: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
        """The voxels this frame marks (sorted keys): those with ``depth_min_points`` of its
        points (``seen``, ``counts``: every voxel with a point), and the pending voxels whose
        points reach that sum with this frame's. Updates the pending store: adds this
        frame's other voxels, drops the ones marked, seen through, past the window, or in
        a column of ``lidar_near`` (:meth:`_lidar_near`: the lidar saw something there)."""
        p = self.params
        strong = counts >= p.depth_min_points
        if p.depth_evidence_window_s <= 0 or p.depth_min_points <= 1:
            return seen[strong]
        keys, count, first = self._pend_keys, self._pend_count, self._pend_stamp
        # past the window, or first seen after this frame: the clock jumped back and
        # they belong to the old time line
        keep = (first >= stamp_s - p.depth_evidence_window_s) & (first <= stamp_s)
        if keys.size:
            keep &= ~(self._seen_through(frame, keys) & ~np.isin(keys, seen))
            keep &= ~np.isin(keys, seen[strong])
            keep &= ~np.isin(keys >> _Z_BITS, lidar_near)
        # this frame's other voxels join: points summed, the earliest first stamp kept
        weak = ~strong
        stamps = np.concatenate([first[keep], np.full(int(weak.sum()), float(stamp_s))])
        points = np.concatenate([count[keep], counts[weak]])
        keys, inv = np.unique(np.concatenate([keys[keep], seen[weak]]), return_inverse=True)
        count = np.bincount(inv, points, minlength=keys.size).astype(np.int32)
        first = np.full(keys.size, math.inf)
        np.minimum.at(first, inv, stamps)
        done = count >= p.depth_min_points
        pending = ~done
        n_pending = int(pending.sum())
        if n_pending > p.depth_max_voxels:       # bounded: the oldest go first
            idx_p = np.flatnonzero(pending)
            pending[idx_p[np.argsort(first[idx_p], kind="stable")
                          [:n_pending - p.depth_max_voxels]]] = False
        self._pend_keys, self._pend_count, self._pend_stamp = (
            keys[pending], count[pending], first[pending])
        return np.union1d(seen[strong], keys[done])

    def forget_since(self, stamp_s: float, jump: tuple[float, float, float] | None = None,
                     recent_s: float = math.inf) -> bool:
        """Forget the voxels last marked, and the pending points first seen, at or after
        ``stamp_s`` (after a SLAM correction moved the poses they were placed at: they are
        re-observed where the corrected map has them); True when the obstacle columns
        changed.

        With ``jump`` (the rigid map-frame transform of the robot's pose at the correction,
        see :meth:`Object3D.moved`), the voxels last marked at or after ``recent_s`` are
        moved by it instead (their centres, binned again; a voxel that lands on a kept one
        keeps the higher score and the later stamp): they were placed at the pose error
        the robot had just before the correction, which the jump corrects."""
        pend = self._pend_stamp < stamp_s
        self._pend_keys, self._pend_count, self._pend_stamp = (
            self._pend_keys[pend], self._pend_count[pend], self._pend_stamp[pend])
        lid = self._lidar_stamp < stamp_s
        self._lidar_cols, self._lidar_stamp = self._lidar_cols[lid], self._lidar_stamp[lid]
        keep = self._stamp < stamp_s
        move = (~keep & (self._stamp >= recent_s) if jump is not None
                else np.zeros_like(keep))
        if keep.all():
            return False
        keys, score, stamp = self._keys[keep], self._score[keep], self._stamp[keep]
        if move.any():
            keys, score, stamp = _merge(keys, score, stamp,
                                        self._moved_keys(self._keys[move], jump),
                                        self._score[move], self._stamp[move])
        return self._store(keys, score, stamp)

    def _moved_keys(self, keys: npt.NDArray[np.int64], jump: tuple[float, float, float]
                    ) -> npt.NDArray[np.int64]:
        """The keys of the voxels ``keys`` with their centres moved by ``jump``."""
        p = self.params
        c = self.centres(keys)
        tx, ty, th = (float(v) for v in jump)
        cs, sn = math.cos(th), math.sin(th)
        x = cs * c[:, 0] - sn * c[:, 1] + tx
        y = sn * c[:, 0] + cs * c[:, 1] + ty
        ix = np.floor(x / p.depth_voxel_m).astype(np.int64)
        iy = np.floor(y / p.depth_voxel_m).astype(np.int64)
        return _pack(ix, iy, _unpack(keys)[2])

    def time_went_back(self, stamp_s: float) -> None:
        """The clock jumped back to ``stamp_s``: the voxels marked later (on the old time
        line) are kept, restamped to ``stamp_s`` so that ``depth_decay_s`` counts from the
        jump; the pending points and lidar-height columns of the old time line are
        dropped."""
        self._stamp = np.minimum(self._stamp, float(stamp_s))
        pend = self._pend_stamp <= stamp_s
        self._pend_keys, self._pend_count, self._pend_stamp = (
            self._pend_keys[pend], self._pend_count[pend], self._pend_stamp[pend])
        lid = self._lidar_stamp <= stamp_s
        self._lidar_cols, self._lidar_stamp = self._lidar_cols[lid], self._lidar_stamp[lid]

    def _lidar_near(self, lidar_cols: npt.NDArray[np.int64], stamp_s: float
                    ) -> npt.NDArray[np.int64]:
        """Columns with, or next to one with, a point at the lidar's height in this frame
        (``lidar_cols``) or in another frame of the evidence window (a frame stamped up to
        the window after this one counts too: frames may come out of order); sorted keys.
        Updates the store with ``lidar_cols`` (columns of frames more than the window
        before or after this one are dropped, so a clock jump leaves none of the old time
        line; at most ``depth_max_voxels``, the oldest dropped first). With
        ``depth_evidence_window_s`` 0: this frame's alone.

        What the lidar saw a moment ago still stands there: the camera loses the
        lidar-height part of a wall or leg in some frames (below its view from close by,
        between the sampled rows from afar), while the SLAM pose the points are placed at
        drifts from frame to frame."""
        p = self.params
        if p.depth_evidence_window_s <= 0:
            return _with_neighbours(lidar_cols)
        keep = ((np.abs(self._lidar_stamp - stamp_s) <= p.depth_evidence_window_s)
                & ~np.isin(self._lidar_cols, lidar_cols))
        cols = np.concatenate([self._lidar_cols[keep], lidar_cols])
        stamps = np.concatenate([self._lidar_stamp[keep],
                                 np.full(lidar_cols.size, float(stamp_s))])
        near = _with_neighbours(cols)
        if cols.size > p.depth_max_voxels:
            newest = np.argsort(stamps, kind="stable")[cols.size - p.depth_max_voxels:]
            cols, stamps = cols[newest], stamps[newest]
        order = np.argsort(cols, kind="stable")
        self._lidar_cols, self._lidar_stamp = cols[order], stamps[order]
        return near

    def _store(self, keys: npt.NDArray[np.int64], score: npt.NDArray[np.int16],
               stamp: npt.NDArray[np.float64]) -> bool:
        """Keep these voxels; True (and a new :attr:`version`) when the obstacle columns
        changed."""
        self._keys, self._score, self._stamp = keys, score, stamp
        columns = np.unique(keys >> _Z_BITS)
        changed = not np.array_equal(columns, self._columns)
        if changed:
            self._columns = columns
            self.version += 1
        return changed

    def _seen_through(self, frame: DepthFrame, keys: npt.NDArray[np.int64]
                      ) -> npt.NDArray[np.bool_]:
        """Voxels whose centre the camera sees past by more than ``depth_clear_margin_m``."""
        p = self.params
        centres = self.centres(keys)
        opt = apply_transform(invert_transform(frame.map_from_optical), centres)
        z = opt[:, 2]
        k = frame.intrinsics
        out = np.zeros(keys.size, bool)
        front = (z > 1e-6) & (z <= p.depth_max_range_m)
        if not front.any():
            return out
        zf = z[front]
        u = np.round(k.fx * opt[front, 0] / zf + k.cx).astype(np.int64)
        vv = np.round(k.fy * opt[front, 1] / zf + k.cy).astype(np.int64)
        inside = (u >= 0) & (u < k.width) & (vv >= 0) & (vv < k.height)
        measured = np.full(zf.shape, np.nan, np.float64)
        measured[inside] = frame.depth_m[vv[inside], u[inside]]
        with np.errstate(invalid="ignore"):
            through = np.isfinite(measured) & (measured > zf + p.depth_clear_margin_m)
        out[np.flatnonzero(front)] = through
        return out

    # ----------------------------------------------------------------- outputs
    def centres(self, keys: npt.NDArray[np.int64] | None = None) -> npt.NDArray[np.float64]:
        """Map-frame centres of the stored voxels (or of ``keys``), shape (N, 3)."""
        p = self.params
        ix, iy, iz = _unpack(self._keys if keys is None else keys)
        return np.stack([(ix + 0.5) * p.depth_voxel_m, (iy + 0.5) * p.depth_voxel_m,
                         p.depth_min_height_m + (iz + 0.5) * p.depth_voxel_height_m], axis=1)

    def mask(self, grid: GridMap) -> npt.NDArray[np.bool_]:
        """Cells of ``grid`` covered by an obstacle column, shape (H, W) bool."""
        out = np.zeros(grid.shape, bool)
        if not self._columns.size:
            return out
        v = self.params.depth_voxel_m
        ix = (self._columns >> _XY_BITS) - _XY_OFF
        iy = (self._columns & ((1 << _XY_BITS) - 1)) - _XY_OFF
        n = max(1, int(math.ceil(v / grid.resolution_m - 1e-9)))
        offs = ((np.arange(n) + 0.5) / n) * v
        ox, oy = np.meshgrid(offs, offs, indexing="ij")
        x = (ix[:, None] * v + ox.ravel()[None, :]).ravel()
        y = (iy[:, None] * v + oy.ravel()[None, :]).ravel()
        r, c = grid.world_to_cells(x, y)
        ok = (r >= 0) & (r < grid.height) & (c >= 0) & (c < grid.width)
        out[r[ok], c[ok]] = True
        return out
