"""Parameters of the RRT frontier detectors and their filter (``rrt.*`` of the
``target_selector``), the ``rrt_exploration`` baseline's detection side.

The assigner's weights (``info_multiplier``, ``hysteresis_radius_m``,
``hysteresis_gain``) are selection parameters
(:class:`~explore_seg.core.selection.SelectionParams`), next to the other strategies'.
Names follow rrt_exploration's ROS parameters (``eta``, ``info_radius``, the filter's
``bandwith_cluster``), with the unit suffix of this package.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from explore_seg.core.fields import INT_MAX, param_meta

_INF = math.inf


@dataclass(frozen=True)
class RrtParams:
    """Parameters of :class:`~explore_seg.core.rrt.RrtFrontierDetector`."""

    global_eta_m: float = field(default=15.0, metadata=param_meta(
        "global RRT (rooted at the start, never reset): longest edge (rrt_exploration's "
        "global detector eta, 15 m in its single-robot launch file)", "m",
        range=(0.0, _INF)))
    local_eta_m: float = field(default=1.0, metadata=param_meta(
        "local RRT (re-rooted at the robot after every frontier point it finds): longest "
        "edge (rrt_exploration's local detector eta)", "m", range=(0.0, _INF)))
    iterations_per_step: int = field(default=100, metadata=param_meta(
        "extensions of each tree per decision (rrt_exploration's detectors run at 100 Hz; "
        "the decision rate_hz is 1)", range=(1, INT_MAX)))
    info_radius_m: float = field(default=1.0, metadata=param_meta(
        "information gain of a frontier point: the unknown area within this radius",
        "m", range=(0.0, _INF)))
    cluster_bandwidth_m: float = field(default=0.3, metadata=param_meta(
        "mean-shift bandwidth merging frontier points (rrt_exploration's filter)", "m",
        range=(0.0, _INF)))
    min_info_gain_m2: float = field(default=0.2, metadata=param_meta(
        "cluster centres with less unknown area within info_radius_m / 2 are dropped "
        "(the filter's explored-point test)", "m^2", range=(0.0, _INF)))
    seed: int = field(default=0, metadata=param_meta(
        "seed of the trees' random samples (same seed and maps, same frontier points)",
        range=(0, INT_MAX)))

    def __post_init__(self) -> None:
        for name in ("global_eta_m", "local_eta_m", "info_radius_m", "cluster_bandwidth_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        if not (math.isfinite(self.min_info_gain_m2) and self.min_info_gain_m2 >= 0):
            raise ValueError(f"min_info_gain_m2 must be finite and >= 0, "
                             f"got {self.min_info_gain_m2}")
        if not 1 <= self.iterations_per_step <= INT_MAX:
            raise ValueError(f"iterations_per_step must be in 1..{INT_MAX}, "
                             f"got {self.iterations_per_step}")
        if not 0 <= self.seed <= INT_MAX:
            raise ValueError(f"seed must be in 0..{INT_MAX}, got {self.seed}")
