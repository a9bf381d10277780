"""Gesture -> action bindings: which gesture arms an arm, sets its origin, stops it or
drives its gripper, and which takes a drone off, lands it, flips it or makes it hover.

A bindings YAML (config/gestures/bindings/default.yaml holds the defaults)::

    arm:
      arm: thumb_up          # a gesture name, a list of names, or [] (unbound)
      origin: rock
      stop: fist
      gripper: pinch
    drone:
      takeoff: unfold
      land: fold
      flip: circle
      hover: []

Sections and actions left out keep their defaults. Gestures: the held built-ins (fist,
thumb_up, pinch, rock, open, thumb_down), a user model's own classes (held like them),
and the events unfold (fist -> open), fold (open -> fist) and circle (either way round).
Arm actions are states, so they take held gestures only; a drone action fires when its
gesture starts.

Applied on the sender's side (hands.tracker.HandTracker), so the consumers need no
change: an arm action sets the flag the arm reads (arm -> thumb_up, origin -> rock,
stop -> fist, gripper -> pinch, pinch_value 0.8 from a gesture other than pinch); a
drone action emits the event the pilot acts on (takeoff -> unfold, land -> fold,
flip -> circle_cw / circle_ccw, hover -> hover: the pilot hovers and, in tilt mode,
takes the hand's place on its next frame as the new neutral point; in paper mode it hovers
until the capture pose is shown again). Raw unfold / fold /
circle events go out only as the actions they are bound to.
"""
from leap_teleop.hands.gestures.temporal import HELD_GESTURES, HandEvent
from leap_teleop.yaml_file import YamlFileError, load_yaml_file

ARM_ACTIONS = ('arm', 'origin', 'stop', 'gripper')
DRONE_ACTIONS = ('takeoff', 'land', 'flip', 'hover')
SECTIONS = {'arm': ARM_ACTIONS, 'drone': DRONE_ACTIONS}
EVENT_GESTURES = ('unfold', 'fold', 'circle')
DEFAULTS = {'arm': {'arm': ('thumb_up',), 'origin': ('rock',), 'stop': ('fist',),
                    'gripper': ('pinch',)},
            'drone': {'takeoff': ('unfold',), 'land': ('fold',), 'flip': ('circle',),
                      'hover': ()}}
# Names the recognizer or the pilot already use: no user gesture may take one.
RESERVED = frozenset(HELD_GESTURES + EVENT_GESTURES
                     + ('circle_cw', 'circle_ccw', 'hand_lost', 'hand_found', 'hover', 'none',
                        'thumb'))
# The raw events that command the pilot: they leave only as the actions bound to them.
_PILOT_EVENTS = {'unfold': 'unfold', 'fold': 'fold', 'circle_cw': 'circle',
                 'circle_ccw': 'circle'}
_WORDS = {'thumb_up': 'thumbs-up', 'thumb_down': 'thumbs-down'}
GRIPPER_CLOSED = 0.8            # pinch_value while a gesture other than pinch holds the gripper
# A flip from a held gesture: the circle radius (m) it reports, so the pilot's guard
# against fingertip loops (flip_min_radius, default 0.025 m) lets a deliberate pose through.
BOUND_FLIP_RADIUS_M = 0.1


class BindingError(ValueError):
    """Bindings that name an unknown section, action or gesture, or clash."""


def _names(value, where):
    if value is None:
        # A blank value reads as if it kept the default; it would unbind the action.
        raise BindingError('%s: no gesture given (write [] to leave it unbound, or leave the '
                           'action out to keep its default)' % where)
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, (list, tuple)) or not all(
            isinstance(v, str) and v.strip() for v in value):
        raise BindingError('%s: a gesture name or a list of them, not %r' % (where, value))
    return tuple(dict.fromkeys(v.strip() for v in value))


class Bindings:
    """Validated bindings: section -> action -> gesture names."""

    def __init__(self, data=None, name='gesture bindings'):
        if data is None:
            data = {}
        if not isinstance(data, dict):
            raise BindingError('%s: a mapping of sections (arm, drone), not %r' % (name, data))
        self.name = name
        self.actions = {s: dict(acts) for s, acts in DEFAULTS.items()}
        for section, acts in data.items():
            if section not in SECTIONS:
                raise BindingError('%s: unknown section %r (sections: %s)'
                                   % (name, section, ', '.join(SECTIONS)))
            if acts is None:
                continue
            if not isinstance(acts, dict):
                raise BindingError('%s: %s: a mapping of actions, not %r' % (name, section, acts))
            for action, value in acts.items():
                if action not in SECTIONS[section]:
                    raise BindingError('%s: unknown %s action %r (%s actions: %s)'
                                       % (name, section, action, section,
                                          ', '.join(SECTIONS[section])))
                self.actions[section][action] = _names(value, '%s: %s.%s'
                                                       % (name, section, action))
        for section, acts in self.actions.items():
            seen = {}
            for action, gestures in acts.items():
                for g in gestures:
                    if section == 'arm' and g in EVENT_GESTURES:
                        raise BindingError('%s: arm.%s: %r is a moment (an event), the arm '
                                           'needs a held gesture' % (name, action, g))
                    if g in seen:
                        raise BindingError('%s: %r is bound to both %s.%s and %s.%s'
                                           % (name, g, section, seen[g], section, action))
                    seen[g] = action

    @property
    def gestures(self):
        """Every gesture bound to something."""
        return {g for acts in self.actions.values() for gs in acts.values() for g in gs}

    def check(self, user_gestures=(), hint=''):
        """BindingError naming the first bound gesture the recognizer cannot report (`hint`
        appended), or a user gesture that takes a reserved name."""
        for g in user_gestures:
            if g in RESERVED:
                raise BindingError('the gesture model\'s class %r takes the name of a built-in '
                                   'gesture or event: retrain it under another --label' % g)
        known = set(HELD_GESTURES) | set(EVENT_GESTURES) | set(user_gestures)
        for section, acts in self.actions.items():
            for action, gestures in acts.items():
                for g in gestures:
                    if g not in known:
                        raise BindingError(
                            '%s: %s.%s: unknown gesture %r (known: %s)%s'
                            % (self.name, section, action, g, ', '.join(sorted(known)), hint))
        return self

    def is_default(self):
        return self.actions == DEFAULTS

    def arm_words(self):
        """Per arm action, its gestures as the arm's state lines name them ('thumbs-up',
        'peace or thumbs-up', 'no gesture (unbound)'): the arm reads only the flags."""
        return {a: ' or '.join(_WORDS.get(g, g) for g in gs) or 'no gesture (unbound)'
                for a, gs in self.actions['arm'].items()}

    def applier(self, user_gestures=()):
        """A BoundActions for a recognizer reporting `user_gestures` (checked)."""
        self.check(user_gestures)
        return BoundActions(self)


class BoundActions:
    """Bindings compiled for the per-frame path: GestureState -> action flags, events."""

    def __init__(self, bindings):
        arm = bindings.actions['arm']
        # per arm action: (built-in held names, user names)
        self._flags = tuple((tuple(g for g in arm[a] if g in HELD_GESTURES),
                             tuple(g for g in arm[a] if g not in HELD_GESTURES))
                            for a in ARM_ACTIONS)
        self._gripper_by_pinch = 'pinch' in arm['gripper']
        self._on_start = {}         # held gesture -> drone actions fired at its start
        self._on_event = {}         # unfold / fold / circle -> drone actions
        for action, gestures in bindings.actions['drone'].items():
            for g in gestures:
                table = self._on_event if g in EVENT_GESTURES else self._on_start
                table.setdefault(g, []).append(action)
        self.identity = bindings.is_default()

    def flags(self, g):
        """(arm, origin, stop, gripper, gripper_value) of a GestureState."""
        # The arm's hold counts frames that show its gesture, never one only held through
        # a frame too unsure to judge (the filter ends a thumbs-up there itself) or carried
        # by a long off-filter (g.unseen).
        if self.identity:
            return (g.thumb_up and 'thumb_up' not in g.unseen, g.rock, g.fist, g.pinch,
                    g.pinch_value if g.pinch else 0.0)
        user = g.user
        out = []
        for k, (builtin, own) in enumerate(self._flags):
            on = False
            for n in builtin:
                if getattr(g, n) and not (k == 0 and n in g.unseen):
                    on = True
                    break
            else:
                for n in own:
                    if n in user and not (k == 0 and n in g.unseen):
                        on = True
                        break
            out.append(on)
        out[0] = out[0] and g.judged
        if not out[3]:
            value = 0.0
        elif self._gripper_by_pinch and g.pinch:
            value = g.pinch_value
        else:
            value = GRIPPER_CLOSED
        return out[0], out[1], out[2], out[3], value

    def events(self, events):
        """The events to send for a frame's recognizer events."""
        if self.identity or not events:
            return events
        out = []
        for e in events:
            source = _PILOT_EVENTS.get(e.gesture)
            if source is not None:
                out.extend(_action_event(a, e) for a in self._on_event.get(source, ()))
                continue
            out.append(e)
            if e.active:
                out.extend(_action_event(a, None) for a in self._on_start.get(e.gesture, ()))
        return out


def _action_event(action, event):
    """The event the pilot acts on for `action`, from `event` (a raw pilot event) or from
    a held gesture's start (None)."""
    if action == 'takeoff':
        return HandEvent('unfold')
    if action == 'land':
        return HandEvent('fold')
    if action == 'hover':
        return HandEvent('hover')
    if event is not None and event.gesture.startswith('circle_'):
        return HandEvent(event.gesture, True, event.value, event.source, event.center)
    return HandEvent('circle_cw', True, BOUND_FLIP_RADIUS_M)


def load_bindings(path=None):
    """Bindings from a YAML file; the defaults when `path` is empty or None."""
    if not path:
        return Bindings(None, 'default gesture bindings')
    try:
        data = load_yaml_file(path, 'gesture bindings')
    except YamlFileError as e:
        raise BindingError(str(e)) from None
    return Bindings(data, 'gesture bindings %s' % path)


__all__ = ['ARM_ACTIONS', 'DRONE_ACTIONS', 'EVENT_GESTURES', 'BOUND_FLIP_RADIUS_M',
           'BindingError', 'Bindings', 'BoundActions', 'GRIPPER_CLOSED', 'RESERVED',
           'load_bindings']
