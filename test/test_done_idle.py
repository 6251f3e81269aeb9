"""Idle after ``exploration_done``: segmentation and object_costmap pause their timers
while the flag is true (``idle_when_done``) and pick up the newest input when it turns
false (issue 24, finding 7: the explorer kept ~50 % of a core busy after done)."""

from __future__ import annotations

from rclpy.parameter import Parameter
from std_msgs.msg import Bool
from std_srvs.srv import Trigger

from explore_seg import convert
from explore_seg.qos import MAP_QOS
from test_segmentation import two_rooms


def _done_publisher(ros):
    return ros.node("done_flag").create_publisher(Bool, "exploration_done", MAP_QOS)


def test_segmentation_pauses_while_done_and_segments_the_newest_map_after(ros):
    from nav_msgs.msg import OccupancyGrid

    from explore_seg.segmentation_node import SegmentationNode

    node = ros.add(SegmentationNode(context=ros.context, parameter_overrides=[
        Parameter("tau_m", value=2.5), Parameter("process_period_s", value=0.02)]))
    helper = ros.node("seg_idle_helper")
    maps = helper.create_publisher(OccupancyGrid, "map", MAP_QOS)
    done = _done_publisher(ros)
    grid = two_rooms(door_at_end=True)
    maps.publish(convert.grid_to_msg(grid, stamp=1_000_000_000))
    ros.spin_until(lambda: node.processed == 1, what="the first map segmented")

    done.publish(Bool(data=True))
    ros.spin_until(lambda: node.paused, what="segmentation paused by exploration_done")
    assert node._timer.is_canceled()               # noqa: SLF001 - no periodic work at all
    maps.publish(convert.grid_to_msg(grid, stamp=2_000_000_000))
    ros.spin_for(0.5)                               # 25 periods: nothing may be processed
    assert node.processed == 1

    done.publish(Bool(data=False))
    ros.spin_until(lambda: node.processed == 2, what="the map kept during the pause segmented")
    assert not node.paused and not node._timer.is_canceled()   # noqa: SLF001


def test_segmentation_keeps_working_when_idle_when_done_is_false(ros):
    from explore_seg.segmentation_node import SegmentationNode

    node = ros.add(SegmentationNode(context=ros.context, parameter_overrides=[
        Parameter("idle_when_done", value=False)]))
    done = _done_publisher(ros)
    done.publish(Bool(data=True))
    ros.spin_for(0.3)
    assert not node.paused and not node._timer.is_canceled()   # noqa: SLF001
    # Switching it on while done pauses at once; a rate change keeps the pause.
    node.set_parameters([Parameter("idle_when_done", value=True)])
    assert node.paused
    node.set_parameters([Parameter("process_period_s", value=0.05)])
    assert node._timer.is_canceled()               # noqa: SLF001


def test_object_costmap_pauses_while_done_and_forgets_the_pause_on_resume(ros):
    from explore_seg.object_costmap_node import ObjectCostmapNode

    node = ros.add(ObjectCostmapNode(context=ros.context, parameter_overrides=[
        Parameter("detector.backend", value="oracle"), Parameter("rate_hz", value=10.0),
        Parameter("input.clock_jump_s", value=0.1)]))
    done = _done_publisher(ros)
    ros.spin_until(lambda: node._time.newest("clock") is not None,   # noqa: SLF001
                   what="the first tick")
    done.publish(Bool(data=True))
    ros.spin_until(lambda: node.paused, what="object costmap paused by exploration_done")
    assert node._timer.is_canceled()               # noqa: SLF001
    assert node._done_gate.subscriptions == []      # noqa: SLF001 - no sensor stream
    ros.spin_for(0.4)                               # the clock moves on by 4 jump thresholds
    node._stall._idle = 5                           # noqa: SLF001 - counts from before
    done.publish(Bool(data=False))
    ros.spin_until(lambda: not node.paused, what="object costmap resumed")
    assert not node._timer.is_canceled()           # noqa: SLF001
    assert len(node._done_gate.subscriptions) == 6  # noqa: SLF001 - camera x4, scan, odom
    assert node._stall._idle == 0                   # noqa: SLF001
    ros.spin_for(0.2)                               # a few ticks after the pause
    assert node.time_jumps == 0                     # the paused time is no clock jump


def test_the_selector_drops_its_pose_subscription_while_done(ros):
    from explore_seg.selector_node import State, TargetSelectorNode

    node = ros.add(TargetSelectorNode(context=ros.context))
    watcher = ros.node("odom_watcher")
    assert len(node._done_gate.subscriptions) == 1     # noqa: SLF001 - odom
    node._state = State.DONE                            # noqa: SLF001 - as after Action.DONE
    node._publish_done(True)                            # noqa: SLF001
    ros.spin_until(lambda: watcher.count_subscribers("odom") == 0,
                   what="the odom subscription dropped")
    resp = node._srv_resume(Trigger.Request(), Trigger.Response())  # noqa: SLF001
    assert resp.success and node.state is State.WAITING_FOR_MAP
    ros.spin_until(lambda: watcher.count_subscribers("odom") == 1,
                   what="the odom subscription made again after ~/resume")
