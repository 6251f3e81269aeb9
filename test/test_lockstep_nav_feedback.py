"""Lock step with nav_feedback: the stand-in's outcomes reach the decision core."""

from __future__ import annotations

import pytest

from sim_bridge.engine import SimParams
from sim_bridge.lockstep import LockstepParams, run_exploration
from sim_bridge.worlds import default_world


@pytest.mark.parametrize("feedback", [True, False])
def test_aborted_goals_are_blacklisted_at_once_only_with_feedback(feedback):
    # The stand-in aborts every goal after 3 s (nav_goal_timeout_s): with feedback each is
    # blacklisted at the next decision; without, only after progress_timeout_s (30 s), which
    # cannot pass within the run's 28 s.
    w = default_world("small_house")
    res = run_exploration(w, "nearest", 1, params=LockstepParams(nav_feedback=feedback,
                                                               max_sim_time_s=28.0),
                          sim_params=SimParams(nav_goal_timeout_s=3.0, compute_coverage=False))
    assert res.nav_aborts >= 1
    if feedback:   # every abort blacklisted its goal at the next decision
        assert res.nav_aborts >= 3 and res.goals_blacklisted >= res.nav_aborts
    else:          # the robot stood still after the abort, no 30 s passed without progress
        assert res.goals_blacklisted == 0
