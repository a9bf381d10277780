"""When a consumer re-establishes its hand connection (control.stream_health), and a real
subscription doing it under a private master (ros.hand_subscription)."""
import json
import os
import subprocess
import sys

import pytest

from leap_teleop.control.sequence_gaps import RESTART_RUN, SequenceGaps
from leap_teleop.control.stream_health import RENEW_IN_PLACE_S, StreamHealth

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def feed(health, t0, t1, late, step=0.01, lag=0.6, growth=0.0):
    """Messages every `step` s from t0 to t1, each `lag` s old (+ growth per s)."""
    t = t0
    while t < t1:
        health.on_message(t, late, lag + growth * (t - t0))
        t += step


def test_on_time_input_never_asks():
    h = StreamHealth(0.5, 2.0)
    for k in range(1000):                     # asked after each message, as a node's timer does
        t = k * 0.01
        h.on_message(t, False, 0.6)
        assert h.due(t + 0.005, 1) is None


def test_late_input_asks_after_its_time_and_again_while_it_lasts():
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    assert h.due(1.0, 1) is None
    feed(h, 1.0, 1.4, late=True)
    assert h.due(1.4, 1) is None
    feed(h, 1.4, 1.5, late=True)
    why = h.due(1.5, 1)
    assert why and why.startswith('every message late for 0.5')
    h.resubscribed(1.5)
    feed(h, 1.5, 1.9, late=True)
    assert h.due(1.9, 1) is None
    feed(h, 1.9, 2.01, late=True)
    assert h.due(2.01, 1)
    h.resubscribed(2.01)
    # one message on time ends the streak
    feed(h, 2.01, 2.3, late=True)
    h.on_message(2.3, late=False)
    feed(h, 2.31, 2.7, late=True)
    assert h.due(2.7, 1) is None            # the streak began again at 2.31
    assert h.resubscriptions == 2


def test_late_input_is_judged_afresh_in_place_first_then_its_connection_is_remade():
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    feed(h, 1.0, 1.5, late=True)
    assert h.due(1.5, 1).startswith('every message late') and h.judge_in_place()
    h.judged_afresh(1.5)
    feed(h, 1.5, 1.9, late=True)            # late again on the same connection
    assert h.due(1.9, 1) is None
    feed(h, 1.9, 2.01, late=True)
    assert h.due(2.01, 1) and not h.judge_in_place()
    h.resubscribed(2.01)
    feed(h, 2.01, 2.6, late=True)           # a new connection: in place first again
    assert h.due(2.6, 1) and h.judge_in_place()
    assert (h.rejudgements, h.resubscriptions) == (1, 1)


def test_input_on_time_for_a_while_allows_another_judgement_in_place():
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    feed(h, 1.0, 1.5, late=True)
    assert h.due(1.5, 1) and h.judge_in_place()
    h.judged_afresh(1.5)
    # on time, but not for RENEW_IN_PLACE_S: a second steady lateness re-makes it
    feed(h, 1.5, 1.5 + RENEW_IN_PLACE_S - 1.0, late=False)
    t = 1.5 + RENEW_IN_PLACE_S - 1.0
    feed(h, t, t + 0.5, late=True)
    assert h.due(t + 0.5, 1) and not h.judge_in_place()
    # on time for RENEW_IN_PLACE_S (one late message restarts the count): in place again
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 0.5, late=True)
    assert h.due(0.5, 1) and h.judge_in_place()
    h.judged_afresh(0.5)
    feed(h, 0.5, 5.0, late=False)
    h.on_message(5.0, True, 0.6)
    feed(h, 5.01, 5.01 + RENEW_IN_PLACE_S - 0.1, late=False)
    t = 5.01 + RENEW_IN_PLACE_S - 0.1
    h.on_message(t, True, 0.6)
    assert h.rejudged
    feed(h, t + 0.01, t + 0.01 + RENEW_IN_PLACE_S + 0.02, late=False)
    t += 0.01 + RENEW_IN_PLACE_S + 0.02
    assert not h.rejudged
    feed(h, t, t + 0.5, late=True)
    assert h.due(t + 0.5, 1) and h.judge_in_place()
    h.judged_afresh(t + 0.5)
    assert (h.rejudgements, h.resubscriptions) == (2, 0)


def test_a_delay_that_is_not_steady_remakes_the_connection_at_once():
    # a backlog being delivered (each message less late than the last) or still building
    for growth in (-1.5, 0.5):
        h = StreamHealth(0.5, 2.0)
        feed(h, 0.0, 1.0, late=False)
        feed(h, 1.0, 1.5, late=True, lag=1.0, growth=growth)
        assert h.due(1.5, 1).startswith('every message late') and not h.judge_in_place()
    # unstamped input has no delay to judge: re-made as before
    h = StreamHealth(0.5, 2.0)
    for k in range(60):
        h.on_message(k * 0.01, True)
    assert h.due(0.6, 1) and not h.judge_in_place()


def test_silence_is_never_judged_in_place():
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    assert h.due(3.0, 1).startswith('no message') and not h.judge_in_place()
    # a late stream's re-made connection that brings nothing: re-made again, not judged
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=True)
    assert h.due(1.0, 1) and h.judge_in_place()
    h.judged_afresh(1.0)
    feed(h, 1.0, 1.6, late=True)
    assert h.due(1.6, 1) and not h.judge_in_place()
    h.resubscribed(1.6)
    assert h.due(3.7, 1).startswith('no message') and not h.judge_in_place()


def test_a_stall_of_the_consumer_itself_is_judged_afresh():
    # The node stood still 2 s (SIGSTOP): its first check after it must not take the
    # silence (nothing read yet) or the lateness for its input's fault.
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    feed(h, 1.0, 1.3, late=True)
    h.stalled(3.3)
    assert h.due(3.3, 1) is None
    feed(h, 3.3, 3.7, late=True)            # the backlog read: late, for less than 0.5 s
    assert h.due(3.7, 1) is None
    feed(h, 3.7, 3.81, late=True)           # still late 0.5 s after the stall: a backlog
    assert h.due(3.81, 1)
    h2 = StreamHealth(0.5, 2.0)
    feed(h2, 0.0, 1.0, late=False)
    h2.stalled(3.0)
    assert h2.due(4.9, 1) is None and h2.due(5.0, 1)   # silent 2 s from the stall on


def test_silence_after_input_asks_once_and_only_with_a_publisher():
    h = StreamHealth(0.5, 2.0)
    assert h.due(0.0, 1) is None and h.due(30.0, 1) is None    # never heard: a start-up wait
    feed(h, 30.0, 31.0, late=False)
    assert h.due(32.9, 1) is None
    assert h.due(33.5, 0) is None           # nobody publishes: nothing to re-establish
    why = h.due(33.5, 1)
    assert why and 'no message for 2.5 s' in why and '1 publisher is connected' in why
    h.resubscribed(33.5)
    assert h.due(60.0, 2) is None           # once per silence: a paused bag costs one line
    feed(h, 60.0, 61.0, late=False)         # the next silence asks again
    assert h.due(63.0, 1)
    assert h.resubscriptions == 1


def test_a_connection_remade_for_lateness_that_brings_nothing_is_remade_again():
    # Seen in a soak: input late under load, a re-subscription, then nothing for minutes.
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=True)
    assert h.due(1.0, 1)
    h.resubscribed(1.0)
    assert h.due(2.9, 1) is None
    why = h.due(3.0, 1)                     # connected: its publisher was sending
    assert why and 'after re-subscribing' in why
    h.resubscribed(3.0)
    assert h.due(6.9, 1) is None and h.due(7.0, 1)      # backing off: 2 s, 4 s, ...
    h.resubscribed(7.0)
    assert h.due(14.9, 1) is None and h.due(15.0, 1)
    h.resubscribed(15.0)
    assert h.due(30.9, 1) is None and h.due(31.0, 1)    # ... up to 8 x 2 s
    h.resubscribed(31.0)
    assert h.due(46.9, 1) is None and h.due(47.0, 1)
    h.resubscribed(47.0)
    feed(h, 47.5, 48.0, late=False)         # it delivers: judged as any connection
    assert h.due(49.9, 1) is None and h.due(50.0, 1)
    h.resubscribed(50.0)
    assert not h.wants_listing(50.4, 0) and h.wants_listing(50.5, 0)  # the back-off starts afresh


def test_a_connection_remade_for_silence_is_not_remade_again_while_connected():
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    assert h.due(3.0, 1)
    h.resubscribed(3.0)
    assert h.due(30.0, 1) is None           # connected and quiet: a paused bag, one line


def test_no_connected_publisher_while_the_master_lists_one_is_remade_with_back_off():
    # Seen in soaks: the publisher dropped a consumer's fresh connection and lived on.
    h = StreamHealth(0.5, 2.0)
    feed(h, 0.0, 1.0, late=False)
    assert not h.wants_listing(1.0, 1)
    assert not h.wants_listing(1.1, 0) and not h.wants_listing(1.5, 0)
    assert h.wants_listing(1.6, 0)          # 0.5 s without a connected publisher: ask
    assert h.due(1.6, 0, listed=0) is None  # nobody publishes (a sender stopped) ...
    assert not h.wants_listing(3.5, 0) and h.wants_listing(3.6, 0)   # ... ask in 2 s
    why = h.due(3.6, 0, listed=1)
    assert why == 'connected to none of the 1 publisher the master lists for 2.5 s', why
    h.resubscribed(3.6)
    assert not h.wants_listing(4.0, 0) and h.wants_listing(4.1, 0)
    assert h.due(4.1, 0, listed=2)          # the new one did not form either ...
    h.resubscribed(4.1)
    assert not h.wants_listing(5.0, 0) and h.wants_listing(5.1, 0)   # ... back off: 1 s
    assert h.due(5.1, 0) is None            # not asked, no verdict on the listing
    h.resubscribed(5.1)
    assert not h.wants_listing(5.2, 1) and h.due(5.2, 1) is None     # formed: no asking
    assert not h.wants_listing(8.0, 1)
    assert not StreamHealth(0.0, 2.0).wants_listing(100.0, 0)         # 0 = never


def test_zero_disables_and_a_clock_jump_back_starts_afresh():
    h = StreamHealth(0.0, 0.0)
    feed(h, 0.0, 5.0, late=True)
    assert h.due(5.0, 1) is None and h.due(50.0, 1) is None
    h = StreamHealth(0.5, 2.0)
    feed(h, 10.0, 11.0, late=True)
    assert h.due(11.0, 1)
    assert h.due(1.0, 1) is None            # a simulator restarted its /clock


CLIENT = r'''
import json, sys, time
import rospy
from leap_teleop.control.input_check import InputStream
from leap_teleop.msg import Hand
from leap_teleop.ros.hand_subscription import HandSubscription

rospy.init_node('stream_health_client')
stream = InputStream(max_age=0.25, gap=1.0)
refused, seqs = [], []

def judge(msg):
    seqs.append(msg.header.seq)
    why = stream.check(msg.header.stamp.to_sec(), rospy.get_time())
    refused.append(why is not None)
    return why

pub = rospy.Publisher('hands', Hand, queue_size=100, tcp_nodelay=True)
sub = HandSubscription('hands', Hand, judge, 'client',
                       {'resubscribe_after': 0.5, 'resubscribe_silent_after': 0.5,
                        'hand_queue_size': 5, 'hand_frame': 'leap_hands'}, stream.reset)
deadline = time.monotonic() + 20
while sub.sub.get_num_connections() == 0 and time.monotonic() < deadline:
    time.sleep(0.05)

def publish(secs, delay, growth=0.0):
    start = time.monotonic()
    end = start + secs
    while time.monotonic() < end:
        h = Hand(present=True)
        grown = growth * (time.monotonic() - start)
        h.header.stamp = rospy.Time.from_sec(rospy.get_time() - delay - grown)
        pub.publish(h)
        time.sleep(0.01)

out = {}
def phase(name, secs, delay=None, growth=0.0):
    before, judged = sub.health.resubscriptions, len(refused)
    afresh = sub.health.rejudgements
    if delay is None:
        time.sleep(secs)
    else:
        publish(secs, delay, growth)
    verdicts = refused[judged:]
    out[name] = {'resubscriptions': sub.health.resubscriptions - before,
                 'judged_afresh': sub.health.rejudgements - afresh,
                 'received': sum(sub.received.values()),
                 'connections': sub.sub.get_num_connections(),
                 'refused': sum(verdicts), 'accepted': len(verdicts) - sum(verdicts),
                 'tail_refused': sum(verdicts[-20:])}

phase('on_time', 1.5, 0.0)
pub.impl.seq += 5                # five messages numbered and lost before this subscriber
phase('late', 2.0, 0.6)          # every message 0.6 s late, as a standing backlog or a lagged
                                 # clock's baseline makes them look
phase('on_time_again', 1.5, 0.0)
phase('growing', 3.0, 0.0, growth=0.8)   # later and later: a backlog still building
phase('on_time_at_last', 1.0, 0.0)
phase('silent', 2.6)             # the publisher lives on, sends nothing
for c in pub.impl.connections:   # the publisher drops the connection and lives on
    c.close()
phase('dropped', 2.0, 0.0)
time.sleep(0.3)                  # the last messages in: counts and numbers read at rest
out['diagnostics'] = dict(sub.diagnostic_values())
out['seq_span'] = seqs[-1] - seqs[0] + 1     # what was sent from the first message on
print(json.dumps(out))
'''


@pytest.mark.integration
def test_a_subscription_reestablishes_late_or_silent_input_and_counts_what_it_got():
    from tools.bench.ros_processes import ros_master
    with ros_master() as env:
        proc = subprocess.run([sys.executable, '-c', CLIENT], env=env, cwd=ROOT, timeout=120,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out['on_time']['resubscriptions'] == 0 and out['on_time']['refused'] == 0, out
    # 2 s of late input: refused for 0.5 s, then judged afresh on the same connection: the
    # steady delay is its new baseline, so its messages are taken, and none is dropped
    assert out['late']['resubscriptions'] == 0 and out['late']['judged_afresh'] == 1, out
    assert 30 <= out['late']['refused'] <= 150, out    # 0.5 s and the 0.25 s check
    assert out['late']['accepted'] >= 30 and out['late']['tail_refused'] == 0, out
    assert out['late']['connections'] == 1, out
    # on time again: taken on the same connection, nothing re-made
    assert out['on_time_again']['resubscriptions'] == 0 and out['on_time_again']['refused'] == 0, out
    assert out['on_time_again']['received'] - out['late']['received'] > 100, out
    # a delay that keeps growing is no steady offset: the connection is re-made
    assert out['growing']['judged_afresh'] == 0 and out['growing']['resubscriptions'] >= 1, out
    assert out['on_time_at_last']['refused'] == 0 and out['on_time_at_last']['accepted'] > 50, out
    assert out['on_time_at_last']['resubscriptions'] == 0, out
    # 2.6 s of silence with the publisher connected: once, after 0.5 s
    assert out['silent']['resubscriptions'] == 1, out
    assert out['silent']['connections'] == 1, out
    # the publisher dropped the connection: nothing tells the subscriber, it finds no
    # connected publisher while the master lists one, and re-subscribes once
    assert out['dropped']['resubscriptions'] == 1, out
    assert out['dropped']['connections'] == 1, out
    assert out['dropped']['received'] - out['silent']['received'] > 50, out
    diag = out['diagnostics']
    assert diag['hand messages from /stream_health_client'] == diag['hand messages received']
    # What never came: the five numbered and never sent at least (and what the dropped
    # connection lost, if anything), and with what came, all sent from the first message on.
    missed = int(diag['hand messages missed from /stream_health_client'])
    assert missed == int(diag['hand messages missed (sequence gaps)']) >= 5, diag
    assert int(diag['hand messages received']) + missed == out['seq_span'], (diag, out)
    # the five lost before any re-subscription are not put down to one
    across = int(diag['hand messages missed across re-subscriptions'])
    assert 0 <= across <= missed - 5, diag
    assert int(diag['hand messages missed from /stream_health_client across re-subscriptions']) == across
    phases = ('on_time', 'late', 'on_time_again', 'growing', 'on_time_at_last', 'silent',
              'dropped')
    assert int(diag['hand re-subscriptions']) == sum(out[k]['resubscriptions'] for k in phases)
    assert int(diag['hand input judged afresh on its connection']) == sum(
        out[k]['judged_afresh'] for k in phases)
    err = proc.stderr
    assert 'client: judging the input on /hands afresh on its connection (every message late' in err
    assert err.index('judging the input on /hands afresh') < err.index(
        're-subscribed to /hands (every message late'), err[-3000:]
    assert 'client: re-subscribed to /hands (every message late for' in proc.stderr, proc.stderr[-3000:]
    assert ('client: re-subscribed to /hands (connected to none of the 1 publisher the master '
            'lists for') in proc.stderr, proc.stderr[-3000:]


def test_hand_messages_in_another_frame_are_refused_with_a_throttled_warning(monkeypatch):
    # Positions in another frame would be read as Leap coordinates: the arm would jump.
    import collections
    import threading

    import rospy

    from leap_teleop.msg import Hand
    from leap_teleop.ros import hand_subscription as hs

    taken, logs = [], []
    sub = hs.HandSubscription.__new__(hs.HandSubscription)
    sub.topic, sub.node, sub._lock = 'hands', 'ur10_arm', threading.Lock()
    sub.health = StreamHealth(0.5, 2.0)
    sub.gaps = SequenceGaps()
    sub.received = collections.Counter()
    sub.callback = lambda msg: taken.append(msg.header.frame_id)
    sub.frame, sub.wrong_frame = 'leap_hands', 0
    monkeypatch.setattr(rospy, 'get_time', lambda: 10.0)
    monkeypatch.setattr(rospy, 'resolve_name', lambda name: '/' + name)
    monkeypatch.setattr(rospy, 'logwarn_throttle', lambda period, text: logs.append((period, text)))
    for seq, frame in enumerate(['leap_hands', '', '/leap_hands', 'world', 'world', 'base_link']):
        msg = Hand()
        msg.header.seq, msg.header.frame_id = seq, frame
        msg.header.stamp = rospy.Time.from_sec(10.0)
        sub._on_message(msg)
    assert taken == ['leap_hands', '', '/leap_hands'] and sub.wrong_frame == 3
    assert sum(sub.received.values()) == 6          # refused ones were received all the same
    assert all(period >= 1.0 for period, _ in logs) and len(logs) == 3   # rospy throttles them
    assert logs[0][1] == ("ur10_arm: refused hand messages on /hands in frame 'world': this "
                          "node reads frame 'leap_hands' (set ~hand_frame to the sender's "
                          "~frame_id, or '' for any)")
    values = dict(sub.diagnostic_values())
    assert values['hand messages refused for their frame'] == '3'
    sub.frame = ''                                   # '' takes any frame
    msg = Hand()
    msg.header.frame_id = 'world'
    sub._on_message(msg)
    assert taken[-1] == 'world'


def test_the_old_subscribers_messages_are_not_current_from_the_re_subscription_on(monkeypatch):
    # The number went up only when the new Subscriber was made, after the consumer's reset
    # (which waits for its lock): the old read's messages in between took the new
    # connection's gap as an ordinary loss.
    import collections
    import threading

    import rospy

    from leap_teleop.msg import Hand
    from leap_teleop.ros import hand_subscription as hs

    sub = hs.HandSubscription.__new__(hs.HandSubscription)
    sub.topic, sub.node, sub._lock, sub._generation = 'hands', 'client', threading.Lock(), 1
    sub.health, sub.gaps = StreamHealth(0.5, 2.0), SequenceGaps()
    sub.received, sub.callback, sub.frame, sub.wrong_frame = collections.Counter(), lambda m: None, '', 0
    monkeypatch.setattr(rospy, 'get_time', lambda: 10.0)

    def deliver(seq, generation):
        msg = Hand()
        msg.header.seq, msg.header.stamp = seq, rospy.Time.from_sec(10.0)
        sub._on_message(msg, generation)
    for seq in range(1, 11):
        deliver(seq, 1)
    sub._reconnected()
    deliver(12, 1)                       # the old read, handled before the new Subscriber exists
    deliver(30, 2)                       # the new connection's first message
    assert dict(sub.gaps.missed) == {'?': 18} and dict(sub.gaps.missed_across_reconnect) == {'?': 17}


def test_a_check_that_fails_is_logged_and_the_next_one_finishes_the_resubscription(monkeypatch):
    # An exception in a check would end its timer's thread: no later check would run.
    import rospy

    from leap_teleop.ros import hand_subscription as hs

    class FakeSubscriber:
        def __init__(self):
            self.closed = False

        def get_num_connections(self):
            return 1

        def unregister(self):
            self.closed = True

    import threading
    sub = hs.HandSubscription.__new__(hs.HandSubscription)
    sub.topic, sub.node, sub._lock = 'hands', 'client', threading.Lock()
    sub.health = StreamHealth(0.5, 2.0)
    sub.gaps = SequenceGaps()
    sub.check_period, sub._last_check, sub._generation = 0.25, None, 1
    first = sub.sub = FakeSubscriber()
    made, logs = [], []

    def fail():
        raise RuntimeError('master unreachable')
    sub.on_new_connection = fail
    monkeypatch.setattr(sub, '_subscribe', lambda: made.append(FakeSubscriber()) or made[-1])
    monkeypatch.setattr(rospy, 'get_time', lambda: 10.0)
    monkeypatch.setattr(rospy, 'resolve_name', lambda name: '/' + name)
    monkeypatch.setattr(rospy, 'logerr_throttle', lambda period, text: logs.append(text))
    monkeypatch.setattr(rospy, 'logwarn', lambda *a: logs.append(a[0] % a[1:]))
    sub.health.judged_afresh(8.0)              # late once already: now re-made
    feed(sub.health, 8.0, 9.9, late=True)
    sub._check()                               # due, unregistered, then the failure
    assert first.closed and sub.sub is None and not made
    assert 'checking the connection to /hands failed: master unreachable' in logs[-1]
    sub._check()                               # the next check subscribes afresh
    assert len(made) == 1 and sub.sub is made[0]
    assert logs[-1] == 'client: re-subscribed to /hands'


def test_a_check_long_after_the_last_one_judges_afresh_instead_of_resubscribing(monkeypatch):
    # A subscription whose node was stopped 2 s: the first check after it finds "no
    # message for 2 s" but must not re-subscribe (the backlog is in the old connection).
    import threading

    import rospy

    from leap_teleop.ros import hand_subscription as hs

    class Connected:
        def get_num_connections(self):
            return 1

        def unregister(self):
            raise AssertionError('re-subscribed after a stall of its own node')

    sub = hs.HandSubscription.__new__(hs.HandSubscription)
    sub.topic, sub.node, sub._lock = 'hands', 'client', threading.Lock()
    sub.health = StreamHealth(0.5, 2.0)
    sub.gaps = SequenceGaps()
    sub.check_period, sub.sub = 0.25, Connected()
    monkeypatch.setattr(rospy, 'get_time', lambda: 12.5)
    feed(sub.health, 0.0, 10.0, late=False)
    sub._last_check = 10.5                      # the last check, 2 s of ROS time before
    sub._check_once()
    assert sub.health.since == 12.5 and sub.health.resubscriptions == 0
    monkeypatch.setattr(rospy, 'get_time', lambda: 13.0)
    sub._check_once()                           # a check on time: nothing due yet
    assert sub.health.resubscriptions == 0


def test_sequence_gaps_count_what_each_publisher_sent_that_never_came():
    gaps = SequenceGaps()
    assert [gaps.add('/player', s) for s in (7, 8, 9, 12, 13)] == [0, 0, 0, 2, 0]
    assert [gaps.add('/other', s) for s in (1, 3)] == [0, 1]   # counted per publisher
    assert gaps.add('/player', 1) == 0          # back to 1: a restarted publisher
    assert gaps.add('/player', 5) == 3
    assert dict(gaps.missed) == {'/player': 5, '/other': 1} and sum(gaps.missed.values()) == 6
    assert gaps.add('/player', 5) == 0 and sum(gaps.missed.values()) == 6   # a repeat is no loss
    # An old connection's last message after the new one's first: a straggler, ignored
    # (taken as a restart, it would count the numbers between again).
    assert [gaps.add('/player', s) for s in (9, 8, 10)] == [3, 0, 0] and sum(gaps.missed.values()) == 9
    assert gaps.add('/player', 5010) == 4999
    assert gaps.add('/player', 20) == 0 and gaps.add('/player', 22) == 1   # far back: a restart


def test_a_short_bag_looping_from_above_1_is_counted_on_every_pass():
    # A bag recorded after the sender started keeps its numbers (here 5000..7999) and loops
    # back only 3000: each later pass was taken as stragglers and its losses never counted.
    gaps = SequenceGaps()
    lost = set(range(6000, 6100))
    for _ in range(3):
        for seq in range(5000, 8000):
            if seq not in lost or _ != 1:
                gaps.add('/play', seq)
    assert gaps.missed['/play'] == 100
    # An old connection's stragglers among the new one's, however many, stay ignored.
    gaps = SequenceGaps()
    for seq in range(100, 200):
        gaps.add('/pub', seq)
    assert [gaps.add('/pub', s) for s in range(150, 150 + RESTART_RUN - 1)] == [0] * (RESTART_RUN - 1)
    assert gaps.add('/pub', 200) == 0 and gaps.add('/pub', 190) == 0 and gaps.add('/pub', 201) == 0
    assert gaps.missed['/pub'] == 0 and gaps.last['/pub'] == 201


def test_a_looping_bags_pass_goes_on_through_a_dropped_connections_last_read():
    # A bag looping from 1001: a re-subscription within the first RESTART_RUN messages of a
    # pass left the old read's rest out of the pass's run, and counted it lost.
    gaps = SequenceGaps()
    for seq in range(1001, 1121):
        gaps.add('/play', seq)
    for seq in range(1001, 1029):                 # the next pass, then a re-subscription
        gaps.add('/play', seq)
    gaps.reconnected()
    for seq in range(1029, 1052):                 # the old read's rest arrives
        gaps.add('/play', seq, current=False)
    for seq in range(1081, 1121):                 # the new connection: 1052..1080 never came
        gaps.add('/play', seq)
    assert gaps.missed['/play'] == 29


@pytest.mark.parametrize('steps, lost', [
    # the new connection's first message before the old read's rest: 1063..1100 never came
    ([('new', range(1001, 1049)), ('R', None), ('new', [1101]), ('old', range(1049, 1063)),
      ('new', range(1102, 1121))], 38),
    # the old read's rest crossing the loop, then the new connection: 1011..1039 never came
    ([('new', range(1001, 1100)), ('R', None),
      ('old', list(range(1100, 1121)) + list(range(1001, 1011))), ('new', range(1040, 1121))], 29)])
def test_a_looping_bag_re_subscribed_counts_what_never_came_whatever_the_order(steps, lost):
    gaps = SequenceGaps()
    for seq in range(1001, 1121):
        gaps.add('/play', seq)
    for kind, seqs in steps:
        if kind == 'R':
            gaps.reconnected()
            continue
        for seq in seqs:
            gaps.add('/play', seq, kind == 'new')
    for seq in range(1001, 1061):                 # one more pass: a pending run completes
        gaps.add('/play', seq)
    assert gaps.missed['/play'] == lost


def test_a_dropped_connections_last_read_is_never_a_restart_nor_the_new_ones_cost():
    # rospy hands on the rest of a dropped connection's last read (up to hand_queue_size
    # messages): 50 of them in a row were taken as a restarted publisher (counting the
    # numbers between again), and one arriving first took the re-connection's gap.
    gaps = SequenceGaps()
    for seq in range(1, 201):
        gaps.add('/pub', seq)
    gaps.reconnected()
    assert gaps.add('/pub', 203, current=False) == 2           # the old read's own loss
    assert gaps.add('/pub', 400) == 196                         # the new connection's first
    old = range(204, 204 + 3 * RESTART_RUN)                     # the old read's rest: late, not
    assert [gaps.add('/pub', s, current=False) for s in old] == [0] * len(old)   # a restart
    assert gaps.add('/pub', 401) == 0 and gaps.last['/pub'] == 401
    assert gaps.add('/pub', 204, current=False) == 0            # twice is once
    assert dict(gaps.missed) == {'/pub': 198 - len(old)}
    assert dict(gaps.missed_across_reconnect) == {'/pub': 196 - len(old)}


def test_a_gap_across_a_reconnection_is_counted_apart_once():
    gaps = SequenceGaps()
    assert [gaps.add('/player', s) for s in (1, 2, 5)] == [0, 0, 2]   # no re-connection: a loss
    gaps.add('/other', 1)
    gaps.reconnected()
    # the old connection's straggler clears nothing; the new connection's first message
    # shows what the re-connection cost, and only that first gap counts as its cost
    assert [gaps.add('/player', s) for s in (4, 9, 12)] == [0, 3, 2]
    assert gaps.add('/other', 2) == 0                # nothing lost from this one
    assert gaps.add('/other', 4) == 1                # a later gap is no re-connection's
    assert dict(gaps.missed) == {'/player': 7, '/other': 1}
    assert dict(gaps.missed_across_reconnect) == {'/player': 3}
    gaps.reconnected()
    assert gaps.add('/player', 1) == 0 and gaps.add('/player', 3) == 1   # restarted: a new count
    assert dict(gaps.missed_across_reconnect) == {'/player': 3}
    gaps.reconnected()
    assert gaps.add('/new', 10) == 0 and gaps.add('/new', 12) == 1   # unknown before it
    assert dict(gaps.missed_across_reconnect) == {'/player': 3}


def test_diagnostics_list_the_newest_publishers_and_count_them_all():
    # Each `rosbag play` is a new anonymous publisher: a node that outlives a hundred
    # replays listed three lines for each in every report.
    import collections
    import threading

    from leap_teleop.ros import hand_subscription as hs

    sub = hs.HandSubscription.__new__(hs.HandSubscription)
    sub._lock, sub.wrong_frame = threading.Lock(), 0
    sub.health = StreamHealth(0.5, 2.0)
    sub.gaps = SequenceGaps()
    sub.received = collections.Counter()
    for k in range(100):
        caller = '/play_%03d' % k
        sub.received[caller] += 10
        for seq in (1, 2, 4):                   # one missed each
            sub.gaps.add(caller, seq)
    values = dict(sub.diagnostic_values())
    assert values['hand messages received'] == '1000'
    assert values['hand messages missed (sequence gaps)'] == '100'
    listed = sorted(k[len('hand messages from '):] for k in values
                    if k.startswith('hand messages from '))
    assert listed == ['/play_%03d' % k for k in range(96, 100)]
