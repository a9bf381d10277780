"""UR10 analytic kinematics: IK -> FK round trips, agreement with PyBullet's FK of the
loaded URDF, nearest-solution selection, and failure without exceptions."""
import math

import numpy as np
import pybullet as p
import pytest

from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.model import urdf_file

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

RNG_SEED = 4


def random_q(rng, n):
    return rng.uniform(kin.JOINT_LOWER, kin.JOINT_UPPER, size=(n, 6))


def regular(q):
    """Away from the wrist, elbow and shoulder singularities (IK is exact but branches
    merge there, so 'the original q is among the solutions' is ill-conditioned)."""
    T0 = kin.fk(q, tcp=False)
    wrist = T0[:3, 3] - kin.D6 * T0[:3, 2]
    return (abs(math.sin(q[4])) > 1e-2 and abs(math.sin(q[2])) > 1e-2
            and math.hypot(wrist[0], wrist[1]) > abs(kin.D4) + 1e-2)


def wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def pose_error(Ta, Tb):
    return (float(np.linalg.norm(Ta[:3, 3] - Tb[:3, 3])),
            kin.rotation_error(Ta[:3, :3], Tb[:3, :3]))


@pytest.mark.parametrize('tcp', [True, False])
def test_ik_fk_round_trip_over_thousands_of_poses(tcp):
    rng = np.random.default_rng(RNG_SEED)
    checked = 0
    for q in random_q(rng, 3000):
        T = kin.fk(q, tcp=tcp)
        sols = kin.ik(T, tcp=tcp)
        assert 1 <= len(sols) <= 8, (q, len(sols))
        for s in sols:
            dp, dr = pose_error(kin.fk(s, tcp=tcp), T)
            assert dp < 1e-6 and dr < 1e-6, (q, s, dp, dr)
        if regular(q):
            # The joints that made the pose are one of the solutions (modulo 2 pi).
            diffs = [np.max(np.abs(wrap(s - q))) for s in sols]
            assert min(diffs) < 1e-6, (q, diffs)
            checked += 1
    assert checked > 2500


def test_regular_poses_give_distinct_solutions_up_to_eight():
    rng = np.random.default_rng(RNG_SEED + 1)
    counts = []
    for q in random_q(rng, 300):
        if regular(q):
            sols = kin.ik(kin.fk(q))
            distinct = {tuple(np.round(s, 6)) for s in sols}
            assert len(distinct) == len(sols), sols
            counts.append(len(sols))
    # Branches come in elbow pairs; a shoulder branch drops out where its arm is too short.
    assert set(counts) <= {2, 4, 6, 8}
    assert counts.count(8) > len(counts) // 4, counts


@pytest.fixture(scope='module')
def bullet_ur10():
    client = p.connect(p.DIRECT)
    body = p.loadURDF(urdf_file(''), useFixedBase=True, physicsClientId=client)
    joints, links = {}, {}
    for i in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, i, physicsClientId=client)
        joints[info[1].decode()] = i
        links[info[12].decode()] = i
    yield client, body, [joints[n] for n in kin.JOINT_NAMES], links
    p.disconnect(client)


def bullet_pose(client, body, link):
    ls = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=client)
    T = np.eye(4)
    T[:3, :3] = np.array(p.getMatrixFromQuaternion(ls[5])).reshape(3, 3)
    T[:3, 3] = ls[4]
    return T


def test_fk_matches_pybullet_fk_of_the_urdf(bullet_ur10):
    client, body, arm_joints, links = bullet_ur10
    rng = np.random.default_rng(RNG_SEED + 2)
    worst = 0.0
    for q in random_q(rng, 500):
        for j, v in zip(arm_joints, q):
            p.resetJointState(body, j, float(v), physicsClientId=client)
        for link, tcp in (('tool0', False), ('tcp_link', True)):
            dp, dr = pose_error(bullet_pose(client, body, links[link]), kin.fk(q, tcp=tcp))
            worst = max(worst, dp)
            assert dp < 1e-6 and dr < 1e-6, (link, q, dp, dr)
    assert worst > 0.0     # compared real numbers


def test_ik_solutions_reach_the_pose_in_pybullet(bullet_ur10):
    client, body, arm_joints, links = bullet_ur10
    rng = np.random.default_rng(RNG_SEED + 3)
    for q in random_q(rng, 100):
        T = kin.fk(q)
        for s in kin.ik(T):
            for j, v in zip(arm_joints, s):
                p.resetJointState(body, j, float(v), physicsClientId=client)
            dp, dr = pose_error(bullet_pose(client, body, links['tcp_link']), T)
            assert dp < 1e-6 and dr < 1e-6


def test_ik_nearest_is_the_nearest_solution_within_limits():
    rng = np.random.default_rng(RNG_SEED + 4)
    for q in random_q(rng, 300):
        q_ref = np.clip(q + rng.normal(0, 0.3, 6), kin.JOINT_LOWER, kin.JOINT_UPPER)
        T = kin.fk(q)
        best = kin.ik_nearest(T, q_ref)
        assert best is not None
        assert np.all(best >= kin.JOINT_LOWER) and np.all(best <= kin.JOINT_UPPER)
        dp, dr = pose_error(kin.fk(best), T)
        assert dp < 1e-6 and dr < 1e-6
        d_best = np.max(np.abs(best - q_ref))
        # No solution (any 2 pi copy within the limits) is nearer.
        for s in kin.ik(T, q6_free=q_ref[5]):
            c = kin.nearest_in_limits(s, q_ref)
            if c is not None:
                assert d_best <= np.max(np.abs(c - q_ref)) + 1e-9
        if regular(q):
            assert d_best <= np.max(np.abs(q - q_ref)) + 1e-6


def test_elbow_limit_is_respected():
    q = np.array([0.3, -1.0, 2.5, -1.0, 1.2, 0.4])
    lower = kin.JOINT_LOWER.copy()
    upper = kin.JOINT_UPPER.copy()
    upper[2] = 2.0            # forbid this elbow-down branch
    s = kin.ik_nearest(kin.fk(q), q, upper=upper, lower=lower)
    assert s is not None and s[2] <= 2.0
    assert pose_error(kin.fk(s), kin.fk(q))[0] < 1e-6


@pytest.mark.parametrize('T', [
    kin.pose([3.0, 0.0, 0.5]),                        # beyond the reach (~1.3 m)
    kin.pose([0.0, 0.0, 2.0]),                        # straight up, too far
    kin.pose([0.0, 0.05, 0.3], np.eye(3)),            # wrist inside the shoulder cylinder
    np.full((4, 4), np.nan),
    np.eye(3),
    'not a pose',
    None,
])
def test_unreachable_or_malformed_poses_fail_quietly(T):
    assert kin.ik(T) == []
    assert kin.ik_nearest(T, kin.HOME_Q) is None


def test_bad_reference_joints_fail_quietly():
    T = kin.fk(kin.HOME_Q)
    assert kin.ik_nearest(T, [np.nan] * 6) is None
    assert kin.ik_nearest(T, [0.0] * 5) is None
    assert kin.ik_nearest(T, 'abc') is None


def test_fuzzed_poses_never_raise():
    rng = np.random.default_rng(RNG_SEED + 5)
    solved = nearest = 0
    for _ in range(2000):
        T = np.eye(4)
        R = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        T[:3, :3] = R * np.sign(np.linalg.det(R))      # a rotation, not a reflection
        T[:3, 3] = rng.uniform(-2.0, 2.0, 3)
        sols = kin.ik(T)
        for s in sols:
            dp, dr = pose_error(kin.fk(s), T)
            assert dp < 1e-6 and dr < 1e-6
        solved += bool(sols)
        best = kin.ik_nearest(T, kin.HOME_Q)
        if best is not None:       # a solution within the limits: it reaches the pose
            assert sols and np.all(best >= kin.JOINT_LOWER) and np.all(best <= kin.JOINT_UPPER)
            dp, dr = pose_error(kin.fk(best), T)
            assert dp < 1e-6 and dr < 1e-6
            nearest += 1
    # Positions in a 4 m cube around a 1.3 m reach: some reachable, most not.
    assert 100 < solved < 1500 and nearest > 100, (solved, nearest)


# -- rotations past pi ----------------------------------------------------------------------
def test_rotation_vector_near_is_the_same_rotation_and_keeps_growing_past_pi():
    axis = np.array([0.6, 0.0, 0.8])
    near = None
    for angle in np.linspace(0.0, 3 * math.pi, 400):
        R = kin.rotation_from_vector(axis * angle)
        w = kin.rotation_vector_near(R, near)
        np.testing.assert_allclose(kin.rotation_from_vector(w), R, atol=1e-9)
        if near is not None:             # no flip of the axis at pi, nor at 2 pi
            assert np.linalg.norm(w - near) < 0.05
        near = w
    np.testing.assert_allclose(near, axis * 3 * math.pi, atol=1e-6)
    # With nothing near it is the plain rotation vector, angle in [0, pi].
    R = kin.rotation_from_vector(axis * 4.0)
    np.testing.assert_allclose(kin.rotation_vector_near(R, None), kin.rotation_vector(R))


def test_limited_tool_rotation_keeps_its_side_over_the_top_and_past_a_half_turn():
    # The tool tilted about base x through straight up: unclamped, the clamp's side (the
    # tilt axis) flips where the tool points up; with the last side handed back it stays.
    down = kin.tool_down()
    flips, near, last, last_plain = 0, None, None, None
    for angle in np.linspace(0.0, 6.0, 300):        # on past 1.5 pi (a higher scale)
        R = kin.rotation_from_vector([angle, 0.0, 0.0]) @ down
        limited, near = kin.limit_tool_rotation(R, 0.5, 0.0, 1.0, near)
        plain, _ = kin.limit_tool_rotation(R, 0.5, 0.0, 1.0)
        if last is not None:
            assert kin.rotation_error(last, limited) < 0.05
            flips += kin.rotation_error(last_plain, plain) > 0.5
        last, last_plain = limited, plain
    assert flips == 1                    # what the swing handed back prevents
    np.testing.assert_allclose(last, kin.rotation_from_vector([0.5, 0.0, 0.0]) @ down, atol=1e-9)
    # A turn about the vertical past pi keeps counting: clamped at +1, not flipped to -1.
    near = None
    for yaw in np.linspace(0.0, 4.0, 200):
        limited, near = kin.limit_tool_rotation(kin.tool_down(yaw), 0.5, 0.0, 1.0, near)
    assert near[1] == pytest.approx(4.0) and kin.tilt_and_yaw(limited)[1] == pytest.approx(1.0)
    # Within the limits the rotation is returned as it is.
    R = kin.rotation_from_vector([0.2, -0.1, 0.3]) @ down
    assert np.array_equal(kin.limit_tool_rotation(R, 0.5, 0.0, 1.0)[0], R)
