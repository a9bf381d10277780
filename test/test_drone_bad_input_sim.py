"""ardrone_sim against bad input: absurd animation durations, out-of-range cmd_vel, and
the type watches on both drone nodes' inputs (no ROS master)."""
import math
import types

import pytest

from leap_teleop.drone import sim as ds
from leap_teleop.drone.pilot import DronePilot, PilotInput, PilotParams
from leap_teleop.drone.sim_runner import RUNNER_PARAMS, DroneSimRunner
from leap_teleop.params import check_params

# needs a simulator: not in make check
pytestmark = pytest.mark.integration


@pytest.fixture
def hovering():
    warnings = []
    r = DroneSimRunner(check_params(RUNNER_PARAMS, {}), use_sim_time=True,
                       warn=lambda key, text: warnings.append((key, text)))
    assert r.sim.takeoff()
    while r.sim.state != ds.HOVERING and r.sim.time < 8.0:
        r.sim.step()
    r.sim.advance(1.0)
    yield r, warnings
    r.close()


def test_an_absurd_animation_duration_is_refused_and_steering_stays(hovering):
    from leap_teleop.ros.nodes.ardrone_sim import ArDroneSimNode
    from leap_teleop.srv import FlightAnimRequest, FlightAnimResponse
    runner, warnings = hovering
    reply = ArDroneSimNode.on_command(None, FlightAnimRequest(type=9, duration=4000000000),
                                      runner.flight_animation, ('type', 'duration'),
                                      FlightAnimResponse(result=True))
    assert reply.result is False
    assert any('0..10000 ms' in text for _, text in warnings)
    assert runner.sim.auto_hover and runner.sim.state == ds.HOVERING
    runner.sim.set_cmd_vel(0.5)                          # steering is not locked out
    runner.sim.advance(1.0)
    assert runner.sim.pitch > 0.05
    runner.sim.set_cmd_vel()
    runner.sim.advance(2.0)
    assert runner.flight_animation(9, 0) == ''            # 0: the default (5 s) still goes
    assert runner.flight_animation(9, 10000) == ''


def test_cmd_vel_beyond_its_range_is_clamped_with_a_warning_the_pilots_never_gives():
    warnings = []
    d = ds.ArDroneSim(warn=lambda key, text: warnings.append(key))
    try:
        assert d.takeoff()
        assert d.set_cmd_vel(1e300, -1e300, 1e38, 0.0, 0.0, 1e300)
        assert d.cmd == (1.0, -1.0, 1.0, 0.0, 0.0, 1.0) and warnings.count('cmd_vel_range') == 1
        d.advance(3.0)                                   # past the warning's rate limit
        warnings.clear()
        # The pilot's own commands, both modes, the hand at the limits of what it takes:
        # tilt is capped at max_cmd; paper's angular x / y are raw mm (auto-hover switch).
        for cfg in (PilotParams(navdata_timeout=10.0),
                    PilotParams(mode='paper', paper_scale=100.0, navdata_timeout=10.0)):
            pilot = DronePilot(cfg)
            pilot.on_navdata(4, 1000, 0.0)
            pilot.on_hand(PilotInput(True, (0.0, 0.2, 0.0), (0.6, -0.8, 0.0), (0.0, 0.6, -0.8)), 0.0)
            pilot.on_gesture('unfold', True, 0.0)
            for k, palm in enumerate([(0.99, 0.99, 0.99), (-0.99, -0.99, -0.99)]):
                pilot.on_hand(PilotInput(True, palm, (0.0, -1.0, 0.0), (1.0, 0.0, 0.0)),
                              0.01 * (k + 1))
            mono, sent = 0.0, []
            while True:
                mono += 1.0
                cmd, _ = pilot.pop(mono)
                if cmd is None:
                    break
                if cmd.kind == 'twist':
                    assert d.set_cmd_vel(*cmd.twist)
                    sent.append(cmd.twist)
            assert max(abs(v) for t in sent for v in t[:3]) == 1.0     # at the limit
        assert 'cmd_vel_range' not in warnings
    finally:
        d.close()


def test_the_drone_nodes_watch_the_types_on_their_inputs(monkeypatch):
    import rospy

    from leap_teleop.ros.drone_inputs import subscribe_ardrone_sim_inputs, subscribe_pilot_inputs
    monkeypatch.setattr(rospy, 'Timer', lambda *a, **k: None)
    subscribed = []
    monkeypatch.setattr(rospy, 'Subscriber', lambda topic, kind, *a, **k: subscribed.append(
        (rospy.resolve_name(topic), kind._type)))
    said = []
    log = type('Log', (), {'warn': lambda self, key, fmt, *a: said.append((key, fmt % a))})()
    pilot = subscribe_pilot_inputs('leapmotion/hand_right', 'leapmotion/gestures', 'right',
                                   None, None, log)
    drone = types.SimpleNamespace(takeoff=None, land=None, reset=None, set_cmd_vel=None)
    sim = subscribe_ardrone_sim_inputs(drone, None, log)
    watched = [(w.topic, w.want) for w in pilot.topics + sim.topics]
    assert watched == [
        ('/leapmotion/hand_right', 'leap_teleop/Hand'),
        ('/leapmotion/gestures', 'leap_teleop/GestureEvent'),
        ('/ardrone/navdata', 'leap_teleop/Navdata'),
        ('/cmd_vel', 'geometry_msgs/Twist'),
        ('/ardrone/takeoff', 'std_msgs/Empty'), ('/ardrone/land', 'std_msgs/Empty'),
        ('/ardrone/reset', 'std_msgs/Empty')]
    # every subscription is watched; the hand's is the HandSubscription's own
    assert subscribed == watched[1:]
    published = [(t, 'std_msgs/String') for t, _ in watched[:2]] + [
        ('/cmd_vel', 'geometry_msgs/Twist')]
    monkeypatch.setattr(rospy, 'get_published_topics', lambda: published)
    assert pilot.check() == {'/leapmotion/hand_right': 'std_msgs/String',
                             '/leapmotion/gestures': 'std_msgs/String', '/ardrone/navdata': None}
    sim.check()
    assert [key for key, _ in said] == ['type_check:/leapmotion/hand_right',
                                        'type_check:/leapmotion/gestures']
    assert ('carries std_msgs/String, but the pilot reads leap_teleop/GestureEvent' in said[1][1]
            and 'publish the sender\'s GestureEvent there' in said[1][1])


def test_the_python_api_never_raises_on_numbers_too_big_for_a_float(hovering):
    # ArDroneSim promises never to raise on bad input: inf as a camera channel and ints
    # beyond a float (as a cmd_vel component or an animation's duration) raised
    # OverflowError. ROS's message types cannot carry them; library users can.
    runner, warnings = hovering
    d = runner.sim
    huge = 10 ** 400
    calls = [
        (d.set_camera_channel, (math.inf,)), (d.set_camera_channel, (-math.inf,)),
        (d.set_cmd_vel, (huge, 0, 0, 0, 0, 0)), (d.set_cmd_vel, (0, 0, 0, 0, 0, -huge)),
        (d.flight_animation, (3, huge)), (d.flight_animation, (3, 2 ** 32)),    # uint32 ms
        (d.set_led_animation, (1, 2.0, huge)), (d.set_led_animation, (1, 2.0, 256)),   # uint8 s
    ]
    for fn, args in calls:
        assert fn(*args) is False, (fn.__name__, args)      # refused with a warning
        d.advance(2.1)                                       # past the warnings' rate limit
    assert [key for key, _ in warnings] == ['camera', 'camera', 'cmd_vel', 'cmd_vel', 'anim',
                                            'anim', 'led', 'led']
    assert d.state == ds.HOVERING and d.cmd == (0.0,) * 6 and d.led_animation is None
    assert d.camera_channel == ds.CAMERA_FRONT
    # the largest values the driver's services carry still go
    assert d.set_led_animation(1, 2.0, 255)
    assert d.flight_animation(ds.FLIP_RIGHT, 2 ** 32 - 1)


def test_advance_and_snapshot_refuse_what_they_cannot_do(hovering):
    # advance(nan / inf / None) raised; a snapshot of a fractional size raised and one of a
    # negative size ended the whole process (the renderer's allocation failed in C++).
    runner, warnings = hovering
    d = runner.sim
    t = d.time
    for seconds in (math.nan, math.inf, None, -1.0, True, 1e9):
        d.advance(seconds)
        assert d.time == t, seconds
        d.advance(2.1)                                       # past the warning's rate limit
        t = d.time
    assert [key for key, _ in warnings].count('advance') == 6
    for size in ((64.5, 48), (0, 48), (-1, 48), (64, -5), (64, 10 ** 6)):
        assert d.snapshot(None, *size) is None, size
        d.advance(2.1)
    assert [key for key, _ in warnings].count('snapshot') == 5
    assert d.snapshot(None, 32, 24).shape == (24, 32, 3)
