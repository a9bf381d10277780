"""Questions a node asks about the ROS graph."""
import collections
import threading
import time

import rosgraph
import rospy


def wait_for_subscribers(own, topics, who, log_every=5.0, warn_after=30.0):
    """Block until every topic in `topics` (resolved names) has a subscriber; False on
    shutdown. `own` maps this node's resolved topic names to its publishers: those count
    once connected, any other topic once the master lists a subscriber. Logs what it
    waits for every `log_every` s, prefixed by `who`; after `warn_after` s as a warning
    that asks whether the reader runs (one that refused a parameter has ended, and its
    launch goes on without it)."""
    master = rosgraph.Master(rospy.get_name())
    last_log = start = rospy.get_time()
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
        now = rospy.get_time()
        if now - last_log >= log_every:
            last_log = now
            if now - start >= warn_after:
                rospy.logwarn('%s: still no subscriber on %s after %.0f s: is the node that '
                              'reads it running? (one that refused a parameter has ended: see '
                              'its FATAL line)', who, ', '.join(waiting), now - start)
            else:
                rospy.loginfo('%s: waiting for subscribers on %s', who, ', '.join(waiting))
        try:
            rospy.sleep(0.05)
        except rospy.ROSTimeMovedBackwardsException:
            # /clock jumped back (a simulator started again): wait on, the time waited kept
            back = now - rospy.get_time()
            start, last_log = start - back, last_log - back
        except rospy.ROSInterruptException:     # shut down while sim time waits: no traceback
            return False
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


WatchedTopic = collections.namedtuple('WatchedTopic', 'topic want reader hint')


class TopicTypeWatch:
    """Says so when a topic a node reads carries another type than it reads: rospy drops
    such a connection with no word to the subscriber. One per node: it asks the master
    every `period` s, once for all its topics, on a rospy.Timer thread of its own (the
    lookup blocks); warns through `log` (a RateLimitedLog, keyed per topic)
    'WHO: TOPIC carries GOT, but READER reads WANT: HINT'."""

    def __init__(self, who, log, period=5.0):
        self.who, self.log = who, log
        self.topics = ()        # WatchedTopic; replaced whole, never changed in place
        # reset: a /clock that jumps back (a looped bag) would otherwise end the timer's thread
        self.timer = rospy.Timer(rospy.Duration(period), self.check, reset=True)

    def add(self, topic, msg_type, reader, hint):
        """Watch `topic`, read as `msg_type` by `reader` (words for the warning)."""
        self.topics += (WatchedTopic(rospy.resolve_name(topic), msg_type._type, reader, hint),)
        return self

    def subscribe(self, topic, msg_type, callback, reader, hint, **kwargs):
        """A rospy.Subscriber of `topic`, watched."""
        self.add(topic, msg_type, reader, hint)
        return rospy.Subscriber(topic, msg_type, callback, **kwargs)

    def check(self, _event=None):
        """{topic: the type the master lists for it, None without a publisher}; {} when the
        master does not answer."""
        topics = self.topics
        try:
            published = dict(rospy.get_published_topics())
        except Exception as e:      # the master gone or busy: try again next period
            self.log.warn('type_check', '%s: cannot ask the master for the types of %s: %s',
                          self.who, ', '.join(w.topic for w in topics), e)
            return {}
        for w in topics:
            got = published.get(w.topic)
            if got is not None and got != w.want:
                self.log.warn('type_check:' + w.topic, '%s: %s carries %s, but %s reads %s: %s',
                              self.who, w.topic, got, w.reader, w.want, w.hint)
        return {w.topic: published.get(w.topic) for w in topics}


class ClockRivalWatch:
    """Logs one error per other node that publishes /clock beside a simulator that is the
    clock under /use_sim_time (a bag played with --clock, another simulator): ROS time then
    jumps between the two and nothing that waits on it moves, with no other word of the
    cause. Asks the master every `period` wall s on a thread of its own: the lookup blocks,
    and it must never hold the physics loop."""

    def __init__(self, who, period=2.0, start=True):
        self.who, self.period = who, period
        self.reported = set()
        self._stop = threading.Event()
        self.thread = None
        if start:
            self.thread = threading.Thread(target=self._run, name='clock_rival_watch', daemon=True)
            self.thread.start()

    def check(self):
        """The other /clock publishers not reported before (each is logged once)."""
        me = rospy.get_name()
        clock = rospy.resolve_name('/clock')    # where this node's clock goes (remapped or not)
        try:
            published = rosgraph.Master(me).getSystemState()[0]
        except Exception:       # the master gone or busy: ask again next period
            return []
        new = sorted({n for topic, nodes in published if topic == clock
                      for n in nodes if n != me} - self.reported)
        if new:
            self.reported.update(new)
            rospy.logerr('%s: %s also publish%s %s: under /use_sim_time this simulator is the '
                         'clock, so ROS time jumps between the two and the robots do not move; run '
                         'the other without a clock (replay.launch: leave use_sim_time false)',
                         self.who, ', '.join(new), 'es' if len(new) == 1 else '', clock)
        return new

    def _run(self):
        while not self._stop.wait(self.period) and not rospy.is_shutdown():
            self.check()

    def stop(self):
        self._stop.set()
