"""Clearance geometry of the pure-pursuit arc check (:meth:`Navigator._arc_clear`).

The planner's lethal zone is judged at cell centres, half a cell diagonal closer than the
obstacle cells' edges; with ``NavParams.arc_check_edges`` the controller measures the
arc's distance to those edges exactly (:func:`edge_distances`), except where the
inflation cost of the arc's cells already proves them far enough (:func:`edge_safe_cost`).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sim_bridge.navigation.params import NavParams


def arc_points(x: float, y: float, yaw: float, kappa: float, s: npt.NDArray[np.float64]
               ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Points at arc lengths ``s`` along the arc of curvature ``kappa`` from (x, y, yaw)."""
    if abs(kappa) < 1e-9:
        return x + s * math.cos(yaw), y + s * math.sin(yaw)
    return (x + (np.sin(yaw + kappa * s) - math.sin(yaw)) / kappa,
            y - (np.cos(yaw + kappa * s) - math.cos(yaw)) / kappa)


def edge_safe_cost(params: NavParams, res: float) -> float | None:
    """A cost grid value at or below which a cell is far enough from every obstacle cell
    for any point in it to keep ``robot_radius_m + arc_clearance_m`` from their edges
    (None: the inflation cost cannot tell). The inflation band's cost
    ``1 + w exp(-s (d - lethal))`` falls with the centre distance d, and an edge is at most
    a cell diagonal closer than the two centres; soft margin and unknown cells cost more,
    so they are measured exactly."""
    p = params
    d_safe = p.robot_radius_m + p.arc_clearance_m + math.sqrt(2.0) * res
    if p.inflation_cost_weight <= 0 or not d_safe < p.inflation_radius_m:
        return None
    return 1.0 + p.inflation_cost_weight * math.exp(
        -p.inflation_cost_scale * max(d_safe - p.lethal_radius_m, 0.0))


def clearance_window(fr: npt.NDArray[np.float64], fc: npt.NDArray[np.float64], k: float,
                     shape: tuple[int, int]) -> tuple[int, int, int, int] | None:
    """Cells (r0, r1, c0, c1) within ``k`` cells of continuous cell coordinates (rows
    ``fr``, cols ``fc``), clipped to ``shape`` (None: empty)."""
    r0 = max(0, int(math.floor(float(fr.min()) - k)))
    r1 = min(shape[0], int(math.ceil(float(fr.max()) + k)) + 1)
    c0 = max(0, int(math.floor(float(fc.min()) - k)))
    c1 = min(shape[1], int(math.ceil(float(fc.max()) + k)) + 1)
    return (r0, r1, c0, c1) if r0 < r1 and c0 < c1 else None


def edge_distances(blocked: npt.NDArray[np.bool_], r0: int, c0: int,
                   fr: npt.NDArray[np.float64], fc: npt.NDArray[np.float64], res: float,
                   reach: float) -> npt.NDArray[np.float64]:
    """Distance (m, at most ``reach``, which may be inf) from points at continuous cell
    coordinates (``fr``, ``fc``) to the nearest edge of a cell of ``blocked``, a window
    whose first cell is (r0, c0)."""
    br, bc = np.nonzero(blocked)
    if br.size == 0:
        return np.full(len(fr), reach)
    du = np.maximum(np.abs(fc[:, None] - (bc[None, :] + c0 + 0.5)) - 0.5, 0.0)
    dv = np.maximum(np.abs(fr[:, None] - (br[None, :] + r0 + 0.5)) - 0.5, 0.0)
    return np.minimum(np.hypot(du, dv).min(axis=1) * res, reach)
