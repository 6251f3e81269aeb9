"""Parameters of the navigation stand-in (planner and controller)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from explore_seg.core.fields import param_meta
from explore_seg.core.grid import OCCUPIED_THRESHOLD


@dataclass(frozen=True)
class NavParams:
    """Planner and controller parameters (defaults follow a TurtleBot3 waffle + Nav2)."""

    robot_radius_m: float = field(default=0.22, metadata=param_meta(
        "radius of the robot's collision disk", "m", range=(0.0, math.inf)))
    inflation_margin_m: float = field(default=0.0, metadata=param_meta(
        "clearance beyond the radius every plan keeps (lethal zone = radius + this)",
        "m", range=(0.0, math.inf)))
    inflation_soft_margin_m: float = field(default=0.05, metadata=param_meta(
        "cells within the lethal zone + this cost inflation_soft_margin_cost more per metre "
        "(Nav2's near-lethal band): paths keep this clearance where the room allows and "
        "still pass doors too narrow for it; raising it keeps plans further from furniture "
        "and walls; 0 = off", "m", range=(0.0, math.inf)))
    inflation_soft_margin_cost: float = field(default=20.0, metadata=param_meta(
        "extra cost per metre inside inflation_soft_margin_m", range=(0.0, math.inf)))
    inflation_edge_cost: float = field(default=50.0, metadata=param_meta(
        "extra cost per metre through cells outside the lethal zone from which the robot's "
        "disk would overlap an obstacle cell (the lethal zone is judged at cell centres, "
        "up to half a cell diagonal closer than the cells' edges): paths avoid them where "
        "another way exists and still pass where none does; 0 = off", range=(0.0, math.inf)))
    inflation_radius_m: float = field(default=0.6, metadata=param_meta(
        "obstacle cost decays to zero at this distance (Nav2 inflation_radius)",
        "m", range=(0.0, math.inf)))
    inflation_cost_weight: float = field(default=3.0, metadata=param_meta(
        "extra cost per metre at the edge of the lethal zone", range=(0.0, math.inf)))
    inflation_cost_scale: float = field(default=6.0, metadata=param_meta(
        "exponential decay rate of the inflation cost (Nav2 cost_scaling_factor)",
        "1/m", range=(0.0, math.inf)))
    allow_unknown: bool = field(default=True, metadata=param_meta(
        "plan through unknown cells (Nav2 planner allow_unknown)"))
    unknown_cost: float = field(default=4.0, metadata=param_meta(
        "extra cost per metre through unknown cells (NavFn: near-lethal)", range=(0.0, math.inf)))
    occupied_threshold: int = field(default=OCCUPIED_THRESHOLD, metadata=param_meta(
        "map/layer cells at or above this value are obstacles", "%", range=(1, 100)))
    planner_goal_tolerance_m: float = field(default=0.5, metadata=param_meta(
        "a blocked goal is replaced by the nearest free cell within this",
        "m", range=(0.0, math.inf)))
    plan_downsample: int = field(default=1, metadata=param_meta(
        "plan on cells this many times coarser (1 = map resolution)", range=(1, 8)))
    plan_window_margin_m: float = field(default=3.0, metadata=param_meta(
        "first search window: path costs up to 1.5 x straight line + this",
        "m", range=(0.0, math.inf)))
    controller_rate_hz: float = field(default=20.0, metadata=param_meta(
        "the path follower computes a new command this often, the last one held in between "
        "(Nav2 controller_frequency); 0 = at every call of control()", "Hz",
        range=(0.0, math.inf)))
    replan_period_s: float = field(default=1.0, metadata=param_meta(
        "replan when the map changed, at most this often (sim time)", "s", range=(0.0, math.inf)))
    switch_cost_ratio: float = field(default=0.8, metadata=param_meta(
        "a replan replaces a still-valid plan only when cheaper than this x its cost",
        range=(0.0, 1.0)))
    blocked_check_period_s: float = field(default=0.2, metadata=param_meta(
        "how often the rest of the plan is checked against new obstacles",
        "s", range=(0.0, math.inf)))
    goal_tolerance_xy_m: float = field(default=0.25, metadata=param_meta(
        "goal reached within this distance (Nav2 xy_goal_tolerance)", "m", range=(0.0, math.inf)))
    goal_tolerance_yaw_rad: float = field(default=0.25, metadata=param_meta(
        "final heading tolerance (Nav2 yaw_goal_tolerance)", "rad", range=(0.0, math.inf)))
    lookahead_m: float = field(default=0.4, metadata=param_meta(
        "pure-pursuit lookahead distance", "m", range=(0.0, math.inf)))
    max_linear_speed_mps: float = field(default=0.26, metadata=param_meta(
        "forward speed limit (TurtleBot3 waffle)", "m/s", range=(0.0, math.inf)))
    max_angular_speed_radps: float = field(default=1.82, metadata=param_meta(
        "turn rate limit (TurtleBot3 waffle)", "rad/s", range=(0.0, math.inf)))
    rotate_in_place_angle_rad: float = field(default=0.8, metadata=param_meta(
        "turn on the spot first when the carrot is further off the heading",
        "rad", range=(0.0, math.pi)))
    heading_gain: float = field(default=2.5, metadata=param_meta(
        "turn rate per rad of heading error when rotating on the spot",
        "1/s", range=(0.0, math.inf)))
    arc_check_edges: bool = field(default=True, metadata=param_meta(
        "the pure-pursuit arc also keeps arc_clearance_m beyond the robot radius from the "
        "edges of obstacle cells (the lethal zone is judged at cell centres, half a cell "
        "diagonal closer); an arc that cannot is shortened toward the plan, and one that "
        "starts closer than that only may not get closer still; false = the lethal zone "
        "only"))
    arc_clearance_m: float = field(default=0.02, metadata=param_meta(
        "clearance beyond the robot radius the arc keeps with arc_check_edges", "m",
        range=(0.0, math.inf)))
    approach_gain: float = field(default=1.0, metadata=param_meta(
        "speed per metre of remaining distance near the goal", "1/s", range=(0.0, math.inf)))
    min_approach_speed_mps: float = field(default=0.05, metadata=param_meta(
        "speed floor while approaching the goal", "m/s", range=(0.0, math.inf)))
    progress_radius_m: float = field(default=0.5, metadata=param_meta(
        "must move this far within progress_timeout_s (Nav2 progress checker)",
        "m", range=(0.0, math.inf)))
    progress_timeout_s: float = field(default=10.0, metadata=param_meta(
        "abort when no progress for this long (0 = off)", "s", range=(0.0, math.inf)))
    goal_timeout_s: float = field(default=600.0, metadata=param_meta(
        "abort a goal after this much sim time (0 = off)", "s", range=(0.0, math.inf)))
    collision_retries: int = field(default=2, metadata=param_meta(
        "after a collision (and the engine's back-up) replan and go on, this many times per "
        "goal, before aborting it (Nav2's navigate_to_pose tree retries its planner/controller "
        "after recoveries); 0 = abort at the first", range=(0, 2**31 - 1)))

    def __post_init__(self) -> None:
        positive = ("robot_radius_m", "lookahead_m", "max_linear_speed_mps",
                    "max_angular_speed_radps", "goal_tolerance_xy_m", "goal_tolerance_yaw_rad",
                    "replan_period_s", "blocked_check_period_s", "heading_gain",
                    "approach_gain", "progress_radius_m", "inflation_cost_scale")
        for name in positive:
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v}")
        non_negative = ("inflation_margin_m", "inflation_cost_weight", "unknown_cost",
                        "inflation_soft_margin_m", "inflation_soft_margin_cost", "arc_clearance_m",
                        "inflation_edge_cost",
                        "planner_goal_tolerance_m", "plan_window_margin_m",
                        "progress_timeout_s", "goal_timeout_s", "min_approach_speed_mps",
                        "controller_rate_hz")
        for name in non_negative:
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {v}")
        if not self.inflation_radius_m >= self.robot_radius_m + self.inflation_margin_m:
            raise ValueError(
                f"inflation_radius_m ({self.inflation_radius_m}) must be >= robot_radius_m + "
                f"inflation_margin_m ({self.robot_radius_m + self.inflation_margin_m})")
        if not 0 < self.switch_cost_ratio <= 1:
            raise ValueError(f"switch_cost_ratio must be in (0, 1], got {self.switch_cost_ratio}")
        if not 0 < self.rotate_in_place_angle_rad <= math.pi:
            raise ValueError(f"rotate_in_place_angle_rad must be in (0, pi], got "
                             f"{self.rotate_in_place_angle_rad}")
        if not 1 <= self.occupied_threshold <= 100:
            raise ValueError(f"occupied_threshold must be in 1..100, got {self.occupied_threshold}")
        if not 1 <= self.plan_downsample <= 8:
            raise ValueError(f"plan_downsample must be in 1..8, got {self.plan_downsample}")
        if not self.collision_retries >= 0:
            raise ValueError(f"collision_retries must be >= 0, got {self.collision_retries}")

    @property
    def lethal_radius_m(self) -> float:
        """Cells closer than this to an obstacle are never planned through."""
        return self.robot_radius_m + self.inflation_margin_m

