"""Floor-plan prediction (explore_seg.core.prediction), its training data
(bench/predictor_data.py) and the ``foresight`` strategy through Explorer.step."""

from __future__ import annotations

import logging
import sys

import numpy as np
import pytest

from explore_seg.core.explorer import Explorer
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import GridMap, grid_from_ascii
from explore_seg.core.prediction.features import CoarseFrame, coarse_fractions, padded_input
from explore_seg.core.prediction.gain import expected_view_gain
from explore_seg.core.prediction.inference import (FloorPlanPredictor, PredictedMap,
                                                   load_predictor)
from explore_seg.core.prediction.model import (WEIGHTS_PATH, build_unet, load_unet,
                                               read_weights, save_unet, stride)
from explore_seg.core.selection import (Action, SelectionParams, Strategy, register,
                                        unregister)
from explore_seg.core.selection.router import Router
from explore_seg.core.selection.strategies.foresight import (STRATEGY, PredictedGains,
                                                             foresight_cost)

torch = pytest.importorskip("torch")

# A corridor (0.2 m per character) with unknown space at both ends; the robot in the
# middle. Upsampled x4 to 0.05 m cells.
CORRIDOR = """
????????????????????????????????????????
????????????????????????????????????????
???????????????##########???????????????
???????????????..........???????????????
???????????????..........???????????????
???????????????....R.....???????????????
???????????????..........???????????????
???????????????##########???????????????
????????????????????????????????????????
????????????????????????????????????????
"""
FACTOR = 4
#: Margin (m) that makes the padded coarse width 40 + 2 * 4 = 48, a multiple of the
#: stride 16, so its middle column is the corridor's middle.
MARGIN_M = 0.8


def corridor() -> tuple[GridMap, tuple[float, float]]:
    g, marks = grid_from_ascii(CORRIDOR, resolution_m=0.2)
    fine = np.kron(g.data, np.ones((FACTOR, FACTOR), dtype=np.int8))
    grid = GridMap(fine, 0.05, (0.0, 0.0))
    r, c = marks["R"][0]
    return grid, grid.cell_to_world(r * FACTOR + 2, c * FACTOR + 2)


class Halves(torch.nn.Module):
    """A stand-in network: logit ``left`` on the left half of its input, ``right`` on the
    right half."""

    def __init__(self, left: float, right: float) -> None:
        super().__init__()
        self.left, self.right = left, right

    def forward(self, x):
        n, _, h, w = x.shape
        out = torch.full((n, h, w), self.right)
        out[:, :, : w // 2] = self.left
        return out


# ------------------------------------------------------------------ features

def test_coarse_fractions_literal():
    d = np.array([[0, 0, -1, -1],
                  [0, 100, -1, -1],
                  [0, 0, 0, 0]], dtype=np.int8)
    f = coarse_fractions(d, 2)
    assert f.shape == (3, 2, 2)
    np.testing.assert_allclose(f[:, 0, 0], [0.75, 0.25, 0.0])
    np.testing.assert_allclose(f[:, 0, 1], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(f[:, 1, 0], [0.5, 0.0, 0.5])   # missing row counts unknown
    np.testing.assert_allclose(f.sum(axis=0), 1.0)


def test_padded_input_frame():
    d = np.zeros((37, 50), dtype=np.int8)
    x, frame = padded_input(d, 4, 3, 16)
    # 10 x 13 coarse cells (the last row and column partly beyond the map) + 2 x 3 margin,
    # padded to multiples of 16.
    assert x.shape == (3, 16, 32) and frame == CoarseFrame(4, (3, 3), (16, 32))
    assert (x[2, :3] == 1).all() and (x[0, 3:12, 3:15] == 1).all()
    assert x[0, 12, 3] == 0.25 and x[2, 12, 3] == 0.75
    np.testing.assert_array_equal(frame.coarse_of([[0, 0], [36, 49], [-100, 999]]),
                                  [[3, 3], [12, 15], [0, 31]])


@pytest.mark.parametrize("call, match", [
    (lambda: coarse_fractions(np.zeros(4), 2), "2D"),
    (lambda: coarse_fractions(np.zeros((4, 4)), 0), "factor"),
    (lambda: padded_input(np.zeros((4, 4)), 2, -1, 8), "margin"),
    (lambda: padded_input(np.zeros((4, 4)), 2, 1, 0), "stride"),
])
def test_feature_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ------------------------------------------------------------------ model

def test_unet_shape_and_weight_file_round_trip(tmp_path):
    torch.manual_seed(3)
    widths = (4, 8, 8)
    net = build_unet(widths).eval()
    s = stride(widths)
    x = torch.rand(2, 3, 3 * s, 2 * s)
    with torch.inference_mode():
        y = net(x)
    assert tuple(y.shape) == (2, 3 * s, 2 * s)
    path = tmp_path / "w.npz"
    save_unet(net, path, widths, 4, {"seed": 3})
    net2, widths2, factor, meta = load_unet(path)
    assert widths2 == widths and factor == 4 and int(meta["seed"]) == 3
    with torch.inference_mode():
        torch.testing.assert_close(net2(x), y)


def test_weight_file_errors(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        read_weights(tmp_path / "none.npz")
    np.savez(tmp_path / "bare.npz", a=np.zeros(3))
    with pytest.raises(ValueError, match="lack meta.widths"):
        read_weights(tmp_path / "bare.npz")
    save_unet(build_unet((4, 8)), tmp_path / "small.npz", (4, 8), 4)
    np.savez(tmp_path / "lie.npz", **{**dict(np.load(tmp_path / "small.npz")),
                                      "meta.widths": np.array([8, 16])})
    with pytest.raises(ValueError, match="do not fit"):
        load_unet(tmp_path / "lie.npz")
    with pytest.raises(ValueError, match="widths"):
        build_unet((4,))


def test_prediction_keeps_known_cells():
    grid, _ = corridor()
    pred = FloorPlanPredictor(Halves(0.0, 0.0), (4, 8, 8, 8), FACTOR, MARGIN_M).predict(grid)
    assert pred.p_free.shape == pred.frame.shape == (32, 48)   # (10 + 8, 40 + 8) padded
    free, occ, unk = pred.fractions
    assert (pred.p_free[occ > 0] == 0).all()
    assert (pred.p_free[free == 1] == 1).all()
    np.testing.assert_allclose(pred.p_free[unk == 1], 0.5)
    assert pred.cell_m == pytest.approx(0.2)


# ------------------------------------------------------------------ gain

def test_expected_gain_follows_the_prediction():
    grid, xy = corridor()
    rc = np.array([grid.world_to_cell(*xy)])
    left_free = FloorPlanPredictor(Halves(20.0, -20.0), (4, 8, 8, 8), FACTOR, MARGIN_M)
    g_left = left_free.predict(grid)
    # Views from the two ends of the corridor (4 fine cells inside its free part).
    ends = np.array([[rc[0, 0], 15 * FACTOR + 2], [rc[0, 0], 24 * FACTOR + 1]])
    gl = expected_view_gain(g_left, ends, range_m=1.5, rays=32)
    assert gl[0] > 1.0 and gl[1] < 1e-6   # sigmoid(-20) ~ 2e-9
    # Walls stop rays: nothing above or below the corridor counts.
    walls = PredictedMap(np.ones_like(g_left.p_free), g_left.fractions, g_left.frame, 0.2)
    g_all = expected_view_gain(walls, ends, range_m=1.5, rays=32)
    assert g_all[0] == pytest.approx(g_all[1], rel=0.15) and g_all[0] > gl[1]


@pytest.mark.parametrize("kw, match", [({"range_m": 0.0}, "range_m"), ({"rays": 3}, "rays")])
def test_expected_gain_errors(kw, match):
    grid, _ = corridor()
    pred = FloorPlanPredictor(Halves(0.0, 0.0), (4, 8), FACTOR, MARGIN_M).predict(grid)
    with pytest.raises(ValueError, match=match):
        expected_view_gain(pred, [[0, 0]], **kw)


# ------------------------------------------------------------------ foresight strategy

def _constant_file(tmp_path, logit: float) -> str:
    """A weight file of a U-Net that predicts ``logit`` everywhere (output layer zero but
    its bias)."""
    widths = (4, 8, 8, 8)
    net = build_unet(widths)
    with torch.no_grad():
        net.head.weight.zero_()
        net.head.bias.fill_(logit)
    path = tmp_path / f"constant_{logit}.npz"
    save_unet(net, path, widths, FACTOR)
    return str(path)


@pytest.fixture
def halves():
    """Registers ``foresight_halves``: foresight's cost and router, its gains from the
    :class:`Halves` stand-in (the plug-in way to hand a strategy another predictor)."""
    names = []

    def make(left: float, right: float) -> str:
        pred = FloorPlanPredictor(Halves(left, right), (4, 8, 8, 8), FACTOR, MARGIN_M)

        def planner(fp, sp):
            return Router(fp, sp, PredictedGains(pred, sp.sensor_range_m, sp.gain_rays,
                                                 fp.occupied_threshold,
                                                 sp.prediction_gain_weight))

        register(Strategy("foresight_halves", foresight_cost, "test", region_term=True,
                          make_planner=planner, goals=STRATEGY.goals), replace=True)
        names.append("foresight_halves")
        return "foresight_halves"

    yield make
    for n in set(names):
        unregister(n)


def _step(strategy: str, **kw):
    grid, xy = corridor()
    fp = FrontierParams(robot_radius_m=0.1, min_group_size_cells=2)
    sp = SelectionParams(strategy=strategy, prediction_margin_m=MARGIN_M, **kw)
    return Explorer(fp, sp).step(0.0, grid, (xy[0], xy[1], 0.0))


@pytest.mark.parametrize("left, right, side", [(20.0, -20.0, "left"), (-20.0, 20.0, "right")])
def test_foresight_goes_where_the_plan_is_predicted(halves, left, right, side):
    out = _step(halves(left, right), prediction_gain_weight=1.0)
    assert out.action is Action.NEW_GOAL
    _, xy = corridor()
    assert (out.goal.xy_m[0] < xy[0]) == (side == "left")


def test_foresight_without_prediction_weight_is_routed(halves):
    a = _step(halves(20.0, -20.0), prediction_gain_weight=0.0)
    b = _step("routed")
    assert a.action is b.action is Action.NEW_GOAL
    assert a.goal.xy_m == b.goal.xy_m
    np.testing.assert_array_equal(a.selection.costs, b.selection.costs)


def test_foresight_runs_without_weights(tmp_path, caplog):
    missing = tmp_path / "none.npz"
    with caplog.at_level(logging.WARNING, logger="explore_seg.core.selection.strategies"):
        a = _step("foresight", prediction_weights=str(missing))
    assert f"{missing} not found" in caplog.text and "rated as routed" in caplog.text
    b = _step("routed")
    assert a.goal.xy_m == b.goal.xy_m


def test_foresight_runs_without_torch(tmp_path, caplog, monkeypatch):
    path = _constant_file(tmp_path, 20.0)
    assert load_predictor(path)[0] is not None
    monkeypatch.setitem(sys.modules, "torch", None)   # `import torch` raises ImportError
    predictor, why = load_predictor(path)
    assert predictor is None and "torch is not installed" in why
    with caplog.at_level(logging.WARNING, logger="explore_seg.core.selection.strategies"):
        a = _step("foresight", prediction_weights=path)
    assert "torch is not installed" in caplog.text
    assert a.action is Action.NEW_GOAL


# ------------------------------------------------------------------ shipped weights

@pytest.mark.skipif(not WEIGHTS_PATH.is_file(), reason="no shipped predictor weights")
def test_shipped_predictor_beats_the_constant_guess_next_to_known_space():
    """On held-back plans, the unknown cells within 1 m of known free space (what a
    viewpoint at a frontier looks into) are predicted better than by their own mean."""
    from scipy import ndimage

    from bench.predictor_data import EVAL_SEEDS, make_samples

    net, widths, factor, _ = load_unet(WEIGHTS_PATH)
    pred = FloorPlanPredictor(net, widths, factor, 2.0)
    ps, ts = [], []
    for plan in make_samples(7, 3, 2, 20, factor, seed_range=EVAL_SEEDS):
        for x, y in zip(plan.inputs, plan.targets):
            # Back to a map: one fine cell per coarse cell, the majority class.
            data = np.where(x[1] > 0, 100, np.where(x[0] >= x[2], 0, -1)).astype(np.int8)
            fine = np.kron(data, np.ones((factor, factor), dtype=np.int8))
            pm = pred.predict(GridMap(fine, 0.05, (0.0, 0.0)))
            (r0, c0), (h, w) = pm.frame.offset_rc, data.shape
            p = pm.p_free[r0:r0 + h, c0:c0 + w]
            near = (data < 0) & ndimage.binary_dilation(data == 0, iterations=5)
            ps.append(p[near])
            ts.append(y[near])
    q = np.clip(np.concatenate(ps).astype(np.float64), 1e-6, 1 - 1e-6)
    t = np.concatenate(ts).astype(np.float64)
    c = float(np.clip(t.mean(), 1e-6, 1 - 1e-6))
    bce = -(t * np.log(q) + (1 - t) * np.log(1 - q)).mean()
    bce_constant = -(t * np.log(c) + (1 - t) * np.log(1 - c)).mean()
    assert t.size > 500 and bce < bce_constant, (t.size, bce, bce_constant)


# ------------------------------------------------------------------ training data

def test_training_data_is_deterministic_and_consistent():
    from bench.predictor_data import TRAIN_SEEDS, crop, make_samples

    a = make_samples(5, 2, 2, 6, 4)
    b = make_samples(5, 2, 2, 6, 4)
    c = make_samples(6, 2, 2, 6, 4)
    for pa, pb in zip(a, b):
        assert pa.name == pb.name
        np.testing.assert_array_equal(pa.inputs, pb.inputs)
        np.testing.assert_array_equal(pa.targets, pb.targets)
    assert [p.name for p in a] != [p.name for p in c]
    for p in a:
        seed = int(p.name.rsplit("_s", 1)[1])
        assert TRAIN_SEEDS[0] <= seed < TRAIN_SEEDS[1]
        np.testing.assert_allclose(p.inputs.sum(axis=1), 1.0, atol=1e-6)
        assert set(np.unique(p.targets)) <= {0.0, 1.0}
        # Cells seen free are inside the building (the scans start inside).
        seen_free = p.inputs[:, 0] == 1.0
        assert (p.targets[seen_free] == 1.0).all()
    x, y = crop(a[0].inputs[0], a[0].targets[0], 32, np.random.default_rng(0))
    assert x.shape == (3, 32, 32) and y.shape == (32, 32)
