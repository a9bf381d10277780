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
arm.step_overshoot_mm        the most the TCP passes beyond where it comes to rest after
                             one of those steps (0.6 s each).
arm.tracking_lag_ms_real     real palm paths (tools/hand_paths.py: the Guinevere open-hand
arm.tracking_rms_m_real      moves and palm swipes of both people, 5 LeapJS takes with an
arm.target_lag_ms_real       open hand moving), one take after another; real data has its
                             own noise, so the reference is the arm's mapping of the
                             unfiltered palm; lag from the cross-correlation of 42 ms-averaged
                             velocities over all takes; target: the filtered TCP target
                             (the palm filter alone) behind the same reference.
arm.jitter_at_rest_mm_real   a real hand held still (LeapJS `pinch`: the palm within 3-6 mm
                             for 2.7 s): rms TCP deviation from its own 0.25 s moving
                             average after 0.5 s; `_unfiltered_` the same of the mapped raw
                             palm (what the arm would do unfiltered).
arm.max_joint_accel          largest commanded joint acceleration in all these runs (the
                             controller's desired state), rad/s^2; arm.max_joint_accel_measured
                             (the synthetic runs) from the velocities PyBullet reports for the
                             simulated joints,
                             differenced over 3 physics steps (12.5 ms; differentiating the
                             positions twice would read numerics as motion).
arm.max_joint_accel_measured_real  the same over the real-motion runs, which hold the
                             joints at the bound for long stretches (the solver's residual
                             shows more there).
"""
import math

import numpy as np

from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources.scripted import ScriptedSource
from leap_teleop.package_files import package_path
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10 import orientation as ori
from leap_teleop.ur10.cell import UR10Cell
from leap_teleop.ur10.teleop import TRACKING, ArmInput, ArmTeleop
from tools import hand_paths
from tools.closed_loop import hand_input, sim_params

ARM = 'ur10_1'
FRAME_HZ = 120.0
# Real frames come at 110-115 Hz, held between them: their velocities are averaged over
# 5 control periods (42 ms) before the cross-correlation, so the hold pattern (a 7 Hz
# beat with the 120 Hz clock) does not pass for motion.
SMOOTH = 5
SETTLE_S = 0.5             # real takes: the hand held at its last position afterwards



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

    def restart(self, params):
        """Arms home and a fresh teleop; the clocks keep going (a take after another)."""
        self.cell.reset()
        self.teleop = ArmTeleop(params)
        self._qd_hist = []         # the reset teleports the joints: no acceleration

    def close(self):
        self.cell.close()


def _arm(loop, palm=(60.0, 300.0, 0.0)):
    # Arming needs the thumbs-up held arm_hold_s (by capture time).
    for _ in range(int(math.ceil((loop.teleop.p.arm_hold_s + 0.1) * FRAME_HZ))):
        loop.period(ArmInput(present=True, palm_mm=palm, thumb_up=True))
    for _ in range(30):
        loop.period(ArmInput(present=True, palm_mm=palm, rock=True))
    assert loop.teleop.status.state == TRACKING


def _xcorr(reference, measured, n, smooth=1):
    """Cross-correlation of the two paths' velocities (summed over the axes) for shifts of
    measured behind reference of 0 .. n-1 samples; smooth > 1 averages both velocities
    over that many samples first (the same for both: no shift of its own)."""
    a, b = np.diff(reference, axis=0), np.diff(measured, axis=0)
    if smooth > 1:
        kernel = np.ones(smooth) / smooth
        a, b = (np.stack([np.convolve(x[:, i], kernel, mode='valid') for i in range(3)], 1)
                for x in (a, b))
    a, b = a - a.mean(0), b - b.mean(0)
    return np.array([np.sum(a[:len(a) - k] * b[k:]) for k in range(n)])


def _peak_s(corr, dt):
    """The shift (s) at the correlation's peak, refined by a parabola through it."""
    k, n = int(np.argmax(corr)), len(corr)
    if 0 < k < n - 1:
        y0, y1, y2 = corr[k - 1], corr[k], corr[k + 1]
        k += 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2)
    return k * dt


def _lag_s(reference, measured, dt, max_lag=0.3):
    """Shift (s) of measured behind reference maximising the cross-correlation of their
    velocities summed over the axes, refined by a parabola through the peak."""
    return _peak_s(_xcorr(reference, measured, int(max_lag / dt)), dt)


def tracking(results, params=None, seed=3):
    """The session's hand path, with tremor, through the recognizer and the arm."""
    script = package_path('config', 'gestures', 'ur10_pick_place_single.yaml')
    source = ScriptedSource(script, realtime=False, noise_mm=0.0, clock=lambda: 0.0)
    interface = LeapInterface()
    loop = Loop(params or sim_params())
    rng = np.random.default_rng(seed)
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


def jitter(results, sigma, key, params=None, seed=5):
    loop = Loop(params or sim_params())
    rng = np.random.default_rng(seed)
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


def _mapped(tel, palm):
    """The arm's mapping of a palm position (mm) to a TCP target, clipped to the box."""
    p = tel.p
    target = tel._tcp_ref + np.asarray(p.axis_map, float) @ (palm - tel._palm_ref) * 0.001 * p.scale
    return np.clip(target, p.workspace_min, p.workspace_max)


def _lead_in(loop, palm, move_s=0.5, hold_s=0.25):
    """Arm with the origin at the centre of the path's box (so a long swipe stays inside
    the arm's reach), then move the hand smoothly to the path's start and hold it there."""
    centre = 0.5 * (palm.min(0) + palm.max(0))
    _arm(loop, tuple(centre))
    steps = int(move_s * FRAME_HZ)
    for i in range(1, steps + 1):
        s = 0.5 - 0.5 * math.cos(math.pi * i / steps)
        loop.period(ArmInput(present=True, palm_mm=tuple(centre + s * (palm[0] - centre))))
    for _ in range(int(hold_s * FRAME_HZ)):
        loop.period(ArmInput(present=True, palm_mm=tuple(palm[0])))


def tracking_real(results, params=None, paths=None):
    """Real palm paths (tools.hand_paths.moving_paths), one take after another: arm home,
    thumbs-up and rock at the take's first palm position, the frames fed at their recorded
    times (a control period without a new frame gets none), then SETTLE_S of the hand held
    at its last position. Real data carries its own noise, so the clean reference is the
    arm's mapping of the unfiltered palm (the latest frame). The lag is the peak of the
    velocity cross-correlation summed over the takes; the rms over all their samples."""
    params = params or sim_params()
    paths = paths or hand_paths.moving_paths()
    loop = Loop(params)
    n = int(0.3 * FRAME_HZ)
    corr_tcp, corr_target = np.zeros(n), np.zeros(n)
    sq, count = 0.0, 0
    try:
        for name, t, palm in paths:
            loop.restart(params)
            _lead_in(loop, palm)
            tel = loop.teleop
            reference, measured, target = [], [], []
            t0, k = loop.t, 0
            while loop.t - t0 <= t[-1] + SETTLE_S:
                arrived = k
                while arrived < len(t) and t[arrived] <= loop.t - t0 + 1e-9:
                    arrived += 1
                fresh = arrived > k or arrived == len(t)      # after the take: held still
                k = arrived
                loop.period(ArmInput(present=True, palm_mm=tuple(palm[k - 1])) if fresh
                            else None)
                if tel.status.state != TRACKING:
                    raise RuntimeError('%s: the arm stopped tracking (%s)'
                                       % (name, tel.status.reason))
                reference.append(_mapped(tel, palm[k - 1]))
                measured.append(loop.tcp()[:3, 3])
                target.append(tel.status.target)
            reference, measured = np.asarray(reference), np.asarray(measured)
            corr_tcp += _xcorr(reference, measured, n, SMOOTH)
            corr_target += _xcorr(reference, np.asarray(target), n, SMOOTH)
            sq += float(np.sum((measured - reference) ** 2))
            count += len(reference)
        results['arm.tracking_lag_ms_real'] = _peak_s(corr_tcp, 1.0 / FRAME_HZ) * 1000
        results['arm.target_lag_ms_real'] = _peak_s(corr_target, 1.0 / FRAME_HZ) * 1000
        results['arm.tracking_rms_m_real'] = math.sqrt(sq / count)
        results['arm.tracking_takes_real'] = float(len(paths))
    finally:
        loop.close()
    return loop


def _jitter_mm(path, window):
    """rms deviation (mm) of a path (m) from its centred moving average over `window`
    samples: the motion faster than the hand's own drift."""
    kernel = np.ones(window) / window
    smooth = np.stack([np.convolve(path[:, i], kernel, mode='valid') for i in range(3)], 1)
    h = window // 2
    rest = path[h:h + len(smooth)] - smooth
    return float(np.sqrt(np.mean(np.sum(rest ** 2, 1)))) * 1000


def jitter_real(results, params=None, path=None):
    """A real hand held still (the stillest shared take, tools.hand_paths.LEAPJS_STILL):
    after the first 0.5 s, the rms TCP deviation from its own 0.25 s moving average (the
    real palm drifts a few mm, which the arm should follow); the same of the arm's mapping
    of the unfiltered palm, for scale (what an unfiltered arm would show)."""
    params = params or sim_params()
    name, t, palm = path or hand_paths.leapjs_path(hand_paths.LEAPJS_STILL)
    loop = Loop(params)
    try:
        _arm(loop, tuple(palm[0]))
        tel = loop.teleop
        tcp, raw = [], []
        t0, k = loop.t, 0
        while loop.t - t0 <= t[-1]:
            arrived = k
            while arrived < len(t) and t[arrived] <= loop.t - t0 + 1e-9:
                arrived += 1
            hand = ArmInput(present=True, palm_mm=tuple(palm[arrived - 1])) \
                if arrived > k else None
            k = arrived
            loop.period(hand)
            if loop.t - t0 > 0.5:
                tcp.append(loop.tcp()[:3, 3])
                raw.append(_mapped(tel, palm[k - 1]))
        window = int(round(0.25 * FRAME_HZ)) | 1
        results['arm.jitter_at_rest_mm_real'] = _jitter_mm(np.asarray(tcp), window)
        results['arm.jitter_at_rest_unfiltered_mm_real'] = _jitter_mm(np.asarray(raw), window)
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


# 1000 steps (~1 min): a p99 of 100 would be their second largest.
def onset(results, n=1000, params=None, seed=11):
    loop = Loop(params or sim_params())
    rng = np.random.default_rng(seed)
    palm = np.array([60.0, 300.0, 0.0])
    latencies, overshoot = [], 0.0
    try:
        _arm(loop, tuple(palm))
        start = None
        for i in range(n):
            path = []
            for _ in range(int(0.6 * FRAME_HZ)):          # at rest
                loop.period(ArmInput(present=True, palm_mm=tuple(palm)))
                path.append(loop.tcp()[:3, 3])
            if start is not None:
                # How far the TCP went past where the previous step came to rest.
                end = path[-1]
                way = (end - start) / max(np.linalg.norm(end - start), 1e-9)
                overshoot = max(overshoot, float(np.max((np.asarray(path) - end) @ way)))
            start = loop.tcp()[:3, 3]
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
        results['arm.step_overshoot_mm'] = overshoot * 1000
    finally:
        loop.close()
    return loop


def run():
    results = {}
    loops = [tracking(results), jitter(results, 5.0 / 6.0, 'arm.jitter_at_rest_mm'),
             jitter(results, 5.0, 'arm.jitter_at_rest_sigma5_mm'), orientation(results),
             onset(results)]
    real = [tracking_real(results), jitter_real(results)]
    results['arm.max_joint_accel'] = max(loop.max_accel_cmd for loop in loops + real)
    results['arm.max_joint_accel_measured'] = max(loop.max_accel_measured for loop in loops)
    results['arm.max_joint_accel_measured_real'] = max(loop.max_accel_measured for loop in real)
    for key in sorted(results):
        print('  %-32s %.5g' % (key, results[key]))
    # the bound the max_joint_accel figures are judged by: a constant, so not a figure
    print('  (the UR10 joint acceleration limit: %.5g rad/s^2)' % float(np.min(kin.MAX_JOINT_ACCEL)))
    return results


if __name__ == '__main__':
    run()
