"""A scripted pick & place for one arm, as joint targets from the analytic IK.

No hand input and no ROS: tests, the bench and the pick & place rostest all replay the
same plan (through UR10Cell directly or through the sim node's topics).
"""
from dataclasses import dataclass

import numpy as np

from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.model import KNUCKLE_CLOSED_RAD

APPROACH_HEIGHT = 0.15      # m above the grasp / drop point for the vertical moves
DROP_CLEARANCE = 0.03       # m between the cube's bottom and the tray floor at release


@dataclass
class Step:
    """Move the arm to q (6 joints, JOINT_NAMES order), or the gripper to a knuckle angle."""
    what: str                # 'arm' | 'gripper'
    target: np.ndarray
    label: str


def pick_place_plan(cfg, arm_name, cube_name, q_start=None, cube_xyz=None):
    """Steps that take cube_name (at cube_xyz, default its configured start) into the
    arm's tray: above, down, close, up, above the tray, down, open, up.
    Raises ValueError when a waypoint has no IK solution within the joint limits."""
    arm = cfg.arm(arm_name)
    cube = np.asarray(cfg.cube(cube_name).xyz if cube_xyz is None else cube_xyz, dtype=float)
    tray = arm.tray
    drop = np.array([tray.xyz[0], tray.xyz[1],
                     tray.floor_z + cfg.cube_size / 2 + DROP_CLEARANCE])
    up = np.array([0.0, 0.0, APPROACH_HEIGHT])
    q = np.array(arm.home if q_start is None else q_start, dtype=float)
    steps = []

    def move(xyz_world, label):
        nonlocal q
        T = kin.pose(arm.point_to_base(xyz_world), kin.tool_down())
        q_new = kin.ik_nearest(T, q)
        if q_new is None:
            raise ValueError('%s: no IK solution for %s at %s' % (arm_name, label, xyz_world))
        q = q_new
        steps.append(Step('arm', q.copy(), label))

    move(cube + up, 'above cube')
    move(cube, 'at cube')
    steps.append(Step('gripper', np.array([KNUCKLE_CLOSED_RAD]), 'close'))
    move(cube + up, 'lift')
    move(drop + up, 'above tray')
    move(drop, 'at tray')
    steps.append(Step('gripper', np.array([0.0]), 'open'))
    move(drop + up, 'retreat')
    return steps


def run_plan(cell, arm_name, steps, settle=0.3, gripper_time=0.5):
    """Play a plan on a UR10Cell (simulated time): each step to completion plus settle s."""
    for step in steps:
        if step.what == 'arm':
            end = cell.move_to(arm_name, step.target)
            cell.run(end - cell.time + settle)
        else:
            cell.set_gripper(arm_name, float(step.target[0]), gripper_time)
            cell.run(gripper_time + settle)


def play_together(cell, tasks, on_step=None, settle=0.3, gripper_time=0.5):
    """Every arm's pick & place ({arm: cube}) at once, plan step by plan step, each step
    held until the slowest arm is there plus `settle` s; on_step(cell) after every physics
    step when given (benchmarks)."""
    plans = {arm: pick_place_plan(cell.config, arm, cube) for arm, cube in tasks.items()}
    for k in range(len(next(iter(plans.values())))):
        ends = []
        for arm, plan in plans.items():
            step = plan[k]
            if step.what == 'arm':
                ends.append(cell.move_to(arm, step.target))
            else:
                ends.append(cell.set_gripper(arm, float(step.target[0]), gripper_time))
        n = max(1, int(round((max(ends) - cell.time + settle) / cell.dt)))
        if on_step is None:
            cell.step(n)
        else:
            for _ in range(n):
                cell.step()
                on_step(cell)
