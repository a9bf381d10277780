"""When a consumer should judge its input afresh or re-establish its connection, no ROS.

Every message of a connection can stay late long after a load has gone: the consumer
judges lateness against the best latency it saw, and a best taken while its own clock
lagged (under simulated time, a /clock that fell behind for a moment) makes every later
message look late by a constant, for ever; a standing backlog (the publisher's queue,
both socket buffers) would look the same. Input refused as late for `after` seconds
without one message on time, its delay steady meanwhile (within STEADY_LAG_SPREAD_S), is
first judged afresh on the same connection: that delay becomes the baseline, nothing is
dropped, and a lagged baseline (the case seen in soaks) is healed. A delay that is not
steady (a backlog being delivered, or still building), or late again on that connection
for `after` seconds, has the connection dropped and made anew, which clears a backlog;
again every `after` seconds while that lasts (late input is refused anyway, and the
backlog may clear at any moment).

A connection can also fall silent while its publisher lives on and serves others; that
does not heal by itself either. On a connection that delivered since it was made, no
message at all for `silent_after` seconds while a publisher is connected re-makes it.
Silence can be legitimate (a paused bag, a source waiting for a device), so a silent
connection is re-made once per silence, not again until a message has come: one log
line, not a storm. A connection can also be dropped by its publisher while the publisher
lives on (seen in soaks: a rospy publisher, finishing the teardown of a consumer's old
connection, also dropped its new one, 40 ms old; rospy matches connections by a cached
socket number). rospy does not reconnect then: the master still lists the publisher, so
nothing tells the subscriber. So a subscription connected to no publisher for `after`
seconds (longer after fruitless tries, up to 8x) asks whether the master lists one, and
is re-made when it does. A re-made connection that replaced a late stream and has
brought nothing for `silent_after` seconds is re-made again too, with the same back-off:
its publisher was sending a moment ago, its silence is not a pause.
"""
import math

from leap_teleop.params import Param

# How much the delay of late input may vary over a streak of `after` seconds and still
# count as steady (a constant offset, not a backlog): s.
STEADY_LAG_SPREAD_S = 0.1

# On-time input for this long after a judgement in place allows another one on the same
# connection (a load that comes back minutes later): s.
RENEW_IN_PLACE_S = 10.0

# A consumer node's ~params for its hand subscription (the arm nodes, the pilots).
HAND_SUBSCRIPTION_PARAMS = {
    # rospy keeps only the newest queue_size messages of each socket read (up to 64 KiB:
    # ~1000 leapcobot messages), so this many is what a stalled consumer can catch up on
    # without a loss: 500 is 4 s of 120 Hz frames. Late ones are refused by age anyway, and
    # a backlog that stays is cleared by re-subscribing.
    'hand_queue_size': Param(500, 'hand messages buffered on the subscription before the '
                                 'oldest is dropped', ge=1, le=2000),
    'resubscribe_after': Param(0.5, 'after this long with every hand message late, judge their '
                                    'lateness afresh on the same connection, and re-establish '
                                    'it when they stay late this long again (again while it '
                                    'lasts); also re-establish it after this long connected to '
                                    'no publisher while the master lists one; 0 = never',
                               unit='s', ge=0.0, le=60.0),
    # At least two checks (0.25 s apart): shorter, a check between two messages of a healthy
    # stream re-made its connection, losing what was in flight.
    'resubscribe_silent_after': Param(2.0, 're-establish it, once, after this long without any '
                                           'message while a publisher is connected; 0 = never',
                                      unit='s', ge=0.5, le=60.0, or_zero=True),
    'hand_frame': Param('leap_hands', 'frame the hand messages must be in (the sender\'s '
                                      '~frame_id); others are refused with a warning, messages '
                                      'with no frame (the original sender\'s) are taken; '
                                      '\'\' takes any frame'),
}


class StreamHealth:
    def __init__(self, after, silent_after):
        """after: seconds of late-only input, or of no connected publisher, before a
        re-subscription; silent_after: of no input while a publisher is connected; 0 = never."""
        self.after = float(after)
        self.silent_after = float(silent_after)
        self.resubscriptions = 0
        self.since = None           # start of the current judgement (first message or check,
                                    # or the last re-subscription)
        self.last_rx = None         # last message of any kind
        self.late_since = None      # first late message since the last one on time
        self.on_time_since = None   # first message on time since the last late one
        self.unconnected_since = None   # first check that found no connected publisher
        self.ask_at = None          # when to ask the master whether one is listed
        self.heard = False          # a message came since the connection was made
        self.remade = False         # the connection is a re-subscription's
        self.remade_late = False    # ... replacing a late stream
        self.fruitless = 0          # re-subscriptions in a row that brought nothing
        self._why = None            # 'late' or 'silent': the reason due() gave last
        self._late_messages = False  # ... and it was every message refused as late
        self.rejudged = False       # lateness judged afresh on this connection already
        self._lags = None           # (lowest, highest) delay of the current late streak
        self.rejudgements = 0

    def on_message(self, now, late, lag=None):
        """A message arrived at `now`; `late` when the consumer refused it as late; `lag`:
        its arrival time minus its stamp (s), when it has one."""
        self.last_rx = now
        self.heard = True
        if self.since is None:
            self.since = now
        if late:
            if self.late_since is None:
                self.late_since = now
                self._lags = None
            if lag is not None and math.isfinite(lag):
                lo, hi = self._lags or (lag, lag)
                self._lags = (min(lo, lag), max(hi, lag))
            self.on_time_since = None
        else:
            self.late_since = None
            if self.on_time_since is None or now < self.on_time_since:
                self.on_time_since = now
            if self.rejudged and now - self.on_time_since >= RENEW_IN_PLACE_S:
                self.rejudged = False

    def stalled(self, now):
        """The consumer itself stood still (its checks stopped coming): the messages that
        piled up meanwhile are not read yet, so its silence and lateness are judged afresh
        from `now`."""
        self.since = now
        self.late_since = None
        self.on_time_since = None       # a stall is no input on time
        if self.last_rx is not None:
            self.last_rx = now
        if self.unconnected_since is not None:
            self.unconnected_since = self.ask_at = None

    def _backoff(self):
        return 2 ** min(self.fruitless, 3)

    def wants_listing(self, now, publishers):
        """Whether due() needs to know how many publishers the master lists: the
        subscription has been connected to none for long enough."""
        if publishers > 0 or self.after <= 0:
            self.unconnected_since = self.ask_at = None
            return False
        if self.unconnected_since is None or now < self.unconnected_since:
            self.unconnected_since = now
            self.ask_at = now + self.after * self._backoff()
        return now >= self.ask_at

    def due(self, now, publishers, listed=None):
        """Why the connection should be re-established now (None: it should not).
        publishers: how many publishers the subscription is connected to; listed: how
        many the master lists, when wants_listing() asked for it (else None)."""
        if self.since is None:
            self.since = now
        if now < self.since:                     # the clock jumped back: judge afresh
            self.since, self.late_since, self.unconnected_since = now, None, None
            self.ask_at = None
            return None
        if self.late_since is not None and self.after > 0:
            late_for = now - max(self.late_since, self.since)
            if late_for >= self.after:
                self._why, self._late_messages = 'late', True
                return 'every message late for %.1f s' % late_for
        self._late_messages = False
        if listed is not None and publishers == 0 and self.unconnected_since is not None:
            if listed > 0:
                self._why = 'silent'
                return 'connected to none of the %d publisher%s the master lists for %.1f s' % (
                    listed, '' if listed == 1 else 's', now - self.unconnected_since)
            # Nobody publishes (a sender not started or gone): ask again in 4 x after,
            # not at every check.
            self.ask_at = now + 4 * self.after
        if (self.heard and publishers > 0 and self.silent_after > 0
                and now - self.last_rx >= self.silent_after):
            self._why = 'silent'
            return 'no message for %.1f s while %d publisher%s connected' % (
                now - self.last_rx, publishers, ' is' if publishers == 1 else 's are')
        if (self.remade and self.remade_late and not self.heard and publishers > 0
                and self.silent_after > 0
                and now - self.since >= self.silent_after * self._backoff()):
            self._why = 'late'
            return 'no message %.1f s after re-subscribing (%d publisher%s connected)' % (
                now - self.since, publishers, '' if publishers == 1 else 's')
        return None

    def judge_in_place(self):
        """Whether the reason due() gave is met by judging the input's lateness afresh on
        the same connection: every message late by a steady delay, and not judged afresh
        on it since it was made or last on time for RENEW_IN_PLACE_S."""
        return (self._late_messages and not self.rejudged and self._lags is not None
                and self._lags[1] - self._lags[0] <= STEADY_LAG_SPREAD_S)

    def judged_afresh(self, now):
        """The consumer judged its input's lateness afresh at `now`, on the same
        connection: late again for `after` seconds, it is re-made."""
        self.rejudged = True
        self.rejudgements += 1
        self.since = now
        self.late_since = None

    def resubscribed(self, now):
        """The connection was re-established at `now`: judge it afresh."""
        self.resubscriptions += 1
        self.rejudged = False
        self.fruitless = self.fruitless + 1 if (self.remade and not self.heard) else 0
        self.remade_late = self._why == 'late'
        self.remade = True
        self.since = now
        self.late_since = None
        self.unconnected_since = now         # until the new connection forms
        self.ask_at = now + self.after * self._backoff()
        self.heard = False
