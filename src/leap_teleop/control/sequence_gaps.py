"""The messages a consumer never got, counted from their header sequence numbers (no ROS).

rospy numbers the messages a process publishes on a topic while any subscriber listens
(header.seq: one count per topic and process, whatever the connection), so a jump in the
numbers of one publisher's messages is what this consumer lost on the way, or missed
while others got it: in the publisher's queue, a socket, its own subscription queue, or
a connection re-made in between. A number that goes back to 1, or far back, is a
restarted publisher (or a looping bag): a new count, nothing lost. One that goes back a
little is a straggler (an old connection's last message, delivered after the new one's
first): ignored, unless RESTART_RUN numbers climb on from it with none beyond the last
(a short bag looping from above 1): then that was a restart, and the count goes on from
there. roscpp keeps the number the message carries, so `rosbag play` shows the
recording's own gaps, and a publisher that leaves it 0 shows none.

A consumer that drops its connection on purpose (a late or silent stream re-made) loses
what the old one still held and what was sent while the new one formed: the first gap
after a re-connection is also counted apart (`missed_across_reconnect`), so what that
choice cost is told from losses with no such cause. The old connection's last read may
still come (add(..., current=False)): before the new connection's first message it is
the stream in its own order; after it, what of it falls in a gap already counted is
taken off again, and it starts no restart (it may go on with a looping bag's pass that
one of its own numbers began).
"""
import collections

# Further back than any subscription queue holds (hand_queue_size <= 2000): a new count.
RESTART_DROP = 4000
# Numbers climbing this long below the last, with no newer one between (0.4 s at 120 Hz):
# a new count, not stragglers (an old connection's few, among the new one's).
RESTART_RUN = 50


class SequenceGaps:
    def __init__(self):
        self.last = {}                          # per publisher: the last number seen
        self.missed = collections.Counter()     # per publisher: messages missed
        self.missed_across_reconnect = collections.Counter()   # ... of them, by a re-connection
        self._reconnected = set()               # publishers not heard since a re-connection
        self._back = {}                         # per publisher: (length, last, gaps) of a run below last
        self._heard_new = set()                 # publishers heard on the new connection
        self._run_hole = {}                     # per publisher: (numbers, those come late) of a run's jump
        self._hole = {}                         # per publisher: (numbers, those come late) of the
                                                # last gap across a re-connection

    def reconnected(self):
        """The consumer re-made its connection: each publisher's next gap is its cost."""
        self._reconnected = set(self.last)
        self._heard_new = set()

    def add(self, publisher, seq, current=True):
        """One message from `publisher` numbered `seq`; returns how many were missed
        just before it. current=False: delivered by a connection the consumer has dropped
        (rospy hands on the rest of its last read, hundreds of messages): it leaves the
        next gap to the new connection, and once that one has spoken an older number is a
        straggler (or goes on with a looping pass under way)."""
        last = self.last.get(publisher)
        if current:
            self._heard_new.add(publisher)
        if last is not None and seq <= last:
            if not current and publisher in self._heard_new:    # a straggler
                run = self._back.get(publisher)
                if run is not None and seq > run[1]:
                    return self._below_last(publisher, seq)     # a looping bag's pass goes on
                hole = self._run_hole.get(publisher)
                if run is not None and hole is not None and seq in hole[0] and seq not in hole[1]:
                    hole[1].add(seq)
                    self._back[publisher] = (run[0], run[1], run[2] - 1)
                    return 0
                self._filled(publisher, seq)
                return 0
            if seq <= 1 or last - seq > RESTART_DROP:
                self._restart(publisher, seq)
                return 0
            return self._below_last(publisher, seq)   # a repeat, a straggler or a restart
        self._back.pop(publisher, None)
        self._run_hole.pop(publisher, None)
        self.last[publisher] = seq
        if last is None:
            return 0
        gap = seq - last - 1
        if gap:
            self.missed[publisher] += gap
            if current and publisher in self._reconnected:
                self.missed_across_reconnect[publisher] += gap
                self._hole[publisher] = (range(last + 1, seq), set())
        if current:
            self._reconnected.discard(publisher)
        return gap

    def _filled(self, publisher, seq):
        """The old connection's message came after all: not missed."""
        hole = self._hole.get(publisher)
        if hole is not None and seq in hole[0] and seq not in hole[1]:
            hole[1].add(seq)
            self.missed[publisher] -= 1
            self.missed_across_reconnect[publisher] -= 1

    def _restart(self, publisher, seq):
        self.last[publisher] = seq
        self._reconnected.discard(publisher)
        self._back.pop(publisher, None)
        self._run_hole.pop(publisher, None)
        self._hole.pop(publisher, None)

    def _below_last(self, publisher, seq):
        run = self._back.get(publisher)
        if run is None or seq <= run[1]:
            self._back[publisher] = (1, seq, 0)
            return 0
        length, prev, gaps = run[0] + 1, seq, run[2] + seq - run[1] - 1
        if seq - run[1] > 1:
            self._run_hole[publisher] = (range(run[1] + 1, seq), set())
        if length < RESTART_RUN:
            self._back[publisher] = (length, prev, gaps)
            return 0
        self._restart(publisher, seq)
        self.missed[publisher] += gaps          # what the run skipped was lost
        return gaps
