"""Simulator engine: collisions, contact counting and the back-off (lock step, no ROS)."""

from __future__ import annotations

import pytest

from sim_bridge.engine import SimEngine, SimParams
from sim_bridge.navigation import NavState
from sim_bridge.world import Primitive
from sim_scenes import FAST, box, chair, cyl, room_world


def desk(x: float, y: float) -> list[Primitive]:
    """Top 0.6 (x) x 1.2 (y) m at 0.72-0.75 m on four 0.05 m legs."""
    legs = [box("desk_1", "table", "leg", x + dx, y + dy, 0.05, 0.05, 0.0, 0.72)
            for dx in (-0.275, 0.275) for dy in (-0.575, 0.575)]
    return legs + [box("desk_1", "table", "top", x, y, 0.6, 1.2, 0.72, 0.75)]


def bench(x: float, y: float) -> list[Primitive]:
    """Seat 0.5 x 1.6 m at 0.42-0.47 m on legs 1.5 m apart: planners see a free lane."""
    legs = [cyl("bench_1", "chair", "leg", x + dx, y + dy, 0.02, 0.0, 0.42)
            for dx in (-0.2, 0.2) for dy in (-0.75, 0.75)]
    return legs + [box("bench_1", "chair", "seat", x, y, 0.5, 1.6, 0.42, 0.47)]


def shelf(x: float, y: float) -> list[Primitive]:
    """A board at 1.5-1.6 m on two posts outside the robot's lane (above robot height)."""
    return [box("shelf_1", "cabinet", "post", x, y - 0.6, 0.05, 0.05, 0.0, 1.6),
            box("shelf_1", "cabinet", "post", x, y + 0.6, 0.05, 0.05, 0.0, 1.6),
            box("shelf_1", "cabinet", "shelf", x, y, 0.4, 1.25, 1.5, 1.6)]


@pytest.mark.parametrize("parts, obj, part, contact_x", [
    (chair(3.0, 2.0), "chair_1", "seat", 3.0 - 0.25 - 0.22),
    (desk(3.0, 2.0), "desk_1", "top", 3.0 - 0.3 - 0.22),
])
def test_driving_into_a_part_above_the_scan_plane_is_one_collision_at_contact(
        parts, obj, part, contact_x):
    eng = SimEngine(room_world(parts), SimParams(**FAST))
    eng.step(0.1)
    # The lidar at 0.17 m sees between the legs: nothing ahead for more than 2 m.
    ahead = eng.latest_scan.ranges[eng.scan_geometry.num_beams // 2]
    assert ahead > 2.0
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(12.0)
    assert eng.metrics.n_collisions == 1
    ev = eng.metrics.collisions[0]
    assert (ev.object, ev.part) == (obj, part)
    step_m = 0.26 * eng.params.physics_dt_s
    assert contact_x - step_m - 1e-6 <= ev.x_m <= contact_x
    assert ev.y_m == pytest.approx(2.0, abs=1e-6)
    # Stopped: the command was zeroed; the robot backed off 0.15 m and stays there.
    x_stop = eng.pose[0]
    assert x_stop == pytest.approx(ev.x_m - 0.15, abs=0.1 * eng.params.physics_dt_s + 1e-6)
    eng.step(2.0)
    assert eng.pose[0] == x_stop and eng.velocity[0] == 0.0


def test_part_above_robot_height_is_no_collision():
    eng = SimEngine(room_world(shelf(3.0, 2.0)), SimParams(**FAST))
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(12.0)
    assert eng.metrics.n_collisions == 0
    assert eng.pose[0] > 3.5


def test_pushing_on_counts_once_and_backing_off_then_again_counts_twice():
    eng = SimEngine(room_world([]), SimParams(collision_backup_m=0.0, **FAST))
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(25.0)
    assert eng.metrics.n_collisions == 1
    assert eng.pose[0] == pytest.approx(6.0 - 0.22, abs=0.26 * 0.02 + 1e-6)
    eng.set_cmd_vel(0.26, 0.0)        # pushes again while touching: same contact
    eng.step(2.0)
    assert eng.metrics.n_collisions == 1 and eng.in_contact
    eng.set_cmd_vel(-0.2, 0.0)
    eng.step(1.0)
    assert not eng.in_contact
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(3.0)
    assert eng.metrics.n_collisions == 2


def test_automatic_back_off_makes_the_next_push_a_new_contact():
    eng = SimEngine(room_world([]), SimParams(collision_backup_m=0.15, **FAST))
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(25.0)
    assert eng.metrics.n_collisions == 1 and not eng.backing_up
    assert eng.pose[0] == pytest.approx(6.0 - 0.22 - 0.15, abs=0.01)
    eng.set_cmd_vel(0.26, 0.0)
    eng.step(3.0)
    assert eng.metrics.n_collisions == 2


@pytest.mark.parametrize("retries", [0, 2])
def test_collision_aborts_the_active_goal_after_the_retries(retries):
    eng = SimEngine(room_world(bench(3.0, 2.0)),
                    SimParams(nav_collision_retries=retries, **FAST))
    eng.step(0.1)
    eng.set_goal(5.0, 2.0, 0.0)       # straight under the seat the lidar cannot see
    eng.run_until(lambda e: e.nav_status.state is not NavState.ACTIVE, 120.0)
    assert eng.nav_status.state is NavState.ABORTED
    assert "collision with bench_1" in eng.nav_status.reason
    # Every retry backs off, replans the same lane and bumps into the seat again.
    assert eng.metrics.n_collisions == retries + 1 and eng.metrics.goals_aborted == 1
    for ev in eng.metrics.collisions:
        assert ev.x_m == pytest.approx(3.0 - 0.25 - 0.22, abs=0.01)


def test_after_a_collision_with_retries_left_the_goal_stays_active_and_is_replanned():
    eng = SimEngine(room_world(bench(3.0, 2.0)), SimParams(nav_collision_retries=1, **FAST))
    eng.step(0.1)
    eng.set_goal(5.0, 2.0, 0.0)
    eng.run_until(lambda e: e.metrics.n_collisions == 1, 60.0)
    plans = eng.navigator.plan_count
    assert eng.nav_status.state is NavState.ACTIVE and eng.backing_up
    eng.run_until(lambda e: not e.backing_up, 10.0)
    eng.step(0.5)
    assert eng.navigator.plan_count > plans              # replanned from the new pose
    assert eng.nav_status.state is NavState.ACTIVE and eng.velocity[0] > 0.0
