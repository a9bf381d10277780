"""UR10Cell: one or two UR10 arms with grippers, a table, cubes and trays in PyBullet.

Plain Python (no ROS). Time is simulated time: step() advances the physics by one
1/physics_hz step and every arm's trajectory follower with it. Arms are driven by
PyBullet position control (the desired position now + the desired motion over the step
as feed-forward velocity, motor and joint speed capped at the UR10 limits), fingers by
force-limited position control.

Grasping is by contact only: when both fingers of a closing gripper touch the same cube,
a helper fixed constraint ties the cube to the TCP; it is removed as soon as the gripper
is commanded open or either finger loses contact. Nothing else ever moves a cube.
"""
import io
import os

import numpy as np
import pybullet as p

from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.config import TABLE_THICKNESS, CellConfig, load_config
from leap_teleop.ur10.model import FINGER_TRAVEL, GRIPPER_JOINT, KNUCKLE_CLOSED_RAD, urdf_file
from leap_teleop.ur10.trajectory import TrajectoryFollower

GRIPPER_MAX_SPEED = 1.6        # knuckle rad/s: about 0.5 s from open to closed (2F-85-like)
GRIPPER_FORCE = 60.0           # N per finger
ARM_FORCE = np.array([330.0, 330.0, 150.0, 54.0, 54.0, 54.0])   # URDF efforts
ARM_POSITION_GAIN = 0.5        # share of the joint's position error removed per physics step
# A trajectory point whose acceleration would take its joint from rest past the speed limit
# sooner than this is refused as a mistake (units, a broken planner): 31-47 rad/s^2 for the
# arm, 10-15x the pi rad/s^2 MoveIt's UR10 configurations and this package plan with.
POINT_ACCEL_RAMP_S = 1.0 / 15.0
# The constraint solver's default residual (1e-7) stops early, leaving joint velocities
# ~5e-4 rad/s off their motor targets: 2 % spurious acceleration. At 1e-14 a free arm
# converges in at most ~40 iterations; an arm squeezing a cube never does (its contacts and
# the grasp constraint hold the cube twice), so the cap only bounds what those steps cost.
SOLVER_RESIDUAL = 1e-14
SOLVER_ITERATIONS = 40
# A cube moving slower than this ((m/s)^2 + (rad/s)^2, ~1 mm/s) for 2 s sleeps until
# something touches it: the physics then skips the cubes at rest (~6e-13 when settled).
CUBE_SLEEP_THRESHOLD = 1e-6
# A cube that has stayed that still for this long is put to sleep at once: the physics would
# only do so after 2 s (its fixed timeout), solving the resting contacts of every cube after a
# reset or a drop all that time. Settled cubes move < 1 um/s, so nothing visible changes.
CUBE_SETTLE_TIME = 0.25
CUBE_CHECK_EVERY = 12          # physics steps between those stillness checks (20 Hz)
# The shoulder link is tested at SWEEP_SAMPLES pan angles (2 deg apart: its points, all
# < 0.25 m from the axis, move < 9 mm between two) against each static body; a body always
# farther than SWEEP_CLEARANCE (the engine's 0.02 m contact threshold + those 9 mm) is
# left out of its collision checks. The table is 0.037 m below it.
SWEEP_SAMPLES = 180
SWEEP_CLEARANCE = 0.03
# How deep (m) an arm link may read inside the floor, the table or a tray at the start
# and count as resting on it, not inside.
ARM_CLEAR_TOLERANCE = 1e-4
GRASP_CHECK_EVERY = 4          # physics steps between contact checks (60 Hz at 240 Hz)
GRASP_LOSS_CHECKS = 3          # consecutive contact-less checks that release a grasp
PAD_NORMAL_MIN_COS = 0.7       # a pad contact's normal is within ~45 deg of the closing axis
# The per-step motor call's constant arguments, as lists (PyBullet reads them fastest).
_ARM_FORCES = ARM_FORCE.tolist()
_ARM_KP = [ARM_POSITION_GAIN] * 6
_ARM_KD = [1.0] * 6
_GRIPPER_FORCES = [GRIPPER_FORCE, GRIPPER_FORCE, 1.0]     # fingers, knuckle
_GRIPPER_KP = [0.2] * 3


class _Arm:
    """PyBullet handles and control state of one arm."""

    def __init__(self, cfg, body, client):
        self.cfg = cfg
        self.name = cfg.name
        self.body = body
        joints, links = {}, {}
        for i in range(p.getNumJoints(body, physicsClientId=client)):
            info = p.getJointInfo(body, i, physicsClientId=client)
            joints[info[1].decode()[len(cfg.prefix):]] = i
            links[info[12].decode()[len(cfg.prefix):]] = i
        self.arm_joints = [joints[n] for n in kin.JOINT_NAMES]
        self.knuckle = joints[GRIPPER_JOINT]
        self.fingers = [joints['left_finger_joint'], joints['right_finger_joint']]
        self.gripper_joints = self.fingers + [self.knuckle]
        self.finger_links = [links['left_finger_link'], links['right_finger_link']]
        self.tcp_link = links['tcp_link']
        self.arm_follower = TrajectoryFollower(
            cfg.home, kin.MAX_JOINT_SPEED, kin.JOINT_LOWER, kin.JOINT_UPPER,
            kin.MAX_JOINT_SPEED / POINT_ACCEL_RAMP_S, kin.JOINT_NAMES)
        self.gripper_follower = TrajectoryFollower(
            [0.0], GRIPPER_MAX_SPEED, [0.0], [KNUCKLE_CLOSED_RAD],
            GRIPPER_MAX_SPEED / POINT_ACCEL_RAMP_S, [GRIPPER_JOINT])
        self.grasp = None              # (constraint id, cube name, knuckle at grasp)
        self.lost_checks = 0
        self.touching = ([], [])       # cube names touched by left, right finger
        # step()'s last arm sample (time, the follower's segment list then, q) and gripper
        # target sent: each is reused while it is still what step() would compute.
        self.sampled = (None, None, None)
        self.gripper_sent = None
        # The desired position whose hold (zero velocity) the arm's motors were last sent:
        # PyBullet's motors keep their targets, so a hold is sent once.
        self.held = None


class UR10Cell:
    """The simulated work cell. config: a CellConfig, a path, or a file name in config/.
    visuals=False: the arms without their visual meshes, for a cell nothing renders (the
    same physics; loading them is most of a cell's start-up)."""

    def __init__(self, config='ur10_cell.yaml', gui=False, visuals=True):
        self.config = config if isinstance(config, CellConfig) else load_config(config)
        self.dt = 1.0 / self.config.physics_hz
        self.gui = bool(gui) and bool(os.environ.get('DISPLAY'))
        self.visuals = bool(visuals) or self.gui
        self.client = p.connect(p.GUI if self.gui else p.DIRECT)
        self.time = 0.0
        self.steps = 0
        c = self.client
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(self.dt, physicsClientId=c)
        p.setPhysicsEngineParameter(solverResidualThreshold=SOLVER_RESIDUAL,
                                    numSolverIterations=SOLVER_ITERATIONS, physicsClientId=c)
        if self.gui:
            p.configureDebugVisualizer(p.COV_ENABLE_GUI, 0, physicsClientId=c)
        self._build_scene()
        self.arms = {}
        for a in self.config.arms:
            body = p.loadURDF(urdf_file(a.prefix, a.base_xyz, a.base_rpy, visuals=self.visuals),
                              useFixedBase=True,
                              flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)
            self.arms[a.name] = arm = _Arm(a, body, c)
            self._cap_arm_speed(arm)
            self._skip_untouchable_pairs(arm)
            for j in arm.fingers + [arm.knuckle]:
                p.changeDynamics(body, j, jointLowerLimit=0.0,
                                 jointUpperLimit=FINGER_TRAVEL if j != arm.knuckle else KNUCKLE_CLOSED_RAD,
                                 physicsClientId=c)
        self._arm_bodies = {a.body for a in self.arms.values()}
        self.reset()
        try:
            self._check_arms_apart()
            self._check_arms_clear()
            self._check_cubes_clear()
        except ValueError:
            self.close()
            raise

    def _check_arms_apart(self):
        """ValueError when two arms touch at their home poses (bases placed too close):
        the solver would throw them apart at the first step."""
        arms = list(self.arms.values())
        for i, a in enumerate(arms):
            for b in arms[i + 1:]:
                if p.getClosestPoints(a.body, b.body, 0.0, physicsClientId=self.client):
                    raise ValueError('cell config %s: arms %s and %s touch at their home poses '
                                     '(bases at %s and %s): place them further apart'
                                     % (self.config.path, a.cfg.name, b.cfg.name,
                                        a.cfg.base_xyz.tolist(), b.cfg.base_xyz.tolist()))

    def _link_name(self, arm, link):
        """An arm's link by name, without the arm's prefix (upper_arm_link)."""
        name = (p.getJointInfo(arm.body, link, physicsClientId=self.client)[12] if link >= 0
                else p.getBodyInfo(arm.body, physicsClientId=self.client)[0]).decode()
        return name[len(arm.cfg.prefix):] if name.startswith(arm.cfg.prefix) else name

    def _check_arms_clear(self):
        """ValueError naming the first arm whose links start inside the floor, the table or
        a tray at its home pose (a base set too low, a home pose reaching down, a tray
        placed around the arm): the solver pushed the links out while the motors pushed
        back home, every joint thrashing at its speed limit for ever."""
        c, path = self.client, self.config.path
        static = [(self.floor, 'the floor', 'move the base or change home'),
                  (self.table, 'the table', 'move the base or change home')]
        static += [(body, "arm %s's tray" % name, 'move the tray or the base, or change home')
                   for name, body in self.trays.items()]
        for arm in self.arms.values():
            # base_link never collides with the static scene (_skip_untouchable_pairs): a base
            # set a little into the table stays still, and only the links above it count.
            base_link = p.getJointInfo(arm.body, arm.arm_joints[0], physicsClientId=c)[16]
            for body, what, fix in static:
                deep = [cp for cp in p.getClosestPoints(arm.body, body, 0.0, physicsClientId=c)
                        if cp[3] != base_link and cp[8] < -ARM_CLEAR_TOLERANCE]
                if deep:
                    cp = min(deep, key=lambda cp: cp[8])
                    raise ValueError(
                        "cell config %s: arm %s's %s starts inside %s at its home pose (base_xyz "
                        '%s, home %s; %.1f mm deep): %s'
                        % (path, arm.name, self._link_name(arm, cp[3]), what,
                           np.round(arm.cfg.base_xyz, 3).tolist(), np.round(arm.cfg.home, 4).tolist(),
                           -1000 * cp[8], fix))

    def _check_cubes_clear(self):
        """ValueError naming the first cube that starts inside an arm at its home pose, a
        tray (its floor or a wall) or another cube: the solver would throw it at the first
        steps (out of an upper arm at 2.35 m/s). The config refuses one inside the table or the floor."""
        c, path = self.client, self.config.path
        tolerance = 1e-3 * self.config.cube_size     # resting contact reads ~0, not inside
        others = [(a.body, "arm %s's " % name) for name, a in self.arms.items()]
        others += [(body, "arm %s's tray" % name) for name, body in self.trays.items()]
        others += [(body, 'cube %r' % name) for name, body in self.cubes.items()]
        for cube in self.config.cubes:
            body = self.cubes[cube.name]
            for other, what in others:
                if other == body:
                    continue
                deep = [cp for cp in p.getClosestPoints(body, other, 0.0, physicsClientId=c)
                        if cp[8] < -tolerance]
                if not deep:
                    continue
                if other in self._arm_bodies:
                    arm = next(a for a in self.arms.values() if a.body == other)
                    what += self._link_name(arm, deep[0][4]) + ' at its home pose'
                raise ValueError('cell config %s: cube %r at %s starts inside %s (%.1f mm deep): '
                                 'move it clear' % (path, cube.name, np.round(cube.xyz, 3).tolist(),
                                                    what, -1000 * min(cp[8] for cp in deep)))

    def _cap_arm_speed(self, arm):
        """Cap each arm motor at the joint's speed limit. PyBullet keeps a motor's
        maxVelocity until it is set again and only the one-joint call sets it, so it is set
        here once (holding home, as step() does after a reset) and the per-step array call
        leaves it in place. That caps the motor's target only: contact and coupling forces
        (the tool driven into the table) spun wrist_3 at 5.6 rad/s against its 3.14. The
        joint's maxJointVelocity clamps its speed in the solver, whatever drives it."""
        for j, q, fj, vmax in zip(arm.arm_joints, arm.cfg.home, _ARM_FORCES,
                                  kin.MAX_JOINT_SPEED):
            p.setJointMotorControl2(arm.body, j, p.POSITION_CONTROL, targetPosition=float(q),
                                    targetVelocity=0.0, force=fj,
                                    positionGain=ARM_POSITION_GAIN, velocityGain=1.0,
                                    maxVelocity=float(vmax), physicsClientId=self.client)
            p.changeDynamics(arm.body, j, maxJointVelocity=float(vmax), physicsClientId=self.client)

    def _skip_untouchable_pairs(self, arm):
        """No collision checks between the static scene (floor, table, trays) and the arm
        links it can never touch or move: base_link, fixed to the world (its contact with
        the table gave zero rows to the solver at every step), and the shoulder link when
        it stays clear of that body all around its pan joint (it moves with no other
        joint). The engine would otherwise test these pairs at every step."""
        c = self.client
        base_link = p.getJointInfo(arm.body, arm.arm_joints[0], physicsClientId=c)[16]
        pan = shoulder = arm.arm_joints[0]     # the pan joint moves the shoulder link
        static = [self.floor, self.table, *self.trays.values()]
        clear = set(static)
        for angle in np.linspace(-np.pi, np.pi, SWEEP_SAMPLES, endpoint=False):
            p.resetJointState(arm.body, pan, float(angle), physicsClientId=c)
            clear = {b for b in clear
                     if not p.getClosestPoints(arm.body, b, SWEEP_CLEARANCE, linkIndexA=shoulder,
                                               physicsClientId=c)}
        p.resetJointState(arm.body, pan, float(arm.cfg.home[0]), physicsClientId=c)
        for body in static:
            p.setCollisionFilterPair(arm.body, body, base_link, -1, 0, physicsClientId=c)
            if body in clear:
                p.setCollisionFilterPair(arm.body, body, shoulder, -1, 0, physicsClientId=c)

    # ---- scene -------------------------------------------------------------------------
    def _box(self, half, xyz, rgba, mass=0.0, friction=0.8):
        c = self.client
        col = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=c)
        vis = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=c)
        body = p.createMultiBody(mass, col, vis, basePosition=xyz, physicsClientId=c)
        p.changeDynamics(body, -1, lateralFriction=friction, physicsClientId=c)
        return body

    def _build_scene(self):
        cfg, c = self.config, self.client
        plane = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=c)
        self.floor = p.createMultiBody(0, plane, physicsClientId=c)
        (tx, ty), (sx, sy), h = cfg.table_center, cfg.table_size, cfg.table_height
        half = TABLE_THICKNESS / 2
        self.table = self._box([sx / 2, sy / 2, half], [tx, ty, h - half], [0.6, 0.45, 0.3, 1])
        self.trays = {}
        for a in cfg.arms:
            t = a.tray
            (ix, iy), (wt, wh) = t.inner, t.wall
            x, y, z = t.xyz
            parts = [([ix / 2 + wt, iy / 2 + wt, wt / 2], [0, 0, wt / 2]),
                     ([wt / 2, iy / 2 + wt, wh / 2], [ix / 2 + wt / 2, 0, wh / 2]),
                     ([wt / 2, iy / 2 + wt, wh / 2], [-ix / 2 - wt / 2, 0, wh / 2]),
                     ([ix / 2, wt / 2, wh / 2], [0, iy / 2 + wt / 2, wh / 2]),
                     ([ix / 2, wt / 2, wh / 2], [0, -iy / 2 - wt / 2, wh / 2])]
            col = p.createCollisionShapeArray([p.GEOM_BOX] * 5, halfExtents=[h for h, _ in parts],
                                              collisionFramePositions=[o for _, o in parts],
                                              physicsClientId=c)
            vis = p.createVisualShapeArray([p.GEOM_BOX] * 5, halfExtents=[h for h, _ in parts],
                                           visualFramePositions=[o for _, o in parts],
                                           rgbaColors=[[0.3, 0.3, 0.35, 1]] * 5, physicsClientId=c)
            self.trays[a.name] = p.createMultiBody(0, col, vis, basePosition=[x, y, z],
                                                   physicsClientId=c)
        half = cfg.cube_size / 2
        self.cubes = {}
        for cube in cfg.cubes:
            body = self._box([half] * 3, cube.xyz, list(cube.rgba), mass=cfg.cube_mass, friction=1.0)
            p.changeDynamics(body, -1, activationState=p.ACTIVATION_STATE_ENABLE_SLEEPING,
                             sleepThreshold=CUBE_SLEEP_THRESHOLD, physicsClientId=c)
            self.cubes[cube.name] = body
        self._cube_by_body = {b: n for n, b in self.cubes.items()}
        self._still_checks = {b: 0 for b in self.cubes.values()}   # consecutive still checks

    # ---- commands ----------------------------------------------------------------------
    def arm(self, name):
        try:
            return self.arms[name]
        except KeyError:
            raise KeyError('no arm %r (arms: %s)' % (name, list(self.arms))) from None

    @property
    def arm_names(self):
        return list(self.arms)

    def command_arm(self, name, points, start_time=None):
        """Follow joint points [(time_from_start, q[6] in JOINT_NAMES order, qd[6]|None
        [, qdd[6]])], or their plan_arm(), from start_time (sim time; None: now), replacing
        the current trajectory from then on. Raises TrajectoryError on a bad command (the
        arm keeps what it was doing). Returns the sim time the last point will be reached."""
        return self.arm(name).arm_follower.command(self.time, points, start_time)

    def command_gripper(self, name, points, start_time=None):
        """Like command_arm for the one gripper joint (knuckle: 0 open .. 0.8 closed)."""
        return self.arm(name).gripper_follower.command(self.time, points, start_time)

    def plan_arm(self, name, points):
        """command_arm's points checked and timed (TrajectoryError when bad) without the
        arm's state: safe beside step(), so a long command need not hold the physics."""
        return self.arm(name).arm_follower.plan(points)

    def plan_gripper(self, name, points):
        return self.arm(name).gripper_follower.plan(points)

    def move_to(self, name, q, duration=0.0):
        """Convenience: one-point trajectory to q (duration stretched to the speed limits)."""
        return self.command_arm(name, [(duration, q, None)])

    def set_gripper(self, name, knuckle, duration=0.0):
        return self.command_gripper(name, [(duration, [knuckle], None)])

    # ---- simulation --------------------------------------------------------------------
    def step(self, n=1):
        c, dt = self.client, self.dt
        for _ in range(n):
            t = self.time + dt
            for arm in self.arms.values():
                self._drive_arm(arm, t)
                gripper = arm.gripper_follower
                g = float((gripper.sample(t)[0] if gripper.segments else gripper.q)[0])
                if g != arm.gripper_sent:     # PyBullet's motors keep their targets
                    f = g * FINGER_TRAVEL / KNUCKLE_CLOSED_RAD
                    p.setJointMotorControlArray(arm.body, arm.gripper_joints,
                                                p.POSITION_CONTROL, targetPositions=[f, f, g],
                                                forces=_GRIPPER_FORCES, positionGains=_GRIPPER_KP,
                                                physicsClientId=c)
                    arm.gripper_sent = g
            p.stepSimulation(physicsClientId=c)
            self.time = t
            self.steps += 1
            if self.steps % GRASP_CHECK_EVERY == 0:
                for arm in self.arms.values():
                    self._update_grasp(arm)
            if self.steps % CUBE_CHECK_EVERY == 0:
                self._sleep_settled_cubes()

    def _drive_arm(self, arm, t):
        """The arm's motor targets for the step from self.time to t.

        PyBullet's motor sets the step's velocity to targetVelocity + positionGain *
        (targetPosition - q) / dt. The feed-forward is the desired motion over this step and
        the correction acts on the error now, so a joint on its trajectory lands on the next
        desired position and its acceleration is the trajectory's (a target for the end of
        the step with the velocity there counts that step twice: ~30 % acceleration
        overshoot). One call for the six joints; their speed caps were set once
        (_cap_arm_speed)."""
        follower = arm.arm_follower
        if not follower.segments:
            # Holding: the target is the held position at zero velocity, what the motors
            # keep once sent (the follower replaces q, never changes it in place).
            q = follower.q
            arm.sampled = (t, follower.segments, q)
            if arm.held is not q:
                p.setJointMotorControlArray(arm.body, arm.arm_joints, p.POSITION_CONTROL,
                                            targetPositions=q.tolist(),
                                            targetVelocities=[0.0] * 6,
                                            forces=_ARM_FORCES, positionGains=_ARM_KP,
                                            velocityGains=_ARM_KD, physicsClientId=self.client)
                arm.held = q
            return
        last_t, last_segments, last_q = arm.sampled
        if last_t == self.time and last_segments is follower.segments:
            q_now = last_q        # the trajectory is the one sampled a step ago
        else:
            q_now = follower.sample(self.time)[0].copy()
        q_next = follower.sample(t)[0].copy()
        arm.sampled = (t, follower.segments, q_next)
        arm.held = None
        p.setJointMotorControlArray(arm.body, arm.arm_joints, p.POSITION_CONTROL,
                                    targetPositions=q_now.tolist(),
                                    targetVelocities=((q_next - q_now) / self.dt).tolist(),
                                    forces=_ARM_FORCES, positionGains=_ARM_KP,
                                    velocityGains=_ARM_KD, physicsClientId=self.client)

    def _sleep_settled_cubes(self):
        """Put to sleep each cube that has been still for CUBE_SETTLE_TIME and touches no
        arm (a sleeping cube reads exactly still and wakes when something touches it)."""
        c = self.client
        needed = int(round(CUBE_SETTLE_TIME / (self.dt * CUBE_CHECK_EVERY)))
        for body, checks in self._still_checks.items():
            (vx, vy, vz), (wx, wy, wz) = p.getBaseVelocity(body, physicsClientId=c)
            motion = vx * vx + vy * vy + vz * vz + wx * wx + wy * wy + wz * wz
            # exactly 0: asleep already
            checks = checks + 1 if 0.0 < motion < CUBE_SLEEP_THRESHOLD else 0
            if checks >= needed:
                checks = 0
                # A cube an arm touches or holds is in play: the physics decides.
                if not any(cp[2] in self._arm_bodies
                           for cp in p.getContactPoints(bodyA=body, physicsClientId=c)):
                    p.changeDynamics(body, -1, activationState=p.ACTIVATION_STATE_SLEEP,
                                     physicsClientId=c)
            self._still_checks[body] = checks

    def run(self, seconds):
        """Step for the given simulated time."""
        self.step(max(1, int(round(seconds / self.dt))))

    def _touching(self, contacts, axis):
        """Cubes a finger link presses with its pad (of its contacts with cubes): contact
        normals along the closing axis (fingertips resting on a cube's top do not count)."""
        out = []
        for cp in contacts:
            name = self._cube_by_body[cp[2]]
            if name not in out and abs(float(np.dot(cp[7], axis))) > PAD_NORMAL_MIN_COS:
                out.append(name)
        return out

    def _update_grasp(self, arm):
        c = self.client
        # One query for the arm (each query walks every contact in the world), split by finger.
        left_link, right_link = arm.finger_links
        contacts = ([], [])
        for cp in p.getContactPoints(bodyA=arm.body, physicsClientId=c):
            if cp[2] in self._cube_by_body:
                if cp[3] == left_link:
                    contacts[0].append(cp)
                elif cp[3] == right_link:
                    contacts[1].append(cp)
        axis = None
        if contacts[0] or contacts[1]:      # the TCP's pose only matters for a cube contact
            orn = p.getLinkState(arm.body, arm.tcp_link, computeForwardKinematics=True,
                                 physicsClientId=c)[5]
            axis = np.array(p.getMatrixFromQuaternion(orn))[[0, 3, 6]]   # TCP x: closing axis
        left, right = (self._touching(cps, axis) for cps in contacts)
        arm.touching = (left, right)
        g_des = float(arm.gripper_follower.q[0])
        if arm.grasp is not None:
            cid, cube, g_grasp = arm.grasp
            opening = g_des < g_grasp - 0.02
            held = cube in left and cube in right
            arm.lost_checks = 0 if held else arm.lost_checks + 1
            if opening or arm.lost_checks >= GRASP_LOSS_CHECKS:
                p.removeConstraint(cid, physicsClientId=c)
                arm.grasp = None
                arm.lost_checks = 0
            return
        both = [n for n in left if n in right]
        if not both:
            return
        # Only a closing gripper squeezing the cube grasps it.
        g_now = self._knuckle(arm)[0]
        if g_des > g_now + 0.01 or g_des >= KNUCKLE_CLOSED_RAD - 1e-6:
            cube = both[0]
            body = self.cubes[cube]
            ls = p.getLinkState(arm.body, arm.tcp_link, computeForwardKinematics=True,
                                physicsClientId=c)
            cpos, corn = p.getBasePositionAndOrientation(body, physicsClientId=c)
            inv_pos, inv_orn = p.invertTransform(ls[0], ls[1])
            rel_pos, rel_orn = p.multiplyTransforms(inv_pos, inv_orn, cpos, corn)
            cid = p.createConstraint(arm.body, arm.tcp_link, body, -1, p.JOINT_FIXED, [0, 0, 0],
                                     rel_pos, [0, 0, 0], parentFrameOrientation=rel_orn,
                                     physicsClientId=c)
            p.changeConstraint(cid, maxForce=50.0, physicsClientId=c)
            arm.grasp = (cid, cube, g_now)
            arm.lost_checks = 0

    # ---- state -------------------------------------------------------------------------
    def _knuckle(self, arm):
        st = p.getJointStates(arm.body, arm.fingers, physicsClientId=self.client)
        k = KNUCKLE_CLOSED_RAD / FINGER_TRAVEL
        return (0.5 * (st[0][0] + st[1][0]) * k, 0.5 * (st[0][1] + st[1][1]) * k)

    def joint_state(self, name):
        """(q[6], qd[6], gripper_knuckle, gripper_knuckle_velocity) measured."""
        arm = self.arm(name)
        st = p.getJointStates(arm.body, arm.arm_joints, physicsClientId=self.client)
        q = np.array([s[0] for s in st])
        qd = np.array([s[1] for s in st])
        g, gd = self._knuckle(arm)
        return q, qd, g, gd

    def desired_state(self, name):
        """The follower's current desired (q, qd) for the arm."""
        f = self.arm(name).arm_follower
        return f.q.copy(), f.qd.copy()

    def trajectory_active(self, name):
        return self.arm(name).arm_follower.active

    def tcp_pose(self, name, world=True):
        """Measured TCP pose (4x4), in the world or in the arm's base_link frame."""
        arm = self.arm(name)
        ls = p.getLinkState(arm.body, arm.tcp_link, computeForwardKinematics=True,
                            physicsClientId=self.client)
        T = np.eye(4)
        T[:3, :3] = np.array(p.getMatrixFromQuaternion(ls[5])).reshape(3, 3)
        T[:3, 3] = ls[4]
        return T if world else arm.cfg.to_base(T)

    def object_poses(self):
        """{cube name: (xyz, quaternion xyzw)} in the world frame."""
        out = {}
        for name, body in self.cubes.items():
            pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
            out[name] = (np.array(pos), np.array(orn))
        return out

    def grasped(self, name):
        """Name of the cube held by the arm's gripper, or None."""
        g = self.arm(name).grasp
        return None if g is None else g[1]

    def fingers_touching(self, name):
        """(cubes touched by the left finger, by the right finger) at the last check."""
        return self.arm(name).touching

    def cube_yaw_error(self, cube):
        """How far (rad, 0..pi/4) the cube's faces are from the world axes, about the
        vertical: 0 for a cube lying square to a tray."""
        q = self.object_poses()[cube][1]
        R = np.array(p.getMatrixFromQuaternion(q)).reshape(3, 3)
        # The cube axis closest to horizontal-x decides; square = a multiple of 90 deg.
        up = int(np.argmax(np.abs(R[2, :])))
        side = R[:, (up + 1) % 3]
        yaw = float(np.arctan2(side[1], side[0]))
        return abs((yaw + np.pi / 4) % (np.pi / 2) - np.pi / 4)

    def in_tray(self, cube, arm_name):
        """True when the cube rests inside the arm's tray."""
        t = self.arm(arm_name).cfg.tray
        pos = self.object_poses()[cube][0]
        return (abs(pos[0] - t.xyz[0]) <= t.inner[0] / 2 and abs(pos[1] - t.xyz[1]) <= t.inner[1] / 2
                and t.floor_z - 0.005 < pos[2] < t.floor_z + self.config.cube_size)

    # ---- reset, camera, teardown ---------------------------------------------------------
    def reset(self):
        """Arms home, gripper open, cubes back at their start, no grasp; time keeps going."""
        c = self.client
        for arm in self.arms.values():
            if arm.grasp is not None:
                p.removeConstraint(arm.grasp[0], physicsClientId=c)
                arm.grasp = None
            for j, q in zip(arm.arm_joints, arm.cfg.home):
                p.resetJointState(arm.body, j, float(q), 0.0, physicsClientId=c)
            for j in arm.fingers + [arm.knuckle]:
                p.resetJointState(arm.body, j, 0.0, 0.0, physicsClientId=c)
            arm.arm_follower.hold(arm.cfg.home)
            arm.gripper_follower.hold([0.0])
            arm.sampled = (None, None, None)
            arm.gripper_sent = None
            arm.held = None
            arm.touching = ([], [])
        for cube in self.config.cubes:
            p.resetBasePositionAndOrientation(self.cubes[cube.name], cube.xyz, cube.quaternion,
                                              physicsClientId=c)
            p.resetBaseVelocity(self.cubes[cube.name], [0, 0, 0], [0, 0, 0], physicsClientId=c)
            # A sleeping cube moved back stays asleep: wake it to settle as a new one does.
            p.changeDynamics(self.cubes[cube.name], -1,
                             activationState=p.ACTIVATION_STATE_WAKE_UP, physicsClientId=c)
            self._still_checks[self.cubes[cube.name]] = 0

    def pose_state(self):
        """What a picture needs, copied: every body's base pose and joint positions."""
        c, out = self.client, []
        for b in range(p.getNumBodies(physicsClientId=c)):
            n = p.getNumJoints(b, physicsClientId=c)
            q = [s[0] for s in p.getJointStates(b, range(n), physicsClientId=c)] if n else []
            out.append((b, p.getBasePositionAndOrientation(b, physicsClientId=c), q))
        return out

    def set_pose_state(self, state):
        """Pose every body as in `state` (from pose_state of a cell of the same config);
        for a render-only cell, which never steps."""
        c = self.client
        for body, (xyz, quat), q in state:
            p.resetBasePositionAndOrientation(body, xyz, quat, physicsClientId=c)
            for j, v in enumerate(q):
                p.resetJointState(body, j, v, physicsClientId=c)

    def snapshot(self, path=None, width=640, height=480, eye=None, target=None, fov=None):
        """Render the cell (TinyRenderer, works headless); PNG bytes, also written to path."""
        if not self.visuals:
            raise RuntimeError('this cell was built with visuals=False: nothing to render')
        from PIL import Image
        cam = self.config.camera
        eye = eye if eye is not None else cam.get('eye', [1.9, -1.3, 1.8])
        target = target if target is not None else cam.get('target', [0.4, 0.0, 0.8])
        fov = fov if fov is not None else cam.get('fov', 50)
        view = p.computeViewMatrix(eye, target, [0, 0, 1], physicsClientId=self.client)
        proj = p.computeProjectionMatrixFOV(fov, width / height, 0.05, 10.0,
                                            physicsClientId=self.client)
        _, _, rgba, _, _ = p.getCameraImage(width, height, view, proj,
                                            renderer=p.ER_TINY_RENDERER,
                                            physicsClientId=self.client)
        img = np.asarray(rgba, dtype=np.uint8).reshape(height, width, 4)[:, :, :3]
        buf = io.BytesIO()
        Image.fromarray(img).save(buf, format='PNG')
        data = buf.getvalue()
        if path:
            with open(path, 'wb') as f:
                f.write(data)
        return data

    def close(self):
        if self.client is not None and p.isConnected(self.client):
            p.disconnect(self.client)
        self.client = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
