"""Per-frame pose rules on a HandGeometry: which held gestures the hand shows.

Every threshold is a pair (to turn on, to stay on): a gesture already on is judged on the
looser one (hysteresis). Lengths are in palm widths, curl is the finger's chord ratio
(see geometry), so the rules hold for small and large hands alike; where a frame lacks
the joints for a ratio the rules fall back to bend angles.

- fist: index..pinky curled, thumb tucked over them, lying alongside the index, or laid
  over the fingers toward their tips (then its tip may sit well thumbward of the index
  knuckle: judged by where it lies, beyond the curled fingers, not only how far out).
  An index hooked at its middle joints with its knuckle straight, beside fingers bent at
  the knuckle, is held out of the fist, not curled.
- thumb_up / thumb_down: the same curled fingers with the thumb out, pointing up / down
  (Leap +y / -y, within THUMB_VERTICAL), out from the side of the fist, and more up /
  down than the hand direction (a fist raised with its fingers up is no thumbs-up). A
  thumb out sideways is neither, nor a fist.
- rock: index and pinky extended, middle and ring folded, thumb either way.
- pinch: thumb tip at the index tip, the other fingers in any state but all curled to
  the thumb like the index with their tips in a row across the hand (a loose fist) and
  not a fist; an "O", every fingertip gathered at the thumb tip, is a pinch.
- open: index..pinky extended, thumb either way, not pinching; one finger reported
  sharply bent is forgiven while the tracker's grab strength stays low and the thumb is
  out (a tracker's mis-tracked finger; a real "three" holds its fourth finger with the
  thumb and shows grab).
"""
import math

from .geometry import num

PINCH_THRESHOLD = 0.2   # original: pinch when strength > 0.2; pinch_value = strength - 0.2

# Chord ratio of a curled finger (fist, thumbs-up): a tight fist ~0.4, a loose one ~0.6, a
# C or O shape ~0.7 and up. Bend fallback (degrees) without joints.
CURLED_CHORD = (0.64, 0.72)
CURLED_BEND = (95.0, 85.0)
# Folded enough for rock's middle and ring (a horns hand rarely folds them as deep).
FOLDED_CHORD = 0.8
FOLDED_BEND = 85.0
# ... but a finger bent down at the knuckle alone (tapping) keeps a straight chord: folded
# needs its chord below this too when the joints are there.
FOLDED_MAX_CHORD = 0.88
# Thumb tip to the nearest index / middle joint in a fist (palm widths): ~0.2..0.8; in a
# C it faces the fingertips across an opening.
FIST_THUMB_NEAR = (0.9, 1.05)
FIST_GRAB_WITHOUT_JOINTS = 0.9
# Extended: nearly straight and pointing along the hand (a relaxed finger bends ~20 deg
# per joint: chord ~0.95, bend ~50).
EXTENDED_CHORD = (0.85, 0.8)
EXTENDED_BEND = (85.0, 95.0)
# ... and an open hand's four fingers bend this little on average (a C shape bends each
# finger about as far as a relaxed hand's most bent one, but all of them).
OPEN_MEAN_BEND = (65.0, 75.0)
# Thumbs-up needs the fingers deeper in the fist to start: every unfold passes through a
# fist with the thumb already out while the fingers are still half-bent.
THUMB_UP_CURLED_CHORD = (0.58, 0.72)
THUMB_UP_CURLED_BEND = (110.0, 85.0)
# Thumb tip thumbward of the index knuckle, palm widths: tucked < 0, alongside the index
# ~0.1..0.4 (the shared takes: a thumb 0.41..0.46 out is already leaving the fist), out
# (thumbs-up) ~0.5..1.3.
THUMB_OUT = (0.4, 0.35)
# A thumbs-up / down shows the thumb well out (camera photos of fists with the thumb laid
# over the fingers reach 0.56..0.62, thumbs-up 0.69..1.1; the shared takes' 0.74..1.3), and
# not laid along the hand (thumb . hand direction below THUMB_UP_MAX_ALONG; a fist's
# alongside thumb 0.9..1).
THUMB_UP_OUT = (0.65, 0.55)
THUMB_UP_MAX_ALONG = 0.95
# ... and pointing out from the side of the fist: thumb . thumbward above this (thumbs-up
# photos 0.40..0.81, 0.26 and up with 4 mm of landmark noise; the shared takes' >= 0.48; a
# thumb laid along an upright fist's fingers points up with them: ~0.06, with noise
# up to ~0.25, where it may also pass the other thumbs-up bars).
THUMB_UP_MIN_THUMBWARD = 0.25
# A thumb lying over the curled fingers: its tip this far (palm widths) out of the palm
# beyond the index's middle joint (a fist's tucked or laid-over thumb 0.2..0.7; a thumb
# swung out beside a fist, the shared takes' -0.7..-0.04). Such a thumb closes a fist
# while its tip stays within THUMB_UP_OUT thumbward: a thumb further out is a thumbs-up
# or leaving the fist (raised thumbs stand out of the palm too: photos 0.16..0.37).
THUMB_OVER = 0.2
# A hooked index: its knuckle flexed less than this (deg) while the middle and ring
# fingers' knuckles bend more than HOOK_OTHERS_KNUCKLE (a fist bends every knuckle alike:
# the shared takes' loose fists keep all four nearly straight, a tight fist bends all
# 50..95).
HOOK_KNUCKLE = 30.0
HOOK_OTHERS_KNUCKLE = 45.0
# Without knuckles: the index bent this much less (deg) than the middle and ring fingers
# (a fist's index bends up to ~75 less than they do: its curl at the low end of the
# range, theirs at the high end; a hooked index 80..130 less).
HOOK_BEND_GAP = 80.0
# ... and pointing up (down) more than the hand direction does, by this much of Leap y
# (thumbs-up photos 0.32..0.66, thumbs-down 0.78, the shared takes' thumbs-up >= 0.34;
# fists raised with the fingers up -0.5..0.03: their thumbs point up with the hand; as
# an angle margin instead, 12 deg let the synthetic raised fists through).
THUMB_BEYOND_HAND = 0.15
# Thumbs-up / down: thumb (knuckle -> tip) within this angle of Leap +y / -y (deg). Real
# thumbs lean toward the fingers (photos: 22..44 deg off vertical as taken, MediaPipe's
# depth adding up to ~10 on a re-shot view); a sideways thumb is 65 and more off (the
# shared take's sideways thumbs, > 60 deg off by the SDK's thumb direction, read 55 and
# up knuckle -> tip).
THUMB_VERTICAL = (50.0, 55.0)
# Thumb-index tip gap (palm widths): touching ~0.2..0.5, apart > 0.9.
PINCH_GAP = (0.6, 0.75)
PINCH_GAP_OPEN = 1.1                 # geometric pinch strength 0 at this gap, 1 at 0.35
PINCH_GAP_CLOSED = 0.35
# In a pinch some other finger is less curled than the index, or the middle tip is well
# clear of the thumb; in an "O" they all curl to the thumb together.
PINCH_CHORD_MARGIN = 0.1
PINCH_BEND_MARGIN = 15.0
PINCH_MIDDLE_CLEAR = 0.9             # palm widths
PINCH_REST_BEND = (100.0, 110.0)     # an "O" bends every other finger more than this
# An "O": the index and pinky tips gathered within this distance across the hand (palm
# widths; an "O" ~0.05, a fist keeps its tips a knuckle row apart: the photos' 0.62..0.85,
# the shared takes' loose fists 0.75..0.95).
O_TIP_SPREAD = 0.4
# The index reaches out to the thumb (~60..135 deg), not curled into the palm under a
# thumb laid over the fist (~150 and up). An "O" is exempt: its index rounds to the
# gathered fingertips as far as a fist's (~100..175 deg), and a fist keeps its tips apart.
PINCH_MAX_INDEX_BEND = 150.0
# Open with one finger reported bent: the thumb must be out (not holding that finger down,
# as in a "three"), and the tracker's grab strength, when it gives one, below this.
OPEN_FORGIVE_GRAB = 0.15
OPEN_FORGIVE_THUMB_OUT = 0.2
_isfinite = math.isfinite


def geometric_pinch_strength(gap):
    """0..1 from the thumb-index gap in palm widths (1 = touching), like the SDK's."""
    if not _isfinite(gap):
        return 0.0
    s = (PINCH_GAP_OPEN - gap) / (PINCH_GAP_OPEN - PINCH_GAP_CLOSED)
    return min(max(s, 0.0), 1.0)


def _curled(c, b, chord_th, bend_th):
    """Either measure suffices: a tracker's curled finger model may keep a long chord
    (ring and pinky) or bend little (a loose fist seen by a camera)."""
    return c < chord_th or b > bend_th


def _folded(c, b):
    return _curled(c, b, FOLDED_CHORD, FOLDED_BEND) and not c >= FOLDED_MAX_CHORD


def classify_geometry(g, hand, active=None, opening=False):
    """Per-frame decisions {gesture: bool}, 'pinch_value' and 'extended' (5 bools) from a
    HandGeometry. `active` = gestures currently on: they are judged on the stay-on
    thresholds. `opening`: the fingers are unfolding fast (a stateful caller knows); no
    thumbs-up starts then."""
    active = active or ()
    bend, chord = g.bend, g.chord
    fist_on = 'fist' in active
    up_on = 'thumb_up' in active or 'thumb_down' in active
    k = 1 if fist_on else 0
    ku = 1 if up_on else 0
    ext_k = 1 if ('open' in active or 'rock' in active) else 0
    cc, cb = CURLED_CHORD[k], CURLED_BEND[k]
    uc, ub = THUMB_UP_CURLED_CHORD[ku], THUMB_UP_CURLED_BEND[ku]
    ec, eb = EXTENDED_CHORD[ext_k], EXTENDED_BEND[ext_k]
    dcc, dcb = CURLED_CHORD[ku], CURLED_BEND[ku]
    curled = thumb_curled = down_curled = True
    ext = [False] * 5
    n_ext = 0
    kn = g.knuckle
    if kn[1] == kn[1] and kn[2] == kn[2] and kn[3] == kn[3]:
        hooked = (kn[1] < HOOK_KNUCKLE and kn[2] > HOOK_OTHERS_KNUCKLE
                  and kn[3] > HOOK_OTHERS_KNUCKLE)
    else:       # (NaN compares False: without bends either, no index counts as hooked)
        hooked = bend[1] < min(bend[2], bend[3]) - HOOK_BEND_GAP
    for i in (1, 2, 3, 4):
        c, b = chord[i], bend[i]
        if (c != c and b != b) or (i == 1 and hooked):
            curled = thumb_curled = down_curled = False
            if c != c and b != b:
                continue
        if curled and not _curled(c, b, cc, cb):
            curled = False
        if thumb_curled and not _curled(c, b, uc, ub):
            thumb_curled = False
        if down_curled and not _curled(c, b, dcc, dcb):
            down_curled = False
        if b < eb and (c != c or c > ec):
            ext[i] = True
            n_ext += 1
    out = g.thumb_out > THUMB_OUT[1 if (up_on or 'open' in active) else 0]
    tw, td = g.basis[0], g.thumb_dir
    thumbward = tw[0] * td[0] + tw[1] * td[1] + tw[2] * td[2]
    # lying on the fist: over the fingers, or, without the index knuckle (thumb-out is
    # then measured from the palm centre, with its tracking noise), pointing along them
    no_knuckle = g.knuckle[1] != g.knuckle[1]
    over = g.thumb_over > THUMB_OVER or (no_knuckle and thumbward < THUMB_UP_MIN_THUMBWARD)
    up_out = (g.thumb_out > THUMB_UP_OUT[ku] and g.thumb_along < THUMB_UP_MAX_ALONG
              and thumbward > THUMB_UP_MIN_THUMBWARD)
    ty = g.thumb_dir[1]
    vert = math.cos(math.radians(THUMB_VERTICAL[ku]))
    # The thumb of a fist lies on the fingers (tucked or alongside), not away from them
    # as in a C. Without the finger joints (tips only) an alongside thumb is as far from
    # the tips as a C's: then a tracker's grab strength near 1 decides.
    near = (g.thumb_to_fingers < FIST_THUMB_NEAR[k]
            or (not g.finger_joints and g.grab >= FIST_GRAB_WITHOUT_JOINTS))
    gap = g.pinch_gap
    pk = 1 if 'pinch' in active else 0
    # every fingertip gathered at the thumb tip: an "O", not a fist
    o_shape = gap < PINCH_GAP[pk] and abs(g.tip_spread) < O_TIP_SPREAD
    # the thumb, not the whole hand, points up (down): a fist raised with the fingers up
    # shows its thumb pointing up with them
    dy = g.basis[2][1]
    thumb_up = (thumb_curled and up_out and ty > vert and ty - dy > THUMB_BEYOND_HAND
                and ('thumb_up' in active or not opening))
    # Thumbs-down arms nothing: the fist's curl suffices (a fist seen from the back, as a
    # thumbs-down mostly is, hides the fingers' middle joints and the camera's landmarks
    # flatten them).
    thumb_down = down_curled and up_out and ty < -vert and dy - ty > THUMB_BEYOND_HAND
    # A thumb lying on the fingers closes the fist up to the thumbs-up bar (without the
    # index knuckle thumb-out is too noisy to bar it: then until a thumbs-up shows).
    # A thumb over the fingers that points along the hand (a raised fist's thumb laid
    # up its fingers) lies on them however far thumbward its tip sits.
    lying = over and (no_knuckle or g.thumb_out <= THUMB_UP_OUT[0]
                      or not (g.thumb_along < THUMB_UP_MAX_ALONG
                              and thumbward > THUMB_UP_MIN_THUMBWARD))
    fist = (curled and near and not o_shape and not (out and not lying)
            and not (thumb_up or thumb_down))
    rock = (ext[1] and ext[4] and _folded(chord[2], bend[2]) and _folded(chord[3], bend[3]))
    pinch = False
    if gap < PINCH_GAP[pk] and not (fist or thumb_up or thumb_down):
        # Some other finger less curled than the index, or the middle tip clear of the
        # thumb: not every finger rounded to the thumb as in an "O".
        c1 = chord[1]
        rest_c = max(chord[2], chord[3], chord[4])
        b1, b2, b3, b4 = bend[1:]
        rest = min(b2, b3, b4)
        pinch = ((o_shape or not b1 >= PINCH_MAX_INDEX_BEND)
                 and (o_shape or g.middle_gap > PINCH_MIDDLE_CLEAR or rest < PINCH_REST_BEND[pk]
                      or rest_c > c1 + PINCH_CHORD_MARGIN or b1 > rest + PINCH_BEND_MARGIN))
    # Horns never have the thumb on the index tip; a pinch with the pinky out does.
    rock = rock and not pinch
    opn = False
    if not pinch and not rock and n_ext >= 3:
        grab = g.grab
        b = [x for x in bend[1:] if x == x]
        flat = len(b) == 4 and sum(b) < 4.0 * OPEN_MEAN_BEND[ext_k]
        if n_ext == 4:
            opn = flat and not grab > 0.8
        elif g.thumb_out > OPEN_FORGIVE_THUMB_OUT and not grab >= OPEN_FORGIVE_GRAB:
            # mean over the three that look extended
            opn = (len(b) == 4
                   and sum(x for x, e in zip(b, ext[1:]) if e) < 3.0 * OPEN_MEAN_BEND[ext_k])
    value = 0.0
    if pinch:
        strength = num(hand.pinch_strength, -1.0)
        if not 0.0 <= strength <= 1.0:
            strength = geometric_pinch_strength(gap)
        value = min(max(strength - PINCH_THRESHOLD, 0.0), 0.8)
    ext[0] = out
    return {'fist': fist, 'thumb_up': thumb_up, 'thumb_down': thumb_down, 'rock': rock,
            'pinch': pinch, 'open': opn, 'pinch_value': value, 'extended': tuple(ext)}
