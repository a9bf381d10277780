"""UR10 forward and analytic inverse kinematics (numpy / math only).

Frames. Every pose here is in the arm's ``base_link`` frame (the URDF's, which is the
UR "Base" DH frame turned by pi about z). The flange is ``tool0`` (DH frame 6). The TCP is
``tool0`` moved ``TCP_OFFSET`` metres along its z axis: the centre between the gripper's
finger pads, where a grasped 5 cm cube's centre sits. Orientation of the TCP = tool0's:
z out of the flange (approach), x the fingers' closing direction.

DH (DESIGN.md section 4): d1 0.1273, a2 -0.612, a3 -0.5723, d4 0.163941, d5 0.1157,
d6 0.0922, alpha (pi/2, 0, 0, pi/2, -pi/2, 0). The inverse is closed form (scalar math,
no iteration): up to 8 solutions, 2 shoulder x 2 wrist x 2 elbow.
"""
import math

import numpy as np

from leap_teleop.vectors import cross3, norm3

D1, A2, A3, D4, D5, D6 = 0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922
ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)
_DH_A = (0.0, A2, A3, 0.0, 0.0, 0.0)
_DH_D = (D1, 0.0, 0.0, D4, D5, D6)

JOINT_NAMES = ('shoulder_pan_joint', 'shoulder_lift_joint', 'elbow_joint',
               'wrist_1_joint', 'wrist_2_joint', 'wrist_3_joint')
# Joint-limited UR10 as in the URDF: +-360 deg, elbow +-180 deg.
JOINT_LOWER = np.array([-2 * math.pi, -2 * math.pi, -math.pi,
                        -2 * math.pi, -2 * math.pi, -2 * math.pi])
JOINT_UPPER = -JOINT_LOWER
# UR10 joint speed limits: 120 deg/s base and shoulder, 180 deg/s the others.
MAX_JOINT_SPEED = np.radians([120.0, 120.0, 180.0, 180.0, 180.0, 180.0])

# Joint acceleration limit used for every motion we command, rad/s^2. The robot limits
# torque, not acceleration; pi rad/s^2 is the conservative figure MoveIt configurations
# of the UR10 use for time parametrisation.
MAX_JOINT_ACCEL = np.full(6, math.pi)

# Flange (tool0) -> TCP along tool0 z, m. Matches the gripper built in ur10/model.py.
TCP_OFFSET = 0.105

# A standard "home": upper arm up, forearm forward, tool pointing straight down.
HOME_Q = np.array([0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0])

# base_link = DH base turned by pi about z.
_BASE_FROM_DH = np.diag([-1.0, -1.0, 1.0, 1.0])

# Tool z pointing down (-z of base_link), fingers closing along base_link y.
TOOL_DOWN = np.array([[0.0, -1.0, 0.0],
                      [-1.0, 0.0, 0.0],
                      [0.0, 0.0, -1.0]])


def tool_down(yaw=0.0):
    """Rotation (base_link frame) with the tool z pointing down, turned by yaw about z."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ TOOL_DOWN


def rot_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


_I3 = np.eye(3)
_I3.flags.writeable = False


def rotation_from_vector(w):
    """Rotation matrix of the rotation vector w (axis * angle, rad): Rodrigues."""
    # Plain floats up to the matrices (the arm's control period runs this): the same
    # arithmetic as numpy on the 3-vector, without its per-call cost.
    x, y, z = np.asarray(w, dtype=float).tolist()
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-12:
        return np.eye(3)
    kx, ky, kz = x / angle, y / angle, z / angle
    K = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
    return _I3 + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def rotation_vector(R):
    """Rotation vector (axis * angle, angle in [0, pi]) of a rotation matrix."""
    R = np.asarray(R, dtype=float)
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    c = max(-1.0, min(1.0, ((r00 + r11) + r22 - 1.0) / 2.0))
    angle = math.acos(c)
    v = (r21 - r12, r02 - r20, r10 - r01)
    if angle < 1e-9:
        return np.array([0.5 * v[0], 0.5 * v[1], 0.5 * v[2]])
    if math.pi - angle < 1e-6:
        # Near pi the antisymmetric part vanishes: take the axis from R + I.
        B = (R + np.eye(3)) / 2.0
        k = B[:, int(np.argmax(np.diag(B)))]
        k = k / np.linalg.norm(k)
        return k * angle
    f = angle / (2.0 * math.sin(angle))
    return np.array([v[0] * f, v[1] * f, v[2] * f])


def rotation_vector_near(R, near):
    """The rotation vector of R nearest `near` (another rotation vector, any length):
    (angle + 2 pi m) * axis. A rotation passing pi then keeps growing instead of
    flipping its axis, so what filters or scales it sees no jump; near None: the
    rotation_vector."""
    w = rotation_vector(R)
    if near is None:
        return w
    x, y, z = w.tolist()
    nx, ny, nz = np.asarray(near, dtype=float).tolist()
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-9:                    # the identity: 2 pi m about near's own axis
        length = math.sqrt(nx * nx + ny * ny + nz * nz)
        if length < math.pi:
            return w
        k = (nx / length, ny / length, nz / length)
        angle = 0.0
    else:
        k = (x / angle, y / angle, z / angle)
    along = k[0] * nx + k[1] * ny + k[2] * nz
    angle += 2.0 * math.pi * round((along - angle) / (2.0 * math.pi))
    return np.array([k[0] * angle, k[1] * angle, k[2] * angle])


_DOWN = (0.0, 0.0, -1.0)


def _swing(z, tilt):
    """The rotation tilting straight down to the tool axis z by `tilt` (rad) about their
    common normal; the identity when z is vertical."""
    axis = cross3(_DOWN, z)
    n = norm3(axis)
    if n < 1e-12:
        return np.eye(3)
    return rotation_from_vector(((axis[0] / n) * tilt, (axis[1] / n) * tilt, (axis[2] / n) * tilt))


def tilt_and_yaw(R):
    """(tilt, yaw) of a tool rotation: tilt = angle of the tool z from straight down
    (rad), yaw = turn about the vertical of the tool once the tilt is undone (the yaw
    of tool_down(yaw)). Together with the tilt axis this is a swing-twist split."""
    R = np.asarray(R, dtype=float)
    z = R[:, 2].tolist()
    tilt = math.acos(max(-1.0, min(1.0, z[0] * 0.0 + z[1] * 0.0 + z[2] * -1.0)))
    level = _swing(z, tilt).T @ R       # pointing straight down: tool_down(yaw)
    upright = level @ TOOL_DOWN.T       # = rot_z(yaw)
    return tilt, math.atan2(upright[1, 0], upright[0, 0])


def limit_tool_rotation(R, max_tilt, yaw_center, max_turn, near=None):
    """R with its tilt from vertical limited to max_tilt and its yaw to
    yaw_center +- max_turn (rad): the orientation counterpart of the workspace box.
    Returns (limited R, (swing, turn)): the swing as a rotation vector taking straight
    down to the tool axis, and the turn from yaw_center. Hand that pair back as `near` on
    the next call: both are then taken nearest their last values (the swing about its
    axis by tilt + 2 pi k, the turn + 2 pi k), so a tool turned on past straight up keeps
    the side it went over on, and a turn past +-pi keeps counting: a clamped target does
    not jump to the other side (a palm turned up from the rock, or less at a higher
    orientation_scale)."""
    R = np.asarray(R, dtype=float)
    z = R[:, 2].tolist()
    tilt = math.acos(max(-1.0, min(1.0, -z[2])))
    near_swing, near_turn = near if near is not None else (None, None)
    axis = cross3(_DOWN, z)
    n = norm3(axis)
    if n > 1e-12:
        axis = (axis[0] / n, axis[1] / n, axis[2] / n)
    else:                               # straight down or up: the axis it had, else any
        m = norm3(near_swing) if near_swing is not None else 0.0
        axis = (1.0, 0.0, 0.0) if m < 1e-12 else tuple(c / m for c in near_swing)
        if tilt < math.pi / 2:
            tilt = 0.0
    angle = tilt
    if near_swing is not None:
        along = axis[0] * near_swing[0] + axis[1] * near_swing[1] + axis[2] * near_swing[2]
        angle += 2.0 * math.pi * round((along - tilt) / (2.0 * math.pi))
    swing = (axis[0] * angle, axis[1] * angle, axis[2] * angle)
    level = rotation_from_vector((axis[0] * tilt, axis[1] * tilt, axis[2] * tilt)).T @ R
    upright = level @ TOOL_DOWN.T               # = rot_z(yaw)
    turn = math.atan2(upright[1, 0], upright[0, 0]) - yaw_center
    reference = 0.0 if near_turn is None else near_turn
    turn += 2.0 * math.pi * round((reference - turn) / (2.0 * math.pi))
    if abs(angle) <= max_tilt and abs(turn) <= max_turn:
        return R, (swing, turn)
    limited = math.copysign(min(abs(angle), max_tilt), angle)
    tilted = rotation_from_vector((axis[0] * limited, axis[1] * limited, axis[2] * limited))
    return tilted @ tool_down(yaw_center + max(-max_turn, min(max_turn, turn))), (swing, turn)


def pose(position, rotation=TOOL_DOWN):
    """4x4 homogeneous transform from a position and a 3x3 rotation."""
    T = np.eye(4)
    T[:3, :3] = rotation
    T[:3, 3] = position
    return T


_DH_COS_SIN_ALPHA = tuple((math.cos(a), math.sin(a)) for a in ALPHA)


def _dh(i, theta):
    ct, st = math.cos(theta), math.sin(theta)
    ca, sa = _DH_COS_SIN_ALPHA[i]
    return np.array([[ct, -st * ca, st * sa, _DH_A[i] * ct],
                     [st, ct * ca, -ct * sa, _DH_A[i] * st],
                     [0.0, sa, ca, _DH_D[i]],
                     [0.0, 0.0, 0.0, 1.0]])


def fk(q, tcp=True):
    """Pose (4x4, base_link frame) of the TCP (tcp=True) or of tool0 for joints q."""
    T = _BASE_FROM_DH.copy()
    for i in range(6):
        T = T @ _dh(i, float(q[i]))
    if tcp:
        T[:3, 3] += TCP_OFFSET * T[:3, 2]
    return T


_TWO_PI = 2 * math.pi
_LOWER_LIST = JOINT_LOWER.tolist()
_UPPER_LIST = JOINT_UPPER.tolist()


def ik(T, tcp=True, q6_free=0.0, eps=1e-9):
    """Every joint solution (list of 6-arrays in (-pi, pi]) that puts the TCP (or tool0)
    at pose T (4x4, base_link). Empty list when unreachable; never raises.

    At a wrist singularity (sin q5 = 0) q6 is not determined; q6_free is used for it.
    """
    return [np.array(s) for s in _ik_tuples(T, tcp, q6_free, eps)]


def _ik_tuples(T, tcp=True, q6_free=0.0, eps=1e-9):
    """ik() as plain tuples (no numpy per solution: ik_nearest is on the control path)."""
    try:
        T = np.asarray(T, dtype=float)
        if T.shape != (4, 4):
            return []
        (r0, r1, r2, _) = T.tolist()      # Python floats: much faster than numpy scalars
        if not all(map(math.isfinite, r0 + r1 + r2)):
            return []
        # base_link -> DH base: negate x and y rows.
        xx, xy, xz = -r0[0], -r1[0], r2[0]
        yx, yy, yz = -r0[1], -r1[1], r2[1]
        zx, zy, zz = -r0[2], -r1[2], r2[2]
        px, py, pz = -r0[3], -r1[3], r2[3]
    except (TypeError, ValueError, IndexError):
        return []
    if tcp:
        px -= TCP_OFFSET * zx
        py -= TCP_OFFSET * zy
        pz -= TCP_OFFSET * zz
    # Wrist centre (origin of frame 5) and the shoulder angle from its distance to z0.
    p5x, p5y, p5z = px - D6 * zx, py - D6 * zy, pz - D6 * zz
    r = math.hypot(p5x, p5y)
    if r < abs(D4) - eps:
        return []
    psi = math.atan2(p5y, p5x)
    phi = math.acos(max(-1.0, min(1.0, D4 / r))) if r > 0 else 0.0
    sols = []
    pi, two_pi = math.pi, 2.0 * math.pi
    # Comparisons instead of abs / min / max calls below (the same results, NaN included):
    # 8 solutions per call on the control path.
    near_one = 1.0 + 1e-9
    for q1 in (psi + phi + math.pi / 2, psi - phi + math.pi / 2):
        s1, c1 = math.sin(q1), math.cos(q1)
        # z1 = (s1, -c1, 0): axis of joints 2, 3, 4; z1 . z6 = cos q5.
        c5 = (px * s1 - py * c1 - D4) / D6
        if c5 > near_one or c5 < -near_one:
            continue
        c5 = c5 if c5 < 1.0 else 1.0        # max(-1.0, min(1.0, c5))
        c5 = c5 if c5 > -1.0 else -1.0
        a5 = math.acos(c5)
        for q5 in (a5, -a5):
            s5 = math.sin(q5)
            if s5 > 1e-10 or s5 < -1e-10:
                # z4 = (z1 x z6) / s5; z1 x z6 = (-c1 zz, -s1 zz, s1 zy + c1 zx)
                z4x, z4y, z4z = -c1 * zz / s5, -s1 * zz / s5, (s1 * zy + c1 * zx) / s5
                q6 = math.atan2(-(z4x * xx + z4y * xy + z4z * xz),
                                -(z4x * yx + z4y * yy + z4z * yz))
            else:
                q6 = q6_free
                # y5 in frame 6 is (s6, c6, 0), and z4 = -y5.
                s6, c6 = math.sin(q6), math.cos(q6)
                z4x = -(s6 * xx + c6 * yx)
                z4y = -(s6 * xy + c6 * yy)
                z4z = -(s6 * xz + c6 * yz)
            # q2 + q3 + q4 from z4 in frame 1 = (s234, -c234, 0); x1 = (c1, s1, 0), y1 = z0.
            q234 = math.atan2(c1 * z4x + s1 * z4y, -z4z)
            # Origin of frame 4 in frame 1 coordinates; the planar 2R problem for q2, q3.
            o4x, o4y, o4z = p5x - D5 * z4x, p5y - D5 * z4y, p5z - D5 * z4z
            ux = c1 * o4x + s1 * o4y
            uy = o4z - D1
            c3 = (ux * ux + uy * uy - A2 * A2 - A3 * A3) / (2 * A2 * A3)
            if c3 > near_one or c3 < -near_one:
                continue
            c3 = c3 if c3 < 1.0 else 1.0        # max(-1.0, min(1.0, c3))
            c3 = c3 if c3 > -1.0 else -1.0
            a3, u_angle = math.acos(c3), math.atan2(uy, ux)
            for q3 in (a3, -a3):
                s3 = math.sin(q3)
                q2 = u_angle - math.atan2(A3 * s3, A2 + A3 * c3)
                q4 = q234 - q2 - q3
                # wrap_angle of each, inline (8 solutions per call on the control path)
                sols.append(((q1 + pi) % two_pi - pi, (q2 + pi) % two_pi - pi,
                             (q3 + pi) % two_pi - pi, (q4 + pi) % two_pi - pi,
                             (q5 + pi) % two_pi - pi, (q6 + pi) % two_pi - pi))
    return sols


def nearest_in_limits(q, q_ref, lower=JOINT_LOWER, upper=JOINT_UPPER):
    """q shifted by multiples of 2 pi per joint to be closest to q_ref within the limits;
    None when some joint has no representative within them."""
    q = np.asarray(q, dtype=float)
    q_ref = np.asarray(q_ref, dtype=float)
    k = np.round((q_ref - q) / (2 * math.pi))
    out = q + 2 * math.pi * k
    for _ in range(2):   # step back inside the limits if the nearest copy is outside
        out = np.where(out > upper, out - 2 * math.pi, out)
        out = np.where(out < lower, out + 2 * math.pi, out)
    if np.any(out > upper + 1e-12) or np.any(out < lower - 1e-12):
        return None
    return out


def _limit_list(limit):
    """Six joint limits as floats (a tuple of six floats, as the control loop passes its
    own, is taken as it is)."""
    if limit.__class__ is tuple and len(limit) == 6:
        return limit
    return np.broadcast_to(limit, (6,)).tolist()


def ik_nearest(T, q_ref, tcp=True, lower=JOINT_LOWER, upper=JOINT_UPPER, accept=None):
    """The IK solution within the joint limits nearest to q_ref (max-abs joint distance),
    among those `accept(q list)` takes when given; None when the pose is unreachable or no
    solution fits. Never raises."""
    try:
        ref = np.asarray(q_ref, dtype=float).reshape(6).tolist()
        if not all(map(math.isfinite, ref)):
            return None
        lo = _LOWER_LIST if lower is JOINT_LOWER else _limit_list(lower)
        hi = _UPPER_LIST if upper is JOINT_UPPER else _limit_list(upper)
    except (TypeError, ValueError):
        return None
    best, best_d = None, math.inf
    # Scalar code: the same arithmetic as nearest_in_limits, without per-joint numpy calls;
    # a candidate is dropped as soon as one joint is already no nearer than the best.
    two_pi = _TWO_PI
    for sol in _ik_tuples(T, tcp=tcp, q6_free=ref[5]):
        out, d, j = [0.0] * 6, 0.0, 0
        for q, r, lo_j, hi_j in zip(sol, ref, lo, hi):
            v = q + two_pi * round((r - q) / two_pi)
            # twice: step back inside the limits if the nearest copy is outside
            if v > hi_j:
                v -= two_pi
            if v < lo_j:
                v += two_pi
            if v > hi_j:
                v -= two_pi
            if v < lo_j:
                v += two_pi
            if v > hi_j + 1e-12 or v < lo_j - 1e-12:
                break
            e = v - r
            if e < 0.0:
                e = -e                   # abs(), without the call
            if e > d:
                d = e
            if d >= best_d:
                break
            out[j] = v
            j += 1
        else:
            if accept is None or accept(out):
                best, best_d = out, d
    return None if best is None else np.array(best)


def rotation_error(Ra, Rb):
    """Angle (rad) of the rotation taking Ra to Rb."""
    c = (np.trace(np.asarray(Ra).T @ np.asarray(Rb)) - 1.0) / 2.0
    return math.acos(max(-1.0, min(1.0, c)))
