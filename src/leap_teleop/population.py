"""A seeded synthetic population of hands and poses to test the recognizer against.

Each person has a hand size (adult 5th-95th percentile), finger proportions, a handedness
and the ways they form each gesture (fist tight or loose with the thumb tucked, alongside
or laid over the fingers, horns with the thumb folded or out, an OK sign with the other
fingers straight, relaxed, curled or all rounded onto the thumb as an "O", ...), a
tracking profile (palm noise 5-10 mm, fingertip jitter, confidence dips, a finger
mis-tracked now and then) and the fields their tracker leaves out (no knuckles, no joints
at all, no SDK strengths, no timestamps). Poses come from joint angles and thumb
placements read off how hands are formed, in the hand's own size, never from the
recognizer's thresholds. Orientation per take: palm down, sideways, tilted up to 60 deg
(fists and the hooked index also upright, as raised to a camera, turned any way about the
forearm; a raised fist with its thumb out is always upright); thumbs-up / down point the
thumb within 45 deg of vertical (leaning toward the fingers up to 45 deg, the hand pitched
to match), a sideways thumb > 65 deg off.

    people = make_people(200, seed=1)
    for frames in take(person, 'fist', rng): ...   # (Hand, timestamp) per frame

GESTURE_POSES name the pose that should show each gesture; CONFUSERS are poses that
should show none (thumbs-down shows only thumb_down).
"""
import math
from dataclasses import dataclass

import numpy as np

from .frame import Finger, Hand

GESTURE_POSES = {'fist': 'fist', 'thumb_up': 'thumbs_up', 'thumb_down': 'thumbs_down',
                 'pinch': 'ok', 'rock': 'horns', 'open': 'open'}
CONFUSERS = ('index', 'two', 'three', 'L', 'hang_loose', 'C', 'O', 'sideways_thumb', 'hook',
             'raised_fist')
POSES = tuple(GESTURE_POSES.values()) + CONFUSERS
# What each pose should show (the rest: nothing).
EXPECTED = {pose: gesture for gesture, pose in GESTURE_POSES.items()}

_FINGERS = ('index', 'middle', 'ring', 'pinky')
# Knuckles in palm widths (index-pinky knuckle distance): thumbward x, out of the palm y,
# toward the fingers z (the hand frame).
_KNUCKLES = np.array([[0.5, 0.0, 1.0], [0.17, 0.0, 1.08], [-0.17, 0.0, 1.0], [-0.5, 0.0, 0.82]])
_THUMB_BASE = np.array([0.55, 0.15, 0.05])
# Finger length knuckle -> tip over palm width, mean (adult proportions) and spread.
_LENGTH = np.array([1.50, 1.65, 1.55, 1.22])
_PHALANX = np.array([0.47, 0.30, 0.23])       # proximal, middle, distal share
_SPLAY = np.array([6.0, 0.0, -6.0, -13.0])    # deg, extended fingers fan out


@dataclass
class Person:
    id: int
    side: str
    palm_width: float            # mm, index-pinky knuckle distance
    lengths: np.ndarray          # (4,) knuckle -> tip, palm widths
    thumb_length: float          # thumb base -> tip when straight, palm widths
    fist_thumb: str              # 'tucked' | 'alongside' | 'over' (laid over the fingers)
    horns_thumb: str             # 'folded' | 'out'
    ok_fingers: str              # 'straight' | 'relaxed' | 'curled' | 'O' (all rounded
                                 # onto the thumb tip, fingertips bunched)
    open_style: str              # 'flat' | 'relaxed'
    looseness: float             # 0 tight .. 1 loose curls
    palm_noise: float            # mm sd
    tip_noise: float             # mm sd
    missing: str                 # '' | 'knuckles' | 'joints' | 'strengths' | 'timestamps'
    mistrack_rate: float         # chance per take of one finger reported sharply bent
    dip_rate: float              # fraction of frames with a confidence dip


def make_people(n, seed=0):
    rng = np.random.default_rng(seed)
    people = []
    for i in range(n):
        # Hand breadth (adult women ~N(80, 4.5) mm, men ~N(89, 4.5)), clipped to the
        # 5th..95th percentile of both (72..97 mm); knuckle centres span ~62 % of it.
        male = rng.random() < 0.5
        breadth = float(np.clip(rng.normal(89.0 if male else 80.0, 4.5), 72.0, 97.0))
        lengths = _LENGTH * rng.normal(1.0, 0.06) * rng.normal(1.0, 0.04, 4)
        people.append(Person(
            id=i, side='right' if rng.random() < 0.85 else 'left',
            palm_width=0.62 * breadth, lengths=lengths,
            thumb_length=float(1.75 * rng.normal(1.0, 0.07)),
            fist_thumb=str(rng.choice(['tucked', 'alongside', 'over'], p=[0.4, 0.4, 0.2])),
            horns_thumb=str(rng.choice(['folded', 'out'])),
            ok_fingers=str(rng.choice(['straight', 'relaxed', 'curled', 'O'],
                                      p=[0.3, 0.4, 0.15, 0.15])),
            open_style=str(rng.choice(['flat', 'relaxed'])),
            looseness=float(rng.random()),
            palm_noise=float(rng.uniform(5.0, 10.0)), tip_noise=float(rng.uniform(1.0, 3.0)),
            missing=str(rng.choice(['', 'knuckles', 'joints', 'strengths', 'timestamps'],
                                   p=[0.45, 0.15, 0.15, 0.15, 0.1])),
            mistrack_rate=float(rng.uniform(0.0, 0.3)), dip_rate=float(rng.uniform(0.0, 0.08))))
    return people


# -- poses: per finger (mcp, pip, dip) flexion in degrees, drawn per take -----------------
def _flex(rng, kind, loose):
    u = rng.uniform
    if kind == 'straight':
        return np.array([u(-5, 12), u(0, 12), u(0, 8)])
    if kind == 'relaxed':
        return np.array([u(5, 25), u(10, 30), u(5, 20)])
    if kind == 'curled':           # in a fist; a loose fist curls less
        return np.array([u(70, 95), u(90, 110), u(45, 75)]) - loose * np.array([15, 15, 15])
    if kind == 'folded':           # folded down (horns' middle and ring, "two"'s others)
        return np.array([u(55, 90), u(75, 110), u(30, 70)])
    if kind == 'C':
        return np.array([u(15, 35), u(30, 55), u(15, 35)])
    if kind == 'O':
        return np.array([u(30, 50), u(45, 70), u(25, 45)])
    if kind == 'pinching':         # the index bent to meet the thumb
        return np.array([u(25, 45), u(30, 55), u(10, 35)])
    if kind == 'hooked':           # bent to about a right angle at the middle and end
        return np.array([u(-5, 20), u(40, 70), u(20, 50)])     # joints, the knuckle straight
    if kind == 'mistracked':       # the tracker shows it sharply bent
        return np.array([u(30, 60), u(60, 100), u(20, 50)])
    raise ValueError(kind)


_SHAPES = {   # pose -> (finger kinds index..pinky, thumb placement)
    'open': (None, 'open'), 'fist': (('curled',) * 4, None),
    'thumbs_up': (('curled',) * 4, 'up'), 'thumbs_down': (('curled',) * 4, 'up'),
    'sideways_thumb': (('curled',) * 4, 'up'),
    'horns': (('straight', 'folded', 'folded', 'straight'), None),
    'ok': (None, 'meet'), 'index': (('straight', 'folded', 'folded', 'folded'), 'tucked'),
    'two': (('straight', 'straight', 'folded', 'folded'), 'tucked'),
    'three': (('straight', 'straight', 'straight', 'folded'), 'over_pinky'),
    'L': (('straight', 'folded', 'folded', 'folded'), 'open'),
    'hang_loose': (('folded', 'folded', 'folded', 'straight'), 'up'),
    'C': (('C',) * 4, 'C'), 'O': (('O',) * 4, 'meet'),
    'hook': (('hooked', 'curled', 'curled', 'curled'), 'tucked'),
    # a fist raised with the fingers up, its thumb out to the side and toward the fingers:
    # the thumb points up with the hand, it is not raised
    'raised_fist': (('curled',) * 4, 'open'),
}


def _finger_chain(knuckle, length, flex, splay_deg):
    """(4, 3) mcp, pip, dip, tip in the hand frame (palm widths): flexion turns the finger
    from +z toward +y (out of the palm), splay fans it about y."""
    s = math.radians(splay_deg)
    pts = [knuckle]
    a = 0.0
    p = knuckle
    for seg, f in zip(_PHALANX * length, flex):
        a += math.radians(f)
        d = np.array([math.sin(s) * math.cos(a), math.sin(a), math.cos(s) * math.cos(a)])
        p = p + seg * d
        pts.append(p)
    return np.array(pts)


def _thumb_chain(tip, rng, high=False):
    """(4, 3) base, knuckle, IP joint, tip of a thumb ending at `tip` (palm widths); the
    joints bow out of the palm a little (high: a thumb lying over a fist rises from the
    palm first, then runs along the fingers)."""
    base = _THUMB_BASE
    v = tip - base
    bow = np.array([0.0, 1.0, 0.0]) * (rng.uniform(0.3, 0.5) if high else rng.uniform(0.05, 0.15))
    return np.array([base, base + 0.45 * v + bow, base + 0.75 * v + 0.6 * bow, tip])


def local_pose(person, pose, rng):
    """(5, 4, 3) joints (mcp, pip, dip, tip; thumb first) in the hand frame, palm widths,
    plus the true flexions (4, 3) of index..pinky."""
    kinds, thumb = _SHAPES[pose]
    loose = person.looseness
    if pose == 'open':
        kinds = (person.open_style if person.open_style == 'relaxed' else 'straight',) * 4
    bunched = pose == 'ok' and person.ok_fingers == 'O'
    if pose == 'ok':
        other = {'straight': 'straight', 'relaxed': 'relaxed', 'curled': 'C',
                 'O': 'O'}[person.ok_fingers]
        kinds = ('O' if bunched else 'pinching', other, other, other)
    if pose == 'fist':
        thumb = person.fist_thumb
    if pose == 'horns':
        thumb = 'tucked' if person.horns_thumb == 'folded' else 'open'
    flex = np.array([_flex(rng, k, loose) for k in kinds])
    splay = _SPLAY * (1.0 if pose in ('open', 'three', 'horns', 'two', 'hang_loose') else 0.3)
    fingers = [_finger_chain(_KNUCKLES[i], person.lengths[i], flex[i], splay[i]) for i in range(4)]
    u = rng.uniform
    if bunched:
        # An "O": the other fingers lean in toward the index at each joint (with the palm
        # cupped) so their tips gather at the index tip's side.
        for i in (1, 2, 3):
            c = fingers[i].copy()
            shift = (fingers[0][3][0] - c[3][0]) * u(0.7, 1.0)
            c[1:, 0] += shift * np.array([0.35, 0.7, 1.0])
            fingers[i] = c
    tl = person.thumb_length
    if thumb in ('open', 'up'):
        # out from the hand: thumbward, a little forward (up: nearly straight out; a
        # thumbs-up / down thumb leans toward the fingers as far as photos show, 45 deg)
        a = math.radians(u(35, 65) if thumb == 'open' else
                         u(0, 45) if pose in ('thumbs_up', 'thumbs_down') else u(0, 20))
        tip = _THUMB_BASE + tl * np.array([math.cos(a), u(-0.05, 0.15), math.sin(a)])
    elif thumb == 'tucked':       # across the curled index and middle
        tip = np.array([u(-0.3, 0.15), u(0.45, 0.75), u(0.7, 1.0)])
    elif thumb == 'over_pinky':   # holding the folded pinky down
        tip = np.array([u(-0.5, -0.2), u(0.5, 0.8), u(0.8, 1.1)])
    elif thumb == 'alongside':    # along the side of the curled index
        tip = np.array([0.5 + u(0.1, 0.3), u(0.45, 0.75), u(1.05, 1.35)])
    elif thumb == 'over':         # laid over the curled fingers, pointing along them: its
        # tip out of the palm beyond the index's middle joint, well thumbward of the knuckle
        pip = fingers[0][1]
        tip = np.array([0.5 + u(0.35, 0.6), pip[1] + u(0.3, 0.6), pip[2] + u(-0.15, 0.15)])
    elif thumb == 'meet':         # at the index tip (OK sign, O)
        d = rng.normal(size=3)
        tip = fingers[0][3] + d / np.linalg.norm(d) * u(0.15, 0.4)
        if bunched:               # ... and the other fingertips round it
            tip = np.mean([f[3] for f in fingers], axis=0) * 0.4 + tip * 0.6
    elif thumb == 'C':            # opposite the fingertips with an opening
        tip = fingers[0][3] + np.array([u(0.0, 0.2), u(-0.1, 0.2), -u(0.9, 1.5)])
    else:
        raise ValueError(thumb)
    joints = np.concatenate([_thumb_chain(tip, rng, high=thumb == 'over')[None],
                             np.array(fingers)])
    return joints, flex


# -- orientation ----------------------------------------------------------------------------
def _rot(axis, deg):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    a = math.radians(deg)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k


def orientation(person, pose, rng):
    """3x3 hand-frame -> Leap axes (columns thumbward, normal, direction)."""
    sgn = 1.0 if person.side == 'right' else -1.0
    # palm down, fingers away from the user: thumbward = -x (right hand), n = -y, d = -z
    base = np.array([[-sgn, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]).T
    d = np.array([0.0, 0.0, -1.0])
    if pose in ('thumbs_up', 'thumbs_down', 'sideways_thumb'):
        # Roll about the hand direction to put the thumbward axis up / down / level,
        # then tilt a little either way.
        roll = {'thumbs_up': -90.0, 'thumbs_down': 90.0}.get(pose, rng.choice([0.0, 180.0]))
        r = _rot(d, -sgn * roll) @ base
        tilt = rng.uniform(-20, 20) if pose != 'sideways_thumb' else rng.uniform(-15, 15)
        r = _rot([1.0, 0.0, 0.0], rng.uniform(-20, 20)) @ _rot(d, tilt) @ r
        return r
    if pose == 'raised_fist' or (pose in ('fist', 'hook') and rng.random() < 0.25):
        # upright, as raised to a camera: fingers up, turned any way about the forearm
        return (_rot([0, 1, 0], rng.uniform(-30, 30)) @ _rot([1, 0, 0], rng.uniform(65, 90))
                @ _rot(d, rng.uniform(-180, 180)) @ base)
    kind = rng.choice(['down', 'sideways', 'tilted'])
    if kind == 'down':
        return _rot([0, 1, 0], rng.uniform(-20, 20)) @ base
    if kind == 'sideways':
        return (_rot([0, 1, 0], rng.uniform(-20, 20))
                @ _rot(d, -sgn * 90.0 + rng.uniform(-15, 15)) @ base)
    return (_rot([0, 1, 0], rng.uniform(-30, 30)) @ _rot([1, 0, 0], rng.uniform(-60, 60))
            @ _rot(d, rng.uniform(-60, 60)) @ base)


THUMB_POSE_DEG = 45.0       # thumbs-up / down: the thumb this near vertical at most


# -- frames -----------------------------------------------------------------------------
def _sdk_grab(flex):
    """A tracker-like grab strength from the true finger flexions: 0 until the fingers
    curl on average past ~70 deg in all (the Leap reports 0 for open hands and for a hand
    with one finger bent 125 deg, 1 for fists), 1 from ~210 deg."""
    return float(np.clip((flex.sum(axis=1).mean() - 70.0) / 140.0, 0.0, 1.0))


def take(person, pose, rng, frames=30, rate=60.0, t0=0.0):
    """[(Hand, timestamp)] of `person` holding `pose` for `frames` frames: one draw of the
    pose and orientation, tremor and tracking noise per frame."""
    joints, flex = local_pose(person, pose, rng)
    rot = orientation(person, pose, rng)
    if pose in ('thumbs_up', 'thumbs_down'):
        # A thumbs-up / down points the thumb (knuckle -> tip) within THUMB_POSE_DEG of
        # vertical: a thumb leaning toward the fingers goes with a hand pitched the other
        # way (drawn again until it does, from a generator of its own so that the other
        # takes keep their draws).
        redraw = None
        for _ in range(50):
            t = rot @ (joints[0, 3] - joints[0, 1])
            if abs(t[1]) / np.linalg.norm(t) >= math.cos(math.radians(THUMB_POSE_DEG)):
                break
            if redraw is None:
                redraw = np.random.default_rng([person.id, POSES.index(pose),
                                                int(abs(joints[0, 3, 0]) * 1e6)])
            rot = orientation(person, pose, redraw)
    s = person.palm_width
    palm = np.array([rng.uniform(-80, 80), rng.uniform(150, 300), rng.uniform(-60, 60)])
    mistracked = rng.integers(1, 5) if rng.random() < person.mistrack_rate else None
    grab = _sdk_grab(flex)
    out = []
    for k in range(frames):
        j = joints
        if mistracked is not None and pose == 'open':
            j = joints.copy()
            i = int(mistracked)
            j[i] = _finger_chain(_KNUCKLES[i - 1], person.lengths[i - 1],
                                 _flex(rng, 'mistracked', 0.0), 0.0)
        # tremor: a slow wobble of the whole hand, a degree or two
        wob = _rot(rng.normal(size=3), rng.normal(0.0, 1.5)) @ rot
        world = (j * s) @ wob.T + palm + rng.normal(0.0, person.tip_noise, j.shape)
        n, d = wob[:, 1], wob[:, 2]
        palm_seen = palm + rng.normal(0.0, person.palm_noise, 3)
        fingers = []
        for i in range(5):
            w = world[i]
            u = w[3] - w[2]
            u = u / np.linalg.norm(u)
            mcp, pip, dip = w[0], w[1], w[2]
            if person.missing == 'knuckles':
                mcp = None
            elif person.missing == 'joints':
                mcp = pip = dip = None
            true_ext = i == 0 or flex[i - 1].sum() < 60
            ext = true_ext if rng.random() > 0.05 else not true_ext
            fingers.append(Finger(tip=w[3], direction=u, extended=bool(ext), mcp=mcp, pip=pip,
                                  dip=dip))
        g = float(np.clip(grab + rng.normal(0, 0.04), 0, 1))
        gap = np.linalg.norm(joints[0, 3] - joints[1, 3])
        p = float(np.clip(1.0 - (gap - 0.3) / 0.8, 0.0, 1.0))
        if person.missing == 'strengths':
            g = p = math.nan
        dipped = rng.random() < person.dip_rate
        conf = float(rng.uniform(0.02, 0.3) if dipped else rng.uniform(0.6, 1.0))
        hand = Hand(side=person.side, palm_position=palm_seen, palm_normal=n, direction=d,
                    grab_strength=g, pinch_strength=p, confidence=conf, fingers=tuple(fingers))
        t = t0 + k / rate
        out.append((hand, math.nan if person.missing == 'timestamps' else t))
    return out


# -- motions: what must and must not make a circle ----------------------------------------
MOTIONS = ('swipe', 'tap', 'point_tap', 'knob', 'translate', 'arc', 'circle', 'finger_circle')
CIRCLE_MOTIONS = ('circle', 'finger_circle')      # the motions that should fire a circle


def motion_take(person, kind, rng, rate=60.0):
    """[(Hand, timestamp)] of `person` making a motion with an open hand (a pinch-grip
    for the knob, pointing for the last two): 'swipe' (a fast stroke across and a slow
    return), 'tap' (the index tapping down and up), 'point_tap' (the same while pointing),
    'knob' (turning the hand about its axis back and forth), 'translate' (straight moves
    between random points), 'arc' (along at most half a circle), 'circle' (the palm once
    round a hand-sized circle), 'finger_circle' (the index tip once round a 40-120 mm
    circle across the finger, as people draw one). Only the last two should fire."""
    u = rng.uniform
    pose = {'knob': 'ok', 'finger_circle': 'index', 'point_tap': 'index'}.get(kind, 'open')
    joints, flex = local_pose(person, pose, rng)
    rot = orientation(person, pose, rng)
    start = np.array([u(-60, 60), u(180, 260), u(-40, 40)])
    if kind == 'swipe':
        dur = u(0.25, 0.4) + u(0.5, 0.8)
    elif kind in ('circle', 'finger_circle'):
        dur = u(0.9, 1.5)
    else:
        dur = u(1.0, 2.0)
    n = int(dur * rate)
    t = np.arange(n) / rate
    path = np.repeat(start[None], n, axis=0)
    roll = np.zeros(n)
    tap = np.zeros(n)
    if kind == 'swipe':
        d = rng.normal(size=3)
        d[1] *= 0.3
        d /= np.linalg.norm(d)
        length, t_out = u(150, 350), u(0.25, 0.4)
        s = np.where(t < t_out, t / t_out, 1.0 - (t - t_out) / (dur - t_out))
        path = start + np.outer(np.clip(s, 0, 1) * length, d)
    elif kind in ('tap', 'point_tap'):
        f = u(2.0, 4.0)
        tap = np.clip(np.sin(2 * np.pi * f * t), 0, None) * u(25, 45)
    elif kind == 'knob':
        f = u(0.8, 1.5)
        roll = np.sin(2 * np.pi * f * t) * u(30, 70)
    elif kind == 'translate':
        pts = start + rng.uniform(-120, 120, (4, 3)) * np.array([1.0, 0.5, 1.0])
        k = np.linspace(0, 3, n)
        i = np.minimum(k.astype(int), 2)
        w = (k - i)[:, None]
        path = pts[i] * (1 - w) + pts[i + 1] * w
    elif kind in ('arc', 'circle'):
        r = u(80, 150) if kind == 'arc' else u(30, 80)
        sweep = u(0.5, 1.0) * math.pi if kind == 'arc' else u(1.1, 1.4) * 2 * math.pi
        a = np.linspace(0, sweep, n) * rng.choice([-1.0, 1.0])
        path = start + r * np.stack([np.cos(a) - 1, np.zeros(n), np.sin(a)], axis=1)
    elif kind == 'finger_circle':
        # the hand carries the index tip round a circle in the plane across the finger
        axis = (joints[1][3] - joints[1][2]) @ rot.T
        axis /= np.linalg.norm(axis)
        e1 = np.cross(axis, [0.0, 1.0, 0.0] if abs(axis[1]) < 0.9 else [1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(axis, e1)
        r = u(40, 120)         # the shared strokes' drawn circles: 60-130 mm
        a = np.linspace(0, u(1.1, 1.4) * 2 * math.pi, n) * rng.choice([-1.0, 1.0])
        path = start + r * (np.outer(np.cos(a) - 1, e1) + np.outer(np.sin(a), e2))
    s = person.palm_width
    d_axis = rot[:, 2]
    out = []
    for k in range(n):
        j = joints
        if tap[k] > 0:
            j = joints.copy()
            f = flex[0] + np.array([tap[k], 0.6 * tap[k], 0.3 * tap[k]])
            j[1] = _finger_chain(_KNUCKLES[0], person.lengths[0], f, 0.0)
        r = _rot(d_axis, roll[k]) @ rot
        world = (j * s) @ r.T + path[k] + rng.normal(0.0, person.tip_noise * 0.5, j.shape)
        fingers = []
        for i in range(5):
            w = world[i]
            dvec = (w[3] - w[2]) / np.linalg.norm(w[3] - w[2])
            fingers.append(Finger(tip=w[3], direction=dvec, extended=True, mcp=w[0], pip=w[1],
                                  dip=w[2]))
        hand = Hand(side=person.side, palm_position=path[k] + rng.normal(0.0, 1.0, 3),
                    palm_normal=r[:, 1], direction=r[:, 2], grab_strength=0.0,
                    pinch_strength=0.0, confidence=1.0, fingers=tuple(fingers))
        out.append((hand, k / rate))
    return out
