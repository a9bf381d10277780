"""Order and lateness checks for one stamped input stream (hand messages), no ROS.

A message is out of order when its stamp is older than the last accepted one, and late
when it arrives more than ``max_age`` later than the stream's best-case latency
(receive time minus stamp, the minimum seen in this stream). Judging lateness against
the stream's own best case, not against the absolute clock, keeps replayed bags (old
stamps) and hosts with unsynchronised clocks working while still catching messages
that were held up. A silence longer than ``gap`` (no message at all, accepted or not)
or the clock jumping back (a simulator publishing /clock restarted) starts a new stream:
a restarted sender (fresh stamps) or a replayed bag (stamps jump back; ``rewound`` says so,
for the consumers to ask for a new arming gesture) is judged afresh,
while a stream that stays delayed keeps being refused (the consumers' watchdogs then stop
the robots) - also across a silence: a source that stalled and then bursts its backlog
(stamps continue, but late) is not a new stream, so only its last max_age s pass. Unstamped
messages (stamp <= 0, as the original sender sent them) are only checked for order.

One message stamped far ahead (a bogus stamp: its latency below the stream's best by more
than ``max_age``) would make every later one look out of order for as long as its lead.
So when the last message taken was such a one, or the first of its stream stamped more than
``max_age`` ahead of this clock (nothing else yet to judge its stamp by), stamped messages
refused as out of order for ``gap`` seconds on end, while they keep coming, start a new
stream. After a message taken normally they never do: an older stream (a second, stale
publisher) stays refused.
"""


class InputStream:
    def __init__(self, max_age, gap):
        self.max_age = float(max_age)      # s; 0 disables the lateness check
        self.gap = float(gap)              # s of silence that ends a stream
        self.reset()

    def reset(self):
        self.last_stamp = None
        self.last_rx = None
        self.best_lag = None
        self.misordered_since = None   # first of the stamped messages refused on end as
                                       # out of order
        self.leapt = False             # the last message taken was stamped far ahead
        self.rewound = False           # the last message taken began a new stream stamped
                                       # before the old one's last (a bag played again)

    def check(self, stamp, now):
        """None if the message is in order and on time (it is then recorded), else why not."""
        rewound = False
        if self.last_rx is not None and (now < self.last_rx or now - self.last_rx > self.gap):
            backlog = (now >= self.last_rx and stamp > 0 and self.max_age > 0
                       and self.last_stamp is not None and stamp >= self.last_stamp
                       and self.best_lag is not None
                       and now - stamp - self.best_lag > self.max_age)
            if not backlog:
                rewound = self.last_stamp is not None and 0 < stamp < self.last_stamp
                self.reset()
        self.last_rx = now
        if self.last_stamp is not None and stamp < self.last_stamp:
            if stamp <= 0:
                return 'out of order: unstamped after stamped messages'
            if self.misordered_since is None:
                self.misordered_since = now
            if not self.leapt or now - self.misordered_since < self.gap:
                return 'out of order: %.3f s older than the last message' % (
                    self.last_stamp - stamp)
            self.reset()                # the stamp that leapt ahead was bogus: a new stream
            self.last_rx = now
        self.misordered_since = None
        # a first message is judged by this clock: a sender's clock may differ a little,
        # and one live message before a stale publisher must still keep that one out
        leapt = self.last_stamp is None and stamp - now > self.max_age
        if stamp > 0 and self.max_age > 0:
            lag = now - stamp
            if self.best_lag is None or lag < self.best_lag:
                leapt = leapt or (self.best_lag is not None and self.best_lag - lag > self.max_age)
                self.best_lag = lag
            elif lag - self.best_lag > self.max_age:
                return 'late: arrived %.3f s after the stream\'s usual latency (max %.3f s)' % (
                    lag - self.best_lag, self.max_age)
        self.last_stamp = stamp
        self.leapt = leapt
        self.rewound = rewound
        return None

    def judge_beside(self, stamp, now):
        """Why an event stamped by the same sender as this stream (a gesture beside its
        hands) is late or stamped ahead of it, judged against the stream's best-case latency
        and not recorded; None when on time or unstamped. With no baseline yet it is judged
        against this clock (nothing else to judge a first one by)."""
        if stamp <= 0 or self.max_age <= 0:
            return None
        lag, best = now - stamp, self.best_lag
        if best is None:
            if abs(lag) > self.max_age:
                return 'stamped %.3f s %s this clock, and no stamped Hand to judge it by' % (
                    abs(lag), 'before' if lag > 0 else 'ahead of')
            return None
        if lag - best > self.max_age:
            return 'late: arrived %.3f s after the Hand stream\'s usual latency (max %.3f s)' % (
                lag - best, self.max_age)
        if best - lag > self.max_age:
            return 'stamped %.3f s ahead of the Hand stream (max %.3f s)' % (best - lag,
                                                                            self.max_age)
        return None
