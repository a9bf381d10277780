"""The messages a consumer never got, counted from their header sequence numbers (no ROS).

rospy numbers the messages a process publishes on a topic while any subscriber listens
(header.seq: one count per topic and process, whatever the connection), so a jump in the
numbers of one publisher's messages is what this consumer lost on the way, or missed
while others got it: in the publisher's queue, a socket, its own subscription queue, or
a connection re-made in between. A number that goes back to 1, or far back, is a
restarted publisher (or a looping bag): a new count, nothing lost. One that goes back a
little is a straggler (an old connection's last message, delivered after the new one's
first): ignored. roscpp keeps the number the message carries, so `rosbag play` shows the
recording's own gaps, and a publisher that leaves it 0 shows none.

A consumer that drops its connection on purpose (a late or silent stream re-made) loses
what the old one still held and what was sent while the new one formed: the first gap
after a re-connection is also counted apart (`missed_across_reconnect`), so what that
choice cost is told from losses with no such cause.
"""
import collections

# Further back than any subscription queue holds (hand_queue_size <= 2000): a new count.
RESTART_DROP = 4000


class SequenceGaps:
    def __init__(self):
        self.last = {}                          # per publisher: the last number seen
        self.missed = collections.Counter()     # per publisher: messages missed
        self.missed_across_reconnect = collections.Counter()   # ... of them, by a re-connection
        self._reconnected = set()               # publishers not heard since a re-connection

    def reconnected(self):
        """The consumer re-made its connection: each publisher's next gap is its cost."""
        self._reconnected = set(self.last)

    def add(self, publisher, seq):
        """One message from `publisher` numbered `seq`; returns how many were missed
        just before it."""
        last = self.last.get(publisher)
        if last is not None and seq <= last:
            if seq <= 1 or last - seq > RESTART_DROP:
                self.last[publisher] = seq          # a restarted publisher
                self._reconnected.discard(publisher)
            return 0                                # a repeat or an old connection's straggler
        self.last[publisher] = seq
        if last is None:
            return 0
        gap = seq - last - 1
        if gap:
            self.missed[publisher] += gap
            if publisher in self._reconnected:
                self.missed_across_reconnect[publisher] += gap
        self._reconnected.discard(publisher)
        return gap
