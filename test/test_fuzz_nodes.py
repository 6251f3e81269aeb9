"""Fuzz suite (issue 24): every node gets its named malformed cases and a few hundred
random messages on each subscribed topic (test/fuzz_support.py), then good input, and
must still produce the correct output, log at most a few lines per second and stay
within a stated allocation bound. Seeded and bounded (about a minute on 2 cores);
messages go straight into the node's own subscription callbacks and timers (no DDS, no
spinning), so the run is deterministic.
"""

from __future__ import annotations

import numpy as np
import pytest
from rclpy.parameter import Parameter
from std_msgs.msg import Bool

from explore_seg import convert
from explore_seg.core.explorer import detect_frontiers
from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.grid import GridMap, grid_from_ascii
from fuzz_support import FuzzReport, LogCapture, fuzz_node, tick
from test_segmentation import two_rooms

#: NaN or overflow in numpy means garbage got past validation: fail on it.
pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")

#: Random messages per subscribed topic (besides the named cases).
PER_TOPIC = 200
#: Allocation bound of a whole fuzz run (tracemalloc peak above the start).
MAX_ALLOC_MB = 64.0
#: Resident memory the run may add (allocator slack included).
MAX_RSS_GROWTH_MB = 100.0
#: Log lines per second allowed on average, and in any run at least this many.
MAX_LINES_PER_S, MIN_LINES_ALLOWED = 3.0, 25

ROOM = "\n".join(["##########"] + ["#........?"] * 5 + ["#...R....?"]
                 + ["#........?"] * 6 + ["##########"])


def _check_bounds(rep: FuzzReport, log: LogCapture) -> None:
    assert rep.peak_alloc_mb < MAX_ALLOC_MB, f"{rep.peak_alloc_mb:.1f} MB allocated at peak"
    assert rep.rss_growth_mb < MAX_RSS_GROWTH_MB, f"RSS grew {rep.rss_growth_mb:.1f} MB"
    allowed = max(MIN_LINES_ALLOWED, MAX_LINES_PER_S * rep.wall_s)
    assert len(log.lines) <= allowed, (
        f"{len(log.lines)} log lines in {rep.wall_s:.1f} s (allowed {allowed:.0f}):\n"
        + "\n".join(m[:160] for _, m in log.lines[:40]))


def _params(**kw) -> list[Parameter]:
    return [Parameter(k, value=v) for k, v in kw.items()]


def _small_map() -> GridMap:
    return grid_from_ascii(ROOM, resolution_m=0.1, origin_xy_m=(-0.5, -0.2))[0]


def _odom(x: float, y: float, t_ns: int, frame: str = "map"):
    return convert.odometry_msg((x, y, 0.0), (0.0, 0.0), frame, "base_link", t_ns)


# ------------------------------------------------------------------ frontier_detector
def test_fuzz_frontier_detector(ros):
    from explore_seg.frontier_node import FrontierDetectorNode

    node = ros.add(FrontierDetectorNode(context=ros.context))
    log = LogCapture(node)
    small = convert.grid_to_msg(_small_map(), stamp=10**9)
    rep = fuzz_node(node, {"map": small, "object_costmap": small},
                    np.random.default_rng(1), PER_TOPIC)
    _check_bounds(rep, log)

    grid = _small_map()
    layer = grid.with_data(np.zeros_like(grid.data))
    node._on_map(convert.grid_to_msg(grid, stamp=2 * 10**9))          # noqa: SLF001
    node._on_layer(convert.grid_to_msg(layer, stamp=2 * 10**9))       # noqa: SLF001
    tick(node)
    want = detect_frontiers(grid, layer, FrontierParams()).frontiers
    assert want and len(node.frontiers) == len(want)
    for got, exp in zip(node.frontiers, want):
        np.testing.assert_array_equal(got.cells, exp.cells)


# ------------------------------------------------------------------ segmentation
def test_fuzz_segmentation(ros):
    from explore_seg.segmentation_node import SegmentationNode

    node = ros.add(SegmentationNode(context=ros.context,
                                    parameter_overrides=_params(tau_m=2.5)))
    log = LogCapture(node)
    rep = fuzz_node(node, {"map": convert.grid_to_msg(_small_map(), stamp=10**9),
                           "exploration_done": Bool(data=False)},
                    np.random.default_rng(2), PER_TOPIC)
    _check_bounds(rep, log)

    node._done_gate._on_done(Bool(data=False))                      # noqa: SLF001
    grid = two_rooms(door_at_end=True)
    node._on_map(convert.grid_to_msg(grid, stamp=5 * 10**9))       # noqa: SLF001
    done = node.processed
    tick(node)
    assert node.processed == done + 1
    labels = node.last_labels
    assert labels.shape == grid.shape and len(np.unique(labels[labels > 0])) == 2
    assert (labels[grid.data != 0] == 0).all()


# ------------------------------------------------------------------ target_selector
def test_fuzz_target_selector(ros):
    from explore_seg.selector_node import State, TargetSelectorNode

    node = ros.add(TargetSelectorNode(context=ros.context, parameter_overrides=_params(
        strategy="nearest", nav_action="")))
    log = LogCapture(node)
    grid = _small_map()
    labels_img, labels_info = convert.labels_to_msgs(
        np.ones(grid.shape, np.int32), grid, convert.ns_to_stamp(10**9))
    good = {"map": convert.grid_to_msg(grid, stamp=10**9),
            "object_costmap": convert.grid_to_msg(grid.with_data(np.zeros_like(grid.data))),
            "regions": labels_img, "regions/info": labels_info,
            "odom": _odom(0.0, 0.0, 10**9), "exploration_done": Bool(data=False)}
    rep = fuzz_node(node, good, np.random.default_rng(3), PER_TOPIC)
    _check_bounds(rep, log)

    # good input: a fresh start, the map, a pose in it -> a goal at the open side
    node._srv_start(*_trigger())                                    # noqa: SLF001
    node._done_gate._on_done(Bool(data=False))                      # noqa: SLF001
    node._on_map(good["map"])                                       # noqa: SLF001
    node._on_layer(good["object_costmap"])                          # noqa: SLF001
    sent = node.goals_sent
    now = node.get_clock().now().nanoseconds
    node._pose_in._on_odom(_odom(-0.5 + 0.45, -0.2 + 0.75, now))             # noqa: SLF001 - cell R
    tick(node)
    assert node.goals_sent == sent + 1 and node.state is State.NAVIGATING
    gx, gy = node.manager.goal.xy_m
    assert 0.1 < gx < 0.5 and 0.0 < gy < 1.2           # near the '?' column (x 0.35)


def _trigger():
    from std_srvs.srv import Trigger

    return Trigger.Request(), Trigger.Response()


# ------------------------------------------------------------------ object_costmap
def test_fuzz_object_costmap(ros):
    from test_object_costmap_node import CHAIR_ID, K, ROBOT, _map_grid, _node, _scene
    from objects_scene import box_parts

    node = _node(ros)
    log = LogCapture(node)
    chair = box_parts((2.5, 0.2), (0.5, 0.5, 0.9))
    depth, sem = _scene([(chair, CHAIR_ID)])
    t0 = 10**9
    header = convert.make_header("camera_color_optical_frame", t0)
    # a small image as the base of the random ones (the scene's 640x480 is for the end)
    tiny = convert.image_to_msg(np.zeros((4, 6), np.uint8), "mono8", header)
    good = {"camera/color/image_raw": tiny, "camera/depth/image_raw": tiny,
            "camera/semantic/image_raw": tiny,
            "camera/color/camera_info": convert.intrinsics_to_msg(K, header),
            "odom": _odom(*ROBOT[:2], t0), "map": convert.grid_to_msg(_map_grid()),
            "exploration_done": Bool(data=False)}
    rep = fuzz_node(node, good, np.random.default_rng(4), PER_TOPIC)
    _check_bounds(rep, log)

    node._done_gate._on_done(Bool(data=False))                      # noqa: SLF001
    node._on_info(good["camera/color/camera_info"])                 # noqa: SLF001
    node._on_map(good["map"])                                       # noqa: SLF001
    rgb = np.zeros(depth.shape + (3,), np.uint8)
    for k in range(6):
        t = 50 * 10**9 + k * 10**9 // 2
        h = convert.make_header("camera_color_optical_frame", t)
        for dt in (-10**7, 10**7):
            node._pose_in._on_odom(_odom(ROBOT[0], ROBOT[1], t + dt))        # noqa: SLF001
        node._on_color(convert.image_to_msg(rgb, "rgb8", h))        # noqa: SLF001
        node._on_depth(convert.image_to_msg(depth, "32FC1", h))     # noqa: SLF001
        node._on_semantic(convert.image_to_msg(sem, "mono8", h))    # noqa: SLF001
        tick(node)
    assert [o.cls for o in node.objects()] == ["chair"]


# ------------------------------------------------------------------ sim_bridge
def test_fuzz_sim_bridge(ros, tmp_path):
    from sim_bridge.node import SimBridgeNode

    node = ros.add(SimBridgeNode(context=ros.context, parameter_overrides=_params(
        world="small_house", output_dir=str(tmp_path), enable_camera=False)))
    log = LogCapture(node)
    x, y = node.engine.pose[:2]
    grid = GridMap(np.zeros((20, 20), np.int8), 0.1, (x - 1.0, y - 1.0))
    good = {"goal_pose": convert.pose_stamped(x + 0.3, y, 0.0, "map"),
            "object_costmap": convert.grid_to_msg(grid)}
    rep = fuzz_node(node, good, np.random.default_rng(5), PER_TOPIC, tick_every=0)
    _check_bounds(rep, log)

    layer_cb = next(s.callback for s in node.subscriptions if s.topic_name == "/object_costmap")
    layer_cb(good["object_costmap"])                # free cells: what the fuzz put there goes
    node._on_goal(convert.pose_stamped(x + 0.5, y, 0.0, "map"))    # noqa: SLF001
    for _ in range(200):
        node.engine.step(0.05)
    st = node.engine.nav_status
    assert st.state.value == "succeeded" and st.goal[:2] == pytest.approx((x + 0.5, y))
    assert np.hypot(node.engine.pose[0] - (x + 0.5), node.engine.pose[1] - y) < 0.3
