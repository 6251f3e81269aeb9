"""The simulator's pose-graph least squares (:mod:`sim_bridge.pose_graph`)."""

import numpy as np
import pytest
from scipy.optimize import least_squares

from explore_seg.core.pose_fusion import compose, inverse
from sim_bridge.pose_graph import Edges, _jacobian, optimise, residuals


def _compose(a, b):
    return np.array(compose(tuple(a), tuple(b)))


def _relative(a, b):
    """The pose ``b`` in the frame of ``a``."""
    return np.array(compose(inverse(tuple(a)), tuple(b)))


def _graph(seed: int, n: int = 30, loops: int = 4):
    """A random walk (true poses), odometry with noise, a few exact loop edges, and the
    dead-reckoned poses as the start."""
    rng = np.random.default_rng(seed)
    truth = [np.zeros(3)]
    for _ in range(n - 1):
        truth.append(_compose(truth[-1], [rng.uniform(0.3, 0.6), 0.0, rng.normal(0, 0.4)]))
    i, j, z, sig = [], [], [], []
    for k in range(1, n):
        i.append(k - 1), j.append(k)
        z.append(_relative(truth[k - 1], truth[k]) + rng.normal(0, [0.03, 0.03, 0.02]))
        sig.append([0.03, 0.02])
    for _ in range(loops):
        a, b = sorted(rng.choice(n, 2, replace=False))
        i.append(a), j.append(b), z.append(_relative(truth[a], truth[b]))
        sig.append([0.005, 0.002])
    edges = Edges(np.array(i), np.array(j), np.array(z), np.array(sig, dtype=float))
    start = [np.zeros(3)]
    for k in range(n - 1):
        start.append(_compose(start[-1], z[k]))
    return np.array(truth), np.array(start), edges


def test_jacobian_matches_finite_differences():
    _, start, edges = _graph(0, n=8, loops=2)
    jac = _jacobian(start, edges).toarray()
    w = np.repeat(1.0 / edges.sigma, [2, 1], axis=1).ravel()
    eps = 1e-6
    for col in range(start.size):
        d = np.zeros(start.size)
        d[col] = eps
        hi = residuals(start + d.reshape(-1, 3), edges).ravel() * w
        lo = residuals(start - d.reshape(-1, 3), edges).ravel() * w
        assert jac[:, col] == pytest.approx((hi - lo) / (2 * eps), abs=1e-4)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_minimum_agrees_with_scipy_least_squares(seed):
    """An independent solver (dense Levenberg-Marquardt) on the same cost finds the same
    poses, at a cost below the dead-reckoned start's and the truth's."""
    truth, start, edges = _graph(seed)
    w = np.repeat(1.0 / edges.sigma, [2, 1], axis=1).ravel()

    def cost(v):
        return residuals(np.vstack([start[:1], v.reshape(-1, 3)]), edges).ravel() * w

    ref = least_squares(cost, start[1:].ravel(), method="lm", xtol=1e-12, ftol=1e-12)
    got = optimise(start, edges, fixed=0)
    assert got[0] == pytest.approx(start[0])
    assert got[1:, :2] == pytest.approx(ref.x.reshape(-1, 3)[:, :2], abs=1e-5)
    dyaw = (got[1:, 2] - ref.x.reshape(-1, 3)[:, 2] + np.pi) % (2 * np.pi) - np.pi
    assert np.abs(dyaw).max() < 1e-5
    def total(p):
        return float(((residuals(p, edges).ravel() * w) ** 2).sum())

    assert total(got) < min(total(start), total(truth))


def test_consistent_measurements_leave_the_poses_and_the_fixed_node_stays():
    truth, _, edges = _graph(4)
    exact = Edges(edges.i, edges.j,
                  np.array([_relative(truth[a], truth[b]) for a, b in zip(edges.i, edges.j)]),
                  edges.sigma)
    assert optimise(truth, exact) == pytest.approx(truth, abs=1e-9)
    moved = truth + [0.5, -0.2, 0.0]   # the graph shifted rigidly; node 5 held
    got = optimise(moved, exact, fixed=5)
    assert got == pytest.approx(moved, abs=1e-9)


def test_error_spreads_by_variance():
    """A 1 m chain of two edges closed by a stiff edge that says 0.9 m: the edge with four
    times the variance takes four fifths of the 0.1 m."""
    poses = np.array([[0.0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]])
    z = np.array([[0.5, 0, 0], [0.5, 0, 0], [0.9, 0, 0]])
    sig = np.array([[0.01, 1e-3], [0.02, 1e-3], [1e-4, 1e-4]])
    got = optimise(poses, Edges(np.array([0, 1, 0]), np.array([1, 2, 2]), z, sig))
    assert got[2, 0] == pytest.approx(0.9, abs=1e-4)
    assert got[1, 0] == pytest.approx(0.5 - 0.02, abs=1e-4)


def test_bad_input_is_refused():
    e = Edges(np.array([0]), np.array([1]), np.zeros((1, 3)), np.ones((1, 2)))
    with pytest.raises(ValueError, match="shape"):
        optimise(np.zeros((2, 2)), e)
    with pytest.raises(ValueError, match="finite"):
        optimise(np.array([[0.0, 0, 0], [np.nan, 0, 0]]), e)
    with pytest.raises(ValueError, match="fixed node"):
        optimise(np.zeros((2, 3)), e, fixed=2)
    with pytest.raises(ValueError, match="expected"):
        Edges(np.array([0]), np.array([1, 2]), np.zeros((1, 3)), np.ones((1, 2)))
    with pytest.raises(ValueError, match="> 0"):
        Edges(np.array([0]), np.array([1]), np.zeros((1, 3)), np.zeros((1, 2)))
    # No edges, one node: nothing to solve.
    empty = Edges(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)),
                  np.zeros((0, 2)))
    assert optimise(np.ones((3, 3)), empty) == pytest.approx(np.ones((3, 3)))
