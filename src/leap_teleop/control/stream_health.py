"""When a consumer should re-establish its input connection, no ROS.

A standing backlog can form anywhere along one connection (the publisher's queue, both
socket buffers) and keep every message late long after the load that built it is gone;
a connection can also fall silent while its publisher lives on and serves others. Neither
heals by itself. Dropping the connection and subscribing afresh clears both. This class
decides when: input refused as late for `after` seconds without one message on time
(again every `after` seconds while that lasts: late input is refused anyway, and the
backlog may clear at any moment), or, on a connection that delivered since it was made,
no message at all for `silent_after` seconds while a publisher is connected. Silence can
be legitimate (a paused bag, a source waiting for a device), so a silent connection is
re-made once per silence, not again until a message has come: one log line, not a storm.
A connection can also be dropped by its publisher while the publisher lives on (seen
in soaks: a rospy publisher, finishing the teardown of a consumer's old connection, also
dropped its new one, 40 ms old; rospy matches connections by a cached socket number).
rospy does not reconnect then: the master still lists the publisher, so nothing tells the
subscriber. So a subscription
connected to no publisher for `after` seconds (longer after fruitless tries, up to 8x)
asks whether the master lists one, and is re-made when it does. A re-made connection that
replaced a late stream and has brought nothing for `silent_after` seconds is re-made again
too, with the same back-off: its publisher was sending a moment ago, its silence is not a
pause.
"""
from leap_teleop.params import Param

# A consumer node's ~params for its hand subscription (the arm nodes, the pilots).
HAND_SUBSCRIPTION_PARAMS = {
    # rospy keeps only the newest queue_size messages of each socket read (up to 64 KiB:
    # ~1000 leapcobot messages), so this many is what a stalled consumer can catch up on
    # without a loss: 500 is 4 s of 120 Hz frames. Late ones are refused by age anyway, and
    # a backlog that stays is cleared by re-subscribing.
    'hand_queue_size': Param(500, 'hand messages buffered on the subscription before the '
                                 'oldest is dropped', ge=1, le=2000),
    'resubscribe_after': Param(0.5, 're-establish the hand connection after this long with every '
                                    'message late (again while it lasts), or connected to no '
                                    'publisher while the master lists one; 0 = never', unit='s',
                               ge=0.0, le=60.0),
    'resubscribe_silent_after': Param(2.0, 're-establish it, once, after this long without any '
                                           'message while a publisher is connected; 0 = never',
                                      unit='s', ge=0.0, le=60.0),
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
        self.unconnected_since = None   # first check that found no connected publisher
        self.ask_at = None          # when to ask the master whether one is listed
        self.heard = False          # a message came since the connection was made
        self.remade = False         # the connection is a re-subscription's
        self.remade_late = False    # ... replacing a late stream
        self.fruitless = 0          # re-subscriptions in a row that brought nothing
        self._why = None            # 'late' or 'silent': the reason due() gave last

    def on_message(self, now, late):
        """A message arrived at `now`; `late` when the consumer refused it as late."""
        self.last_rx = now
        self.heard = True
        if self.since is None:
            self.since = now
        if late:
            if self.late_since is None:
                self.late_since = now
        else:
            self.late_since = None

    def stalled(self, now):
        """The consumer itself stood still (its checks stopped coming): the messages that
        piled up meanwhile are not read yet, so its silence and lateness are judged afresh
        from `now`."""
        self.since = now
        self.late_since = None
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
                self._why = 'late'
                return 'every message late for %.1f s' % late_for
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

    def resubscribed(self, now):
        """The connection was re-established at `now`: judge it afresh."""
        self.resubscriptions += 1
        self.fruitless = self.fruitless + 1 if (self.remade and not self.heard) else 0
        self.remade_late = self._why == 'late'
        self.remade = True
        self.since = now
        self.late_since = None
        self.unconnected_since = now         # until the new connection forms
        self.ask_at = now + self.after * self._backoff()
        self.heard = False
