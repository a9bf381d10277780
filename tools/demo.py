"""The headless demo: scripted hands -> the real sender -> two UR10 arms picking and
placing cubes, and the AR.Drone taking off, flying, flipping and landing, all in
PyBullet. Ends by itself, prints a summary table and writes demo_output/: summary.json,
ur10.gif (+ its PNG frames, each with an inset of the hand driving each arm), drone.gif
(a chase view of the flight with the drone's front camera inset, re-rendered from the
recorded odometry) and drone_flight.png (altitude, x, y and state against time, with
the gestures that caused each change).

usage: python -m tools.demo [--gui 0|1] [--out demo_output] [--tasks ur10,drone]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

import numpy as np

from leap_teleop.drone.sim import STATE_NAMES
from leap_teleop.hands.sources.scripted import GestureScript
from leap_teleop.package_files import package_path
from tools.bench.ros_processes import free_port

UR10_SCRIPT = 'ur10_pick_place_dual.yaml'
DRONE_SCRIPT = 'drone_flight.yaml'
# arm -> (hand, cube it picks)
UR10_TASKS = {'ur10_1': ('right', 'cube_red'), 'ur10_2': ('left', 'cube_yellow')}
# Where each arm's hand inset goes on the cell snapshot: next to that arm.
HAND_CORNER = {'ur10_1': 'left', 'ur10_2': 'right'}
SNAPSHOT_PERIOD_S = 1.0
SETTLE_S = 3.0
MAX_WAIT_S = 240.0          # give up on sessions that never start
PLACEMENT_TOLERANCE_M = 0.03


def say(msg):
    print('[demo] %s' % msg, flush=True)


class DemoMonitor:
    """A rospy node in this process watching the demo graph."""

    def __init__(self, tasks):
        import rosgraph
        import rospy
        deadline = time.monotonic() + 60
        while not rosgraph.is_master_online() and time.monotonic() < deadline:
            time.sleep(0.2)
        from nav_msgs.msg import Odometry

        from leap_teleop.msg import ArmStatus, Navdata
        self.rospy = rospy
        rospy.init_node('demo_monitor', disable_signals=True)
        self.tasks = tasks
        self.drone_states, self.drone_odom = [], None
        self.drone_track, self.drone_state_times, self.drone_gestures = [], [], []
        self.drone_camera = []
        self.hands = {}                   # side -> latest Hand (the arms' sender)
        self.hand_events = {}             # side -> (time, gesture) of the latest event
        self.arm_states = {arm: [] for arm in UR10_TASKS}
        self.cubes = {}
        self.first_frame = {}
        from leap_teleop.msg import Hand, leapcobotright
        if 'ur10' in tasks:
            rospy.Subscriber('/leapmotion/data_right', leapcobotright,
                             lambda m: self.first_frame.setdefault('ur10', time.monotonic()),
                             queue_size=1)
        if 'drone' in tasks:
            rospy.Subscriber('/drone/leapmotion/hand_right', Hand,
                             lambda m: self.first_frame.setdefault('drone', time.monotonic()),
                             queue_size=1)
        if 'drone' in tasks:
            from sensor_msgs.msg import Image

            from leap_teleop.msg import GestureEvent
            rospy.Subscriber('/drone/ardrone/navdata', Navdata, self._on_nav, queue_size=50)
            rospy.Subscriber('/drone/ardrone/odometry', Odometry, self._on_odom, queue_size=50)
            rospy.Subscriber('/drone/leapmotion/gestures', GestureEvent, self._on_drone_gesture,
                             queue_size=50)
            rospy.Subscriber('/drone/ardrone/front/image_raw', Image, self._on_camera,
                             queue_size=1, buff_size=2 ** 22)
        if 'ur10' in tasks:
            from leap_teleop.msg import GestureEvent
            for side in ('right', 'left'):
                rospy.Subscriber('/leapmotion/hand_%s' % side, Hand,
                                 lambda m, s=side: self.hands.__setitem__(s, m), queue_size=1)
            rospy.Subscriber('/leapmotion/gestures', GestureEvent, self._on_arm_gesture,
                             queue_size=50)
        if 'ur10' in tasks:
            from leap_teleop.ros.ur10_conversions import OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE
            rospy.Subscriber(OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, self._on_objects,
                             queue_size=5)
            for arm in UR10_TASKS:
                rospy.Subscriber('/%s/ur10_arm/status' % arm, ArmStatus,
                                 lambda m, a=arm: self._on_arm(a, m), queue_size=20)

    def _on_nav(self, msg):
        if not self.drone_states or self.drone_states[-1] != msg.state:
            self.drone_states.append(msg.state)
            # Header stamps (wall clock here): one clock for every source, unlike arrival
            # times, which differ per connection.
            self.drone_state_times.append((msg.header.stamp.to_sec(), msg.state))

    def _on_odom(self, msg):
        self.drone_odom = msg
        if 'drone' in self.first_frame:
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            self.drone_track.append((msg.header.stamp.to_sec(), p.x, p.y, p.z,
                                     q.x, q.y, q.z, q.w))

    def _on_drone_gesture(self, msg):
        if msg.active:
            self.drone_gestures.append((msg.header.stamp.to_sec(), msg.gesture))

    def _on_camera(self, msg):
        # A small copy, at most twice a second: the chase GIF's inset.
        now = msg.header.stamp.to_sec()
        if 'drone' not in self.first_frame or (
                self.drone_camera and now - self.drone_camera[-1][0] < 0.5):
            return
        rgb = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.width, 3)
        self.drone_camera.append((now, np.ascontiguousarray(rgb[::2, ::2])))

    def _on_arm_gesture(self, msg):
        if msg.active:
            side = 'right' if msg.side == 0 else 'left'
            self.hand_events[side] = (time.monotonic(), msg.gesture)

    def hand_insets(self):
        """An inset per arm of the hand driving it, as it is now."""
        from tools.demo_pictures import hand_inset
        return [(HAND_CORNER[arm], hand_inset(self.hands.get(hand), '%s: %s hand'
                                              % (arm, hand)))
                for arm, (hand, _) in UR10_TASKS.items()]

    def _on_arm(self, arm, msg):
        if not self.arm_states[arm] or self.arm_states[arm][-1] != msg.state:
            self.arm_states[arm].append(msg.state)

    def _on_objects(self, msg):
        from leap_teleop.ros.ur10_conversions import object_positions
        self.cubes = object_positions(msg)

    def snapshot(self, service):
        from std_srvs.srv import Trigger
        try:
            self.rospy.wait_for_service(service, 0.5)
            res = self.rospy.ServiceProxy(service, Trigger)()
            return res.message if res.success else None
        except Exception:   # a missed frame only thins the GIF
            return None


def make_gif(pngs, path, frame_s=SNAPSHOT_PERIOD_S):
    from PIL import Image
    frames = [Image.open(p).convert('RGB') for p in pngs if p]
    if not frames:
        return False
    frames[0].save(path, save_all=True, append_images=frames[1:],
                   duration=int(frame_s * 1000), loop=0, optimize=True)
    return True


def evaluate_ur10(mon):
    from leap_teleop.ur10.config import load_config
    cell = load_config('ur10_dual_cell.yaml')
    out = {}
    for arm, (hand, cube) in UR10_TASKS.items():
        tray = cell.arm(arm).tray
        pos = mon.cubes.get(cube)
        if pos is None:
            out['ur10_pick_place_%s' % arm] = {'success': False, 'error': 'no cube pose'}
            continue
        err = float(np.linalg.norm(np.asarray(pos[:2]) - np.asarray(tray.xyz[:2])))
        in_tray = err < PLACEMENT_TOLERANCE_M and pos[2] < tray.floor_z + cell.cube_size
        out['ur10_pick_place_%s' % arm] = {
            'success': bool(in_tray), 'hand': hand, 'cube': cube,
            'placement_error_m': round(err, 4), 'cube_final_xyz': [round(float(x), 4) for x in pos],
            'arm_states': mon.arm_states[arm]}
    return out


def _compress(states):
    """Navdata states for people: flying and hovering alternate while the hand moves."""
    out = []
    for s in states:
        name = 'flying' if s in (3, 4) else STATE_NAMES.get(s, str(s))
        if not out or out[-1] != name:
            out.append(name)
    return out


def evaluate_drone(mon):
    names = _compress(mon.drone_states)
    key = [s for s in mon.drone_states if s in (2, 6, 9, 8)]
    ok = key == [2, 6, 9, 8, 2] and 4 in mon.drone_states
    # The gestures the drone's sender recognized: a flight without its flip says whether
    # the circle was never seen or was seen and not acted on.
    result = {'success': bool(ok), 'state_sequence': names,
              'navdata_states': list(mon.drone_states),
              'gestures': [name for _, name in mon.drone_gestures]}
    if mon.drone_odom is not None:
        p = mon.drone_odom.pose.pose.position
        result['final_xyz'] = [round(p.x, 3), round(p.y, 3), round(p.z, 3)]
    return {'drone_flight': result}


TASKS = ('ur10', 'drone')
# What a run writes in --out; only these go before a run, whatever else the folder holds.
OUTPUT_NAME = re.compile(r'(summary\.json|roslaunch\.log|(ur10|drone)\.gif|ur10_\d{3,}\.png'
                         r'|drone_flight\.png|rotated_grasp\.png)$')


def clear_earlier_outputs(out):
    """Remove an earlier run's outputs from `out` (a frame count may have shrunk)."""
    for name in os.listdir(out):
        if OUTPUT_NAME.match(name):
            os.unlink(os.path.join(out, name))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--gui', type=int, default=0, help='1: open the PyBullet windows')
    ap.add_argument('--out', default='demo_output')
    ap.add_argument('--tasks', default='ur10,drone')
    args = ap.parse_args(argv)
    tasks = [t for t in args.tasks.split(',') if t]
    unknown = sorted(set(tasks) - set(TASKS))
    if unknown or not tasks:        # before the folder is touched or a graph starts
        ap.error('--tasks: %s (tasks: %s, comma-separated)'
                 % ('no task %s' % ', '.join(unknown) if unknown else 'no task given', ','.join(TASKS)))
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    clear_earlier_outputs(out)
    gui = bool(args.gui) and bool(os.environ.get('DISPLAY'))
    if args.gui and not gui:
        say('GUI=1 but no DISPLAY: running headless')
    durations = {}
    if 'ur10' in tasks:
        durations['ur10'] = GestureScript.load(package_path('config', 'gestures',
                                                            UR10_SCRIPT)).duration
    if 'drone' in tasks:
        durations['drone'] = GestureScript.load(package_path('config', 'gestures',
                                                             DRONE_SCRIPT)).duration
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port,
               ROS_HOSTNAME='127.0.0.1', ROS_IP='127.0.0.1', ROS_LOG_DIR=os.path.join(out, 'ros_log'))
    os.environ.update({k: env[k] for k in ('ROS_MASTER_URI', 'ROS_HOSTNAME', 'ROS_IP',
                                          'ROS_LOG_DIR')})
    log_path = os.path.join(out, 'roslaunch.log')
    say('starting the ROS graph (sender, %s) on a private master, port %d; log: %s'
        % (' + '.join(tasks), port, log_path))
    with open(log_path, 'w') as log:
        launch = subprocess.Popen(
            ['roslaunch', '-p', str(port), 'leap_teleop', 'demo.launch',
             'gui:=%s' % str(gui).lower(), 'ur10:=%s' % str('ur10' in tasks).lower(),
             'drone:=%s' % str('drone' in tasks).lower()],
            env=env, stdout=log, stderr=subprocess.STDOUT)
        try:
            mon, summary, shots = run_demo(tasks, durations)
        finally:
            launch.send_signal(2)
            try:
                launch.wait(20)
            except subprocess.TimeoutExpired:
                launch.kill()
                launch.wait()
    # How the graph took Ctrl-C (0: every node stopped on SIGINT), as a user's would.
    summary['roslaunch_status'] = launch.returncode
    # The pictures after the graph has gone: on 2 cores it would slow them and they it.
    write_pictures(mon, summary, shots, tasks, out)
    if 'ur10' in tasks:
        # The rotated-cube task (yaw orientation mode), in the closed loop in simulated time.
        from tools import rotated_task
        say('rotated cubes (30 / 60 deg), yaw orientation mode, closed loop')
        summary['tasks'].update(rotated_task.run(os.path.join(out, 'rotated_grasp.png')))
    return report(summary, out)


def run_demo(tasks, durations):
    """Watch the sessions to their end: (the monitor, the summary of each task, the
    snapshots taken: {name: [PNG or None]} and {PNG: hand insets})."""
    mon = DemoMonitor(tasks)
    services = {}
    if 'ur10' in tasks:
        services['ur10'] = '/ur10_sim/snapshot'
    if 'drone' in tasks:
        mon.rospy.wait_for_service('/drone/ardrone/snapshot', 120)
    say('waiting for the simulations to come up')
    for service in services.values():
        mon.rospy.wait_for_service(service, 120)
    say('playing the gesture sessions (%s)' % ', '.join(
        '%s %.0f s' % kv for kv in durations.items()))
    pngs = {name: [] for name in services}
    insets = {}
    t0 = time.monotonic()
    next_shot, last_print = t0, t0
    while True:
        now = time.monotonic()
        # Each session runs from its sender's first frame; the demo ends when all are over.
        ends = [mon.first_frame.get(task, now) + d + SETTLE_S for task, d in durations.items()]
        if now >= max(ends) or now - t0 > MAX_WAIT_S:
            break
        if now >= next_shot:
            next_shot += SNAPSHOT_PERIOD_S
            for name, service in services.items():
                png = mon.snapshot(service)
                pngs[name].append(png)
                if png and name == 'ur10':
                    insets[png] = mon.hand_insets()
        if now - last_print >= 5.0:
            last_print = now
            parts = ['%.0f s' % (now - t0)]
            for arm, states in (mon.arm_states.items() if 'ur10' in tasks else ()):
                parts.append('%s %s' % (arm, states[-1] if states else '-'))
            if mon.drone_states:
                parts.append('drone %s' % STATE_NAMES.get(mon.drone_states[-1], '?'))
            say(', '.join(parts))
        time.sleep(0.02)
    summary = {'tasks': {}}
    if 'ur10' in tasks:
        summary['tasks'].update(evaluate_ur10(mon))
    if 'drone' in tasks:
        summary['tasks'].update(evaluate_drone(mon))
    for name, task in summary['tasks'].items():
        task['session_s'] = round(durations['drone' if name.startswith('drone') else 'ur10'], 1)
    mon.rospy.signal_shutdown('demo done')
    return mon, summary, (pngs, insets)


def write_pictures(mon, summary, shots, tasks, out):
    """The cell GIF (each frame with its hand insets) and the drone's pictures in `out`;
    their names go into summary['gifs']."""
    pngs, insets = shots
    for png, hand_pics in insets.items():
        from tools.demo_pictures import arm_frame_with_insets
        if os.path.exists(png):
            arm_frame_with_insets(png, hand_pics)
    for name, files in pngs.items():
        frames = [f for f in files if f]
        for i, f in enumerate(frames):
            os.replace(f, os.path.join(out, '%s_%03d.png' % (name, i)))
        kept = [os.path.join(out, '%s_%03d.png' % (name, i)) for i in range(len(frames))]
        if make_gif(kept, os.path.join(out, '%s.gif' % name)):
            summary.setdefault('gifs', []).append('%s.gif' % name)
    if 'drone' in tasks:
        summary.setdefault('gifs', []).extend(drone_pictures(mon, out))


def drone_pictures(mon, out):
    """The chase-view GIF and the flight plot of the recorded flight."""
    from tools import demo_pictures
    if len(mon.drone_track) < 10:
        say('no drone track recorded: no drone pictures')
        return []
    say('rendering the drone pictures (%d poses, %d camera frames)'
        % (len(mon.drone_track), len(mon.drone_camera)))
    track, states = mon.drone_track, mon.drone_state_times
    gestures, camera = mon.drone_gestures, mon.drone_camera
    written = []
    try:
        demo_pictures.flight_plot(track, states, gestures, os.path.join(out, 'drone_flight.png'))
        written.append('drone_flight.png')
    except ImportError as e:                      # matplotlib missing: the GIF still comes
        say('no flight plot: %s' % e)
    frames = demo_pictures.chase_gif(track, states, gestures, os.path.join(out, 'drone.gif'),
                                     camera)
    if frames:
        written.append('drone.gif')
    return written


def report(summary, out):
    with open(os.path.join(out, 'summary.json'), 'w') as f:
        json.dump(summary, f, indent=1)
    print('\n%-26s %-8s %-12s %s' % ('task', 'success', 'error (m)', 'details'))
    for name, task in summary['tasks'].items():
        err = task.get('placement_error_m')
        details = ' -> '.join(task.get('state_sequence', [])) or task.get('cube', '')
        print('%-26s %-8s %-12s %s' % (name, 'yes' if task['success'] else 'NO',
                                      '%.3f' % err if err is not None else '-', details))
        if not task['success'] and 'gestures' in task:
            print('%-26s %-8s %-12s gestures: %s' % ('', '', '', ', '.join(task['gestures'])))
    print('\nwrote %s/summary.json and %s' % (out, ', '.join(summary.get('gifs', [])) or 'no GIFs'))
    ok = all(t['success'] for t in summary['tasks'].values())
    print('demo %s' % ('succeeded' if ok else 'FAILED'))
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())
