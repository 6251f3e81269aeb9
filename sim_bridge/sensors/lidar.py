"""Simulated planar lidar of the 2.5D world.

:class:`Lidar` casts ``num_beams`` rays in the scan plane against the rectangles and
circles that the plane cuts out of the world's primitives (analytic ray/segment and
ray/circle intersection). Each scan first culls primitives beyond the range and then
tests every primitive only against the beams inside its angular extent, so the work
grows with what the robot sees, not with the size of the world.

Beam ``k`` of a scan points at ``angle_min + k * angle_increment`` from the robot
heading with ``angle_min = -pi`` and ``angle_increment = 2 pi / num_beams``; robot poses
are ``(x, y, yaw)`` of ``base_footprint`` in the world frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.fields import param_meta
from sim_bridge.sensors.common import require_positive
from sim_bridge.world import World

#: Candidate beams of primitives: (first beam, beam count, primitive row in its table,
#: is a circle), one entry per primitive.
_Spans = tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.int64],
               npt.NDArray[np.bool_]]


@dataclass(frozen=True)
class LidarParams:
    """Planar 360-degree lidar (TurtleBot3 LDS-like; the paper used a 5 m range)."""

    num_beams: int = field(default=360, metadata=param_meta(
        "beams per revolution", range=(3, 2**31 - 1)))
    range_min_m: float = field(default=0.12, metadata=param_meta(
        "closer hits read -inf (REP 117 'too close')", "m", range=(0.0, math.inf)))
    range_max_m: float = field(default=5.0, metadata=param_meta(
        "farther hits read +inf (LDS real: 3.5 m; the paper used 5 m)",
        "m", range=(0.0, math.inf)))
    scan_height_m: float = field(default=0.17, metadata=param_meta(
        "height of the scan plane above the floor", "m", range=(0.0, math.inf)))
    noise_std_m: float = field(default=0.0, metadata=param_meta(
        "std of Gaussian range noise (applied when an rng is given)", "m", range=(0.0, math.inf)))
    rate_hz: float = field(default=5.0, metadata=param_meta(
        "scan rate (TurtleBot3's LDS-01 and LDS-02 spin at 300 rpm: 5 scans a second, as "
        "in turtlebot3_gazebo's lidar)", "Hz", range=(0.0, math.inf)))
    mount_xy_m: tuple[float, float] = field(default=(-0.064, 0.0), metadata=param_meta(
        "lidar position in base_footprint (TurtleBot3 waffle base_scan)", "m"))

    def __post_init__(self) -> None:
        if int(self.num_beams) != self.num_beams or self.num_beams < 3:
            raise ValueError(f"num_beams must be an integer >= 3, got {self.num_beams}")
        require_positive("range_min_m", self.range_min_m)
        require_positive("rate_hz", self.rate_hz)
        if not self.range_max_m > self.range_min_m or not math.isfinite(self.range_max_m):
            raise ValueError(f"range_max_m must be finite and > range_min_m "
                             f"{self.range_min_m}, got {self.range_max_m}")
        if not (math.isfinite(self.scan_height_m) and self.scan_height_m >= 0):
            raise ValueError(f"scan_height_m must be >= 0, got {self.scan_height_m}")
        if not (math.isfinite(self.noise_std_m) and self.noise_std_m >= 0):
            raise ValueError(f"noise_std_m must be >= 0, got {self.noise_std_m}")
        if len(self.mount_xy_m) != 2 or not all(math.isfinite(v) for v in self.mount_xy_m):
            raise ValueError(f"mount_xy_m must be 2 finite values, got {self.mount_xy_m}")

    @property
    def angle_min_rad(self) -> float:
        """Angle of beam 0 from the robot heading."""
        return -math.pi

    @property
    def angle_increment_rad(self) -> float:
        """Angle between consecutive beams."""
        return 2.0 * math.pi / self.num_beams

    @property
    def angle_max_rad(self) -> float:
        """Angle of the last beam."""
        return self.angle_min_rad + (self.num_beams - 1) * self.angle_increment_rad


class Lidar:
    """Analytic 2D ray caster of a world's scan-plane cross-section.

    Parameters
    ----------
    world : World
        Primitives with ``zmin <= scan_height_m <= zmax`` are seen (boxes as their four
        edges, cylinders as circles).
    params : LidarParams
    """

    def __init__(self, world: World, params: LidarParams | None = None) -> None:
        self.params = params or LidarParams()
        h = self.params.scan_height_m
        seen = [(i, p) for i, p in enumerate(world.primitives) if p.zmin <= h <= p.zmax]
        segs, seg_prim, circles, circ_prim = [], [], [], []
        for i, p in seen:
            if p.shape == "box":
                c, s = math.cos(p.yaw), math.sin(p.yaw)
                hx, hy = p.size[0] / 2, p.size[1] / 2
                corners = [(p.x + c * u - s * v, p.y + s * u + c * v)
                           for u, v in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]
                for k in range(4):
                    (ax, ay), (bx, by) = corners[k], corners[(k + 1) % 4]
                    segs.append((ax, ay, bx - ax, by - ay))
                    seg_prim.append(i)
            else:
                circles.append((p.x, p.y, p.size[0]))
                circ_prim.append(i)
        self._seg = np.asarray(segs, np.float64).reshape(-1, 4)       # px, py, ex, ey
        self._seg_prim = np.asarray(seg_prim, np.int64)
        self._seg_mid = self._seg[:, :2] + 0.5 * self._seg[:, 2:]
        self._seg_half = 0.5 * np.hypot(self._seg[:, 2], self._seg[:, 3])
        self._circ = np.asarray(circles, np.float64).reshape(-1, 3)   # cx, cy, r
        self._circ_prim = np.asarray(circ_prim, np.int64)
        n = self.params.num_beams
        self._rel = self.params.angle_min_rad + np.arange(n) * self.params.angle_increment_rad

    @property
    def num_segments(self) -> int:
        """Number of segments (box edges) in the scan plane."""
        return int(self._seg.shape[0])

    @property
    def num_circles(self) -> int:
        """Number of circles (cylinders) in the scan plane."""
        return int(self._circ.shape[0])

    def origin(self, pose: tuple[float, float, float]) -> tuple[float, float]:
        """World (x, y) of the lidar for a robot pose."""
        x, y, yaw = pose
        mx, my = self.params.mount_xy_m
        c, s = math.cos(yaw), math.sin(yaw)
        return x + c * mx - s * my, y + s * mx + c * my

    def scan(self, pose: tuple[float, float, float],
             rng: np.random.Generator | None = None) -> npt.NDArray[np.float32]:
        """Ranges of one scan.

        Parameters
        ----------
        pose : tuple of float
            Robot (x, y, yaw) in the world.
        rng : numpy.random.Generator, optional
            Source of range noise (``noise_std_m``); no noise without it.

        Returns
        -------
        ndarray of float32, shape (num_beams,)
            Range of beam ``k`` (angle ``-pi + k * 2 pi / num_beams`` from the heading):
            ``+inf`` when nothing lies within ``range_max_m``, ``-inf`` when the nearest
            hit is closer than ``range_min_m``, else the distance in metres.
        """
        return self.scan_with_hits(pose, rng)[0]

    def _segment_spans(self, ox: float, oy: float, a0: float) -> _Spans | None:
        """Wall segments within range of the sensor at (ox, oy) and the beams (beam 0 at
        angle ``a0``) their angular extent covers; None when there is none."""
        p = self.params
        n, inc, two_pi = p.num_beams, p.angle_increment_rad, 2.0 * math.pi
        if not self._seg.shape[0]:
            return None
        dmx = self._seg_mid[:, 0] - ox
        dmy = self._seg_mid[:, 1] - oy
        near = np.flatnonzero(dmx * dmx + dmy * dmy < (p.range_max_m + self._seg_half) ** 2)
        if not near.size:
            return None
        sg = self._seg[near]
        wx, wy = sg[:, 0] - ox, sg[:, 1] - oy
        t0 = np.arctan2(wy, wx)
        t1 = np.arctan2(wy + sg[:, 3], wx + sg[:, 2])
        d = np.mod(t1 - t0 + math.pi, two_pi) - math.pi
        lo = np.mod(np.where(d >= 0, t0, t1) - a0, two_pi)
        k0 = np.floor(lo / inc).astype(np.int64)
        k1 = np.floor((lo + np.abs(d)) / inc).astype(np.int64) + 1
        return k0, np.minimum(k1 - k0 + 1, n), near, np.zeros(near.size, bool)

    def _circle_spans(self, ox: float, oy: float, a0: float) -> _Spans | None:
        """Circles (posts, legs) within range of the sensor at (ox, oy) and the beams
        (beam 0 at angle ``a0``) their angular extent covers; None when there is none."""
        p = self.params
        n, inc, two_pi = p.num_beams, p.angle_increment_rad, 2.0 * math.pi
        if not self._circ.shape[0]:
            return None
        cx = self._circ[:, 0] - ox
        cy = self._circ[:, 1] - oy
        r = self._circ[:, 2]
        dist = np.hypot(cx, cy)
        near = np.flatnonzero(dist < p.range_max_m + r)
        if not near.size:
            return None
        dn, rn = dist[near], r[near]
        half = np.where(dn > rn, np.arcsin(np.minimum(rn / np.maximum(dn, 1e-12), 1.0)),
                        math.pi)
        lo = np.mod(np.arctan2(cy[near], cx[near]) - half - a0, two_pi)
        k0 = np.floor(lo / inc).astype(np.int64)
        k1 = np.floor((lo + 2 * half) / inc).astype(np.int64) + 1
        return k0, np.minimum(k1 - k0 + 1, n), near, np.ones(near.size, bool)

    def _segment_hits(self, s_id: npt.NDArray[np.int64], bx: npt.NDArray[np.float64],
                      by: npt.NDArray[np.float64], ox: float, oy: float
                      ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """Range along each beam (direction (bx, by) from (ox, oy)) to its segment
        ``s_id`` (inf: missed) and the segment's primitive."""
        sg = self._seg[s_id]
        wx, wy = sg[:, 0] - ox, sg[:, 1] - oy
        ex, ey = sg[:, 2], sg[:, 3]
        den = bx * ey - by * ex
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = (wx * ey - wy * ex) / den
            ss = (wx * by - wy * bx) / den
        ok = (den != 0) & (ss >= 0.0) & (ss <= 1.0) & (tt >= 0.0)
        return np.where(ok, tt, np.inf), self._seg_prim[s_id]

    def _circle_hits(self, c_id: npt.NDArray[np.int64], bx: npt.NDArray[np.float64],
                     by: npt.NDArray[np.float64], ox: float, oy: float
                     ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64]]:
        """Range along each beam (direction (bx, by) from (ox, oy)) to its circle
        ``c_id`` (the far side when the sensor is inside; inf: missed) and the circle's
        primitive."""
        cc = self._circ[c_id]
        wx, wy = cc[:, 0] - ox, cc[:, 1] - oy
        b = wx * bx + wy * by
        disc = b * b - (wx * wx + wy * wy - cc[:, 2] ** 2)
        root = np.sqrt(np.maximum(disc, 0.0))
        tin = b - root
        tt = np.where(tin >= 0.0, tin, b + root)
        ok = (disc >= 0.0) & (tt >= 0.0)
        return np.where(ok, tt, np.inf), self._circ_prim[c_id]

    def scan_with_hits(self, pose: tuple[float, float, float],
                       rng: np.random.Generator | None = None
                       ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]:
        """:meth:`scan` plus the index (into ``world.primitives``) of what each beam hit.

        Returns
        -------
        ranges : ndarray of float32, shape (num_beams,)
        hit_index : ndarray of int64, shape (num_beams,)
            -1 where the beam reads ``+inf``.
        """
        p = self.params
        n = p.num_beams
        inc = p.angle_increment_rad
        ox, oy = self.origin(pose)
        yaw = float(pose[2])
        a0 = yaw + p.angle_min_rad
        rmax = p.range_max_m
        # ---- candidate (primitive, beam) pairs from the angular extents
        spans = [sp for sp in (self._segment_spans(ox, oy, a0), self._circle_spans(ox, oy, a0))
                 if sp is not None]
        ranges = np.full(n, np.inf)
        hit = np.full(n, -1, np.int64)
        if spans:
            k0, cnt, idx, is_circ = (np.concatenate(col) for col in zip(*spans))
            total = int(cnt.sum())
            starts = np.cumsum(cnt) - cnt
            owner = np.repeat(np.arange(cnt.size), cnt)
            beam = (np.repeat(k0, cnt) + np.arange(total) - starts[owner]) % n
            ang = a0 + beam * inc
            dx, dy = np.cos(ang), np.sin(ang)
            t = np.full(total, np.inf)
            prim = np.empty(total, np.int64)
            seg_pairs = ~is_circ[owner]
            if seg_pairs.any():
                sel = np.flatnonzero(seg_pairs)
                t[sel], prim[sel] = self._segment_hits(idx[owner[sel]], dx[sel], dy[sel], ox, oy)
            if (~seg_pairs).any():
                sel = np.flatnonzero(~seg_pairs)
                t[sel], prim[sel] = self._circle_hits(idx[owner[sel]], dx[sel], dy[sel], ox, oy)
            np.minimum.at(ranges, beam, t)
            win = np.isfinite(t) & (t == ranges[beam])
            hit[beam[win]] = prim[win]
        if p.noise_std_m > 0 and rng is not None:
            fin = np.isfinite(ranges)
            ranges[fin] = np.maximum(ranges[fin] + rng.normal(0.0, p.noise_std_m, int(fin.sum())),
                                     0.0)
        too_close = ranges < p.range_min_m
        beyond = ranges > rmax
        ranges[too_close] = -np.inf
        ranges[beyond] = np.inf
        hit[beyond] = -1
        return ranges.astype(np.float32), hit
