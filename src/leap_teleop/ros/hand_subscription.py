"""A consumer's hand-input subscription: counts what arrives and what went missing (header
sequence gaps) per publisher; when its input stays late, judges it afresh on the same
connection, then re-establishes the connection if it stays late; re-establishes it too when
it falls silent while a publisher is connected, or loses every publisher the master still
lists (control.stream_health says when)."""
import collections
import threading

import rosgraph
import rospy

from leap_teleop.control.sequence_gaps import SequenceGaps
from leap_teleop.control.stream_health import StreamHealth

# Checks missed in a row that mean the node itself stalled, not its input.
STALL_CHECKS = 4
LISTED_PUBLISHERS = 4       # per-publisher counts on /diagnostics (the totals count every one)


class HandSubscription:
    def __init__(self, topic, msg_type, callback, node, p, on_new_connection,
                 check_period=0.25):
        """callback(msg) returns why the message was refused (None if it was not); a
        reason starting with 'late' counts against the connection. p: the node's params
        (HAND_SUBSCRIPTION_PARAMS: queue size, when to re-subscribe). on_new_connection()
        is called after each re-subscription, and to judge a late stream afresh on its
        connection: the consumer forgets the stream's latency baseline."""
        self.topic, self.msg_type, self.callback = topic, msg_type, callback
        self.on_new_connection = on_new_connection
        self.node, self.queue_size = node, int(p['hand_queue_size'])
        self.frame = p['hand_frame'].lstrip('/')     # tf1 names may start with '/'
        self.wrong_frame = 0                           # messages refused for their frame
        self.health = StreamHealth(p['resubscribe_after'], p['resubscribe_silent_after'])
        self.received = collections.Counter()          # per publisher (caller id)
        self.gaps = SequenceGaps()                     # what each publisher sent that never came
        self._lock = threading.Lock()
        self.check_period = float(check_period)
        self._last_check = None                        # ROS time of the last check
        self._generation = 1                           # of the current Subscriber
        self.sub = self._subscribe()
        # Its own timer thread: a re-subscription talks to the master and may block; no
        # watchdog of the node shares this thread. reset: a /clock that jumps back (a
        # restarted simulator) would otherwise end the timer's thread.
        self.timer = (rospy.Timer(rospy.Duration.from_sec(check_period), self._check, reset=True)
                      if self.health.after > 0 or self.health.silent_after > 0 else None)

    def _subscribe(self):
        # Numbered: a dropped connection's last read still reaches the callback afterwards.
        return rospy.Subscriber(self.topic, self.msg_type, self._on_message,
                                callback_args=self._generation, queue_size=self.queue_size,
                                tcp_nodelay=True)

    def _on_message(self, msg, generation=None):
        caller = (getattr(msg, '_connection_header', None) or {}).get('callerid', '?')
        self.received[caller] += 1
        frame = msg.header.frame_id.lstrip('/')
        if self.frame and frame and frame != self.frame:
            # positions in another frame would be read as Leap coordinates: a jump
            with self._lock:            # one callback thread per publisher's connection
                self.wrong_frame += 1
            why = 'frame %r, not %r' % (msg.header.frame_id, self.frame)
            rospy.logwarn_throttle(5.0, '%s: refused hand messages on %s in frame %r: this node '
                                   'reads frame %r (set ~hand_frame to the sender\'s ~frame_id, '
                                   'or \'\' for any)' % (self.node, rospy.resolve_name(self.topic),
                                                        msg.header.frame_id, self.frame))
        else:
            why = self.callback(msg)
        now = rospy.get_time()
        with self._lock:                 # one hold per message: this is every hand message
            self.gaps.add(caller, msg.header.seq, generation is None or generation == self._generation)
            self.health.on_message(now, bool(why) and why.startswith('late'),
                                   now - msg.header.stamp.to_sec())

    def _check(self, _event=None):
        # An exception would end the timer's thread, and every later check with it.
        try:
            self._check_once()
        except Exception as e:   # noqa: BLE001 - logged; the next check tries again
            rospy.logerr_throttle(5.0, '%s: checking the connection to %s failed: %s'
                                  % (self.node, rospy.resolve_name(self.topic), e))

    def _check_once(self):
        # ROS time, as the timer's period: a simulation slower than real time is no stall
        now, last = rospy.get_time(), self._last_check
        self._last_check = now
        if last is not None and now - last > STALL_CHECKS * self.check_period:
            # This process stood still (SIGSTOP, starved): the receive thread has not read
            # what piled up yet, and re-subscribing now would lose it.
            with self._lock:
                self.health.stalled(now)
            return
        if self.sub is None:         # a re-subscription that failed half-way: finish it
            self._reconnected()
            self.sub = self._subscribe()
            rospy.logwarn('%s: re-subscribed to %s', self.node, rospy.resolve_name(self.topic))
            return
        publishers = self.sub.get_num_connections()
        with self._lock:
            ask = self.health.wants_listing(now, publishers)
        # Outside the lock: the master may be slow, the message callback must not wait.
        listed = self._listed_publishers() if ask else None
        with self._lock:
            why = self.health.due(now, publishers, listed)
            if why is None:
                return
            in_place = self.health.judge_in_place()
            if in_place:
                self.health.judged_afresh(now)
            else:
                self.health.resubscribed(now)
        if in_place:
            # Nothing dropped: a baseline taken while this node's clock lagged is healed;
            # late again on this connection, it is re-made.
            self.on_new_connection()
            rospy.logwarn('%s: judging the input on %s afresh on its connection (%s)', self.node,
                          rospy.resolve_name(self.topic), why)
            return
        # Unregister first: a second Subscriber on the same topic would share the old
        # connections instead of making new ones.
        old, self.sub = self.sub, None
        old.unregister()
        self._reconnected()
        self.on_new_connection()
        self.sub = self._subscribe()
        rospy.logwarn('%s: re-subscribed to %s (%s)', self.node, rospy.resolve_name(self.topic), why)

    def _reconnected(self):
        # Before anything that may wait (the consumer's lock): from here on the old
        # Subscriber's messages are not current, and the next gap is the new connection's.
        with self._lock:
            self._generation += 1
            self.gaps.reconnected()

    def _listed_publishers(self):
        """How many publishers the master lists for the topic."""
        topic = rospy.resolve_name(self.topic)
        state = rosgraph.Master(rospy.get_name()).getSystemState()
        return sum(len(nodes) for name, nodes in state[0] if name == topic)

    def diagnostic_values(self):
        counts = dict(self.received)        # a copy: the callback thread adds publishers
        with self._lock:
            missed = dict(self.gaps.missed)
            across = dict(self.gaps.missed_across_reconnect)
        values = [('hand messages received', str(sum(counts.values()))),
                  ('hand messages missed (sequence gaps)', str(sum(missed.values()))),
                  ('hand messages missed across re-subscriptions', str(sum(across.values())))]
        # The newest publishers only: each `rosbag play` is a new anonymous one, and a
        # node that outlives many would carry them all in every report.
        for caller in sorted(list(counts)[-LISTED_PUBLISHERS:]):
            n = counts[caller]
            values += [('hand messages from %s' % caller, str(n)),
                       ('hand messages missed from %s' % caller, str(missed.get(caller, 0))),
                       ('hand messages missed from %s across re-subscriptions' % caller,
                        str(across.get(caller, 0)))]
        return values + [('hand messages refused for their frame', str(self.wrong_frame)),
                         ('hand re-subscriptions', str(self.health.resubscriptions)),
                         ('hand input judged afresh on its connection',
                          str(self.health.rejudgements))]
