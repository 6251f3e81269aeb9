"""wrap_angle: the half-open range [-pi, pi) at both ends, and the value the simulator's
pure pursuit steers by."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explore_seg.core.angles import wrap_angle, wrap_angles
from explore_seg.core.pose_fusion import compose, inverse
from sim_bridge.navigation import wrap_angle as nav_wrap_angle

PI = math.pi


def _modular(a: float) -> float:
    """The modular formula the function is built on, without the upper-end guard."""
    return (a + PI) % (2.0 * PI) - PI


@pytest.mark.parametrize("a, expected", [
    (PI, -PI), (-PI, -PI), (3 * PI, -PI), (-3 * PI, -PI),
    (0.0, 0.0), (0.5 * PI, 0.5 * PI), (-0.5 * PI, -0.5 * PI),
])
def test_both_ends_of_a_half_turn_map_to_minus_pi(a, expected):
    assert wrap_angle(a) == expected


def test_just_inside_either_end_stays_there():
    for a in (PI - 1e-12, -PI + 1e-12, math.nextafter(-PI, 0.0)):
        assert wrap_angle(a) == pytest.approx(a, abs=1e-15)
        assert -PI <= wrap_angle(a) < PI
    # One ulp below pi is pi after the shift by pi (rounding): the lower end as well.
    assert wrap_angle(math.nextafter(PI, 0.0)) == -PI


def test_a_value_that_rounds_up_to_pi_is_minus_pi():
    a = math.nextafter(-PI, -math.inf)          # one ulp beyond -pi
    assert _modular(a) == PI                     # the bare formula leaves the range
    assert wrap_angle(a) == -PI


def test_range_and_equivalence_on_random_angles():
    rng = np.random.default_rng(0)
    for a in rng.uniform(-40.0, 40.0, 20000):
        w = wrap_angle(float(a))
        assert -PI <= w < PI
        turns = (a - w) / (2.0 * PI)
        assert abs(turns - round(turns)) < 1e-12


def test_same_bits_as_the_modular_formula_inside_the_range():
    """The simulator's pursuit and navigator steer by this value; lock-step runs repeat
    bit for bit only if it does not change."""
    rng = np.random.default_rng(1)
    values = np.concatenate([rng.uniform(-2 * PI, 2 * PI, 20000),
                             [PI, -PI, 2 * PI, -2 * PI, 1e-300, -1e-300]])
    for a in values:
        assert wrap_angle(float(a)) == _modular(float(a))


def test_navigation_and_pose_fusion_share_the_function():
    assert nav_wrap_angle is wrap_angle
    # compose / inverse give headings in [-pi, pi): a half turn composed is -pi.
    assert compose((0.0, 0.0, 0.5 * PI), (0.0, 0.0, 0.5 * PI))[2] == -PI
    assert inverse((0.0, 0.0, -PI))[2] == -PI


def test_the_array_form_gives_the_scalar_values():
    rng = np.random.default_rng(2)
    values = np.concatenate([rng.uniform(-40.0, 40.0, 5000),
                             [PI, -PI, 2 * PI, math.nextafter(-PI, -math.inf), 0.0]])
    assert wrap_angles(values).tolist() == [wrap_angle(float(a)) for a in values]
