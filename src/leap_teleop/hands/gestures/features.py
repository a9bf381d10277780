"""Hand-invariant feature vectors for the learned pose models.

One vector per hand, the same for small and large hands, for either side and for any
orientation of the hand: joints are expressed in the hand's own frame (thumbward, palm
normal, hand direction; see geometry) and in palm widths, bones as unit directions in that
frame, plus fingertip gaps and the cosines between successive bones.

- `leap_features(hand)`: each finger's joints from its own knuckle (trackers place the
  knuckles by a fixed palm model of their own: the Leap SDK's sit at the same place in
  every hand, so where they sit says nothing), from a tracker's 3-D joints (Leap SDKs, recordings, scripts, a camera's
  lifted landmarks). None when the hand lacks the joints: such a hand shows no gesture.
- `keypoint_features(xy)`: 21 2-D image landmarks (MediaPipe order), the only thing a
  webcam's community keypoint files hold, turned in the picture so that the wrist ->
  middle knuckle axis points up (people hold their hands and cameras at any roll; which
  way the thumb points in the picture is the thumbs-up guard's business, not the
  model's). Image y grows downward; a left hand is a mirrored right one, so callers
  score both the landmarks and their mirror image. `keypoint_features_rows(xy)`: the
  same numbers for many sets at once (training).
"""
import math

import numpy as np

from leap_teleop.hands.gestures.geometry import TIP_PAIRS, hand_geometry

LEAP_FEATURES = 5 * 3 * 3 + 5 * 3 * 3 + 7 + 10
KEYPOINT_FEATURES = 21 * 2 + 20 * 2 + 7 + 15 + 5 + 5 + 3
_TIP_A = np.array([a for a, _ in TIP_PAIRS])
_TIP_B = np.array([b for _, b in TIP_PAIRS])
# where each finger's two successive-bone cosines sit in the (15, 15) Gram matrix of its
# bones, flattened
_BONE_COS = np.array([15 * i + i + 1 for f in range(5) for i in (3 * f, 3 * f + 1)])
# MediaPipe landmark chains: wrist -> each finger's four joints
_CHAINS = np.array([[0, 1, 2, 3, 4], [0, 5, 6, 7, 8], [0, 9, 10, 11, 12],
                    [0, 13, 14, 15, 16], [0, 17, 18, 19, 20]])
_MP_TIPS = np.array([4, 8, 12, 16, 20])
_isfinite = math.isfinite
# Keypoints are pixels or the community's normalised values: anything larger is no hand.
MAX_KEYPOINT = 1e6
# Index-to-pinky knuckle distance of upright landmarks (largest coordinate 1) under which
# the landmarks are collapsed, not a hand: no features. Real rows (a hand edge-on): 0.018
# and more.
MIN_KEYPOINT_PALM_WIDTH = 0.002


def leap_features(hand, geometry=None):
    """Feature vector (LEAP_FEATURES,) of a Hand with 3-D joints, or None."""
    g = geometry if geometry is not None else hand_geometry(hand)
    if g is None or g.joints is None:
        return None
    bones = g.bones.reshape(15, 3)                  # unit bones, hand frame
    cos = bones.dot(bones.T).take(_BONE_COS)        # (5, 2) flattened
    out = np.concatenate((g.reach.ravel(), g.bones.ravel(), g.tip_gaps, cos))
    # a finite sum of squares: all finite (else the exact test: it may have overflowed)
    return out if _isfinite(out.dot(out)) or np.isfinite(out).all() else None


def normalize_keypoints(xy):
    """The community's normalisation of 21 image landmarks: relative to the wrist,
    divided by the largest absolute coordinate. (21, 2) array, or None when degenerate or
    beyond MAX_KEYPOINT."""
    p = np.asarray(xy, dtype=float).reshape(21, 2)
    if not np.abs(p).max() <= MAX_KEYPOINT:         # NaN compares false
        return None
    p = p - p[0]
    m = np.abs(p).max()
    if not m > 0.0:
        return None
    return p / m


def upright_keypoints(xy):
    """The community-normalised landmarks (normalize_keypoints) turned so that the wrist
    -> middle knuckle axis points up (-y), divided again by the largest absolute
    coordinate; (21, 2) or None when degenerate."""
    p = normalize_keypoints(xy)
    if p is None:
        return None
    ax, ay = p[9]
    n = math.hypot(ax, ay)
    if n > 1e-6:
        c, s = -ay / n, ax / n
        p = p @ np.array([[c, -s], [s, c]])
        p /= np.abs(p).max()
    return p


def keypoint_features(xy):
    """Feature vector (KEYPOINT_FEATURES,) of 21 2-D landmarks (any scale and roll), or
    None (collapsed landmarks: see MIN_KEYPOINT_PALM_WIDTH): the upright landmarks, bone
    directions, fingertip gaps and the cosines between successive bones, each finger's
    straightness (knuckle-to-tip distance over its bones' length), each tip's reach from
    the wrist and the thumb tip's gaps to the index knuckles. Not mirror-invariant by
    itself: see module doc."""
    p = upright_keypoints(xy)
    if p is None:
        return None
    w = math.hypot(*(p[5] - p[17]))             # palm width, the unit of the gaps
    if not w >= MIN_KEYPOINT_PALM_WIDTH:
        return None
    chain = p[_CHAINS]                               # (5, 5, 2)
    d = np.diff(chain, axis=1)
    length = np.sqrt((d * d).sum(axis=2))            # (5, 4)
    bones = d / np.maximum(length[..., None], 1e-9)
    tips = p[_MP_TIPS]
    gaps = np.sqrt(((tips[_TIP_A] - tips[_TIP_B]) ** 2).sum(axis=1)) / w
    cos = (bones[:, 1:] * bones[:, :-1]).sum(axis=2)  # (5, 3)
    # a folded finger's tip comes back towards its knuckle: a fist and a thumb out of it
    # differ by the thumb's straightness and how far its tip sits from the index
    straight = (np.sqrt(((chain[:, 4] - chain[:, 1]) ** 2).sum(axis=1))
                / np.maximum(length[:, 1:].sum(axis=1), 1e-9))
    reach = np.sqrt((tips * tips).sum(axis=1))
    thumb = np.sqrt(((p[4] - p[[5, 9, 6]]) ** 2).sum(axis=1)) / w
    out = np.concatenate((p.ravel(), bones.ravel(), np.minimum(gaps, 10.0), cos.ravel(),
                          straight, reach, np.minimum(thumb, 10.0)))
    return out if np.isfinite(out).all() else None


def keypoint_features_rows(xy):
    """keypoint_features of n sets of landmarks (n, 21, 2) at once, for training: the same
    numbers, each step done as keypoint_features does it on one set (math.hypot where it
    takes math.hypot, the same matrix product, the same sums). (n, KEYPOINT_FEATURES)
    rows and a mask of the sets that have features (keypoint_features not None); rows
    outside the mask are zeros."""
    p = np.array(xy, dtype=float).reshape(-1, 21, 2)
    feats = np.zeros((len(p), KEYPOINT_FEATURES))
    idx = np.flatnonzero((np.abs(p) <= MAX_KEYPOINT).all(axis=(1, 2)))   # NaN: false
    p = p[idx] - p[idx, :1]
    m = np.abs(p).max(axis=(1, 2))
    keep = m > 0.0
    idx, p = idx[keep], p[keep] / m[keep, None, None]
    ok = np.zeros(len(feats), dtype=bool)
    if not len(idx):                # no set has features: nothing to compute
        return feats, ok
    # upright_keypoints: turned where the wrist -> middle knuckle axis has a length
    hyp = math.hypot
    ax, ay = p[:, 9, 0].tolist(), p[:, 9, 1].tolist()
    n = np.array([hyp(a, b) for a, b in zip(ax, ay)])
    turn = np.flatnonzero(n > 1e-6)
    c, s = -p[turn, 9, 1] / n[turn], p[turn, 9, 0] / n[turn]
    rot = np.empty((len(turn), 2, 2))
    rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1] = c, -s, s, c
    q = np.matmul(p[turn], rot)
    q /= np.abs(q).max(axis=(1, 2))[:, None, None]
    p[turn] = q
    v = p[:, 5] - p[:, 17]
    w = np.array([hyp(a, b) for a, b in zip(v[:, 0].tolist(), v[:, 1].tolist())])
    wide = w >= MIN_KEYPOINT_PALM_WIDTH
    idx, p, w = idx[wide], p[wide], w[wide]
    if not len(idx):
        return feats, ok
    chain = p[:, _CHAINS]                            # (n, 5, 5, 2)
    d = np.diff(chain, axis=2)
    length = np.sqrt((d * d).sum(axis=3))            # (n, 5, 4)
    bones = d / np.maximum(length[..., None], 1e-9)
    tips = p[:, _MP_TIPS]
    gaps = np.sqrt(((tips[:, _TIP_A] - tips[:, _TIP_B]) ** 2).sum(axis=2)) / w[:, None]
    cos = (bones[:, :, 1:] * bones[:, :, :-1]).sum(axis=3)
    straight = (np.sqrt(((chain[:, :, 4] - chain[:, :, 1]) ** 2).sum(axis=2))
                / np.maximum(length[:, :, 1:].sum(axis=2), 1e-9))
    reach = np.sqrt((tips * tips).sum(axis=2))
    thumb = np.sqrt(((p[:, 4, None] - p[:, [5, 9, 6]]) ** 2).sum(axis=2)) / w[:, None]
    k = len(p)
    out = np.concatenate((p.reshape(k, -1), bones.reshape(k, -1), np.minimum(gaps, 10.0),
                          cos.reshape(k, -1), straight, reach, np.minimum(thumb, 10.0)), axis=1)
    finite = np.isfinite(out).all(axis=1)
    feats[idx[finite]] = out[finite]
    ok[idx[finite]] = True
    return feats, ok


def rotate_keypoints(xy, angle):
    """The landmarks turned in the picture by `angle` (rad)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.asarray(xy, dtype=float).reshape(21, 2) @ np.array([[c, -s], [s, c]]).T


def mirror_keypoints(xy):
    """The same landmarks as a mirror image (x negated)."""
    p = np.array(xy, dtype=float).reshape(21, 2)
    p[:, 0] = -p[:, 0]
    return p


# Where a Leap hand's wrist sits from its palm centre, hand frame, palm widths (median of
# the Guinevere takes, which carry the wrist): the landmark a camera sees first.
WRIST_FROM_PALM = (-0.17, -0.03, -1.15)


def hand_landmarks(hand, geometry=None):
    """(21, 3) MediaPipe-ordered landmarks of a Hand with 3-D joints, in its own frame
    (thumbward, normal, direction) and palm widths, or None."""
    g = geometry if geometry is not None else hand_geometry(hand)
    if g is None or g.joints is None:
        return None
    local = (g.joints - np.array(g.palm)) @ np.array(g.basis).T / g.palm_width
    return np.vstack((np.array(WRIST_FROM_PALM)[None], local.reshape(20, 3)))
