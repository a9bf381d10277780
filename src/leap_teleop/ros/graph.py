"""Questions a node asks about the ROS graph."""
import time

import rosgraph
import rospy


def wait_for_subscribers(own, topics, who, log_every=5.0):
    """Block until every topic in `topics` (resolved names) has a subscriber; False on
    shutdown. `own` maps this node's resolved topic names to its publishers: those count
    once connected, any other topic once the master lists a subscriber. Logs what it
    waits for every `log_every` s, prefixed by `who`."""
    master = rosgraph.Master(rospy.get_name())
    last_log = rospy.get_time()
    while not rospy.is_shutdown():
        others = [t for t in topics if t not in own]
        listened = set()
        if others:
            try:
                listened = {t for t, nodes in master.getSystemState()[1] if nodes}
            except (rosgraph.MasterError, OSError):
                pass
        waiting = [t for t in topics if (own[t].get_num_connections() == 0 if t in own
                                         else t not in listened)]
        if not waiting:
            return True
        if rospy.get_time() - last_log >= log_every:
            last_log = rospy.get_time()
            rospy.loginfo('%s: waiting for subscribers on %s', who, ', '.join(waiting))
        rospy.sleep(0.05)
    return False


def wait_for_first_message(seen, topic, who, log_every=5.0):
    """Block until `seen` (a threading.Event the subscriber of `topic` sets) is set; False
    on shutdown. Logs 'who: waiting for TOPIC' every `log_every` s (wall time: the clock
    may not run yet)."""
    last_log = time.monotonic()
    while not seen.wait(0.2):
        if rospy.is_shutdown():
            return False
        if time.monotonic() - last_log >= log_every:
            last_log = time.monotonic()
            rospy.loginfo('%s: waiting for %s', who, rospy.resolve_name(topic))
    return True


class TopicTypeWatch:
    """Says so when `topic` carries another type than `msg_type`: rospy drops such a
    connection with no word to the subscriber. Asks the master every `period` s on a
    rospy.Timer thread of its own (the lookup blocks); warns through `log` (a
    RateLimitedLog) 'WHO: TOPIC carries GOT, but READER reads WANT: HINT'."""

    def __init__(self, topic, msg_type, who, reader, hint, log, period=5.0):
        self.topic, self.want = rospy.resolve_name(topic), msg_type._type
        self.who, self.reader, self.hint, self.log = who, reader, hint, log
        self.timer = rospy.Timer(rospy.Duration(period), self.check)

    def check(self, _event=None):
        """The type the master lists for the topic (None: no publisher, or no answer)."""
        try:
            published = dict(rospy.get_published_topics())
        except Exception as e:      # the master gone or busy: try again next period
            self.log.warn('type_check:' + self.topic, '%s: cannot ask the master for %s: %s',
                          self.who, self.topic, e)
            return None
        got = published.get(self.topic)
        if got is not None and got != self.want:
            # keyed by topic: watches of one node's several inputs share its log
            self.log.warn('type_check:' + self.topic, '%s: %s carries %s, but %s reads %s: %s',
                          self.who, self.topic, got, self.reader, self.want, self.hint)
        return got
