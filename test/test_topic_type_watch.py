"""TopicTypeWatch: one master question per check for all of a node's inputs (no master:
rospy's calls are replaced)."""
import rospy
from geometry_msgs.msg import Twist
from std_msgs.msg import Empty

from leap_teleop.ros.graph import TopicTypeWatch


class Log:
    def __init__(self):
        self.lines = []

    def warn(self, key, fmt, *args):
        self.lines.append((key, fmt % args))


def watch_of(monkeypatch, published):
    timers = []
    monkeypatch.setattr(rospy, 'Timer', lambda *a, **k: timers.append(a))
    asked = []

    def get_published_topics():
        asked.append(1)
        if isinstance(published, Exception):
            raise published
        return published
    monkeypatch.setattr(rospy, 'get_published_topics', get_published_topics)
    log = Log()
    watch = TopicTypeWatch('node', log).add('cmd_vel', Twist, 'the drone', 'publish a Twist')
    watch.add('/ardrone/land', Empty, 'the drone', 'publish an Empty')
    return watch, log, asked, timers


def test_one_timer_and_one_master_question_for_every_topic(monkeypatch):
    watch, log, asked, timers = watch_of(monkeypatch, [['/cmd_vel', 'std_msgs/String'],
                                                       ['/ardrone/land', 'std_msgs/Empty']])
    assert len(timers) == 1
    assert watch.check() == {'/cmd_vel': 'std_msgs/String', '/ardrone/land': 'std_msgs/Empty'}
    assert asked == [1]
    assert log.lines == [('type_check:/cmd_vel', 'node: /cmd_vel carries std_msgs/String, but '
                          'the drone reads geometry_msgs/Twist: publish a Twist')]


def test_a_topic_without_publisher_is_none_and_no_warning(monkeypatch):
    watch, log, _, _ = watch_of(monkeypatch, [['/cmd_vel', 'geometry_msgs/Twist']])
    assert watch.check() == {'/cmd_vel': 'geometry_msgs/Twist', '/ardrone/land': None}
    assert log.lines == []


def test_a_master_that_does_not_answer_is_one_warning_naming_the_topics(monkeypatch):
    watch, log, _, _ = watch_of(monkeypatch, OSError('connection refused'))
    assert watch.check() == {}
    (key, line), = log.lines
    assert key == 'type_check'
    assert '/cmd_vel, /ardrone/land' in line and 'connection refused' in line


def test_a_long_wait_for_a_reader_becomes_a_warning_that_asks_whether_it_runs(monkeypatch):
    # A reader that refused its parameters had ended; the sender said only, at INFO level
    # every 5 s for ever, that it was waiting.
    import rosgraph

    from leap_teleop.ros import graph
    clock, said = [0.0], []

    class Master:
        def __init__(self, _name):
            pass

        def getSystemState(self):
            return [[], [('/seen', ['/a'])], []]

    def sleep(dt):
        clock[0] += 1.0
        if clock[0] > 40:
            raise SystemExit
    monkeypatch.setattr(rosgraph, 'Master', Master)
    monkeypatch.setattr(rospy, 'get_name', lambda: '/sender')
    monkeypatch.setattr(rospy, 'get_time', lambda: clock[0])
    monkeypatch.setattr(rospy, 'sleep', sleep)
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: False)
    monkeypatch.setattr(rospy, 'loginfo', lambda fmt, *a: said.append(('info', fmt % a)))
    monkeypatch.setattr(rospy, 'logwarn', lambda fmt, *a: said.append(('warn', fmt % a)))
    try:
        graph.wait_for_subscribers({}, ['/seen', '/unread'], 'sender')
    except SystemExit:
        pass
    assert said[0] == ('info', 'sender: waiting for subscribers on /unread')
    assert [lv for lv, _ in said] == ['info'] * 5 + ['warn'] * 3
    assert said[-1][1].startswith('sender: still no subscriber on /unread after 40 s: is the '
                                  'node that reads it running?')
    assert graph.wait_for_subscribers({}, ['/seen'], 'sender')
