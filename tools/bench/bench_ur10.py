"""UR10 benchmarks, all measured side by side in one run.

ik.us_per_solve             kinematics.ik_nearest (all analytic solutions + choice of the
                            nearest within limits) per TCP pose, microseconds.
ik.speedup_vs_pybullet      pybullet.calculateInverseKinematics (default settings, seeded
                            at home) time / ik_nearest time on the same poses.
ik.max_err_m                worst TCP position error of ik_nearest over those poses (FK of
                            the answer vs the pose), m; ik.pybullet_err_m_p50 / _max the same
                            for PyBullet's answers (checked with PyBullet's own FK).
sim.ur10_rtf_1arm           headless UR10Cell real-time factor running scripted pick &
                            places (trajectory following, gripper, contact grasping).
sim.ur10_rtf_2arm           the same with two arms working at once (dual cell).
sim.ur10_raw_rtf_1arm       bare PyBullet stepping of the same one-arm scene doing the same
                            motion (the cell's recorded motor targets replayed with one
                            motor call per arm and gripper per step; no follower, grasp
                            checks or state reads).
sim.ur10_rtf_ratio_vs_raw   sim.ur10_rtf_1arm / sim.ur10_raw_rtf_1arm: the cost of the
                            cell's control layer, less what it saves: the cell puts settled
                            cubes to sleep after 0.25 s, the bare replay's wait for the
                            engine's 2 s, so the ratio can exceed 1.
sim.ur10_static_rtf_1arm    stepSimulation of the scene with nothing moving (for scale: a
                            moving arm in contact costs the physics engine about twice that).
"""
import time

import numpy as np
import pybullet as p

from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.cell import UR10Cell
from leap_teleop.ur10.pick_place import play_together

N_POSES = 2000


def _poses(n, seed=7):
    """Reachable TCP poses (FK of random joints within +-pi) and a reference near each."""
    rng = np.random.default_rng(seed)
    qs = rng.uniform(-np.pi, np.pi, size=(n, 6))
    refs = qs + rng.normal(0.0, 0.2, size=qs.shape)
    return [kin.fk(q) for q in qs], refs


def ik_figures():
    """Both solvers on the same poses, timed in alternating chunks so that load from
    other processes hits both alike."""
    poses, refs = _poses(N_POSES)
    client = p.connect(p.DIRECT)
    try:
        from leap_teleop.ur10.model import urdf_file
        body = p.loadURDF(urdf_file(''), useFixedBase=True, physicsClientId=client)
        info = [p.getJointInfo(body, i, physicsClientId=client)
                for i in range(p.getNumJoints(body, physicsClientId=client))]
        index = {j[1].decode(): j[0] for j in info}
        tcp = {j[12].decode(): j[0] for j in info}['tcp_link']
        movable = [j[0] for j in info if j[2] != p.JOINT_FIXED]
        for name, q in zip(kin.JOINT_NAMES, kin.HOME_Q):
            p.resetJointState(body, index[name], float(q), physicsClientId=client)
        targets = [(T[:3, 3].tolist(), _quat(T[:3, :3])) for T in poses]
        answers, sols, ours, theirs = [], [], 0.0, 0.0
        chunk = 100
        for i in range(0, len(poses), chunk):
            t0 = time.perf_counter()
            answers += [kin.ik_nearest(T, r) for T, r in zip(poses[i:i + chunk],
                                                             refs[i:i + chunk])]
            t1 = time.perf_counter()
            sols += [p.calculateInverseKinematics(body, tcp, pos, orn, physicsClientId=client)
                     for pos, orn in targets[i:i + chunk]]
            t2 = time.perf_counter()
            ours += t1 - t0
            theirs += t2 - t1
        errors = [np.linalg.norm(kin.fk(q)[:3, 3] - T[:3, 3])
                  for q, T in zip(answers, poses) if q is not None]
        pb_err = []
        for sol, (pos, _) in zip(sols, targets):
            for j, v in zip(movable, sol):
                p.resetJointState(body, j, v, physicsClientId=client)
            got = p.getLinkState(body, tcp, computeForwardKinematics=True,
                                 physicsClientId=client)[4]
            pb_err.append(np.linalg.norm(np.subtract(got, pos)))
    finally:
        p.disconnect(client)
    n = len(poses)
    return {
        'ik.us_per_solve': ours / n * 1e6,
        'ik.pybullet_us_per_solve': theirs / n * 1e6,
        'ik.speedup_vs_pybullet': theirs / ours,
        'ik.solved_fraction': len(errors) / n,
        'ik.max_err_m': float(max(errors)),
        'ik.pybullet_err_m_p50': float(np.median(pb_err)),
        'ik.pybullet_err_m_max': float(np.max(pb_err)),
    }


def _quat(R):
    """Rotation matrix -> quaternion (x, y, z, w), robust for every rotation."""
    m = R
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = np.sqrt(tr + 1.0) * 2
        return [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4]
    i = int(np.argmax([m[0, 0], m[1, 1], m[2, 2]]))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k]) * 2
    q = [0.0, 0.0, 0.0, (m[k, j] - m[j, k]) / s]
    q[i] = s / 4
    q[j] = (m[j, i] + m[i, j]) / s
    q[k] = (m[k, i] + m[i, k]) / s
    return q


def cell_rtf(config, tasks, rounds=3, raw=False):
    """Real-time factor of the cell running each arm's pick & place at once, `rounds`
    times (reset in between); tasks: {arm: cube}. With raw, each round is followed by
    the bare replay of the same motion (raw_replay) in a second scene, so that load from
    other processes hits both alike. Returns (rtf, cubes placed, raw rtf or None)."""
    targets = motor_targets(config, tasks) if raw else None
    cell = UR10Cell(config)
    bare = UR10Cell(config) if raw else None
    try:
        placed, sim, wall, raw_sim, raw_wall = 0, 0.0, 0.0, 0.0, 0.0
        for _ in range(rounds):
            cell.reset()
            t_sim, t0 = cell.time, time.perf_counter()
            play_together(cell, tasks)
            wall += time.perf_counter() - t0
            sim += cell.time - t_sim
            placed += sum(cell.in_tray(cube, arm) for arm, cube in tasks.items())
            if raw:
                bare.reset()
                raw_wall += raw_replay(bare, targets)
                raw_sim += len(targets) * bare.dt
        return sim / wall, placed, (raw_sim / raw_wall if raw else None)
    finally:
        cell.close()
        if bare is not None:
            bare.close()


def motor_targets(config, tasks):
    """The per-step motor targets the cell sends during the pick & place (untimed)."""
    cell = UR10Cell(config)
    targets = []
    try:
        play_together(cell, tasks, lambda c: targets.append(
            [(a.arm_follower.q.tolist(), a.arm_follower.qd.tolist(),
              float(a.gripper_follower.q[0])) for a in c.arms.values()]))
    finally:
        cell.close()
    return targets


def raw_replay(cell, targets):
    """Bare PyBullet stepping of the cell's scene doing the same motion: one motor call
    per arm and per gripper with the recorded targets, then stepSimulation; no trajectory
    following, grasp checks or state reads. Returns the wall time."""
    from leap_teleop.ur10.cell import ARM_FORCE, ARM_POSITION_GAIN, GRIPPER_FORCE
    from leap_teleop.ur10.model import FINGER_TRAVEL, KNUCKLE_CLOSED_RAD
    c, arms = cell.client, list(cell.arms.values())
    forces, kp, kd = ARM_FORCE.tolist(), [ARM_POSITION_GAIN] * 6, [1.0] * 6
    t0 = time.perf_counter()
    for per_arm in targets:
        for arm, (q, qd, g) in zip(arms, per_arm):
            p.setJointMotorControlArray(arm.body, arm.arm_joints, p.POSITION_CONTROL,
                                        targetPositions=q, targetVelocities=qd,
                                        forces=forces, positionGains=kp,
                                        velocityGains=kd, physicsClientId=c)
            f = g * FINGER_TRAVEL / KNUCKLE_CLOSED_RAD
            p.setJointMotorControlArray(arm.body, arm.fingers + [arm.knuckle],
                                        p.POSITION_CONTROL, targetPositions=[f, f, g],
                                        forces=[GRIPPER_FORCE, GRIPPER_FORCE, 1.0],
                                        positionGains=[0.2] * 3, physicsClientId=c)
        p.stepSimulation(physicsClientId=c)
    return time.perf_counter() - t0


def static_rtf(config, seconds):
    """stepSimulation alone with nothing moving (a lower bound of the physics cost)."""
    cell = UR10Cell(config)
    try:
        n = int(round(seconds / cell.dt))
        t0 = time.perf_counter()
        for _ in range(n):
            p.stepSimulation(physicsClientId=cell.client)
        return n * cell.dt / (time.perf_counter() - t0)
    finally:
        cell.close()


def run():
    out = ik_figures()
    one, two = {'ur10_1': 'cube_green'}, {'ur10_1': 'cube_green', 'ur10_2': 'cube_cyan'}
    rtf1, placed1, raw1 = cell_rtf('ur10_cell.yaml', one, raw=True)
    rtf2, placed2, _ = cell_rtf('ur10_dual_cell.yaml', two)
    if placed1 != 3 or placed2 != 6:
        raise RuntimeError('benchmark pick & place failed (%d/3, %d/6 cubes placed)'
                           % (placed1, placed2))
    out.update({
        'sim.ur10_rtf_1arm': rtf1,
        'sim.ur10_rtf_2arm': rtf2,
        'sim.ur10_raw_rtf_1arm': raw1,
        'sim.ur10_rtf_ratio_vs_raw': rtf1 / raw1,
        'sim.ur10_static_rtf_1arm': static_rtf('ur10_cell.yaml', 5.0),
    })
    return out


if __name__ == '__main__':
    for key, value in sorted(run().items()):
        print('%-28s %.6g' % (key, value))
