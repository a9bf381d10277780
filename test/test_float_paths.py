"""The plain-float fast paths of the control loop give numpy's floats exactly, and the
cached or trimmed set-up steps give what they replace."""
import math
import re

import numpy as np
import pytest

from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10 import orientation as ori
from leap_teleop.ur10.config import load_config
from leap_teleop.ur10.model import build_urdf
from leap_teleop.vectors import cross3, norm3, rpy_matrix, unit


def _norm(a):
    """numpy's norm of a short vector as a plain sum of squares. np.linalg.norm of a 1-D
    array goes through BLAS's dot, which on CPUs with fused multiply-add kernels (AVX-512
    OpenBLAS) rounds the last place differently from one machine to another."""
    return float(np.sqrt(np.sum(a * a)))


def test_norm3_cross3_and_unit_give_numpys_floats_bit_for_bit():
    rng = np.random.default_rng(3)
    for a, b in rng.normal(size=(2000, 2, 3)) * rng.choice([1e-6, 1.0, 1e3], size=(2000, 1, 1)):
        assert norm3(a.tolist()) == _norm(a)
        assert cross3(a.tolist(), b.tolist()) == tuple(np.cross(a, b).tolist())
        assert unit(a).tobytes() == (a / _norm(a)).tobytes()
    assert np.isnan(unit(np.zeros(3))).all()
    assert unit(np.zeros(3), fallback='none') == 'none'


def _rodrigues(w):
    """rotation_from_vector written with numpy, as it was."""
    w = np.asarray(w, dtype=float)
    angle = _norm(w)
    if angle < 1e-12:
        return np.eye(3)
    k = w / angle
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def test_rotations_match_their_numpy_forms_bit_for_bit():
    rng = np.random.default_rng(4)
    for w in rng.normal(size=(500, 3)) * rng.choice([1e-13, 1e-3, 1.0], size=(500, 1)):
        R = kin.rotation_from_vector(w)
        assert R.tobytes() == _rodrigues(w).tobytes()
        v = kin.rotation_vector(R)
        c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
        angle = math.acos(c)
        axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
        if angle >= 1e-9:
            assert v.tobytes() == (axis * (angle / (2.0 * math.sin(angle)))).tobytes()


def test_rpy_matrix_is_yaw_after_pitch_after_roll():
    rng = np.random.default_rng(5)
    for r, p, y in rng.uniform(-math.pi, math.pi, (50, 3)):
        rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
        ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
        rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
        assert np.allclose(np.reshape(rpy_matrix(r, p, y), (3, 3)), rz @ ry @ rx, atol=1e-12)


@pytest.mark.parametrize('rotate, turn, swing', [(0.0, 0.0, 0.0), (0.3, -0.4, 0.2),
                                                 (0.0, math.pi / 2, 0.0), (2.0, 1.0, -1.2)])
def test_hand_rotation_keeps_its_angles(rotate, turn, swing):
    from leap_teleop.hands.tracker import hand_angles
    R = ori.hand_rotation(rotate, turn, swing)
    assert np.allclose(R @ R.T, np.eye(3), atol=1e-12)
    normal, direction = R @ np.array([0.0, -1.0, 0.0]), R @ np.array([0.0, 0.0, -1.0])
    roll, yaw, pitch = hand_angles(normal, direction)
    if abs(turn) < math.pi / 2 - 1e-6:
        assert (yaw, pitch) == pytest.approx((turn, swing), abs=1e-9)
        assert roll == pytest.approx(rotate, abs=1e-9)


def test_ik_nearest_takes_limits_as_arrays_or_float_tuples_alike():
    rng = np.random.default_rng(5)
    lower = np.concatenate([kin.JOINT_LOWER[:3], [-4.0, -3.0, -5.0]])
    upper = np.concatenate([kin.JOINT_UPPER[:3], [1.0, 3.0, 5.0]])
    for _ in range(200):
        T = kin.fk(rng.uniform(-3, 3, 6))
        ref = rng.uniform(-3, 3, 6)
        a = kin.ik_nearest(T, ref, lower=lower, upper=upper)
        b = kin.ik_nearest(T, ref, lower=tuple(lower.tolist()), upper=tuple(upper.tolist()))
        assert (a is None and b is None) or a.tobytes() == b.tobytes()


def test_render_hand_frame_is_orthonormal_with_the_thumb_on_its_side():
    for side in ('right', 'left'):
        h = render_hand(side, 'open', (0.0, 200.0, 0.0), (0.1, -1.0, 0.0), (0.0, 0.3, -1.0))
        n, d = h.palm_normal, h.direction
        assert np.linalg.norm(n) == pytest.approx(1.0) and np.linalg.norm(d) == pytest.approx(1.0)
        assert float(n @ d) == pytest.approx(0.0, abs=1e-12)
        thumb = h.fingers[0].mcp - h.palm_position
        assert (float(thumb @ np.cross(d, n)) > 0) == (side == 'right')


def test_to_base_is_the_placements_inverse():
    cfg = load_config('ur10_dual_rotated_cell.yaml')
    for arm in cfg.arms:
        T = kin.fk(kin.HOME_Q)
        assert arm.to_base(T).tobytes() == (np.linalg.inv(arm.world_T_base) @ T).tobytes()
        assert np.allclose(arm.to_world(arm.to_base(T)), T, atol=1e-12)


def test_a_urdf_without_visuals_differs_in_the_arms_visual_meshes_alone():
    full, bare = build_urdf('ur10_1_'), build_urdf('ur10_1_', visuals=False)
    assert '.dae' in full and '.dae' not in bare
    assert '<visual>' in bare                       # the gripper's boxes keep theirs
    assert (re.sub('<visual>.*?</visual>', '', full, flags=re.S)
            == re.sub('<visual>.*?</visual>', '', bare, flags=re.S))


def test_trajectory_float_paths_give_the_array_paths_floats():
    from leap_teleop.ur10.trajectory import _hermite, _hermite_peak
    rng = np.random.default_rng(6)
    for _ in range(300):
        q0, q1, v0, v1 = rng.normal(size=(4, 6)) * rng.choice([1e-6, 1.0, 5.0])
        T, s = float(rng.uniform(1e-3, 2.0)), float(rng.choice([0.0, 1.0, rng.uniform()]))
        fast, slow = _hermite(q0, q1, v0, v1, T, s), _hermite(q0, q1, v0, v1, T, np.float64(s))
        assert all(a.tobytes() == b.tobytes() for a, b in zip(fast, slow))
        rows = [x[None] for x in (q0, q1, v0, v1)]              # 2-D: the array path
        assert _hermite_peak(q0, q1, v0, v1, T).tobytes() == _hermite_peak(*rows, T)[0].tobytes()


def test_one_euro_3_vector_path_gives_the_array_paths_floats():
    from leap_teleop.control.one_euro import OneEuroFilter
    rng = np.random.default_rng(7)
    flat, rows = OneEuroFilter(0.3, 4.0, 1.0), OneEuroFilter(0.3, 4.0, 1.0)
    t = 0.0
    for x in rng.normal(size=(300, 3)).cumsum(axis=0):
        t += 0.008
        a, b = flat.update(x, t), rows.update(x[None], t)      # (1, 3): the array path
        assert a.tobytes() == b[0].tobytes() and flat.speed == rows.speed
