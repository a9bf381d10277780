"""What the pose rules measure on one hand, in the hand's own units.

Lengths are in palm widths (the distance between the index and pinky knuckles, or a
nominal adult value when the frame has no knuckles), finger curl is the tip-to-knuckle
chord over the finger's own bone length (1 straight, ~0.4 in a tight fist), directions are
unit vectors: nothing depends on the size of the hand, its orientation or the tracker
(a Leap frame and a camera's landmarks give the same joints).

Hand frame used throughout (from palm normal n and hand direction d): x = thumbward
(cross(d, n) for a right hand, its negative for a left one), y = n (out of the palm),
z = d (toward the fingers). One code path serves both hands.
"""
import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np

# Index-to-pinky knuckle distance used when a frame has no knuckle positions (mm; adult
# hands span ~45..65 mm between the joint centres).
NOMINAL_PALM_WIDTH_MM = 55.0
PALM_WIDTH_RANGE_MM = (25.0, 120.0)      # outside: the knuckles are mis-tracked
# Where the index knuckle sits thumbward of the palm centre, in palm widths (when the
# frame has no knuckles the thumb is measured from there).
INDEX_KNUCKLE_THUMBWARD = 0.45
# How far out of the palm a fist's index middle joint stands, in palm widths (its
# proximal bone, ~0.7 long, turned 70..95 deg): where a thumb lying over the fingers is
# measured from when the frame has no finger joints.
FIST_INDEX_PIP_HEIGHT = 0.7

# Signed flexion below this (deg) is a curl past 180, not a hyperextended finger.
FLEX_WRAP_DEG = -60.0

_NAN = math.nan
_isfinite = math.isfinite
_sqrt = math.sqrt
_mdist = math.dist
_atan2 = math.atan2
_degrees = math.degrees


@dataclass(slots=True)
class HandGeometry:
    """What the rules look at. NaN where the frame lacks the data."""
    bend: Tuple[float, ...]     # 5 bends, degrees: the larger of the distal bone's
                                # flexion from the hand direction toward the palm
                                # (-60..300) and its angle to the proximal bone
    chord: Tuple[float, ...]    # 5 tip-to-knuckle distances / the finger's bone length
    knuckle: Tuple[float, ...]  # 5 knuckle flexions, degrees: the proximal bone's turn
                                # from the hand direction toward the palm (NaN: thumb, or
                                # no knuckle / middle joint)
    palm_width: float           # mm, the unit of the rest
    thumb_out: float            # palm widths: thumb tip thumbward of the index knuckle
    thumb_over: float           # palm widths: thumb tip out of the palm beyond the index's
                                # middle joint (> 0: lying over the curled fingers; without
                                # that joint, beyond where a fist holds it)
    thumb_dir: tuple            # unit (x, y, z), Leap axes: where the thumb points
    thumb_along: float          # thumb_dir . hand direction (1: laid along the hand)
    pinch_gap: float            # palm widths, thumb tip to index tip
    tip_spread: float           # palm widths, index tip thumbward of the pinky tip (a
                                # fist keeps them a knuckle row apart, an "O" gathers them)
    middle_gap: float           # palm widths, thumb tip to middle tip
    thumb_to_fingers: float     # palm widths, thumb tip to the nearest index / middle
                                # joint (pip, dip, tip)
    finger_joints: bool         # index and middle pip and dip are there
    grab: float                 # the tracker's grab strength 0..1, NaN when absent
    tips_world: list            # 5 [x, y, z] fingertips, mm, Leap axes
    basis: tuple                # rows: thumbward, normal, direction (Leap axes), unit
    palm: list                  # [x, y, z] palm centre, mm


def f3(v):
    """[x, y, z] (numbers) of a 3-vector, or None when absent / malformed."""
    if v.__class__ is np.ndarray:
        return v.tolist() if v.shape == (3,) else None
    if v is None or len(v) != 3:
        return None
    return [float(v[0]), float(v[1]), float(v[2])]


def num(x, default=0.0):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return default
    return x if math.isfinite(x) else default


def _unit(x, y, z):
    n = _sqrt(x * x + y * y + z * z)
    if n > 0.0 and n != math.inf:
        return x / n, y / n, z / n
    return _NAN, _NAN, _NAN


def _angle_deg(c):
    """acos in degrees of a cosine; NaN stays NaN."""
    if c != c:
        return _NAN
    return math.degrees(math.acos(1.0 if c > 1.0 else -1.0 if c < -1.0 else c))


_ndarray = np.ndarray


def _joint(v):
    """A finite joint position or None (a missing or non-finite joint is not there)."""
    if v is None:
        return None
    if v.__class__ is _ndarray and v.shape == (3,):
        p = v.tolist()
    else:
        p = f3(v)
        if p is None:
            return None
    return p if _isfinite(p[0] + p[1] + p[2]) else None


def hand_geometry(hand):
    """HandGeometry of a Hand, or None when its palm frame is unusable (non-finite or
    degenerate normal / direction, missing fingers or fingertips)."""
    fingers = hand.fingers
    if len(fingers) != 5:
        return None
    try:
        palm = f3(hand.palm_position)
        n = f3(hand.palm_normal)
        d = f3(hand.direction)
        if palm is None or n is None or d is None:
            return None
        px, py, pz = palm
        nx, ny, nz = n
        dx, dy, dz = d
        if not (_isfinite(px + py + pz) and _isfinite(nx + ny + nz) and _isfinite(dx + dy + dz)):
            return None
        nn = _sqrt(nx * nx + ny * ny + nz * nz)
        if nn < 1e-6:
            return None
        nx, ny, nz = nx / nn, ny / nn, nz / nn
        k = dx * nx + dy * ny + dz * nz
        dx, dy, dz = dx - nx * k, dy - ny * k, dz - nz * k
        dn = _sqrt(dx * dx + dy * dy + dz * dz)
        if dn < 1e-6:
            return None
        dx, dy, dz = dx / dn, dy / dn, dz / dn
        # thumbward = d x n for a right hand, its negative for a left one
        s = -1.0 if hand.side == 'left' else 1.0
        tx, ty, tz = s * (dy * nz - dz * ny), s * (dz * nx - dx * nz), s * (dx * ny - dy * nx)
        tips, bend, chord, knuckle, mcps, pips, dips = [], [], [], [], [], [], []
        dirs = []
        for i, f in enumerate(fingers):
            # (the ndarray case inline: this runs for 20 joints of every hand of every frame)
            v = f.tip
            tip = v.tolist() if v.__class__ is _ndarray and v.shape == (3,) else f3(v)
            if tip is None or not _isfinite(tip[0] + tip[1] + tip[2]):
                return None
            tips.append(tip)
            ax, ay, az = tip
            v = f.dip
            dip = v.tolist() if v.__class__ is _ndarray and v.shape == (3,) else _joint(v)
            if dip is not None and not _isfinite(dip[0] + dip[1] + dip[2]):
                dip = None
            v = f.pip
            pip = v.tolist() if v.__class__ is _ndarray and v.shape == (3,) else _joint(v)
            if pip is not None and not _isfinite(pip[0] + pip[1] + pip[2]):
                pip = None
            v = f.mcp
            mcp = v.tolist() if v.__class__ is _ndarray and v.shape == (3,) else _joint(v)
            if mcp is not None and not _isfinite(mcp[0] + mcp[1] + mcp[2]):
                mcp = None
            mcps.append(mcp)
            pips.append(pip)
            dips.append(dip)
            # The distal bone (dip -> tip); the SDK's finger direction when the joint is
            # absent (it follows the middle bone on real captures: the second choice).
            ux = _NAN
            if dip is not None:
                ux, uy, uz = ax - dip[0], ay - dip[1], az - dip[2]
                ld = _sqrt(ux * ux + uy * uy + uz * uz)
                if ld > 1e-3 and ld != math.inf:
                    ux, uy, uz = ux / ld, uy / ld, uz / ld
                else:
                    ux = _NAN
            if ux != ux:
                fd = _joint(f.direction)
                ux, uy, uz = _unit(*fd) if fd is not None else (_NAN, _NAN, _NAN)
            dirs.append((ux, uy, uz))
            if i == 0:              # the rules read the thumb's position and direction only
                bend.append(_NAN)
                chord.append(_NAN)
                knuckle.append(_NAN)
                continue
            # Signed in the plane of the hand direction and the palm normal (fingers curl
            # toward the normal), so a fist's ~250 deg does not fold back to ~110.
            flex = _degrees(_atan2(ux * nx + uy * ny + uz * nz, ux * dx + uy * dy + uz * dz))
            if flex < FLEX_WRAP_DEG:
                flex += 360.0
            c = kf = _NAN
            if pip is not None and mcp is not None:
                vx, vy, vz = pip[0] - mcp[0], pip[1] - mcp[1], pip[2] - mcp[2]
                lp = _sqrt(vx * vx + vy * vy + vz * vz)
                if lp > 1e-3:
                    kf = _degrees(_atan2(vx * nx + vy * ny + vz * nz, vx * dx + vy * dy + vz * dz))
                    curl = _angle_deg((vx * ux + vy * uy + vz * uz) / lp)
                    if curl > flex:                 # the larger of the two (NaN loses)
                        flex = curl
                    if dip is not None:
                        length = lp + _mdist(dip, pip) + ld
                        if length > 1e-3:
                            c = _mdist(tip, mcp) / length
            chord.append(c)
            knuckle.append(kf)
            bend.append(flex)
        # Palm width from the index and pinky knuckles, when they are there and plausible.
        width = NOMINAL_PALM_WIDTH_MM
        im, pm = mcps[1], mcps[4]
        if im is not None and pm is not None:
            w = _mdist(im, pm)
            if PALM_WIDTH_RANGE_MM[0] <= w <= PALM_WIDTH_RANGE_MM[1]:
                width = w
        inv = 1.0 / width
        th, ix = tips[0], tips[1]
        if im is not None:
            out = ((th[0] - im[0]) * tx + (th[1] - im[1]) * ty + (th[2] - im[2]) * tz) * inv
        else:
            out = ((th[0] - px) * tx + (th[1] - py) * ty + (th[2] - pz) * tz) * inv \
                - INDEX_KNUCKLE_THUMBWARD
        ip = pips[1]
        if ip is not None:
            over = ((th[0] - ip[0]) * nx + (th[1] - ip[1]) * ny + (th[2] - ip[2]) * nz) * inv
        else:
            over = ((th[0] - px) * nx + (th[1] - py) * ny + (th[2] - pz) * nz) * inv \
                - FIST_INDEX_PIP_HEIGHT
        # Where the thumb points: its knuckle (the Leap's thumb 'pip', a camera's MCP) to
        # its tip, else its distal bone, else its direction.
        tp = pips[0]
        thumb_dir = _unit(th[0] - tp[0], th[1] - tp[1], th[2] - tp[2]) if tp is not None \
            else (_NAN, _NAN, _NAN)
        if thumb_dir[0] != thumb_dir[0]:
            thumb_dir = dirs[0]
        grab = num(hand.grab_strength, _NAN)
        if not 0.0 <= grab <= 1.0:
            grab = _NAN
    except (TypeError, ValueError, AttributeError, IndexError, OverflowError):
        return None
    return HandGeometry(bend=tuple(bend), chord=tuple(chord), knuckle=tuple(knuckle),
                        palm_width=width, thumb_out=out, thumb_over=over,
                        thumb_dir=thumb_dir,
                        thumb_along=thumb_dir[0] * dx + thumb_dir[1] * dy + thumb_dir[2] * dz,
                        pinch_gap=_mdist(th, ix) * inv,
                        tip_spread=((ix[0] - tips[4][0]) * tx + (ix[1] - tips[4][1]) * ty
                                    + (ix[2] - tips[4][2]) * tz) * inv,
                        middle_gap=_mdist(th, tips[2]) * inv,
                        thumb_to_fingers=min([_mdist(th, j) for j in (
                            ix, tips[2], pips[1], pips[2], dips[1], dips[2]) if j is not None]) * inv,
                        finger_joints=None not in (pips[1], pips[2], dips[1], dips[2]),
                        grab=grab, tips_world=tips,
                        basis=((tx, ty, tz), (nx, ny, nz), (dx, dy, dz)), palm=palm)
