"""The arm teleop's parameters, declared once: the `Param` tables are the single source of
ArmTeleopParams (its fields and defaults are generated from TELEOP_PARAMS), of ur10_arm's
~params and --help, of its dynamic_reconfigure server and of the docs' parameter table.
config/ur10_teleop.yaml sets the same names (a test keeps it inside these declarations).
"""
import math

import numpy as np

from leap_teleop.control.stream_health import HAND_SUBSCRIPTION_PARAMS
from leap_teleop.params import Param, check_params, declared_fields
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10 import orientation as ori

MODES = ('imitation', 'joystick')
GRIPPER_MODES = ('binary', 'proportional')
ORIENTATION_MODES = ('fixed', 'yaw', 'full')
TWO_PI = 2 * math.pi

# Every ArmTeleopParams field. Timeouts and speeds have upper bounds too.
TELEOP_PARAMS = {
    'mode': Param('imitation', 'imitation (TCP follows the palm) or joystick (speed beyond the '
                               'dead zone)', choices=MODES),
    # Leap axes (x right, y up, z toward the user) -> arm base axes.
    'axis_map': Param([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                      'Leap axes -> arm base axes, rows = base x, y, z', length=3,
                      item=Param([0.0, 0.0, 0.0], '', length=3, ge=-1.0, le=1.0)),
    'scale': Param(2.5, 'imitation: robot m per hand m', gt=0.0, le=10.0),
    'dead_zone': Param(0.03, 'joystick: radius around the origin that moves nothing', unit='m',
                       gt=0.0, le=0.3),
    'joystick_gain': Param(2.0, 'joystick: TCP m/s per m of palm beyond the dead zone',
                           unit='1/s', gt=0.0, le=20.0),
    'max_tcp_speed': Param(0.25, 'joystick: speed cap of the TCP target (the arm catching up '
                                 'with it can go faster for a moment)', unit='m/s', gt=0.0, le=1.0),
    'workspace_min': Param([0.25, -0.9, 0.0], 'TCP target box, low corner (base frame)',
                           unit='m', length=3, ge=-3.0, le=3.0),
    'workspace_max': Param([1.15, 0.9, 0.9], 'TCP target box, high corner', unit='m',
                           length=3, ge=-3.0, le=3.0),
    'tool_yaw': Param(0.0, 'tool turned about z by this (pointing down)', unit='rad',
                      ge=-TWO_PI, le=TWO_PI),
    'orientation': Param('fixed', 'fixed (tool down, turned by tool_yaw), yaw (tool yaw follows '
                                  'the hand\'s turn) or full (the tool turns as the palm)',
                         choices=ORIENTATION_MODES),
    'orientation_scale': Param(1.0, 'tool rotation per hand rotation', gt=0.0, le=5.0),
    'max_tool_tilt': Param(0.8, 'tool axis at most this far from straight down', unit='rad',
                           ge=0.0, le=math.pi / 2),
    'max_tool_turn': Param(1.6, 'tool yaw at most this far from its yaw at the rock',
                           unit='rad', ge=0.0, le=math.pi),
    'wrist_lower': Param([-TWO_PI] * 3, 'wrist 1-3 lower limits the IK may use', unit='rad',
                         length=3, ge=-TWO_PI - 1e-3, le=TWO_PI + 1e-3),
    'wrist_upper': Param([TWO_PI] * 3, 'wrist 1-3 upper limits the IK may use', unit='rad',
                         length=3, ge=-TWO_PI - 1e-3, le=TWO_PI + 1e-3),
    'filter_min_cutoff_hz': Param(0.2, 'One Euro on the palm: cutoff at rest; 0 = off',
                                  unit='Hz', ge=0.0, le=100.0),
    'filter_beta': Param(0.05, 'One Euro on the palm: cutoff added per palm speed',
                         unit='Hz/(mm/s)', ge=0.0, le=10.0),
    'filter_d_cutoff_hz': Param(0.35, 'One Euro on the palm: cutoff of the speed estimate',
                                unit='Hz', gt=0.0, le=100.0),
    'rotation_min_cutoff_hz': Param(0.3, 'One Euro on the hand\'s rotation vector: cutoff at '
                                         'rest; 0 = off', unit='Hz', ge=0.0, le=100.0),
    'rotation_beta': Param(4.0, 'One Euro on the rotation: cutoff added per turning speed',
                           unit='Hz/(rad/s)', ge=0.0, le=1000.0),
    'rotation_d_cutoff_hz': Param(1.0, 'One Euro on the rotation: cutoff of the speed '
                                       'estimate', unit='Hz', gt=0.0, le=100.0),
    'max_joint_speed': Param(0.05, 'every joint at most this fast (lowered live, a faster '
                                   'joint slows to it at max_joint_accel)', unit='rad/s', gt=0.0,
                             le=float(min(kin.MAX_JOINT_SPEED))),
    'max_joint_accel': Param(0.5, 'every joint accelerates at most this much while tracking; '
                                  'a hold (stall, fist, lost hand, IK failure) brakes at the '
                                  'UR10\'s own limit, to stop as soon as it can (lowered live, '
                                  'it comes down over 1 s, at once when every joint can stop '
                                  'within 0.1 s at it)',
                             unit='rad/s^2',
                             gt=0.0, le=float(min(kin.MAX_JOINT_ACCEL))),
    'servo_gain': Param(10.0, 'joint error -> velocity correction on top of the goal\'s own '
                              'velocity', unit='1/s', gt=0.0, le=100.0),
    'servo_lead': Param(0.0, 'the servo aims at the joint goal extrapolated this far ahead '
                             'along its velocity (a short prediction; 0 = none)', unit='s',
                        ge=0.0, le=0.1),
    'servo_reach_fast': Param(False, 'each command reaches its velocity as fast as the '
                                     'acceleration bound allows, then holds it to the '
                                     'horizon (else: evenly over the horizon)'),
    'command_horizon': Param(0.024, 'time of each trajectory\'s first point (with its '
                                    'velocity; the second is rest); ur10_arm takes at least '
                                    '1.5 times its longest step interval of the last 0.25 s '
                                    '(at most 1.5 periods of ~rate), so that each command '
                                    'lasts until the next',
                             unit='s', ge=0.004, le=0.5),
    'command_lead': Param(0.0, 'each trajectory starts this far after it is planned (its '
                               'header stamp): a command that reaches the controller within '
                               'it continues the last one exactly, a later one joins it '
                               'faster than max_joint_accel', unit='s', ge=0.0, le=0.05),
    'min_duration': Param(0.05, 'shortest hold trajectory sent: a hold from motion comes to '
                                'rest as fast as it can and stays there until then', unit='s',
                          gt=0.0, le=5.0),
    # Lower bounds well above a message interval: below it every ordinary gap between
    # two frames (or joint states) is a stall, and the arm stops and starts each message.
    'input_timeout': Param(0.2, 'no hand input this long -> hold (watchdog); fresh input '
                                'resumes from the current pose', unit='s', ge=0.05, le=10.0),
    'disarm_after': Param(1.0, 'no hand input this long -> disarm (a new thumbs-up needed); '
                               'at least input_timeout', unit='s', gt=0.0, le=10.0),
    'gripper_mode': Param('binary', 'binary (closed while pinching) or proportional',
                          choices=GRIPPER_MODES),
    'gripper_binary_closed': Param(0.43, 'binary: knuckle when closed', unit='rad',
                                   ge=0.0, le=0.8),
    'gripper_reach_mm': Param(10.0, 'the gripper opens or closes once the tool is this close '
                                     'to where the hand puts it (an arm still catching up '
                                     'would grasp or release short of it)', unit='mm',
                              gt=0.0, le=500.0),
    'gripper_wait_s': Param(1.0, 'longest an opening or closing waits for the tool to get '
                                 'there (0 = at once)', unit='s', ge=0.0, le=10.0),
    'max_palm_mm': Param(1000.0, '|palm| beyond this is a tracking error, ignored', unit='mm',
                         gt=0.0, le=2000.0),
    'max_input_age': Param(0.25, 'drop a message arriving this much later than the stream\'s '
                                 'best latency', unit='s', gt=0.0, le=10.0),
    'reanchor_beyond': Param(0.1, 'after a hand-input stall, the origin is re-anchored when the hand '
                                  'moved the target further than this (or turned the tool\'s '
                                  'target more than 0.3 rad, in the yaw and full orientation '
                                  'modes) during the silence (what it did unseen is not '
                                  'driven), and always in joystick mode; either way the arm '
                                  'catches up its lag from before the stall at the servo\'s limits',
                             unit='m', ge=0.0, le=2.0),
    'joint_timeout': Param(0.5, 'no joint states this long -> hold (commands stop); fresh '
                                'states resume from the current pose', unit='s',
                           ge=0.05, le=10.0),
    'joint_loss_after': Param(3.0, 'no joint states this long -> disarm and forget the robot '
                                   '(gone or restarted); at least joint_timeout', unit='s',
                              gt=0.0, le=30.0),
    'arm_hold_s': Param(0.3, 'a thumbs-up must be held this long before it arms (by its '
                             'messages\' stamps and by their receipt)', unit='s',
                        ge=0.0, le=5.0),
}

# ur10_arm's own ~params (the wiring of one arm), then every teleop one: the launch files
# load config/ur10_teleop.yaml into the node's namespace.
ARM_NODE_PARAMS = {
    'hand': Param('right', 'which hand drives this arm', choices=('right', 'left')),
    'hand_topic': Param('', 'leapcobot topic; default leapmotion/data_<hand>', ros_name=True),
    # The loop is also the watchdog's clock: at least 10 Hz.
    'rate': Param(125.0, 'control loop rate (it also runs on each new hand message)',
                  unit='Hz', ge=10.0, le=1000.0),
    'joint_prefix': Param('', 'prefix of the joint names in commands and joint_states (e.g. ur10_1_)'),
    'gesture_bindings': Param('', "the sender's gesture bindings YAML, so the state lines name the "
                              'gestures that arm, set the origin and stop; empty = the defaults',
                              path=True),
    'status_rate': Param(10.0, 'ArmStatus publishing rate (also on every change)', unit='Hz',
                         ge=0.1, le=1000.0),
    # 50: in alternated soaks with a load burst, 10 lost commands on the way to a stalled
    # subscriber in all three runs, 50 in none
    'command_queue_size': Param(50, 'arm and gripper commands queued per subscriber',
                                ge=1, le=2000),
    **HAND_SUBSCRIPTION_PARAMS,
    **TELEOP_PARAMS,
}

# Changeable while running (dynamic_reconfigure): gains, the dead zone, filter constants,
# speed limits, the arming hold. Modes, geometry, watchdog times and topics stay start-up only.
ARM_RECONFIGURABLE = ('scale', 'dead_zone', 'joystick_gain', 'max_tcp_speed',
                      'orientation_scale', 'max_tool_tilt', 'max_tool_turn',
                      'filter_min_cutoff_hz', 'filter_beta', 'filter_d_cutoff_hz',
                      'rotation_min_cutoff_hz', 'rotation_beta', 'rotation_d_cutoff_hz',
                      'max_joint_speed', 'max_joint_accel', 'servo_gain', 'servo_lead',
                      'gripper_binary_closed', 'gripper_reach_mm', 'gripper_wait_s',
                      'arm_hold_s')


@declared_fields(TELEOP_PARAMS)
class ArmTeleopParams:
    """The arm teleop's configuration: one field per TELEOP_PARAMS entry, its default."""

    @classmethod
    def from_dict(cls, values):
        """Build from a dict (YAML / ROS params); unknown keys and bad values raise
        ValueError naming them."""
        unknown = set(values) - set(TELEOP_PARAMS)
        if unknown:
            raise ValueError('unknown arm teleop parameters: %s' % ', '.join(sorted(unknown)))
        p = cls(**values)
        p.validate()
        return p

    def summary(self):
        """The settings an operator checks first, in words (the node logs them at start)."""
        return ('mode %s, orientation %s, gripper %s, max joint speed %.3g rad/s, acceleration '
                '%.3g rad/s^2' % (self.mode, self.orientation, self.gripper_mode,
                                  self.max_joint_speed, self.max_joint_accel))

    def validate(self):
        """Check every field against TELEOP_PARAMS (ParamError, a ValueError, names the
        first bad one), then what involves two fields."""
        for name, value in check_params(TELEOP_PARAMS, vars(self)).items():
            setattr(self, name, value)
        lo, hi = np.asarray(self.workspace_min, float), np.asarray(self.workspace_max, float)
        if np.any(lo >= hi):
            raise ValueError('workspace_min %s must be below workspace_max %s on every axis '
                             '(not on %s)' % (list(self.workspace_min), list(self.workspace_max),
                                              'xyz'[int(np.argmax(lo >= hi))]))
        if not ori.axis_map_rank(self.axis_map) == 3:
            raise ValueError('axis_map must be invertible (every hand axis moves the robot)')
        bad = np.asarray(self.wrist_lower, float) >= np.asarray(self.wrist_upper, float)
        if np.any(bad):
            raise ValueError('wrist_lower %s must be below wrist_upper %s for every wrist joint '
                             '(not for wrist %d)' % (list(self.wrist_lower), list(self.wrist_upper),
                                                     int(np.argmax(bad)) + 1))
        if self.joint_loss_after < self.joint_timeout:
            raise ValueError('joint_loss_after (%g s) must be at least joint_timeout (%g s)'
                             % (self.joint_loss_after, self.joint_timeout))
        if self.disarm_after < self.input_timeout:
            raise ValueError('disarm_after (%g s) must be at least input_timeout (%g s)'
                             % (self.disarm_after, self.input_timeout))
