"""Takeoff and land are one message each, so one published before the driver's subscriber
has connected is lost for good (a twist is not: the next one replaces it). HeldOneShot
keeps the latest takeoff or land until its topic has a subscriber: a takeoff for at most
`takeoff_hold` seconds and only while the pilot still wants it (a drone leaving the ground
long after the gesture, or after a fold, would surprise the person who made it); a land
for as long as it takes, since landing is the safe action whenever the driver appears.
"""
import time


class HeldOneShot:
    """send(cmd) publishes a takeoff / land Command at once (publish(cmd, None)) when
    connected(kind) says its topic has a subscriber, else holds it (a newer one replaces
    it: the latest gesture wins); send_held(), called often on the same thread, publishes
    it once connected (publish(cmd, seconds it was held)), and drops a takeoff held longer
    than takeoff_hold or that takeoff_wanted() no longer allows. Counts: held, dropped
    (takeoffs)."""

    def __init__(self, publish, connected, takeoff_hold, takeoff_wanted=None,
                 clock=time.monotonic, warn=None):
        self.publish = publish
        self.connected = connected
        self.takeoff_hold = float(takeoff_hold)
        self.takeoff_wanted = takeoff_wanted or (lambda: True)
        self.clock = clock                    # wall pacing: how long a connection takes
        self.warn = warn or (lambda key, text: None)
        self.pending = None                   # (Command, time it was held)
        self.held = 0
        self.dropped = 0

    def send(self, cmd):
        """True when published now; False when held for the driver (or, a takeoff with no
        hold, dropped)."""
        if self.pending is not None:
            self.warn('one_shot_replaced', '%s held for the driver replaced by %s'
                      % (self.pending[0].kind, cmd.kind))
            self.pending = None
        if self.connected(cmd.kind):
            self.publish(cmd, None)
            return True
        if cmd.kind == 'takeoff' and self.takeoff_hold <= 0.0:
            self._drop('nothing listens on ardrone/takeoff (takeoff_hold 0)')
            return False
        self.pending = (cmd, self.clock())
        self.held += 1
        self.warn('held_' + cmd.kind, 'nothing listens on ardrone/%s yet: the %s waits for '
                  'the driver%s' % (cmd.kind, cmd.kind,
                                    ' (%.2f s at most)' % self.takeoff_hold
                                    if cmd.kind == 'takeoff' else ''))
        return False

    def send_held(self):
        """The held Command once published, else None. A takeoff's limits are checked
        before the connection, so a late call (a stalled thread) never sends it late."""
        if self.pending is None:
            return None
        cmd, since = self.pending
        waited = self.clock() - since
        if cmd.kind == 'takeoff':
            why = ('nothing listened on ardrone/takeoff within %.2f s' % self.takeoff_hold
                   if waited > self.takeoff_hold
                   else None if self.takeoff_wanted()
                   else 'the pilot no longer wants it (fold, lost hand or navdata)')
            if why is not None:
                self.pending = None
                self._drop(why)
                return None
        if not self.connected(cmd.kind):
            return None
        self.pending = None
        self.publish(cmd, waited)
        return cmd

    def _drop(self, why):
        self.dropped += 1
        self.warn('takeoff_dropped', 'takeoff dropped: %s' % why)
