"""What recognition measures on one hand: its own frame and units.

Hand frame used throughout (from palm normal n and hand direction d): x = thumbward
(cross(d, n) for a right hand, its negative for a left one), y = n (out of the palm),
z = d (toward the fingers), so one code path serves both hands (a left hand is a mirrored
right one). Lengths are in palm widths: the distance between the index and pinky
knuckles, or a nominal adult value when the frame has no usable knuckles.
"""
import math
import operator
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

# Index-to-pinky knuckle distance used when a frame has no knuckle positions (mm; adult
# hands span ~45..65 mm between the joint centres).
NOMINAL_PALM_WIDTH_MM = 55.0
# No tracker reports a hand this far out (100 m): a coordinate beyond it is garbage, and
# its squares would overflow.
MAX_COORD_MM = 1e5
# Knuckle width outside this: the knuckles are mis-tracked (a hand collapsed onto one
# point has none apart) and the joints say nothing: the hand has no joints. Real hands of
# the shared Leap data: 43..73 mm.
PALM_WIDTH_RANGE_MM = (25.0, 120.0)
# A finger whose bones add up to less than this (palm widths) has collapsed onto a point:
# the hand has no joints. Real hands: 0.86 and more (the pinky).
MIN_FINGER_BONES = 0.3
# Where the index knuckle sits thumbward of the palm centre, in palm widths (when the
# frame has no knuckles the thumb is measured from there).
INDEX_KNUCKLE_THUMBWARD = 0.45
# A finger counts as extended (the Hand message's per-finger flags, circles) when nearly
# straight, tip-to-knuckle over its bone length, and its last bone points along the hand
# rather than into the palm (deg); the thumb when its tip stands this far (palm widths)
# thumbward of the index knuckle.
EXTENDED_CHORD = 0.85
EXTENDED_MAX_FLEX_DEG = 85.0
THUMB_OUT = 0.35
_COS_FLEX = math.cos(math.radians(EXTENDED_MAX_FLEX_DEG))
# fingertip pairs whose gaps the features use: thumb to every other tip, neighbouring tips
TIP_PAIRS = ((0, 1), (0, 2), (0, 3), (0, 4), (1, 2), (2, 3), (3, 4))


def _difference_rows():
    """(38, 20): times the (20, 3) joints (finger by finger: mcp, pip, dip, tip), each
    finger's pip, dip and tip from its knuckle (rows 0..14), its three bones (15..29),
    the TIP_PAIRS gaps (30..36) and the thumb tip from the index knuckle (37): one matrix
    product instead of a dozen small ones."""
    rows = np.zeros((38, 20))
    for f in range(5):
        for k in range(3):
            rows[3 * f + k, 4 * f + k + 1], rows[3 * f + k, 4 * f] = 1.0, -1.0
            rows[15 + 3 * f + k, 4 * f + k + 1], rows[15 + 3 * f + k, 4 * f + k] = 1.0, -1.0
    for i, (a, b) in enumerate(TIP_PAIRS):
        rows[30 + i, 4 * a + 3], rows[30 + i, 4 * b + 3] = 1.0, -1.0
    rows[37, 3], rows[37, 4] = 1.0, -1.0
    return rows


_DIFFS = _difference_rows()
_ONES_COLUMN = np.ones((3, 1))
_NORM_FLOOR = np.full((38, 1), 1e-9)   # an array: numpy converts a Python float per call
_F64_ONLY = {np.dtype(float)}
_dtype = operator.attrgetter('dtype')
_isfinite = math.isfinite


@dataclass(slots=True)
class HandGeometry:
    basis: tuple                  # rows: thumbward, normal, direction (Leap axes), unit
    palm: list                    # [x, y, z] palm centre, mm
    palm_width: float             # mm, the unit of the rest
    joints: Optional[np.ndarray]  # (5, 4, 3) mcp, pip, dip, tip per finger, mm; None
                                  # when any joint is missing or they are mis-tracked
                                  # (PALM_WIDTH_RANGE_MM, MIN_FINGER_BONES)
    local: Optional[np.ndarray]   # the joints in the hand frame, palm widths (origin: the
                                  # tracker's), None without joints
    bones: Optional[np.ndarray]   # (5, 3, 3) unit bone directions in the hand frame
    bone_length: Optional[np.ndarray]   # (5, 3) palm widths
    reach: Optional[np.ndarray]   # (5, 3, 3) pip, dip, tip from the finger's knuckle, hand
                                  # frame, palm widths
    tip_gaps: Optional[np.ndarray]   # (7,) palm widths between the TIP_PAIRS fingertips
    tips_world: list              # 5 [x, y, z] fingertips, mm
    thumb_dir: Tuple[float, float, float]   # unit, Leap axes: the thumb's knuckle -> tip
    pinch_gap: float              # palm widths, thumb tip to index tip
    extended: Tuple[bool, ...]    # 5 flags, see EXTENDED_*


def num(x, default=0.0):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return default
    return x if math.isfinite(x) else default


def f3(v):
    """[x, y, z] (numbers) of a 3-vector, or None when absent / malformed."""
    if v.__class__ is np.ndarray:
        return v.tolist() if v.shape == (3,) else None
    if v is None or len(v) != 3:
        return None
    return [float(v[0]), float(v[1]), float(v[2])]


def _vec(v):
    """A finite [x, y, z] list of floats, or None."""
    if v is None:
        return None
    try:
        if v.__class__ is np.ndarray:
            if v.shape != (3,):
                return None
            x, y, z = v.tolist()
        else:
            x, y, z = (float(c) for c in v)
    except (TypeError, ValueError):
        return None
    return [x, y, z] if abs(x) < MAX_COORD_MM and abs(y) < MAX_COORD_MM and abs(z) < MAX_COORD_MM \
        else None


def hand_geometry(hand):
    """HandGeometry of a Hand, or None when its palm frame is unusable (non-finite or
    degenerate normal / direction, missing fingers or fingertips)."""
    try:
        fingers = hand.fingers
        if len(fingers) != 5:
            return None
        palm, n, d = _vec(hand.palm_position), _vec(hand.palm_normal), _vec(hand.direction)
        if palm is None or n is None or d is None:
            return None
        joints = None
        f0, f1, f2, f3, f4 = fingers
        parts = [f0.mcp, f0.pip, f0.dip, f0.tip, f1.mcp, f1.pip, f1.dip, f1.tip,
                 f2.mcp, f2.pip, f2.dip, f2.tip, f3.mcp, f3.pip, f3.dip, f3.tip,
                 f4.mcp, f4.pip, f4.dip, f4.tip]
        try:
            if set(map(_dtype, parts)) == _F64_ONLY:
                # contiguous float64 (what the sources make): their bytes joined cost a
                # third of np.concatenate (a non-contiguous one raises TypeError)
                j = np.frombuffer(bytearray().join(parts))
            else:
                raise TypeError
        except (TypeError, AttributeError):
            try:
                j = np.concatenate(parts).astype(float, copy=False).reshape(-1)
            except (TypeError, ValueError):
                j = None                            # a joint missing or malformed
        # a sum of squares under MAX_COORD_MM squared: every joint finite and in range
        # (NaN compares false)
        if j is not None and j.shape == (60,) and j.dot(j) < MAX_COORD_MM * MAX_COORD_MM:
            joints = j.reshape(20, 3)
        if joints is not None:
            jl = j.tolist()                         # joint i at jl[3 * i:3 * i + 3]
            tip_list = [jl[9:12], jl[21:24], jl[33:36], jl[45:48], jl[57:60]]
        else:
            tip_list = [_vec(f.tip) for f in fingers]
            if any(x is None for x in tip_list):
                return None
    except (TypeError, ValueError, AttributeError, IndexError):
        return None
    # the hand frame in plain floats: numpy's cross and norm cost more than they save here
    nx, ny, nz = n
    nn = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not nn > 1e-6:
        return None
    nx, ny, nz = nx / nn, ny / nn, nz / nn
    dx, dy, dz = d
    k = dx * nx + dy * ny + dz * nz
    dx, dy, dz = dx - nx * k, dy - ny * k, dz - nz * k
    dn = math.sqrt(dx * dx + dy * dy + dz * dz)
    if not dn > 1e-6:
        return None
    dx, dy, dz = dx / dn, dy / dn, dz / dn
    sgn = -1.0 if hand.side == 'left' else 1.0
    t = (sgn * (dy * nz - dz * ny), sgn * (dz * nx - dx * nz), sgn * (dx * ny - dy * nx))
    n, d = (nx, ny, nz), (dx, dy, dz)
    width = NOMINAL_PALM_WIDTH_MM
    if joints is not None:
        w = math.dist(jl[12:15], jl[48:51])         # index and pinky knuckles
        if PALM_WIDTH_RANGE_MM[0] <= w <= PALM_WIDTH_RANGE_MM[1]:
            width = w
        else:
            joints = None
    local = bones = length = reach = gaps = None
    if joints is not None:
        # ndarray.dot, not @: the same product at half the call overhead on arrays this small
        local = joints.dot(np.array((t[0] / width, n[0] / width, d[0] / width,
                                     t[1] / width, n[1] / width, d[1] / width,
                                     t[2] / width, n[2] / width, d[2] / width)).reshape(3, 3))
        diffs = _DIFFS.dot(local)                   # rows: see _difference_rows
        norms = np.sqrt((diffs * diffs).dot(_ONES_COLUMN))  # (38, 1)
        nl = norms[:, 0].tolist()                   # plain floats: cheaper than numpy sums
        # each finger's three bones (rows 15..29): a collapsed finger means no joints
        if not min(nl[15] + nl[16] + nl[17], nl[18] + nl[19] + nl[20], nl[21] + nl[22] + nl[23],
                   nl[24] + nl[25] + nl[26], nl[27] + nl[28] + nl[29]) >= MIN_FINGER_BONES:
            joints = local = None
    thumb_dir = None
    if joints is not None:
        thumb_dir = _unit3(jl[9] - jl[3], jl[10] - jl[4], jl[11] - jl[5])   # pip -> tip
    if thumb_dir is None:
        fd = _vec(fingers[0].direction)
        thumb_dir = _unit3(*fd) if fd is not None else None
    if thumb_dir is None:
        thumb_dir = (math.nan,) * 3
    if joints is not None:
        unit = diffs / np.maximum(norms, _NORM_FLOOR)
        reach = diffs[:15].reshape(5, 3, 3)
        bones = unit[15:30].reshape(5, 3, 3)
        length = norms[15:30].reshape(5, 3)
        gaps = norms[30:37, 0]
        extended = _extended_from_local(diffs, unit, nl)
        local = local.reshape(5, 4, 3)
        joints = joints.reshape(5, 4, 3)
    else:
        extended = _extended(tip_list, palm, t, d, width, fingers)
    return HandGeometry(basis=(t, n, d), palm=palm, palm_width=width, joints=joints,
                        local=local, bones=bones, bone_length=length, reach=reach,
                        tip_gaps=gaps, tips_world=tip_list, thumb_dir=thumb_dir,
                        pinch_gap=math.dist(tip_list[0], tip_list[1]) / width,
                        extended=extended)


def _unit3(x, y, z):
    n = math.sqrt(x * x + y * y + z * z)
    return (x / n, y / n, z / n) if n > 1e-9 and _isfinite(n) else None


def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _extended_from_local(diffs, unit, nl):
    """5 flags from the _DIFFS rows in the hand frame, as they are, as unit vectors and
    their norms (a list; see EXTENDED_*)."""
    flex = unit[17:30:3, 2].tolist()                # each finger's last bone, along z
    flags = [float(diffs[37, 0]) > THUMB_OUT]       # thumb tip thumbward of index knuckle
    for f in (1, 2, 3, 4):
        b = 15 + 3 * f
        chord = nl[3 * f + 2] / max(nl[b] + nl[b + 1] + nl[b + 2], 1e-9)
        flags.append(chord > EXTENDED_CHORD and flex[f] > _COS_FLEX)
    return tuple(flags)


def _extended(tips, palm, t, d, width, fingers):
    """Without joints: the tracker's own flags where it gives them, else the tip ahead of
    the palm."""
    out = _dot([a - b for a, b in zip(tips[0], palm)], t) / width - INDEX_KNUCKLE_THUMBWARD
    flags = [out > THUMB_OUT]
    for i in (1, 2, 3, 4):
        flag = fingers[i].extended
        flags.append(bool(flag) if flag is not None
                     else _dot([a - b for a, b in zip(tips[i], palm)], d) / width > 1.0)
    return tuple(flags)
