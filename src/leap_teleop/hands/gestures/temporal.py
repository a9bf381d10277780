"""Held gestures over time: the temporal filter and the events it emits.

A held gesture turns on after `on_frames` consistent frames (and `on_time` seconds, per
gesture), off after `off_frames`; frames too unsure to judge hold the state for a moment,
then let go (all but a thumbs-up, which such a frame ends). Events: start / stop of each
held gesture (and of a user's own gestures), unfold (fist -> open) and fold (open -> fist).
Fold and unfold land or launch a drone, so they need a deliberate change: the first shape
held FOLD_HOLD_S, the second one shown within FOLD_GAP_S of its end and held
FOLD_CONFIRM_S (a fist or an open hand misread for a moment while a hand swipes, pinches
or turns is no fold; the event comes FOLD_CONFIRM_S after the second shape appears). Both
holds count judged frames only, each with its own frame interval: frames too unsure to
judge neither end a shape nor add to its hold, so a misread carried through them never
completes a fold, and one such frame inside a deliberate hold does not split it. A stalled
stream (a frame interval longer than FOLD_GAP_S and STALL_FACTOR times the median of the
stream's recent ones, so a sim clock running fast spaces frames wider without stalling
them) or a stamp going back ends both shapes: what came before it never pairs with what
comes after.
"""
import collections
import math
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

HELD_GESTURES = ('fist', 'thumb_up', 'pinch', 'rock', 'open', 'thumb_down')
HOLD_LOW_CONFIDENCE_S = 0.25       # held gestures survive this long on unusable frames
FOLD_HOLD_S = 0.3
FOLD_GAP_S = 0.5
FOLD_CONFIRM_S = 0.15
FOLD_FRAME_CREDIT_S = 0.25          # the most one frame adds to a hold (5 Hz video adds 0.2)
STALL_FACTOR = 4.0                  # a frame interval this many usual ones (and > FOLD_GAP_S): a stall
STALL_WINDOW = 16                   # the recent frame intervals the usual one is the median of
# A gesture the off-filter still holds counts toward a hold (the arm's, a fold's) for at
# most this many judged frames after the last that showed it, as the default off_frames
# (3) holds it: a longer off-filter smooths a flickering pinch, it does not make a glimpse
# of a thumbs-up an arming hold or a 3-frame misread fist a fold.
CARRY_CREDIT_FRAMES = 2


@dataclass
class HandEvent:
    gesture: str
    active: bool = True
    value: float = 0.0
    # Circles only: what traced it ('palm' or a finger name, as the SDK's circles belong
    # to one pointable) and its centre [x, y, z] in mm, Leap axes.
    source: str = ''
    center: Optional[Tuple[float, float, float]] = None


@dataclass
class GestureState:
    fist: bool = False
    thumb_up: bool = False
    pinch: bool = False
    pinch_value: float = 0.0           # 0..0.8
    rock: bool = False
    open: bool = False
    finger_extended: Tuple[bool, ...] = (False,) * 5
    events: List[HandEvent] = field(default_factory=list)
    thumb_down: bool = False           # its own gesture: bound to nothing, never a thumbs-up
    label: str = ''                    # the pose model's winning class this frame
    probability: float = 0.0           # ... and its probability
    user: Tuple[str, ...] = ()         # a user's own gestures held now
    judged: bool = True                # False: a frame too unsure to judge (held state)
    unseen: Tuple[str, ...] = ()       # held, but not shown for over CARRY_CREDIT_FRAMES: no hold


class HeldFilter:
    """Per-frame decisions -> filtered held gestures and their start / stop, fold and
    unfold events."""

    def __init__(self, on_frames=3, off_frames=3, on_time=None, extra=()):
        self.on_frames = max(1, int(on_frames))
        self.off_frames = max(1, int(off_frames))
        self.on_time = dict(on_time or {})
        self.names = HELD_GESTURES + tuple(extra)
        self.reset()

    def reset(self):
        self.active = set()
        self._count = {name: 0 for name in self.names}
        self._since = {name: 0.0 for name in self.names}
        self._lapsed = {}               # carried past its credit: name -> frames shown since
        self._lapsed_since = {}         # ... the first of them
        self._last_confident = -math.inf
        self._shape = None              # 'fist' / 'open' held now, or None
        self._shape_since = 0.0
        self._shape_held = 0.0          # ... judged frames' time in it
        self._shape_seen = 0.0          # ... its last judged frame
        self._judged_before = False     # the frame before this one was judged
        self._frame_t = None            # the frame before this one, judged or not
        self._intervals = collections.deque(maxlen=STALL_WINDOW)   # the recent frame intervals > 0
        self._stale_shape = None        # the shape the filter holds over a stall, until it changes
        self._confirmed = False         # ... held FOLD_CONFIRM_S (a fold / unfold judged)
        self._last_shape = None         # the last confirmed one that ended: its hold, its end
        self._last_held = 0.0
        self._last_end = 0.0

    def update(self, raw, timestamp):
        """Feed one usable frame's decisions {gesture: bool}; the set of active ones."""
        self._last_confident = timestamp
        active, count = self.active, self._count
        for name in self.names:
            want = bool(raw.get(name))
            if want == (name in active):
                count[name] = 0
                continue
            if count[name] == 0:
                self._since[name] = timestamp
            count[name] += 1
            if want:
                done = (count[name] >= self.on_frames and
                        timestamp - self._since[name] >= self.on_time.get(name, 0.0) - 1e-9)
            else:
                done = count[name] >= self.off_frames
            if done:
                count[name] = 0
                if want:
                    active.add(name)
                else:
                    active.discard(name)
        # a gesture carried past its credit stays unseen until shown on_frames in a row
        # again, as if it had stopped (a glimpse of it is no more than a glimpse)
        lapsed = self._lapsed
        for name in list(lapsed):
            if name not in active:
                del lapsed[name]
            elif raw.get(name):
                if lapsed[name] == 0:
                    self._lapsed_since[name] = timestamp
                lapsed[name] += 1
                if lapsed[name] >= self.on_frames and timestamp - self._lapsed_since[name] \
                        >= self.on_time.get(name, 0.0) - 1e-9:
                    del lapsed[name]
            else:
                lapsed[name] = 0
        for name in active:
            if count[name] > CARRY_CREDIT_FRAMES:
                lapsed[name] = 0
        return active

    def carried(self):
        """The held gestures not shown for more than CARRY_CREDIT_FRAMES judged frames."""
        count, lapsed = self._count, self._lapsed
        return tuple(n for n in self.active if count[n] > CARRY_CREDIT_FRAMES or n in lapsed)

    def unusable(self, timestamp):
        """An unusable frame: hold what we had for a moment, then let go; a thumbs-up
        at once (it arms a robot after a hold, which must be seen, not assumed)."""
        if timestamp - self._last_confident > HOLD_LOW_CONFIDENCE_S:
            self.active.clear()
        self.active.discard('thumb_up')
        for name in self.names:
            # a gesture turning on starts again; one turning off goes on turning off (an
            # unsure frame every other one kept a misread shape on for good)
            if name not in self.active:
                self._count[name] = 0
                self._lapsed.pop(name, None)
            elif name in self._lapsed:      # ... as does one carried past its credit, shown again
                self._lapsed[name] = 0
        return self.active

    def _stalled(self, dt):
        """Whether a frame interval dt breaks the stream: back in time, or longer than
        FOLD_GAP_S and STALL_FACTOR times the median of the recent ones (any such interval
        before STALL_WINDOW / 4 of them are known). A median, so dropped frames or a stall
        do not stretch it, nor a stopped clock's equal stamps (not counted) shrink it; a
        clock that speeds up is followed within STALL_WINDOW / 2 frames."""
        recent = self._intervals
        stalled = dt < 0.0
        if dt > FOLD_GAP_S:             # rare: only then the median (the lower middle one)
            stalled = len(recent) < STALL_WINDOW // 4 or \
                dt > STALL_FACTOR * sorted(recent)[(len(recent) - 1) // 2]
        if dt > 0.0:
            recent.append(dt)
        return stalled

    def events(self, state, prev, timestamp, judged=True, raw_shape=None):
        """Events of the change from `prev` to `state` (GestureStates) at `timestamp`;
        judged: the frame was judged (not one whose state is only held); raw_shape: the
        shape ('fist', 'open' or None) this frame shows before the filter."""
        events = []
        for name in HELD_GESTURES:
            now = getattr(state, name)
            if now != getattr(prev, name):
                events.append(HandEvent(name, now,
                                           state.pinch_value if name == 'pinch' else 0.0))
        for name in set(state.user) ^ set(prev.user):
            events.append(HandEvent(name, name in state.user))
        judged_before, self._judged_before = self._judged_before, judged
        stalled = self._frame_t is not None and self._stalled(timestamp - self._frame_t)
        if stalled:
            # A stalled stream or a rewound stamp: no shape spans it (the filter still holds
            # the one before for a few frames, which would measure the gap as none).
            self._shape, self._confirmed, self._last_shape = None, False, None
        # A judged frame counts its own interval (capped: a stalled stream's gap is no hold);
        # an unsure frame counts nothing.
        frame_dt = (0.0 if self._frame_t is None
                    else min(max(timestamp - self._frame_t, 0.0), FOLD_FRAME_CREDIT_S))
        self._frame_t = timestamp
        if not judged:              # held state only: the shapes wait for a judged frame
            return events
        # A shape carried past its credit by a long off-filter is no longer the shape: its
        # end (where the gap to the next one starts) is where it was last shown.
        unseen = state.unseen
        shape = ('fist' if state.fist and 'fist' not in unseen else
                 'open' if state.open and 'open' not in unseen else None)
        if stalled:
            self._stale_shape = shape
        elif shape != self._stale_shape:
            self._stale_shape = None
        if shape is not None and shape == self._stale_shape and raw_shape != shape:
            # held over the stall by the filter, not seen: no hold (at 5 fps or under a fast
            # sim clock the filter's few frames would make a first shape of their own)
            frame_dt = 0.0
        if shape != self._shape:
            if self._shape is not None and self._confirmed:
                # ... up to the frame that ends it, when that one follows a judged frame
                self._last_shape = self._shape
                self._last_held = self._shape_held + (frame_dt if judged_before else 0.0)
                self._last_end = timestamp if judged_before else self._shape_seen
            self._shape, self._shape_since, self._shape_held = shape, timestamp, 0.0
            self._confirmed = False
        else:
            self._shape_held += frame_dt
        self._shape_seen = timestamp
        if shape is not None and not self._confirmed \
                and self._shape_held >= FOLD_CONFIRM_S - 1e-9:
            self._confirmed = True
            if self._last_shape not in (None, shape) and self._last_held >= FOLD_HOLD_S - 1e-9 \
                    and self._shape_since - self._last_end <= FOLD_GAP_S:
                events.append(HandEvent('unfold' if shape == 'open' else 'fold'))
            self._last_shape = None
        return events
