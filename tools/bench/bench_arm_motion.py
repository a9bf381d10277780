"""Arm motion quality in the closed loop (ArmTeleop -> UR10Cell, simulated time, the sim
profile: max_joint_speed 1 rad/s, max_joint_accel = the UR10's pi rad/s^2).

arm.tracking_lag_ms          the pick & place session's hand path (ur10_pick_place_single)
                             with tremor (9 Hz, 0.5 mm, per axis) and 0.3 mm sensor noise;
                             lag of the measured TCP path behind the mapped clean hand path
                             (the arm's own mapping of the noise-free palm): the shift that
                             maximises their cross-correlation (velocities, all axes).
arm.tracking_rms_m           rms |TCP - mapped clean hand path| over the same run, unshifted.
arm.jitter_at_rest_mm        the hand holds still with 5 mm of palm noise (Gaussian, 5 mm
                             peak-to-peak per axis: sigma 5/6 mm); rms TCP deviation from its
                             mean over the last 3 of 5 s.
arm.jitter_at_rest_sigma5_mm the same with sigma 5 mm per axis (for scale; no goal).
arm.orientation_rms_deg      full mode; the hand turns (rotate, turn, swing as the messages
                             carry them: smooth, beyond the dead bands, with 0.3 deg tremor);
                             rms angle between the measured tool rotation and the mapped clean
                             hand rotation while it moves.
arm.onset_latency_p99_ms     a 20 mm palm step at a random phase of the 120 Hz frame / control
                             / 240 Hz physics clocks -> first measured joint motion
                             (> 1e-4 rad), over 100 steps.
arm.max_joint_accel          largest commanded joint acceleration in all these runs (the
                             controller's desired state), rad/s^2; arm.max_joint_accel_measured
                             from the velocities PyBullet reports for the simulated joints,
                             differenced over 3 physics steps (12.5 ms; differentiating the
                             positions twice would read numerics as motion).
"""
import math

import numpy as np

from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources.scripted import ScriptedSource
from leap_teleop.ros.node import package_path
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10 import orientation as ori
from leap_teleop.ur10.cell import UR10Cell
from leap_teleop.ur10.teleop import TRACKING, ArmInput, ArmTeleop
from tools.closed_loop import hand_input, sim_params

ARM = 'ur10_1'
FRAME_HZ = 120.0



class Loop:
    """One arm, hand inputs fed by the caller, control at the frame rate, physics at 240 Hz;
    records the measured TCP and joints and the controller's accelerations."""

    def __init__(self, params, config='ur10_cell.yaml'):
        self.cell = UR10Cell(config)
        self.teleop = ArmTeleop(params)
        self.substeps = int(round(self.cell.config.physics_hz / FRAME_HZ))
        self.t = 0.0
        self.max_accel_cmd = 0.0
        self.max_accel_measured = 0.0
        self._qd_hist = []

    def period(self, hand, record=None):
        """Feed one hand input (or None), run one control period and its physics."""
        if hand is not None:
            hand.stamp = self.t
            self.teleop.on_hand(hand, self.t)
        q, _, _, _ = self.cell.joint_state(ARM)
        self.teleop.on_joints(q)
        cmd = self.teleop.step(self.t)
        if cmd.points:
            self.cell.command_arm(ARM, cmd.points, cmd.stamp)
        follower = self.cell.arm(ARM).arm_follower
        for _ in range(self.substeps):
            self.cell.step()
            self.max_accel_cmd = max(self.max_accel_cmd, float(np.max(np.abs(follower.qdd))))
            qd = self.cell.joint_state(ARM)[1]
            self._qd_hist.append(qd)
            if len(self._qd_hist) > 4:
                self._qd_hist.pop(0)
                a = (self._qd_hist[-1] - self._qd_hist[0]) / (3 * self.cell.dt)
                self.max_accel_measured = max(self.max_accel_measured, float(np.max(np.abs(a))))
            if record is not None:
                record(self.cell.time)
        self.t += 1.0 / FRAME_HZ
        return cmd

    def tcp(self):
        return self.cell.tcp_pose(ARM, world=False)

    def close(self):
        self.cell.close()


def _arm(loop, palm=(60.0, 300.0, 0.0)):
    # Arming needs the thumbs-up held arm_hold_s (by capture time).
    for _ in range(int(math.ceil((loop.teleop.p.arm_hold_s + 0.1) * FRAME_HZ))):
        loop.period(ArmInput(present=True, palm_mm=palm, thumb_up=True))
    for _ in range(30):
        loop.period(ArmInput(present=True, palm_mm=palm, rock=True))
    assert loop.teleop.status.state == TRACKING


def _lag_s(reference, measured, dt, max_lag=0.3):
    """Shift (s) of measured behind reference maximising the cross-correlation of their
    velocities summed over the axes, refined by a parabola through the peak."""
    a, b = np.diff(reference, axis=0), np.diff(measured, axis=0)
    a, b = a - a.mean(0), b - b.mean(0)
    n = int(max_lag / dt)
    corr = np.array([np.sum(a[:len(a) - k] * b[k:]) for k in range(n)])
    k = int(np.argmax(corr))
    if 0 < k < n - 1:
        y0, y1, y2 = corr[k - 1], corr[k], corr[k + 1]
        k += 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    return k * dt


def tracking(results):
    """The session's hand path, with tremor, through the recognizer and the arm."""
    script = package_path('config', 'gestures', 'ur10_pick_place_single.yaml')
    source = ScriptedSource(script, realtime=False, noise_mm=0.0, clock=lambda: 0.0)
    interface = LeapInterface()
    loop = Loop(sim_params())
    rng = np.random.default_rng(3)
    phase = rng.uniform(0, 2 * math.pi, 3)
    mapped, measured = [], []
    try:
        A = np.asarray(loop.teleop.p.axis_map, float)
        lo, hi = np.asarray(loop.teleop.p.workspace_min), np.asarray(loop.teleop.p.workspace_max)
        for frame in source.frames():
            states = interface.on_frame(frame)
            hand = hand_input(states['right'])
            clean = np.asarray(hand.palm_mm, float)
            tremor = 0.5 * np.sin(2 * math.pi * 9.0 * loop.t + phase) + rng.normal(0, 0.3, 3)
            hand.palm_mm = tuple(clean + tremor) if hand.present else hand.palm_mm
            loop.period(hand)
            tel = loop.teleop
            if tel.status.state == TRACKING and tel._palm_ref is not None and not hand.rock:
                target = tel._tcp_ref + A @ (clean - tel._palm_ref) * 0.001 * tel.p.scale
                mapped.append(np.clip(target, lo, hi))
                measured.append(loop.tcp()[:3, 3])
        mapped, measured = np.asarray(mapped), np.asarray(measured)
        results['arm.tracking_rms_m'] = float(np.sqrt(np.mean(np.sum((measured - mapped) ** 2, 1))))
        results['arm.tracking_lag_ms'] = _lag_s(mapped, measured, 1.0 / FRAME_HZ) * 1000
        results['arm.tracking_samples'] = float(len(mapped))
    finally:
        loop.close()
    return loop


def jitter(results, sigma, key):
    loop = Loop(sim_params())
    rng = np.random.default_rng(5)
    palm = np.array([60.0, 300.0, 0.0])
    try:
        _arm(loop, palm)
        held = palm + np.array([30.0, -20.0, -30.0])     # move, then hold still there
        for _ in range(int(1.0 * FRAME_HZ)):
            loop.period(ArmInput(present=True, palm_mm=tuple(held)))
        tcp = []
        for k in range(int(5.0 * FRAME_HZ)):
            noisy = held + rng.normal(0.0, sigma, 3)
            loop.period(ArmInput(present=True, palm_mm=tuple(noisy)))
            if k >= 2 * FRAME_HZ:
                tcp.append(loop.tcp()[:3, 3])
        tcp = np.asarray(tcp)
        results[key] = float(np.sqrt(np.mean(np.sum((tcp - tcp.mean(0)) ** 2, 1)))) * 1000
    finally:
        loop.close()
    return loop


def orientation(results):
    loop = Loop(sim_params(orientation='full'))
    rng = np.random.default_rng(9)
    palm = (60.0, 300.0, 0.0)
    errors = []
    try:
        _arm(loop, palm)
        tel = loop.teleop
        for k in range(int(8.0 * FRAME_HZ)):
            t = k / FRAME_HZ
            ramp = min(1.0, t / 1.0)
            # What the messages carry (after the sender's dead bands), rad.
            clean = ramp * np.array([0.35 * math.sin(2 * math.pi * 0.2 * t),
                                     0.45 * math.sin(2 * math.pi * 0.15 * t + 1.0),
                                     0.30 * math.sin(2 * math.pi * 0.25 * t + 2.0)])
            noisy = clean + np.radians(0.3) * rng.normal(size=3)
            loop.period(ArmInput(present=True, palm_mm=palm, rotate=noisy[0], turn=noisy[1],
                                  swing=noisy[2]))
            want = tel._tool_rotation(kin.rotation_vector(ori.hand_rotation(*clean)))
            if t > 1.0:
                errors.append(kin.rotation_error(want, loop.tcp()[:3, :3]))
        results['arm.orientation_rms_deg'] = math.degrees(float(np.sqrt(np.mean(
            np.square(errors)))))
    finally:
        loop.close()
    return loop


def onset(results, n=100):
    loop = Loop(sim_params())
    rng = np.random.default_rng(11)
    palm = np.array([60.0, 300.0, 0.0])
    latencies = []
    try:
        _arm(loop, tuple(palm))
        for i in range(n):
            for _ in range(int(0.6 * FRAME_HZ)):          # at rest
                loop.period(ArmInput(present=True, palm_mm=tuple(palm)))
            q0 = loop.cell.joint_state(ARM)[0]
            # The step happens at a random instant inside the next frame period: the frame
            # carrying it is captured at the end of that period.
            step_at = loop.t - rng.uniform(0.0, 1.0 / FRAME_HZ)
            moved = []
            sign = 1.0 if i % 2 == 0 else -1.0
            palm = palm + sign * np.array([0.0, 0.0, 20.0])

            def record(t):
                if not moved and np.max(np.abs(loop.cell.joint_state(ARM)[0] - q0)) > 1e-4:
                    moved.append(t)
            for _ in range(int(0.2 * FRAME_HZ)):
                loop.period(ArmInput(present=True, palm_mm=tuple(palm)), record)
                if moved:
                    break
            if moved:
                latencies.append(moved[0] - step_at)
        lat = np.asarray(latencies) * 1000
        results['arm.onset_latency_p50_ms'] = float(np.percentile(lat, 50))
        results['arm.onset_latency_p99_ms'] = float(np.percentile(lat, 99)) if len(lat) == n \
            else math.inf
    finally:
        loop.close()
    return loop


def run():
    results = {}
    loops = [tracking(results), jitter(results, 5.0 / 6.0, 'arm.jitter_at_rest_mm'),
             jitter(results, 5.0, 'arm.jitter_at_rest_sigma5_mm'), orientation(results),
             onset(results)]
    results['arm.max_joint_accel'] = max(loop.max_accel_cmd for loop in loops)
    results['arm.max_joint_accel_measured'] = max(loop.max_accel_measured for loop in loops)
    results['arm.ur10_joint_accel_limit'] = float(np.min(kin.MAX_JOINT_ACCEL))
    for key in sorted(results):
        print('  %-32s %.5g' % (key, results[key]))
    return results


if __name__ == '__main__':
    run()
