"""A SLAM-like mapping error model (ROS-free): drift, keyframes, loop closures, re-render.

Without it the simulator maps every scan at the robot's true pose. A real robot's map comes
from slam_toolbox, whose pose estimate drifts between loop closures and whose map is
re-rendered from the optimised pose graph when a loop closes, so the map moves under the
robot. :class:`SlamErrorModel` reproduces that mechanism:

* **Drift**: the estimated pose integrates the true motion between scans with noise, a
  random walk whose variance grows with the distance travelled (position and heading) and
  the angle turned (heading), as odometry + scan matching does. The drift is the map <-
  world transform ``D = estimate o true^-1``; the SLAM pose is ``D o true pose``.
* **Keyframes**: like slam_toolbox (``minimum_travel_distance`` /
  ``minimum_travel_heading``), only a scan taken after ``keyframe_travel_m`` of travel or
  ``keyframe_turn_rad`` of turning since the last keyframe enters the graph and the map.
  Each keyframe is mapped at ``D o sensor pose o jitter`` (per-scan jitter: the scan
  matcher's residual), so walls come out a few centimetres thick and doubled where the
  drift changed between two visits.
* **Pose graph**: the keyframes are its nodes; consecutive keyframes are joined by the
  drifted estimate's relative pose (odometry + scan matching), with the standard
  deviations the drift accumulated between them.
* **Loop closures**: when a new keyframe lies within ``loop_radius_m`` of a keyframe taken
  at least ``loop_min_travel_m`` of travel earlier (and that much travel after the last
  closure), an edge joins the two with their true relative pose (the scan match), with
  the per-keyframe jitter as its standard deviation, and the whole graph is re-solved by
  least squares (:func:`sim_bridge.pose_graph.optimise`, keyframe 0 fixed), as
  slam_toolbox's optimiser does at a closure: the correction spreads over the loop, and
  keyframes mapped before earlier closures move too where a loop passes through them. The
  current drift becomes the new keyframe's. The map is then re-rendered from the
  corrected keyframe poses, unless no keyframe moved by half a cell.

Navigation and collisions stay in the true world; the explorer gets the map and the SLAM
pose. Nothing here draws from the simulator's sensor noise generator, so sensor noise is
the same with the model on or off.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.angles import wrap_angle
from explore_seg.core.fields import check_non_negative, param_meta
from explore_seg.core.grid import GridMap
from explore_seg.core.pose_fusion import Pose2D, compose, inverse
from sim_bridge.mapping import MappingParams, ScanMapper
from sim_bridge.pose_graph import Edges, optimise

#: Below this true displacement between two scans (m, rad) the robot counts as standing
#: still: no drift accumulates.
_STILL_M, _STILL_RAD = 1e-6, 1e-6
#: Smallest standard deviations of a pose-graph edge (m, rad): with zero drift or jitter
#: the optimisation still has finite weights.
_MIN_SIGMA_M, _MIN_SIGMA_RAD = 1e-4, 1e-5


def is_keyframe(last: Pose2D | None, pose: Pose2D, min_travel_m: float,
                min_turn_rad: float) -> bool:
    """slam_toolbox's keyframe rule: a scan taken at ``pose`` enters the pose graph and the
    map when it is the first (``last`` None) or the robot moved at least ``min_travel_m``
    (``minimum_travel_distance``) or turned at least ``min_turn_rad``
    (``minimum_travel_heading``) since the last keyframe, taken at ``last``. With 0 and 0
    every scan is a keyframe.

    The one home of the rule: the mapping error model, the engine's published map and the
    node's SLAM poses use it.

    >>> is_keyframe((0.0, 0.0, 0.0), (0.3, 0.0, 0.0), 0.5, 0.5)
    False
    >>> is_keyframe((0.0, 0.0, 0.0), (0.3, 0.0, 0.6), 0.5, 0.5)
    True
    """
    if last is None:
        return True
    moved = math.hypot(pose[0] - last[0], pose[1] - last[1])
    turned = abs(wrap_angle(pose[2] - last[2]))
    return moved >= min_travel_m or turned >= min_turn_rad


@dataclass(frozen=True)
class SlamErrorParams:
    """Numbers of the mapping error model (see the module docstring)."""

    drift_xy_m: float = field(default=0.02, metadata=param_meta(
        "std of the position random walk after 1 m of travel (grows with the square root "
        "of the distance)", "m"))
    drift_yaw_per_m_rad: float = field(default=0.003, metadata=param_meta(
        "std of the heading random walk after 1 m of travel", "rad"))
    drift_yaw_per_rad: float = field(default=0.005, metadata=param_meta(
        "std of the heading random walk after 1 rad of turning", "rad"))
    jitter_xy_m: float = field(default=0.015, metadata=param_meta(
        "std of the per-keyframe position error (scan matcher residual)", "m"))
    jitter_yaw_rad: float = field(default=0.004, metadata=param_meta(
        "std of the per-keyframe heading error", "rad"))
    keyframe_travel_m: float = field(default=0.5, metadata=param_meta(
        "a scan enters the map after this much travel since the last keyframe "
        "(slam_toolbox minimum_travel_distance)", "m"))
    keyframe_turn_rad: float = field(default=0.5, metadata=param_meta(
        "... or this much turning (slam_toolbox minimum_travel_heading)", "rad"))
    loop_radius_m: float = field(default=3.0, metadata=param_meta(
        "a keyframe closes a loop with an old keyframe within this distance "
        "(slam_toolbox loop_search_maximum_distance)", "m"))
    loop_min_travel_m: float = field(default=10.0, metadata=param_meta(
        "the old keyframe lies at least this much travel back, and the last closure too",
        "m"))

    def __post_init__(self) -> None:
        check_non_negative(self, ("drift_xy_m", "drift_yaw_per_m_rad", "drift_yaw_per_rad",
                                  "jitter_xy_m", "jitter_yaw_rad", "keyframe_travel_m",
                                  "keyframe_turn_rad"))
        for name in ("loop_radius_m", "loop_min_travel_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")


#: ``realistic``: slam_toolbox on a TurtleBot3-class robot in a house. The numbers give
#: about 0.1 m of position error after 10-20 m without a closure, in line with:
#: - "From Simulation to Reality: Comparative Performance Analysis of SLAM Toolbox and
#:   Cartographer in ROS 2", Electronics 14(24) 4822 (2025), ATE 0.13 m for SLAM Toolbox:
#:   https://www.mdpi.com/2079-9292/14/24/4822
#: - slam_toolbox issue #664 "Jumpings in Slamtoolbox output": 5-6 cm pose jumps at
#:   corrections with EKF odometry: https://github.com/SteveMacenski/slam_toolbox/issues/664
#: Keyframe and loop search numbers are slam_toolbox's defaults (0.5 m, 0.5 rad, 3 m);
#: the heading walk is the mechanism's choice (no published per-metre figure found).
REALISTIC = SlamErrorParams()

#: ``harsh``: poor odometry (~2-3 % of distance before scan matching, wheel slip), rare
#: closures (a 1.5 m search radius after 20 m): decimetre-scale doubled walls and map jumps
#: of tens of centimetres, as in slam_toolbox issue #167 "Map making error":
#: https://github.com/SteveMacenski/slam_toolbox/issues/167
HARSH = SlamErrorParams(drift_xy_m=0.05, drift_yaw_per_m_rad=0.01, drift_yaw_per_rad=0.015,
                        jitter_xy_m=0.03, jitter_yaw_rad=0.01, loop_radius_m=1.5,
                        loop_min_travel_m=20.0)

#: Named profiles of ``SimParams.mapping_error`` ("none": no model, "custom": the
#: individual ``mapping_*`` parameters).
PROFILES: dict[str, SlamErrorParams] = {"realistic": REALISTIC, "harsh": HARSH}


@dataclass(frozen=True)
class LoopClosure:
    """One correction: the keyframes it joined, how far the SLAM pose jumped, and whether
    the map was re-rendered."""

    keyframe: int
    matched: int
    shift_m: float
    shift_rad: float
    rerendered: bool
    #: The rigid map-frame transform that took the SLAM pose from before to after it
    #: (``drift after o drift before^-1``).
    jump: Pose2D = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class LidarGeometry:
    """What :meth:`ScanMapper.integrate_scan` needs besides the pose and ranges."""

    angle_min_rad: float
    angle_increment_rad: float
    range_max_m: float
    range_min_m: float


class SlamErrorModel:
    """The erroneous map and SLAM pose of one run (see the module docstring).

    Parameters
    ----------
    params : SlamErrorParams
    center_xy_m : (float, float)
        Where the map starts (the start pose), as for :class:`ScanMapper`.
    mapping : MappingParams
    lidar : LidarGeometry
    seed : int
        Seeds the drift and jitter (its own generator).

    Examples
    --------
    >>> m = SlamErrorModel(SlamErrorParams(), (0.0, 0.0), MappingParams(),
    ...                    LidarGeometry(0.0, 0.1, 3.0, 0.1), seed=0)
    >>> m.estimate((1.0, 2.0, 0.5))           # no motion yet: no drift
    (1.0, 2.0, 0.5)
    """

    def __init__(self, params: SlamErrorParams, center_xy_m: tuple[float, float],
                 mapping: MappingParams, lidar: LidarGeometry, seed: int) -> None:
        self.params = params
        self._center = (float(center_xy_m[0]), float(center_xy_m[1]))
        self._mapping = mapping
        self._lidar = lidar
        self._rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, 0x51A4])
        self._mapper = ScanMapper(self._center, mapping)
        self._version_base = 0
        self._drift: Pose2D = (0.0, 0.0, 0.0)
        self._last_true: Pose2D | None = None
        self._path_m = 0.0
        self._turn_rad = 0.0
        # Keyframes: true base pose, true sensor pose, drift and jitter at capture, ranges,
        # travel and turning at capture.
        self._kf_base: list[Pose2D] = []
        self._kf_sensor: list[Pose2D] = []
        self._kf_drift: list[Pose2D] = []
        self._kf_jitter: list[Pose2D] = []
        self._kf_ranges: list[npt.NDArray[np.float32]] = []
        self._kf_path: list[float] = []
        self._kf_turn: list[float] = []
        # Pose-graph edges: (i, j, measured pose of j in i's frame, (sigma_xy, sigma_yaw)).
        self._edges: list[tuple[int, int, Pose2D, tuple[float, float]]] = []
        self._last_closure_path_m = 0.0
        self.closures: list[LoopClosure] = []

    # ------------------------------------------------------------------ state
    @property
    def drift(self) -> Pose2D:
        """The current map <- world transform (identity: no error)."""
        return self._drift

    @property
    def version(self) -> int:
        """Changes whenever the map changed (a keyframe mapped or a re-render)."""
        return self._version_base + self._mapper.version

    @property
    def n_keyframes(self) -> int:
        """Keyframes in the graph (scans in the map)."""
        return len(self._kf_base)

    @property
    def path_m(self) -> float:
        """True distance travelled, summed scan to scan."""
        return self._path_m

    def estimate(self, true_pose: Pose2D) -> Pose2D:
        """The SLAM pose (map frame) of a true pose: the current drift composed with it."""
        return compose(self._drift, true_pose)

    def keyframe_pose(self, i: int) -> Pose2D:
        """The map-frame sensor pose keyframe ``i`` is mapped at."""
        return compose(compose(self._kf_drift[i], self._kf_sensor[i]), self._kf_jitter[i])

    def grid(self, stamp_ns: int = 0) -> GridMap:
        """The erroneous map."""
        return self._mapper.grid(stamp_ns)

    # ------------------------------------------------------------------ input
    def add_scan(self, true_pose: Pose2D, sensor_pose: Pose2D,
                 ranges: npt.NDArray[np.float32]) -> bool:
        """Advance the drift to ``true_pose`` (base) and, for a keyframe, map the scan
        taken from ``sensor_pose`` (true); True when the map changed.

        Raises
        ------
        ValueError
            On a non-finite pose.
        """
        if not all(math.isfinite(v) for v in (*true_pose, *sensor_pose)):
            raise ValueError(f"poses must be finite, got {true_pose}, {sensor_pose}")
        self._advance_drift(true_pose)
        if not self._is_keyframe(true_pose):
            return False
        p = self.params
        jx, jy, jyaw = self._rng.normal(0.0, 1.0, 3)
        self._kf_base.append(tuple(float(v) for v in true_pose))  # type: ignore[arg-type]
        self._kf_sensor.append(tuple(float(v) for v in sensor_pose))  # type: ignore[arg-type]
        self._kf_drift.append(self._drift)
        self._kf_jitter.append((float(jx) * p.jitter_xy_m, float(jy) * p.jitter_xy_m,
                                float(jyaw) * p.jitter_yaw_rad))
        self._kf_ranges.append(np.array(ranges, dtype=np.float32))
        self._kf_path.append(self._path_m)
        self._kf_turn.append(self._turn_rad)
        k = len(self._kf_base) - 1
        if k > 0:
            self._edges.append(self._odometry_edge(k))
        matched = self._loop_candidate(k)
        if matched is not None and self._close_loop(k, matched):
            return True
        self._integrate(self._mapper, k)
        return True

    def shift(self, correction: Pose2D) -> None:
        """Move the whole pose graph (every keyframe and the current pose) by the rigid
        map-frame transform ``correction`` and re-render: the map and the SLAM pose jump
        together, as when an optimisation re-anchors the graph."""
        self._kf_drift = [compose(correction, d) for d in self._kf_drift]
        self._drift = compose(correction, self._drift)
        self._rerender()

    # --------------------------------------------------------------- internals
    def _advance_drift(self, true_pose: Pose2D) -> None:
        last = self._last_true
        self._last_true = true_pose
        if last is None:
            return
        d = compose(inverse(last), true_pose)
        dist, turn = math.hypot(d[0], d[1]), abs(d[2])
        if dist <= _STILL_M and turn <= _STILL_RAD:
            return
        self._path_m += dist
        self._turn_rad += turn
        p = self.params
        nx, ny, nyaw = self._rng.normal(0.0, 1.0, 3)
        s_xy = p.drift_xy_m * math.sqrt(dist)
        s_yaw = math.sqrt(p.drift_yaw_per_m_rad ** 2 * dist + p.drift_yaw_per_rad ** 2 * turn)
        est = compose(compose(self._drift, last),
                      (d[0] + float(nx) * s_xy, d[1] + float(ny) * s_xy,
                       d[2] + float(nyaw) * s_yaw))
        self._drift = compose(est, inverse(true_pose))

    def _is_keyframe(self, true_pose: Pose2D) -> bool:
        return is_keyframe(self._kf_base[-1] if self._kf_base else None, true_pose,
                           self.params.keyframe_travel_m, self.params.keyframe_turn_rad)

    def _loop_candidate(self, k: int) -> int | None:
        """The nearest old keyframe keyframe ``k`` closes a loop with, or None."""
        p = self.params
        here = self._kf_path[k]
        if here - self._last_closure_path_m < p.loop_min_travel_m:
            return None
        path = np.asarray(self._kf_path[:k])
        old = np.flatnonzero(here - path >= p.loop_min_travel_m)
        if old.size == 0:
            return None
        xy = np.asarray([self._kf_base[i][:2] for i in old])
        d = np.hypot(xy[:, 0] - self._kf_base[k][0], xy[:, 1] - self._kf_base[k][1])
        best = int(np.argmin(d))
        return int(old[best]) if d[best] <= p.loop_radius_m else None

    def _odometry_edge(self, k: int) -> tuple[int, int, Pose2D, tuple[float, float]]:
        """The edge from keyframe ``k - 1`` to ``k``: the drifted estimate's relative pose,
        with the standard deviations of the drift accumulated between them."""
        p = self.params
        prev = compose(self._kf_drift[k - 1], self._kf_base[k - 1])
        z = compose(inverse(prev), compose(self._drift, self._kf_base[k]))
        dist = self._kf_path[k] - self._kf_path[k - 1]
        turn = self._kf_turn[k] - self._kf_turn[k - 1]
        s_xy = max(p.drift_xy_m * math.sqrt(dist), _MIN_SIGMA_M)
        s_yaw = max(math.sqrt(p.drift_yaw_per_m_rad ** 2 * dist
                              + p.drift_yaw_per_rad ** 2 * turn), _MIN_SIGMA_RAD)
        return k - 1, k, z, (s_xy, s_yaw)

    def _close_loop(self, k: int, j: int) -> bool:
        """Join keyframes ``j`` and ``k`` by their true relative pose and re-solve the
        graph; True when the map was re-rendered."""
        p = self.params
        z = compose(inverse(self._kf_base[j]), self._kf_base[k])
        self._edges.append((j, k, z, (max(p.jitter_xy_m, _MIN_SIGMA_M),
                                      max(p.jitter_yaw_rad, _MIN_SIGMA_RAD))))
        n = len(self._kf_base)
        before = [self.keyframe_pose(i) for i in range(n)]
        start = np.asarray([compose(self._kf_drift[i], self._kf_base[i]) for i in range(n)])
        edges = Edges(np.asarray([e[0] for e in self._edges], dtype=np.int64),
                      np.asarray([e[1] for e in self._edges], dtype=np.int64),
                      np.asarray([e[2] for e in self._edges], dtype=np.float64),
                      np.asarray([e[3] for e in self._edges], dtype=np.float64))
        solved = optimise(start, edges, fixed=0)
        self._kf_drift = [compose(tuple(float(v) for v in solved[i]),  # type: ignore[arg-type]
                                  inverse(self._kf_base[i])) for i in range(n)]
        old_pose = self.estimate(self._last_true)  # type: ignore[arg-type]
        old_drift, self._drift = self._drift, self._kf_drift[k]
        new_pose = self.estimate(self._last_true)  # type: ignore[arg-type]
        self._last_closure_path_m = self._kf_path[k]
        # Re-render only when some keyframe's beams moved by half a cell at full range.
        moved = max(math.hypot(a[0] - b[0], a[1] - b[1])
                    + abs(wrap_angle(a[2] - b[2])) * self._lidar.range_max_m
                    for a, b in zip(before, (self.keyframe_pose(i) for i in range(n))))
        rerender = moved > 0.5 * self._mapping.resolution_m
        self.closures.append(LoopClosure(
            k, j, math.hypot(new_pose[0] - old_pose[0], new_pose[1] - old_pose[1]),
            abs(wrap_angle(new_pose[2] - old_pose[2])), rerender,
            compose(self._drift, inverse(old_drift))))
        if rerender:
            self._rerender()
        return rerender

    def _integrate(self, mapper: ScanMapper, i: int) -> None:
        g = self._lidar
        mapper.integrate_scan(self.keyframe_pose(i), self._kf_ranges[i], g.angle_min_rad,
                              g.angle_increment_rad, g.range_max_m, g.range_min_m)

    def _rerender(self) -> None:
        """Rebuild the map from every keyframe at its current pose."""
        self._version_base += self._mapper.version + 1
        mapper = ScanMapper(self._center, self._mapping)
        for i in range(len(self._kf_base)):
            self._integrate(mapper, i)
        self._mapper = mapper
