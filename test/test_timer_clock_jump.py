"""The nodes' rospy.Timers keep running when ROS time jumps back, as /clock does on every
loop of `rosbag play --clock -l` (no master: sim time is set in-process). Without
reset=True the timer's thread ended with ROSTimeMovedBackwardsException, for good."""
import time

import pytest
import rospy

# rospy's own sim-time calls
pytestmark = pytest.mark.filterwarnings('ignore:notifyAll:DeprecationWarning')


class SimTime:
    def __init__(self):
        self.timers = []

    def __call__(self, t):
        rospy.rostime._set_rostime(rospy.Time.from_sec(t))


@pytest.fixture
def sim_time():
    """set(t): ROS time is sim time t (s); its .timers are stopped afterwards, then wall
    time is back."""
    was = rospy.rostime.is_rostime_initialized()
    rospy.rostime.set_rostime_initialized(True)
    clock = SimTime()
    clock(100.0)
    yield clock
    for timer in clock.timers:
        timer.shutdown()
    rospy.rostime.switch_to_wallclock()         # wakes a timer thread still asleep
    for timer in clock.timers:
        timer.join(5.0)
    rospy.rostime.set_rostime_initialized(was)


def run_clock(set_time, start, end, step=0.25, wall=0.01):
    t = start
    while t <= end:
        set_time(t)
        time.sleep(wall)
        t += step


def calls_after_a_jump_back(set_time, calls, timer):
    run_clock(set_time, 100.0, 106.0)
    before = len(calls)
    run_clock(set_time, 50.0, 56.0)                # the bag loops: 106 s -> 50 s
    after = calls[before:]
    assert before >= 3
    assert timer.is_alive() or after, 'the timer thread ended at the jump'
    return after


def test_the_topic_type_watch_checks_on_after_the_clock_jumps_back(sim_time, monkeypatch):
    from leap_teleop.ros.graph import TopicTypeWatch
    calls = []
    monkeypatch.setattr(TopicTypeWatch, 'check', lambda self, _event=None: calls.append(rospy.get_time()))
    watch = TopicTypeWatch('node', log=None, period=1.0)
    sim_time.timers.append(watch.timer)
    after = calls_after_a_jump_back(sim_time, calls, watch.timer)
    assert len(after) >= 3 and all(t < 60 for t in after)


def test_the_diagnostics_timer_updates_on_after_the_clock_jumps_back(sim_time):
    from leap_teleop.ros.diagnostics import update_every

    class Updater:
        calls = []

        def update(self):
            self.calls.append(rospy.get_time())
    timer = update_every(Updater(), 0.5)
    sim_time.timers.append(timer)
    after = calls_after_a_jump_back(sim_time, Updater.calls, timer)
    assert len(after) >= 6 and all(t < 60 for t in after)


class Published:
    """Stands in for an Updater's /diagnostics publisher (no master): the report times."""

    def __init__(self):
        self.stamps = []

    def publish(self, msg):
        self.stamps.append(msg.header.stamp.to_sec())


@pytest.mark.parametrize('back_to', [50.0, 0.0])     # a looped bag; a simulator started again
def test_the_diagnostics_report_on_after_the_clock_jumps_back(sim_time, monkeypatch, back_to):
    """The real Updater, called every 0.25 s of sim time as update_every and the control
    loops do: the library's update() waited for /clock to pass the last report again."""
    from leap_teleop.ros.diagnostics import FixedPeriodUpdater
    published = Published()
    monkeypatch.setattr(rospy, 'Publisher', lambda *args, **kwargs: published)
    updater = FixedPeriodUpdater(1.0)
    updater.setHardwareID('hw')
    updater.add('task', lambda stat: stat.summary(0, 'fine'))

    def run(start, end):
        for i in range(int((end - start) / 0.25) + 1):
            sim_time(start + 0.25 * i)
            updater.update()
    run(100.0, 106.0)
    before = len(published.stamps)
    run(back_to, back_to + 6.0)
    after = published.stamps[before:]
    assert before >= 5
    assert 5 <= len(after) <= 7 and all(back_to <= t <= back_to + 6.0 for t in after), after
    assert all(b - a >= updater.period for a, b in zip(after, after[1:])), after


def test_waiting_for_subscribers_waits_on_after_the_clock_jumps_back(sim_time, monkeypatch):
    """The sender's ~wait_for_subscribers under sim time: rospy.sleep raised
    ROSTimeMovedBackwardsException out of it when /clock jumped back (a simulator started
    again), which ended the sender before its source started."""
    import threading

    from leap_teleop.ros.graph import wait_for_subscribers
    said, jumped, done = [], threading.Event(), threading.Event()
    monkeypatch.setattr(rospy, 'loginfo', lambda fmt, *a: said.append((jumped.is_set(), fmt % a)))

    class OwnPublisher:
        def get_num_connections(self):
            return int(rospy.get_time() >= 6.0 and jumped.is_set())     # a reader 1 s after the jump

    def clock():        # runs until the wait is over: rospy.sleep waits for sim time
        run_clock(sim_time, 100.0, 101.0, step=0.01)
        jumped.set()
        t = 5.0
        while not done.is_set() and t < 30.0:
            sim_time(t)
            time.sleep(0.01)
            t += 0.01
    ticking = threading.Thread(target=clock, daemon=True)
    ticking.start()
    try:
        assert wait_for_subscribers({'/leapmotion/data_right': OwnPublisher()}, ['/leapmotion/data_right'],
                                    'sender', log_every=0.2)
    except rospy.ROSTimeMovedBackwardsException as e:     # a KeyboardInterrupt: would end pytest
        pytest.fail('raised out of the wait: %r' % e)
    finally:
        done.set()
        ticking.join(10.0)
    assert sum(after for after, _ in said) >= 3, said     # and it says so on
    assert said[-1][1] == 'sender: waiting for subscribers on /leapmotion/data_right'


def test_a_shutdown_while_waiting_for_subscribers_under_sim_time_is_false_not_a_traceback(monkeypatch):
    # Under sim time rospy.sleep raises ROSInterruptException on Ctrl-C: the sender ended
    # with a traceback and status 1 (under wall time the loop sees is_shutdown and ends).
    from leap_teleop.ros.graph import wait_for_subscribers

    class Unheard:
        def get_num_connections(self):
            return 0

    def interrupted(_):
        raise rospy.ROSInterruptException('ROS shutdown request')
    monkeypatch.setattr(rospy, 'sleep', interrupted)
    monkeypatch.setattr(rospy, 'get_time', lambda: 1.0)
    try:
        stopped = wait_for_subscribers({'/leapmotion/data_right': Unheard()}, ['/leapmotion/data_right'],
                                       'sender')
    except rospy.ROSInterruptException as e:     # a KeyboardInterrupt: would end pytest
        pytest.fail('raised out of the wait: %r' % e)
    assert stopped is False


def test_the_hand_markers_latency_text_goes_on_after_the_clock_jumps_back(sim_time, monkeypatch):
    from leap_teleop.params import check_params
    from leap_teleop.ros.graph import TopicTypeWatch
    from leap_teleop.ros.nodes import hand_markers
    calls = []
    monkeypatch.setattr(TopicTypeWatch, 'check', lambda self, _event=None: None)
    monkeypatch.setattr(hand_markers.HandMarkersNode, 'on_latency_timer',
                        lambda self, _event: calls.append(rospy.get_time()))
    node = hand_markers.HandMarkersNode(check_params(hand_markers.PARAMS, {}))
    sim_time.timers += [node.timer, node.type_watch.timer]
    try:
        after = calls_after_a_jump_back(sim_time, calls, node.timer)
    finally:
        for sub in node.subs + [node.latency.sub]:
            sub.unregister()
    assert len(after) >= 3 and all(t < 60 for t in after)
