"""Hand source -> LeapInterface -> ArmTeleop -> UR10Cell in one process, in simulated
time and without ROS: the same logic the nodes run, for fast tests, benchmarks and the
demo's pictures."""
from dataclasses import dataclass, field

import numpy as np
import yaml

from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources.scripted import ScriptedSource
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.cell import UR10Cell
from leap_teleop.ur10.config import config_path
from leap_teleop.ur10.teleop import TRACKING, ArmInput, ArmTeleop, ArmTeleopParams


def sim_params(**overrides):
    """The arm's parameters from config/ur10_teleop.yaml as the simulation launch files set
    them (faster joints, the UR10's acceleration limit), with `overrides`."""
    with open(config_path('ur10_teleop.yaml')) as f:
        values = yaml.safe_load(f)
    values.update(max_joint_speed=1.0, max_joint_accel=float(kin.MAX_JOINT_ACCEL[0]))
    values.update(overrides)
    for key in ('axis_map', 'workspace_min', 'workspace_max', 'wrist_lower', 'wrist_upper'):
        values[key] = tuple(tuple(v) if isinstance(v, list) else v for v in values[key])
    return ArmTeleopParams.from_dict(values)


def hand_input(state):
    """The leapcobot view of a HandState, as the arm node receives it."""
    return ArmInput(present=state.present, palm_mm=state.palm_position, fist=state.fist,
                     thumb_up=state.thumb_up, pinch=state.pinch, pinch_value=state.pinch_value,
                     rock=state.rock, stamp=state.timestamp, rotate=state.rotate,
                     turn=state.turn, swing=state.swing)


@dataclass
class ArmRun:
    states: list = field(default_factory=list)        # (t, teleop state) on change
    tracking_errors: list = field(default_factory=list)   # |TCP - target| while tracking, m
    max_joint_speed_seen: float = 0.0


def run_session(script, cell_config, arms, params=None, control_hz=120.0, settle_s=1.0,
                on_period=None):
    """Play `script` into one ArmTeleop per arm ({arm name: hand side}) driving a
    UR10Cell. Returns (cell, {arm: ArmRun}); the caller closes the cell.
    on_period(cell, t) is called every control period (for snapshots); without it the
    cell is never rendered, so it loads no visual meshes."""
    cell = UR10Cell(cell_config, visuals=on_period is not None)
    source = ScriptedSource(script, realtime=False, clock=lambda: 0.0)
    interface = LeapInterface()
    teleops = {arm: ArmTeleop(params or ArmTeleopParams()) for arm in arms}
    runs = {arm: ArmRun() for arm in arms}
    steps_per_period = max(1, int(round(cell.config.physics_hz / control_hz)))
    period = steps_per_period / cell.config.physics_hz
    frames = iter(source.frames())
    pending = next(frames, None)
    t = 0.0
    end = source.script.duration + settle_s
    while t < end:
        while pending is not None and pending.timestamp <= t:
            states = interface.on_frame(pending)
            for arm, side in (arms.items() if states else ()):
                teleops[arm].on_hand(hand_input(states[side]), t)
            pending = next(frames, None)
        for arm, teleop in teleops.items():
            q, qd, _, _ = cell.joint_state(arm)
            teleop.on_joints(q)
            cmd = teleop.step(t)
            if cmd.points:
                cell.command_arm(arm, cmd.points, cmd.stamp)
            if cmd.gripper is not None:
                cell.set_gripper(arm, cmd.gripper, 0.1)
            run = runs[arm]
            state = teleop.status.state
            if not run.states or run.states[-1][1] != state:
                run.states.append((t, state))
            run.max_joint_speed_seen = max(run.max_joint_speed_seen, float(np.max(np.abs(qd))))
            if state == TRACKING and len(teleop.status.target) == 3:
                tcp = cell.tcp_pose(arm, world=False)[:3, 3]
                run.tracking_errors.append(float(np.linalg.norm(tcp - teleop.status.target)))
        cell.step(steps_per_period)
        t += period
        if on_period is not None:
            on_period(cell, t)
    return cell, runs
