"""The Leap listener: frames in, a thread-safe per-hand snapshot and gestures out.

Mirrors the original leap_interface.py API (``li.get_right_hand_palmpos()`` ...), but:
frames arrive from any HandSource on the interface's own thread, both hands are
swapped in under one lock (no torn reads), every flag is cleared when a hand leaves,
and listeners are called once per frame instead of being polled.
"""
import logging
import math
import threading

from leap_teleop.hands.frame import SIDES, Frame
from leap_teleop.hands.gestures import GestureRecognizer
from leap_teleop.hands.sources.source import SourceError
from leap_teleop.hands.tracker import DEAD_BANDS, HandState, HandTracker

log = logging.getLogger(__name__)


class LeapInterface:
    """Listener over a HandSource. Call start() to run the source on a thread, or
    feed frames yourself with on_frame(frame)."""

    def __init__(self, source=None, recognizer_factory=GestureRecognizer, sides=SIDES,
                 dead_bands=DEAD_BANDS, bindings=None):
        """dead_bands: per rotation angle (low, high) rad, or None for the raw rotation;
        bindings: gesture -> action bindings (see HandTracker)."""
        self.source = source
        self._trackers = {side: HandTracker(side, recognizer_factory(), dead_bands, bindings)
                          for side in sides}
        self._lock = threading.Lock()
        self._states = {side: HandState(side) for side in sides}
        self._listeners = []
        self._hand_listeners = []
        self._thread = None
        self.frames_seen = 0
        self.rejected_frames = 0
        self.error = None
        self.finished = threading.Event()

    # -- listener side -------------------------------------------------------------
    def add_listener(self, callback):
        """callback(frame, states) runs on the source thread once per frame;
        states maps side -> HandState. Keep it short."""
        self._listeners.append(callback)

    def add_hand_listener(self, callback):
        """callback(frame, state) runs as soon as one side's HandState is ready, before
        the other side is processed: for consumers where latency matters."""
        self._hand_listeners.append(callback)

    def on_frame(self, frame):
        """Process one frame; a frame without a usable capture time is dropped (counted,
        warned) since its stamp would order nothing downstream. Returns the states, or
        None for a dropped frame."""
        try:
            stamp = float(frame.timestamp)
        except (TypeError, ValueError):
            stamp = math.nan
        if not (math.isfinite(stamp) and stamp >= 0.0):
            self.rejected_frames += 1
            if self.rejected_frames in (1, 10, 100) or self.rejected_frames % 1000 == 0:
                log.warning('dropped %d frame(s) without a valid capture time (got %r)',
                            self.rejected_frames, frame.timestamp)
            return None
        frame = self._one_hand_per_side(frame)
        states = {}
        for side, tracker in self._trackers.items():
            states[side] = state = tracker.update(frame.hand(side), frame.timestamp, frame.id)
            for callback in self._hand_listeners:
                callback(frame, state)
        with self._lock:
            self._states = states
            self.frames_seen += 1
        for callback in self._listeners:
            callback(frame, states)
        return states

    def _one_hand_per_side(self, frame):
        """The frame with one hand of each side, for every listener alike: the one followed
        (by id), else the most confident. A tracker may type two hands alike, and the
        first listed, whichever it was, moved the hand by 90 mm from frame to frame."""
        sides = [h.side for h in frame.hands]
        if len(set(sides)) == len(sides):
            return frame
        def rank(hand):
            tracker = self._trackers.get(hand.side)
            followed = tracker is not None and tracker.hand_id is not None \
                and hand.id == tracker.hand_id
            c = hand.confidence
            return followed, float(c) if isinstance(c, (int, float)) and c == c else 0.0

        chosen = {}
        for hand in frame.hands:            # on a tie the first listed stays
            if hand.side not in chosen or rank(hand) > rank(chosen[hand.side]):
                chosen[hand.side] = hand
        kept = set(map(id, chosen.values()))
        return Frame(frame.id, frame.timestamp, [h for h in frame.hands if id(h) in kept],
                     frame.gestures)

    def start(self):
        if self.source is None:
            raise RuntimeError('LeapInterface.start() needs a source')
        self._thread = threading.Thread(target=self._run, name='leap_interface', daemon=True)
        self._thread.start()
        return self

    def _run(self):
        try:
            for frame in self.source.frames():
                self.on_frame(frame)
        except SourceError as e:    # a device gone, a file gone bad: the owner says so
            self.error = e
        except Exception as e:   # a bug: its traceback; the owner decides what to do
            log.exception('hand source failed: %s', e)
            self.error = e
        finally:
            self.finished.set()

    def stop(self, timeout=2.0):
        if self.source is not None:
            self.source.stop()
        if self._thread is not None:
            self._thread.join(timeout)

    def recognizers(self):
        """{side: GestureRecognizer}, for tuning while running."""
        return {side: tracker.recognizer for side, tracker in self._trackers.items()}

    # -- getters ------------------------------------------------------------------
    def snapshot(self, side=None):
        """The latest HandState of `side`, or a dict of both (one consistent frame)."""
        with self._lock:
            states = self._states
        return states if side is None else states[side]

    def get_is_right_hand(self):
        return self.snapshot('right').present

    def get_is_left_hand(self):
        return self.snapshot('left').present


# The original getters, for both hands from one table: get_<side>_hand_<name>().
_GETTERS = {
    'palmpos': 'palm_position', 'fist': 'fist', 'thumb_up': 'thumb_up', 'pinch': 'pinch',
    'pinch_value': 'pinch_value', 'origin_frame': 'origin_set',
    'set_origin_frame_detected': 'rock', 'rotate_value': 'rotate', 'turn_value': 'turn',
    'swing_value': 'swing', 'normal': 'palm_normal', 'direction': 'direction',
    'velocity': 'palm_velocity', 'grab_strength': 'grab_strength',
    'pinch_strength': 'pinch_strength', 'open': 'open', 'state': None,
}


def _make_getter(side, attr):
    def getter(self):
        state = self.snapshot(side)
        return state if attr is None else getattr(state, attr)
    getter.__name__ = 'get_%s_hand_%s' % (side, attr or 'state')
    getter.__doc__ = 'The %s hand\'s %s from the latest frame.' % (side, attr or 'HandState')
    return getter


for _side in SIDES:
    for _name, _attr in _GETTERS.items():
        setattr(LeapInterface, 'get_%s_hand_%s' % (_side, _name), _make_getter(_side, _attr))
