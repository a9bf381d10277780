"""One frame's pose: the learned model's class with its probability, and the explicit
guards that stand beside it.

The model (classifier.PoseClassifier, fitted on real people by hands/gestures/train.py)
says which pose the hand shows: fist, open, pinch (an OK sign), rock (horns), a fist with
the thumb out, or none of them (two, three, four, L, hang loose, C, pointing, peace...),
plus any class a user trained. A Leap-family hand is judged from its 3-D joints, a
camera hand from its 21 image landmarks (and their mirror image: one code path for
either hand).

Guards that no model can lift:
- thumbs-up (it arms a robot) needs the model's thumb class at THUMB_UP_MIN_P or more
  AND the thumb measured pointing up: the thumb (knuckle -> tip) rising by THUMB_RISE_MIN
  and the hand's thumb side turned up by THUMB_SIDE_MIN, together by THUMB_UP_SCORE, in
  Leap y of unit vectors. Real thumbs-up takes (two people): rise 0.34 and up, side 0.21
  and up, together 1.19..1.67; the same fist with its thumb out ahead, palm up or down:
  95 % below 0.64 together; thumbs-down: -1.36 and below together. A thumb leaning as far
  as a real one (rise 0.3..0.4, the LeapJS paddle take's most leaning frames too) passes;
  a thumb out sideways (palm up or down) or down never does; thumbs-down mirrors the
  rule. Camera hands: the thumb tip above every other landmark, its last bone within
  CAMERA_THUMB_MAX_DEG of up in the picture.
- a class wins only at MIN_P or more; below, the frame shows no gesture.
"""
import math

import numpy as np

from leap_teleop.hands.gestures.features import keypoint_features, leap_features, mirror_keypoints
from leap_teleop.hands.gestures.geometry import num
from leap_teleop.hands.gestures.temporal import HELD_GESTURES
from leap_teleop.hands.sources.landmarks import MIDDLE_MCP, WRIST, gap_pinch_strength

PINCH_THRESHOLD = 0.2   # original: pinch when strength > 0.2; pinch_value = strength - 0.2
# Geometric pinch strength from the thumb-index tip gap (palm widths): 1 at 0.35, 0 at 1.1.
PINCH_GAP_OPEN = 1.1
PINCH_GAP_CLOSED = 0.35
MIN_P = 0.5                 # a winning class below this is no gesture
# thumbs-up arms a robot: the model must be sure of a thumb out of a fist. People the
# model never saw show one at 0.67..0.99 (a real thumbs-up take: 0.67..0.72); a fist whose
# thumb rises above its fingers as it moves reaches it too, and the direction guard below
# is what keeps those out. This floor and the direction guard's were set on the two
# Guinevere people's takes, whom the evaluation also scores: for them its thumbs-up
# figures are not out of sample (at 0.70 none of their four thumbs-up takes arms).
THUMB_UP_MIN_P = 0.65
THUMB_UP_SCORE = 1.0        # thumb rise + thumb side up (Leap y of unit vectors), see above
THUMB_RISE_MIN = 0.3
THUMB_SIDE_MIN = 0.15
# Camera thumbs-up: the thumb tip above every other landmark by this share of the hand's
# extent in the picture, its last two bones pointing up, the last one within
# CAMERA_THUMB_MAX_DEG of straight up (the labelled thumbs-up photos, turned up to 45 deg
# either way: 52 deg at most; a fist's thumb laid over its fingers, turned 45 deg so that
# its tip is highest: 73).
CAMERA_THUMB_RISE = 0.05
CAMERA_THUMB_MAX_DEG = 60.0
_CAMERA_THUMB_COS = math.cos(math.radians(CAMERA_THUMB_MAX_DEG))
_EXTRA = {}                 # a model's classes -> its user classes (a key each in the decisions)
_isfinite = math.isfinite


def geometric_pinch_strength(gap):
    """0..1 from the thumb-index gap in palm widths (1 = touching), like the SDK's."""
    if not _isfinite(gap):
        return 0.0
    s = (PINCH_GAP_OPEN - gap) / (PINCH_GAP_OPEN - PINCH_GAP_CLOSED)
    return min(max(s, 0.0), 1.0)


def image_pinch_strength(xy):
    """0..1 from the picture's landmarks, as the camera source measures it in 3-D, over the
    palm's length in the picture (wrist to middle knuckle); 1.0 when that cannot be measured."""
    try:
        xy = np.asarray(xy, dtype=float)[:, :2]
        palm = float(np.hypot(*(xy[MIDDLE_MCP] - xy[WRIST])))
        if not (_isfinite(palm) and palm > 0.0) or not np.isfinite(xy).all():
            return 1.0
        return gap_pinch_strength(xy, palm)
    except (TypeError, ValueError, IndexError):
        return 1.0


def thumb_up_score(g, hand):
    """(thumb rise, thumb side up) in Leap y: the thumb's knuckle -> tip direction and the
    hand's thumbward axis. Positive both: up; negative both: down."""
    return g.thumb_dir[1], g.basis[0][1]


def thumb_points(g, hand):
    """'up', 'down' or None (sideways, forward, unknown)."""
    rise, side = thumb_up_score(g, hand)
    if not (_isfinite(rise) and _isfinite(side)):
        return None
    if rise >= THUMB_RISE_MIN and side >= THUMB_SIDE_MIN and rise + side >= THUMB_UP_SCORE:
        return 'up'
    if rise <= -THUMB_RISE_MIN and side <= -THUMB_SIDE_MIN and rise + side <= -THUMB_UP_SCORE:
        return 'down'
    return None


def camera_thumb_points(xy):
    """'up', 'down' or None from 21 image landmarks (y grows downward)."""
    p = np.asarray(xy, dtype=float).reshape(21, 2)
    extent = float(np.ptp(p[:, 1])) or 1.0
    others = np.delete(p, (2, 3, 4), axis=0)[:, 1]
    tip_y, ip_y, mcp_y = p[4, 1], p[3, 1], p[2, 1]
    dx, dy = p[4] - p[3]
    n = math.hypot(dx, dy)
    vertical = n > 0.0 and abs(dy) / n >= _CAMERA_THUMB_COS
    if not vertical:
        return None
    if others.min() - tip_y > CAMERA_THUMB_RISE * extent and tip_y < ip_y < mcp_y:
        return 'up'
    if tip_y - others.max() > CAMERA_THUMB_RISE * extent and tip_y > ip_y > mcp_y:
        return 'down'
    return None


def pose_probabilities(hand, g, model):
    """(classes, probabilities) of the hand under `model`, or None when the hand lacks
    what the model reads."""
    if model.family == 'keypoints':
        xy = getattr(hand, 'image_landmarks', None)
        if xy is None:
            return None
        a, b = keypoint_features(xy), keypoint_features(mirror_keypoints(xy))
        if a is None or b is None:
            return None
        return model.classes, 0.5 * (model.proba(a) + model.proba(b))
    x = leap_features(hand, g)
    if x is None:
        return None
    return model.classes, model.proba(x)


def classify_pose(hand, g, model):
    """Per-frame decisions {gesture: bool} for the held gestures, plus 'pinch_value',
    'extended' (5 bools), 'label' (the winning class or '') and 'probability'; user
    classes appear under their own names. `g` (the HandGeometry) may be None for a hand
    known only by its image landmarks."""
    out = dict.fromkeys(HELD_GESTURES, False)
    out['extended'] = g.extended if g is not None else (False,) * 5
    out['pinch_value'] = 0.0
    out['label'], out['probability'] = '', 0.0
    scored = pose_probabilities(hand, g, model)
    if scored is None:
        return out
    classes, p = scored
    extra = _EXTRA.get(classes)
    if extra is None:
        extra = _EXTRA[classes] = tuple(c for c in classes if c not in out
                                        and c not in ('none', 'thumb'))
    for c in extra:
        out[c] = False
    i = int(p.argmax())
    best, prob = classes[i], float(p[i])
    if not prob >= 0.0:     # NaN (argmax picks it): a model that says nothing here
        return out
    out['label'], out['probability'] = best, prob
    if prob < MIN_P or best == 'none':
        return out
    if best in ('thumb', 'thumb_up', 'thumb_down'):
        if model.family == 'keypoints':
            way = camera_thumb_points(hand.image_landmarks)
        else:
            way = thumb_points(g, hand)
        if way == 'up' and best != 'thumb_down' and prob >= THUMB_UP_MIN_P:
            out['thumb_up'] = True
        elif way == 'down' and best != 'thumb_up':
            out['thumb_down'] = True
        return out
    out[best] = True
    if best == 'pinch':
        strength = num(hand.pinch_strength, -1.0)
        if not 0.0 <= strength <= 1.0:
            strength = (geometric_pinch_strength(g.pinch_gap) if g is not None
                        else image_pinch_strength(hand.image_landmarks))
        out['pinch_value'] = min(max(strength - PINCH_THRESHOLD, 0.0), 0.8)
    return out
