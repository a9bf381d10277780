"""Ultraleap Gemini through its LeapC Python bindings (`import leap`: leap.Connection,
leap.Listener.on_tracking_event).

The bindings are not on PyPI: build them from Ultraleap's leapc-python-bindings against
an installed Gemini (5.x) service. The import is optional: without it, constructing the
source raises SourceError saying what to install; a service that does not answer ends
frames() with a SourceError saying so.
"""
import contextlib
import time

from leap_teleop.hands.frame import Finger, TrackedHand, measured
from leap_teleop.hands.skeleton import bounded_point
from leap_teleop.hands.sources.device_queue import PushQueue, attr, wait_loop, xyz
from leap_teleop.hands.sources.source import HandSource, SourceError

INSTALL_HINT = ('the "leapc" source needs Ultraleap\'s LeapC Python bindings (import leap): '
                'install the Ultraleap Gemini hand-tracking service, then build and pip '
                'install leapc-python-bindings (leapc-cffi and leap); or use source:=leap '
                '(SDK v2), recording or scripted')
CONNECT_HINT = ('leapc source: cannot connect to the Ultraleap hand-tracking service (is it '
                'installed and running?): %s: %s')


def _import():
    try:
        import leap
    # Not only ImportError: the bindings raise a plain Exception when the service's
    # leapc_cffi folder is not where they look.
    except Exception as e:
        raise SourceError('%s (%s)' % (INSTALL_HINT, e))
    return leap


def _side(leap, hand_type):
    left = getattr(getattr(leap, 'HandType', None), 'Left', None)
    if left is not None and hand_type == left:
        return 'left'
    return 'left' if 'left' in str(hand_type).lower() else 'right'


def convert_hand(leap, h):
    palm = attr(h, 'palm')
    fingers = []
    for d in (attr(h, 'digits') or ())[:5]:
        prox, inter, dist = attr(d, 'proximal'), attr(d, 'intermediate'), attr(d, 'distal')
        tip = xyz(attr(dist, 'next_joint'))
        dip = xyz(attr(dist, 'prev_joint'))
        direction = tip - dip
        n = float((direction @ direction) ** 0.5)
        # LeapC measures each bone's width, not the digit's.
        widths = tuple(measured(attr(attr(d, b), 'width'))
                       for b in ('metacarpal', 'proximal', 'intermediate', 'distal'))
        fingers.append(Finger(tip=tip, direction=direction / n if n > 0 else direction,
                              extended=bool(attr(d, 'is_extended')),
                              mcp=xyz(attr(prox, 'prev_joint')),
                              pip=xyz(attr(inter, 'prev_joint')), dip=dip,
                              bone_widths=None if None in widths else widths,
                              carpal=bounded_point(attr(attr(d, 'metacarpal'), 'prev_joint'))))
    visible_us = measured(attr(h, 'visible_time'))      # LeapC: microseconds
    return TrackedHand(side=_side(leap, attr(h, 'type')), palm_position=xyz(attr(palm, 'position')),
                palm_velocity=xyz(attr(palm, 'velocity')), palm_normal=xyz(attr(palm, 'normal')),
                direction=xyz(attr(palm, 'direction')),
                grab_strength=float(attr(h, 'grab_strength') or 0.0),
                pinch_strength=float(attr(h, 'pinch_strength') or 0.0),
                confidence=float(attr(h, 'confidence') or 0.0),
                fingers=tuple(fingers) if len(fingers) == 5 else (), id=int(attr(h, 'id') or 0),
                palm_width=measured(attr(palm, 'width')),
                time_visible=visible_us * 1e-6 if visible_us is not None else None)


class LeapCSource(HandSource):
    """Frames from an Ultraleap device through the Gemini service."""

    def __init__(self, clock=time.time, **_ignored):
        self.leap = _import()
        self._clock = clock
        self.rate_hz = None

    def frames(self):
        leap = self.leap
        pq = PushQueue(self._clock, monotonic=time.monotonic)

        class LeapCFrameListener(leap.Listener):
            def on_tracking_event(listener, event):
                pq.put_converted('leapc', lambda: (
                    attr(event, 'tracking_frame_id'), attr(event, 'timestamp'),
                    [convert_hand(leap, h) for h in attr(event, 'hands') or ()]))

        with contextlib.ExitStack() as opened:
            # The bindings' own errors (open() times out when the service does not answer)
            # are the device's state, not a bug: one line, not a traceback.
            try:
                connection = leap.Connection()
                connection.add_listener(LeapCFrameListener())
                opened.enter_context(connection.open())
                mode = getattr(getattr(leap, 'TrackingMode', None), 'Desktop', None)
                if mode is not None and hasattr(connection, 'set_tracking_mode'):
                    connection.set_tracking_mode(mode)
            except Exception as e:
                raise SourceError(CONNECT_HINT % (type(e).__name__, e)) from None
            yield from wait_loop(self, pq)


__all__ = ['LeapCSource']
