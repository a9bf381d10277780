"""A simulator under /use_sim_time is the clock: another /clock publisher beside it (a bag
played with --clock) made ROS time jump between the two and the robots never moved, with
no line naming the cause. Each simulator now logs one error naming the other publisher
(no master: rosgraph's and rospy's calls are replaced)."""
import types

import rosgraph
import rospy

from leap_teleop.ros import cell_state_topics, drone_state_topics
from leap_teleop.ros.graph import ClockRivalWatch
from leap_teleop.ur10.config import load_config


def fake_graph(monkeypatch, publishers, me='/ur10_sim'):
    """`publishers`: [(topic, [node])] as the master lists them, or an exception it raises."""
    errors = []

    class FakeMaster:
        def __init__(self, _name):
            pass

        def getSystemState(self):
            if isinstance(publishers, Exception):
                raise publishers
            return [list(publishers), [], []]
    monkeypatch.setattr(rosgraph, 'Master', FakeMaster)
    monkeypatch.setattr(rospy, 'get_name', lambda: me)
    monkeypatch.setattr(rospy, 'logerr', lambda fmt, *args: errors.append(fmt % args))
    return errors


def test_a_bag_publishing_clock_beside_the_simulator_is_one_error_naming_it(monkeypatch):
    publishers = [('/clock', ['/ur10_sim', '/gesture_player']), ('/rosout', ['/ur10_sim'])]
    errors = fake_graph(monkeypatch, publishers)
    watch = ClockRivalWatch('ur10_sim', start=False)
    assert watch.check() == ['/gesture_player']
    (line,) = errors
    assert line.startswith('ur10_sim: /gesture_player also publishes /clock')
    assert 'use_sim_time' in line and 'replay.launch' in line
    assert watch.check() == [] and len(errors) == 1      # once, however long it lasts


def test_the_simulator_alone_on_clock_is_no_error(monkeypatch):
    errors = fake_graph(monkeypatch, [('/clock', ['/ur10_sim'])])
    assert ClockRivalWatch('ur10_sim', start=False).check() == []
    assert errors == []


def test_a_master_that_does_not_answer_is_asked_again_without_a_line(monkeypatch):
    errors = fake_graph(monkeypatch, OSError('connection refused'))
    assert ClockRivalWatch('ardrone_sim', start=False).check() == []
    assert errors == []


def test_a_later_second_publisher_is_named_too(monkeypatch):
    publishers = [('/clock', ['/uav1/ardrone_sim', '/gesture_player'])]
    errors = fake_graph(monkeypatch, publishers, me='/uav1/ardrone_sim')
    watch = ClockRivalWatch('ardrone_sim', start=False)
    watch.check()
    publishers.append(('/clock', ['/uav2/ardrone_sim']))
    assert watch.check() == ['/uav2/ardrone_sim']
    assert [line.split(' also')[0] for line in errors] == ['ardrone_sim: /gesture_player',
                                                            'ardrone_sim: /uav2/ardrone_sim']


def test_the_watch_asks_on_a_thread_of_its_own_until_stopped(monkeypatch):
    errors = fake_graph(monkeypatch, [('/clock', ['/ur10_sim', '/gesture_player'])])
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: False)
    watch = ClockRivalWatch('ur10_sim', period=0.01)
    try:
        for _ in range(200):
            if errors:
                break
            watch.thread.join(0.01)
        assert len(errors) == 1
    finally:
        watch.stop()
        watch.thread.join(1.0)
    assert not watch.thread.is_alive()


def test_both_simulators_watch_only_when_they_are_the_clock(monkeypatch):
    made = []
    monkeypatch.setattr(cell_state_topics, 'ClockRivalWatch', made.append)
    monkeypatch.setattr(drone_state_topics, 'ClockRivalWatch', made.append)
    monkeypatch.setattr(rospy, 'Publisher', lambda *a, **k: None)
    monkeypatch.setattr(drone_state_topics.tf2_ros, 'TransformBroadcaster', lambda: None)
    monkeypatch.setattr(drone_state_topics.tf2_ros, 'StaticTransformBroadcaster',
                        lambda: types.SimpleNamespace(sendTransform=lambda frames: None))
    monkeypatch.setattr(drone_state_topics, 'static_frames', lambda *a: [])
    config = load_config('ur10_dual_cell.yaml')
    frames = types.SimpleNamespace(odom='odom', base='base')
    p = {'enable_navdata_altitude': False, 'world_frame': 'world', 'odom_in_world': (0, 0, 0),
         'path_length': 10, 'path_min_step': 0.01, 'markers': False}
    for use_sim_time in (False, True):
        cell_state_topics.CellStateTopics(config, 5, use_sim_time)
        drone_state_topics.DroneStateTopics(p, frames, None, use_sim_time)
    assert made == ['ur10_sim', 'ardrone_sim']


def test_a_simulator_whose_clock_is_renamed_watches_that_name(monkeypatch):
    # The soak renames the drone simulator's clock (/drone/sim_clock): it named the arm
    # simulator on /clock as a rival, falsely.
    publishers = [('/clock', ['/ur10_sim']), ('/drone/sim_clock', ['/ardrone_sim'])]
    errors = fake_graph(monkeypatch, publishers, me='/ardrone_sim')
    monkeypatch.setattr(rospy, 'resolve_name', lambda name: '/drone/sim_clock' if name == '/clock' else name)
    assert ClockRivalWatch('ardrone_sim', start=False).check() == [] and errors == []
    publishers.append(('/drone/sim_clock', ['/ardrone_sim', '/gesture_player']))
    assert ClockRivalWatch('ardrone_sim', start=False).check() == ['/gesture_player']
    assert errors[0].startswith('ardrone_sim: /gesture_player also publishes /drone/sim_clock')
