"""GoalStatusTracker (attribution of action goals) and the stand-in's GoalBook."""

from __future__ import annotations

import pytest

from explore_seg.core.selection import NavOutcome
from explore_seg.core.selection.nav_status import (STATUS_ABORTED, STATUS_ACCEPTED,
                                                   STATUS_CANCELED, STATUS_EXECUTING,
                                                   STATUS_SUCCEEDED, GoalStatusTracker,
                                                   StatusEntry)
from sim_bridge.navigation import GoalBook, NavState, NavStatus, OutcomeFollower

OLD, MINE, OTHER = b"o" * 16, b"m" * 16, b"x" * 16


def _outcomes(events):
    return [(e.outcome, e.goal_xy_m) for e in events if e.kind == "outcome"]


@pytest.mark.parametrize("status,outcome", [(STATUS_SUCCEEDED, NavOutcome.SUCCEEDED),
                                            (STATUS_ABORTED, NavOutcome.ABORTED),
                                            (STATUS_CANCELED, NavOutcome.CANCELED)])
def test_newest_new_goal_after_our_publish_is_ours_and_ends_once(status, outcome):
    t = GoalStatusTracker(2.0)
    t.update([StatusEntry(OLD, STATUS_EXECUTING, 1.0)], 1.0)     # before our publish
    t.goal_sent(5.0, (1.0, 2.0))
    ev = t.update([StatusEntry(OLD, STATUS_ABORTED, 1.0),         # preempted old goal
                   StatusEntry(MINE, STATUS_ACCEPTED, 5.01)], 5.02)
    assert [e.kind for e in ev] == ["accepted"] and t.goal_id == MINE
    assert _outcomes(t.update([StatusEntry(MINE, status, 5.01)], 6.0)) == [(outcome, (1.0, 2.0))]
    assert t.update([StatusEntry(MINE, status, 5.01)], 6.5) == []   # repeated array: once
    assert not t.active


def test_our_cancel_is_reported_as_ours():
    t = GoalStatusTracker(2.0)
    t.goal_sent(0.0, (1.0, 2.0))
    t.update([StatusEntry(MINE, STATUS_EXECUTING, 0.0)], 0.1)
    t.cancel_requested()
    assert _outcomes(t.update([StatusEntry(MINE, STATUS_CANCELED, 0.0)], 0.2)) == [
        (NavOutcome.CANCELED_BY_US, (1.0, 2.0))]


def test_republish_moves_attribution_to_the_new_goal():
    t = GoalStatusTracker(2.0)
    t.goal_sent(0.0, (1.0, 2.0))
    t.update([StatusEntry(MINE, STATUS_EXECUTING, 0.0)], 0.1)
    t.goal_sent(1.0, (1.0, 2.0))
    ev = t.update([StatusEntry(MINE, STATUS_ABORTED, 0.0),
                   StatusEntry(OTHER, STATUS_EXECUTING, 1.0)], 1.1)
    assert _outcomes(ev) == [] and t.goal_id == OTHER


def test_goal_never_accepted_is_rejected_only_while_a_status_publisher_exists():
    t = GoalStatusTracker(2.0)
    t.goal_sent(10.0, (1.0, 2.0))
    assert t.check_timeout(20.0, publisher_present=False) is None   # fallback: progress
    assert t.check_timeout(11.0, publisher_present=True) is None
    assert t.check_timeout(5.0, publisher_present=True) is None     # clock reset: restart
    assert t.check_timeout(6.9, publisher_present=True) is None
    ev = t.check_timeout(7.1, publisher_present=True)
    assert ev.outcome is NavOutcome.REJECTED and ev.goal_xy_m == (1.0, 2.0)
    assert not t.active


def test_bad_entries_are_reported_and_skipped():
    t = GoalStatusTracker(2.0)
    t.goal_sent(0.0, (1.0, 2.0))
    ev = t.update([StatusEntry(b"short", STATUS_EXECUTING, 0.0),
                   StatusEntry(OTHER, 42, 0.0),
                   StatusEntry(MINE, STATUS_EXECUTING, 0.0)], 0.1)
    assert [e.kind for e in ev] == ["ignored", "ignored", "accepted"]
    assert "expected 16 bytes" in ev[0].message and "not a GoalStatus code" in ev[1].message
    assert t.goal_id == MINE


def test_an_old_finished_goal_first_seen_after_our_publish_is_not_ours():
    t = GoalStatusTracker(2.0)
    t.goal_sent(100.0, (1.0, 2.0))
    assert t.update([StatusEntry(OLD, STATUS_SUCCEEDED, 50.0)], 100.1) == []
    assert t.goal_id is None


def test_statuses_for_goals_we_never_sent_change_nothing():
    t = GoalStatusTracker(2.0)
    assert t.update([StatusEntry(OTHER, STATUS_ABORTED, 0.0)], 0.0) == []
    assert t.goal_id is None and not t.active


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan")])
def test_accept_timeout_must_be_positive(value):
    with pytest.raises(ValueError, match="accept_timeout_s must be finite and > 0"):
        GoalStatusTracker(value)


def test_goal_book_follows_the_navigator_and_aborts_a_preempted_goal():
    b = GoalBook(keep=2)
    g1 = b.accept(1.0)
    assert b.follow(NavState.ACTIVE) and not b.follow(NavState.ACTIVE)
    g2 = b.accept(2.0)
    assert [(e.goal_id, e.status) for e in b.entries()] == [(g1, STATUS_ABORTED),
                                                             (g2, STATUS_ACCEPTED)]
    assert b.cancel_targets(bytes(16), 0.0) == [g2]
    assert b.cancel_targets(bytes(16), 1.5) == []
    assert b.cancel_targets(g1, 0.0) == []
    assert b.follow(NavState.SUCCEEDED) and not b.follow(NavState.ABORTED)
    b.accept(3.0)
    assert len(b.entries()) == 2 and not b.known(g1)


def test_outcome_follower_reports_the_goal_sent_once():
    f = OutcomeFollower()
    assert f.poll(NavStatus(NavState.ABORTED, "x", (1.0, 2.0, 0.0))) is None   # none sent
    f.sent((1.0, 2.0))
    assert f.poll(NavStatus(NavState.ACTIVE, "", (1.0, 2.0, 0.0))) is None
    assert f.poll(NavStatus(NavState.ABORTED, "x", (3.0, 2.0, 0.0))) is None   # another goal
    assert f.poll(NavStatus(NavState.ABORTED, "x", (1.0, 2.0, 0.0))) == (
        NavOutcome.ABORTED, (1.0, 2.0))
    assert f.poll(NavStatus(NavState.ABORTED, "x", (1.0, 2.0, 0.0))) is None
