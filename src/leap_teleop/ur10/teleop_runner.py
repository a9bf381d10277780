"""The arm teleop as the ur10_arm node runs it, without ROS: ArmTeleop behind one lock
(callbacks feed it from their threads and never wait for a step), stepped at the rate and
right after each new hand, and when its status is reported."""
import threading

from leap_teleop.repeat_limit import RepeatLimit
from leap_teleop.ur10.teleop import HOLDING, ArmTeleop

HAND_SLACK = 1.5    # periods the timer waits after a step a hand woke


class ArmTeleopRunner:
    """One arm's ArmTeleop, fed by on_hand / on_joints from any thread and stepped by run()."""

    def __init__(self, params, rate, gesture_words=None):
        self.period = 1.0 / float(rate)
        # the longest the loop waits between two steps (after a hand: HAND_SLACK periods)
        self.teleop = ArmTeleop(params, HAND_SLACK * self.period, gesture_words)
        self.lock = threading.Lock()
        self.wake = threading.Event()

    def on_hand(self, hand, now):
        """Store one ArmInput and wake the loop; returns why it was ignored (None if it was not)."""
        with self.lock:
            why = self.teleop.on_hand(hand, now)
        self.wake.set()
        return why

    def on_joints(self, q, now, qd=None):
        """Whether the state was taken (False: non-finite or impossible positions)."""
        with self.lock:
            return self.teleop.on_joints(q, now, qd)

    def new_input_connection(self):
        with self.lock:
            self.teleop.new_input_connection()

    def retune(self, changes):
        """Checked changes of reconfigurable parameters, applied between two steps."""
        with self.lock:
            self.teleop.retune(changes)

    def run(self, clock, stopped, tick):
        """Until stopped(): step right after each new hand, and once a period while none
        comes, at clock(); then tick(command, (state, reason, origin_set), now) outside
        the lock. After a hand the timer waits HAND_SLACK periods: a stream near the rate
        (a 120 Hz Leap against a 125 Hz loop) then steps once per hand, not once for the
        hand and again for a timer that ends just before the next one."""
        woken = False
        while not stopped():
            woken = self.wake.wait(self.period * (HAND_SLACK if woken else 1.0))
            self.wake.clear()
            now = clock()
            with self.lock:
                cmd = self.teleop.step(now)
                status = self.teleop.status
                snapshot = (status.state, status.reason, status.origin_set)
            tick(cmd, snapshot, now)


class StatusReporter:
    """When to publish the status: at once when the (state, reason, origin_set) snapshot
    changes, else at `rate` per second. Each change is told to info(text), or warn(text)
    for a hold, as 'STATE (REASON)': the same text at most once per `log_period` s, with a
    count of the repeats left out (a target on the edge of reach flips between holding and
    tracking many times a second; the status itself still goes out on every change)."""

    def __init__(self, rate, info, warn, log_period=2.0):
        self.period = 1.0 / float(rate)
        self.info, self.warn = info, warn
        self._last = None
        self._last_sent = 0.0
        self._logged = RepeatLimit(log_period)      # per text

    def _tell(self, snapshot, now):
        text = '%s (%s)' % snapshot[:2]
        n = self._logged.take(text, now)
        if n is not None:
            (self.warn if snapshot[0] == HOLDING else self.info)(text + RepeatLimit.suffix(n))

    def due(self, snapshot, now):
        """True when the status goes out now (time `now`, s)."""
        changed = snapshot != self._last
        if changed:
            self._tell(snapshot, now)
        elif now - self._last_sent < self.period:
            return False
        self._last, self._last_sent = snapshot, now
        return True
