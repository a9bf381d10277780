"""The messages a consumer never got, counted from their header sequence numbers (no ROS).

rospy numbers the messages a process publishes on a topic while any subscriber listens
(header.seq: one count per topic and process, whatever the connection), so a jump in the
numbers of one publisher's messages is what this consumer lost on the way, or missed
while others got it: in the publisher's queue, a socket, its own subscription queue, or
a connection re-made in between. A number that goes back is a restarted publisher (or a
looping bag): a new count, nothing lost. roscpp keeps the number the message carries, so
`rosbag play` shows the recording's own gaps, and a publisher that leaves it 0 shows none.
"""
import collections


class SequenceGaps:
    def __init__(self):
        self.last = {}                          # per publisher: the last number seen
        self.missed = collections.Counter()     # per publisher: messages missed

    def add(self, publisher, seq):
        """One message from `publisher` numbered `seq`; returns how many were missed
        just before it."""
        last = self.last.get(publisher)
        self.last[publisher] = seq
        if last is None or seq <= last:
            return 0
        gap = seq - last - 1
        if gap:
            self.missed[publisher] += gap
        return gap

    def total(self):
        return sum(self.missed.values())
