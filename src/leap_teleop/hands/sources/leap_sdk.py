"""The Leap Motion SDK v2 (`import Leap`: Leap.Controller, Leap.Listener.on_frame).

The v2 Python binding ships with the (discontinued) Leap Motion SDK 2.3.1 for Python 2;
for Python 3 it must be rebuilt from the SDK's LeapPython SWIG sources. The import is
optional: without it, constructing the source raises SourceError saying what to install.
"""
import time

from leap_teleop.hands.frame import FINGER_NAMES, Finger, TrackedHand, measured, measured3
from leap_teleop.hands.skeleton import bounded_point
from leap_teleop.hands.sources.device_queue import PushQueue, attr, wait_loop, xyz
from leap_teleop.hands.sources.source import HandSource, SourceError

INSTALL_HINT = ('the "leap" source needs the Leap Motion SDK v2 Python binding (import Leap): '
                'install the Leap Motion SDK 2.3.1 and its service, put LeapPython and '
                'Leap.py (rebuilt for Python 3) on PYTHONPATH; or use source:=leapc '
                '(Ultraleap Gemini), recording or scripted')


def _import():
    try:
        import Leap
    except Exception as e:      # a SWIG binding may fail to load with other errors
        raise SourceError('%s (%s)' % (INSTALL_HINT, e))
    return Leap


def _bone_types(Leap):
    B = Leap.Bone
    return (B.TYPE_METACARPAL, B.TYPE_PROXIMAL, B.TYPE_INTERMEDIATE, B.TYPE_DISTAL)


def convert_hand(Leap, h):
    side = 'right' if attr(h, 'is_right') else 'left'
    fingers = [None] * 5
    for f in attr(h, 'fingers') or ():
        i = attr(f, 'type')
        if not isinstance(i, int) or not 0 <= i < 5 or fingers[i] is not None:
            continue
        joints = {}
        bone = getattr(f, 'bone', None)
        if bone is not None:
            try:
                joints['mcp'] = xyz(bone(Leap.Bone.TYPE_PROXIMAL).prev_joint)
                joints['pip'] = xyz(bone(Leap.Bone.TYPE_INTERMEDIATE).prev_joint)
                joints['dip'] = xyz(bone(Leap.Bone.TYPE_DISTAL).prev_joint)
            except Exception:       # a binding without bones: tip and direction only
                joints = {}
            try:                    # the carpal joint: bounded, never at the joints' cost
                joints['carpal'] = bounded_point(bone(Leap.Bone.TYPE_METACARPAL).prev_joint)
            except Exception:
                pass
        widths = None
        if bone is not None:
            try:
                widths = tuple(measured(attr(bone(t), 'width')) for t in _bone_types(Leap))
            except Exception:       # sizes are extras: never lose the joints for them
                widths = None
            if widths is not None and None in widths:
                widths = None
        fingers[i] = Finger(tip=xyz(attr(f, 'tip_position')), direction=xyz(attr(f, 'direction')),
                            extended=bool(attr(f, 'is_extended')), width=measured(attr(f, 'width')),
                            bone_widths=widths, **joints)
    return TrackedHand(side=side, palm_position=xyz(attr(h, 'palm_position')),
                palm_velocity=xyz(attr(h, 'palm_velocity')),
                palm_normal=xyz(attr(h, 'palm_normal')), direction=xyz(attr(h, 'direction')),
                grab_strength=float(attr(h, 'grab_strength') or 0.0),
                pinch_strength=float(attr(h, 'pinch_strength') or 0.0),
                confidence=float(attr(h, 'confidence') or 0.0),
                fingers=tuple(fingers) if all(f is not None for f in fingers) else (),
                id=int(attr(h, 'id') or 0), palm_width=measured(attr(h, 'palm_width')),
                sphere_radius=measured(attr(h, 'sphere_radius')),
                sphere_center=measured3(attr(h, 'sphere_center')),
                time_visible=measured(attr(h, 'time_visible')))


class LeapSdkSource(HandSource):
    """Frames from a Leap Motion controller through the v2 SDK."""

    def __init__(self, clock=time.time, **_ignored):
        self.Leap = _import()
        self._clock = clock
        self.rate_hz = None

    def frames(self):
        Leap = self.Leap
        pq = PushQueue(self._clock, monotonic=time.monotonic)

        class SdkFrameListener(Leap.Listener):
            def on_frame(listener, controller):
                def convert():
                    f = controller.frame()
                    return (attr(f, 'id'), attr(f, 'timestamp'),
                            [convert_hand(Leap, h) for h in attr(f, 'hands') or ()])
                pq.put_converted('leap', convert)

        listener = SdkFrameListener()
        try:
            controller = Leap.Controller()
            controller.add_listener(listener)
        except Exception as e:      # the binding's own error: one line, not a traceback
            raise SourceError('leap source: cannot start the Leap Motion controller (is the '
                              'Leap service installed and running?): %s: %s'
                              % (type(e).__name__, e)) from None
        try:
            yield from wait_loop(self, pq)
        finally:
            controller.remove_listener(listener)


__all__ = ['LeapSdkSource', 'FINGER_NAMES']
