"""Least-squares optimisation of a 2D pose graph (ROS-free), as a SLAM back end does.

slam_toolbox keeps every keyframe as a node (x, y, yaw) and every odometry / scan-match
step and every loop closure as an edge (a measured relative pose with its uncertainty),
and at each closure re-solves the whole graph (sparse pose adjustment, Ceres). The
simulator's mapping error model (:mod:`sim_bridge.slam_error`) does the same with
:func:`optimise`: Gauss-Newton on the weighted squared edge errors, one node held fixed.

Each step solves the sparse normal equations with SuperLU (``scipy.sparse.linalg.spsolve``).
``scipy.optimize.least_squares`` takes sparse Jacobians only with its iterative ``lsmr``
trust-region solver; on random-walk graphs with loops (``test/test_sim_pose_graph.py``'s
``_graph``) it took 9.1 CPU s for 100 nodes and 291 s for 400 (119,700 evaluations) and
stopped short of the minimum (cost 55.7 against 53.6, poses up to 1.7 m apart), where this
Gauss-Newton iteration took 0.006 and 0.025 s: hence the few lines around a library solve.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from explore_seg.core.angles import wrap_angles

#: Gauss-Newton stops when no pose moves more than this (m or rad) in one step.
_CONVERGED = 1e-7


@dataclass(frozen=True)
class Edges:
    """The graph's edges, one row each: the measured pose of node ``j`` in the frame of
    node ``i`` (``z``: dx, dy, dyaw) and its standard deviations (``sigma``: x and y share
    one, then yaw)."""

    i: npt.NDArray[np.int64]
    j: npt.NDArray[np.int64]
    z: npt.NDArray[np.float64]       # (m, 3)
    sigma: npt.NDArray[np.float64]   # (m, 2)

    def __post_init__(self) -> None:
        m = self.i.shape[0]
        if self.j.shape != (m,) or self.z.shape != (m, 3) or self.sigma.shape != (m, 2):
            raise ValueError(f"edges: i {self.i.shape}, j {self.j.shape}, z {self.z.shape},"
                             f" sigma {self.sigma.shape}; expected (m,), (m,), (m, 3), (m, 2)")
        if m and not np.all(np.isfinite(self.sigma) & (self.sigma > 0)):
            raise ValueError("edge standard deviations must be finite and > 0")


def residuals(poses: npt.NDArray[np.float64], edges: Edges) -> npt.NDArray[np.float64]:
    """The edges' errors (predicted minus measured relative pose, yaw wrapped), ``(m, 3)``,
    unweighted."""
    pi, pj = poses[edges.i], poses[edges.j]
    c, s = np.cos(pi[:, 2]), np.sin(pi[:, 2])
    dx, dy = pj[:, 0] - pi[:, 0], pj[:, 1] - pi[:, 1]
    return np.column_stack((c * dx + s * dy - edges.z[:, 0],
                            -s * dx + c * dy - edges.z[:, 1],
                            wrap_angles(pj[:, 2] - pi[:, 2] - edges.z[:, 2])))


def _jacobian(poses: npt.NDArray[np.float64], edges: Edges) -> sp.csr_matrix:
    """d residuals / d poses, ``(3m, 3n)``, each row scaled by its edge's 1 / sigma."""
    m, n = edges.i.shape[0], poses.shape[0]
    pi, pj = poses[edges.i], poses[edges.j]
    c, s = np.cos(pi[:, 2]), np.sin(pi[:, 2])
    dx, dy = pj[:, 0] - pi[:, 0], pj[:, 1] - pi[:, 1]
    wxy, wyaw = 1.0 / edges.sigma[:, 0], 1.0 / edges.sigma[:, 1]
    one = np.ones(m)
    # Rows r = 3e + k (k: x, y, yaw residual); columns 3i + l, 3j + l.
    rows: list[npt.NDArray[np.int64]] = []
    cols: list[npt.NDArray[np.int64]] = []
    vals: list[npt.NDArray[np.float64]] = []

    entries = (  # (residual, node, pose component, derivative, weight)
        (0, edges.i, 0, -c, wxy), (0, edges.i, 1, -s, wxy),
        (0, edges.i, 2, -s * dx + c * dy, wxy),
        (1, edges.i, 0, s, wxy), (1, edges.i, 1, -c, wxy),
        (1, edges.i, 2, -c * dx - s * dy, wxy),
        (0, edges.j, 0, c, wxy), (0, edges.j, 1, s, wxy),
        (1, edges.j, 0, -s, wxy), (1, edges.j, 1, c, wxy),
        (2, edges.i, 2, -one, wyaw), (2, edges.j, 2, one, wyaw))
    for k, node, comp, v, w in entries:
        rows.append(3 * np.arange(m) + k)
        cols.append(3 * node + comp)
        vals.append(v * w)
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(3 * m, 3 * n))


def optimise(poses: npt.NDArray[np.float64], edges: Edges, fixed: int = 0,
             max_iterations: int = 20) -> npt.NDArray[np.float64]:
    """The poses ``(n, 3)`` (x, y, yaw) that minimise the edges' weighted squared errors,
    node ``fixed`` held where it is, starting from ``poses``; yaw wrapped to [-pi, pi).

    Examples
    --------
    Three sides of a square measured by odometry (the last one 0.1 m short) and an edge
    from the start to the last corner, stiffer than the odometry: the 0.1 m of error
    spreads evenly over the three sides (equal sigmas), the last corner comes home.

    >>> p = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0.1, 1, 0]])
    >>> z = np.array([[1.0, 0, 0], [0, 1, 0], [-0.9, 0, 0], [0, 1, 0]])
    >>> e = Edges(np.array([0, 1, 2, 0]), np.array([1, 2, 3, 3]), z,
    ...           np.array([[0.1, 0.01]] * 3 + [[0.01, 0.01]]))
    >>> np.round(optimise(p, e)[:, 0], 3)
    array([0.   , 0.967, 0.933, 0.   ])
    """
    x = np.array(poses, dtype=np.float64)
    n = x.shape[0]
    if x.shape != (n, 3) or not np.all(np.isfinite(x)):
        raise ValueError(f"poses must be finite with shape (n, 3), got {x.shape}")
    if not 0 <= fixed < n:
        raise ValueError(f"fixed node {fixed} outside 0..{n - 1}")
    if edges.i.size == 0 or n == 1:
        return x
    free = np.ones(3 * n, dtype=bool)
    free[3 * fixed:3 * fixed + 3] = False
    w = np.repeat(1.0 / edges.sigma, [2, 1], axis=1).ravel()
    for _ in range(max_iterations):
        jac = _jacobian(x, edges)[:, free]
        r = residuals(x, edges).ravel() * w
        h = (jac.T @ jac).tocsc()
        # A tiny damping keeps nodes that no edge constrains (a graph in pieces) solvable.
        h = h + sp.identity(h.shape[0], format="csc") * 1e-9
        step = np.zeros(3 * n)
        step[free] = -spla.spsolve(h, jac.T @ r)
        x += step.reshape(n, 3)
        if np.max(np.abs(step)) < _CONVERGED:
            break
    x[:, 2] = wrap_angles(x[:, 2])
    return x
