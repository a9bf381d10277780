"""Soak test (`make soak`): the full dual-arm + drone graph for 30 simulated minutes.

usage: python -m tools.soak [--minutes 30] [--rtf 1.0] [--out soak_results.json]

Runs on a private master with /use_sim_time: the dual UR10 simulator is the clock (at
--rtf times real time), the drone simulator runs at the same factor (its own /clock is
remapped away so there is one time base). Instead of the sender (whose scripted source
paces itself on wall time) this process replays the gesture sessions paced by the sim
clock, like `rosbag play` would: the dual pick and place (leapcobot, both hands) and the
drone flight (Hand + GestureEvent, namespace drone/), pre-rendered through the sender's
own code (LeapInterface + conversions), restamped with the sim time when sent, in a loop;
each cycle resets the UR10 cell first.

Input timeouts (arm input_timeout / disarm_after / max_input_age, pilot hand_timeout /
disarm_after / max_input_age / navdata_timeout / land_after) are sim seconds; the soak
scales them by --rtf so that they keep their real-time wall tolerance. Measured: RSS of
every node (after the first cycle vs the end), hand -> arm command and hand -> cmd_vel
latency per cycle and its drift (median of the last cycles minus the first), lost
messages (hand topics: sent vs received; joint_states, arm commands, navdata: sequence
gaps; each consumer's own count of gaps in the player's numbering, in all and after the
load burst), inputs the nodes rejected, pick and place and flight successes.
Writes soak_results.json afresh (soak.rss_growth_pct, goal <= 5; soak.dropped_msgs =
messages lost in transport, goal 0; soak.rejected_inputs = inputs the nodes refused as
late / out of order / invalid; and the rest), as `make bench` writes its file: this
run's figures only, `_sources` and `_failed` (a soak that fails writes no figure).
"""
import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import traceback
import xmlrpc.client

import numpy as np

ARMS = {'ur10_1': ('right', 'cube_red'), 'ur10_2': ('left', 'cube_yellow')}
PLAYER = '/soak'           # this process's node: the consumers count what came from it
# Each consumer node (as its /diagnostics status names it) and the topic it reads.
CONSUMERS = {'ur10_1/ur10_arm': '/leapmotion/data_right', 'ur10_2/ur10_arm': '/leapmotion/data_left',
             'drone/drone_pilot': '/drone/leapmotion/hand_right'}
# The graph's own nodes: one that is gone (refused a parameter, crashed) ends the soak
# rather than leaving its figures out.
NODES = ('/ur10_sim', '/ur10_1/ur10_arm', '/ur10_2/ur10_arm', '/drone/drone_pilot',
         '/drone/ardrone_sim')
LAUNCH = """<launch>
  <param name="/use_sim_time" value="true"/>
  <include file="$(find leap_teleop)/launch/ur10_dual_sim.launch">
    <arg name="use_sim_time" value="true"/>
    <arg name="realtime_factor" value="{rtf}"/>
  </include>
  <include file="$(find leap_teleop)/launch/ur10_arm.launch">
    <arg name="arm" value="ur10_1"/> <arg name="hand" value="right"/>
    <arg name="max_joint_speed" value="1.0"/>
  </include>
  <include file="$(find leap_teleop)/launch/ur10_arm.launch">
    <arg name="arm" value="ur10_2"/> <arg name="hand" value="left"/>
    <arg name="max_joint_speed" value="1.0"/>
  </include>
  <!-- Input timeouts are sim seconds: scaled by the speed-up they keep their wall-clock
       tolerance (scheduling hiccups on a loaded machine are wall-clock). -->
  <param name="ur10_1/ur10_arm/input_timeout" value="{input_timeout}"/>
  <param name="ur10_1/ur10_arm/disarm_after" value="{disarm_after}"/>
  <param name="ur10_1/ur10_arm/max_input_age" value="{max_age}"/>
  <param name="ur10_1/ur10_arm/resubscribe_after" value="{resubscribe_after}"/>
  <param name="ur10_1/ur10_arm/resubscribe_silent_after" value="{resubscribe_silent_after}"/>
  <param name="ur10_1/ur10_arm/hand_queue_size" value="{hand_queue_size}"/>
  <param name="ur10_1/ur10_arm/command_queue_size" value="{command_queue_size}"/>
  <param name="ur10_2/ur10_arm/input_timeout" value="{input_timeout}"/>
  <param name="ur10_2/ur10_arm/disarm_after" value="{disarm_after}"/>
  <param name="ur10_2/ur10_arm/max_input_age" value="{max_age}"/>
  <param name="ur10_2/ur10_arm/resubscribe_after" value="{resubscribe_after}"/>
  <param name="ur10_2/ur10_arm/resubscribe_silent_after" value="{resubscribe_silent_after}"/>
  <param name="ur10_2/ur10_arm/hand_queue_size" value="{hand_queue_size}"/>
  <param name="ur10_2/ur10_arm/command_queue_size" value="{command_queue_size}"/>
  <param name="ur10_sim/joint_states_queue_size" value="{joint_states_queue_size}"/>
  <group ns="drone">
    <rosparam command="load" file="$(find leap_teleop)/config/ardrone.yaml"/>
    <param name="drone_pilot/hand_timeout" value="{hand_timeout}"/>
    <param name="drone_pilot/navdata_timeout" value="{navdata_timeout}"/>
    <param name="drone_pilot/land_after" value="{land_after}"/>
    <param name="drone_pilot/disarm_after" value="{disarm_after}"/>
    <param name="drone_pilot/max_input_age" value="{max_age}"/>
    <param name="drone_pilot/resubscribe_after" value="{resubscribe_after}"/>
    <param name="drone_pilot/resubscribe_silent_after" value="{resubscribe_silent_after}"/>
    <param name="drone_pilot/hand_queue_size" value="{hand_queue_size}"/>
    <node pkg="leap_teleop" type="drone_pilot.py" name="drone_pilot"/>
    <node pkg="leap_teleop" type="ardrone_sim.py" name="ardrone_sim">
      <param name="realtime_factor" value="{rtf}"/>
      <!-- The longest battery the node accepts: it never runs flat during a soak. -->
      <param name="battery_flight_time" value="100000.0"/>
      <remap from="/clock" to="/drone/sim_clock"/>
    </node>
  </group>
</launch>
"""


def render(script, kinds, topics, rate_hz=None):
    """[(t, topic, msg)] of one gesture session through the sender's code, t from 0."""
    from leap_teleop.hands.leap_interface import LeapInterface
    from leap_teleop.hands.sources.scripted import ScriptedSource
    from leap_teleop.ros import hand_conversions
    out = []
    interface = LeapInterface(sides=list(topics))
    t0 = [None]

    def on_hand(frame, state):
        for kind, msg in hand_conversions.hand_messages(state):
            if kind in kinds:
                out.append((frame.timestamp - t0[0], topics[state.side][kind], msg))
    interface.add_hand_listener(on_hand)
    for frame in ScriptedSource(script, rate_hz=rate_hz, realtime=False).frames():
        if t0[0] is None:
            t0[0] = frame.timestamp
        interface.on_frame(frame)
    return out


class SoakMonitor:
    """Subscribes what the graph produces; counts, sequence gaps, latency samples."""

    def __init__(self, hand_topics):
        import rospy
        from geometry_msgs.msg import Twist
        from sensor_msgs.msg import JointState
        from trajectory_msgs.msg import JointTrajectory

        from leap_teleop.msg import ArmStatus, Hand, Navdata
        from leap_teleop.ros import hand_conversions
        from leap_teleop.ros.ur10_conversions import OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE
        self.lock = threading.Lock()
        self.received, self.last_seq, self.gaps = {}, {}, {}
        self.last_rx = {}
        self.lat = {}                    # key -> [(cycle, seconds)]
        self.cycle = 0
        self.status = {}
        self.cubes = {}
        self.nav_states = []
        big = dict(queue_size=2000, buff_size=2 ** 24, tcp_nodelay=True)
        for side, topic in hand_topics['arms'].items():
            rospy.Subscriber(topic, hand_conversions.LEAPCOBOT_TYPES[side], self.on_input, topic, **big)
        rospy.Subscriber(hand_topics['drone'], Hand, self.on_input, hand_topics['drone'], **big)
        for arm, (side, _) in ARMS.items():
            rospy.Subscriber('/%s/joint_states' % arm, JointState, self.on_seq,
                             '/%s/joint_states' % arm, **big)
            rospy.Subscriber('/%s/arm_controller/command' % arm, JointTrajectory, self.on_cmd,
                             (arm, hand_topics['arms'][side]), **big)
            rospy.Subscriber('/%s/ur10_arm/status' % arm, ArmStatus, self.on_status, arm,
                             queue_size=10)
        rospy.Subscriber('/drone/ardrone/navdata', Navdata, self.on_nav, **big)
        rospy.Subscriber('/drone/cmd_vel', Twist, self.on_twist, hand_topics['drone'], **big)
        rospy.Subscriber(OBJECT_POSES_TOPIC, OBJECT_POSES_TYPE, self.on_objects, queue_size=2)
        from diagnostic_msgs.msg import DiagnosticArray
        self.diag_rejected = {}
        self.consumer_received, self.resubscriptions = {}, {}   # per consumer, their own count
        self.judged_afresh = {}             # ... of their input, on its connection
        self.consumer_missed = {}           # ... of the player's messages that never came
        self.consumer_missed_reconnect = {}  # ... of them, across the consumer's re-subscriptions
        rospy.Subscriber('/diagnostics', DiagnosticArray, self.on_diag, queue_size=50)

    def on_diag(self, msg):
        with self.lock:
            for st in msg.status:
                for kv in st.values:
                    if kv.key == 'rejected inputs':
                        self.diag_rejected[st.name] = int(kv.value)
                    elif kv.key == 'hand messages from %s' % PLAYER:
                        self.consumer_received[st.name] = int(kv.value)
                    elif kv.key == 'hand messages missed from %s' % PLAYER:
                        self.consumer_missed[st.name] = int(kv.value)
                    elif kv.key == 'hand messages missed from %s across re-subscriptions' % PLAYER:
                        self.consumer_missed_reconnect[st.name] = int(kv.value)
                    elif kv.key == 'hand re-subscriptions':
                        self.resubscriptions[st.name] = int(kv.value)
                    elif kv.key == 'hand input judged afresh on its connection':
                        self.judged_afresh[st.name] = int(kv.value)

    def _seq(self, topic, msg):
        seq = msg.header.seq
        last = self.last_seq.get(topic)
        if last is not None and seq > last + 1:
            self.gaps[topic] = self.gaps.get(topic, 0) + seq - last - 1
        self.last_seq[topic] = seq
        self.received[topic] = self.received.get(topic, 0) + 1

    def on_input(self, msg, topic):
        with self.lock:
            self.received[topic] = self.received.get(topic, 0) + 1
            self.last_rx[topic] = time.monotonic()

    def on_seq(self, msg, topic):
        with self.lock:
            self._seq(topic, msg)

    def on_cmd(self, msg, args):
        # The monitor's view, periodic commands included: a health figure to watch drift,
        # not the capture-to-command age per input (make bench's pipeline keys).
        arm, hand_topic = args
        now = time.monotonic()
        with self.lock:
            self._seq(arm + '/command', msg)
            t_hand = self.last_rx.get(hand_topic)
            if t_hand is not None and now - t_hand < 0.5:
                self.lat.setdefault('arm', []).append((self.cycle, now - t_hand))

    def on_twist(self, msg, hand_topic):
        now = time.monotonic()
        with self.lock:
            t_hand = self.last_rx.get(hand_topic)
            if t_hand is not None and now - t_hand < 0.5 and (msg.linear.x or msg.linear.y
                                                              or msg.linear.z or msg.angular.z):
                self.lat.setdefault('drone', []).append((self.cycle, now - t_hand))

    def on_status(self, msg, arm):
        with self.lock:
            self.status[arm] = msg

    def on_nav(self, msg):
        with self.lock:
            self._seq('/drone/ardrone/navdata', msg)
            if not self.nav_states or self.nav_states[-1][1] != msg.state:
                self.nav_states.append((self.cycle, msg.state))

    def on_objects(self, msg):
        from leap_teleop.ros.ur10_conversions import object_positions
        with self.lock:
            self.cubes = object_positions(msg)


def node_pids(master_uri):
    import rosgraph
    master = rosgraph.Master('/soak', master_uri=master_uri)
    pids = {}
    for names in master.getSystemState():
        for _, nodes in names:
            for n in nodes:
                if n in pids or n == '/soak':
                    continue
                try:
                    pids[n] = xmlrpc.client.ServerProxy(master.lookupNode(n)).getPid('/soak')[2]
                except Exception:       # noqa: BLE001 - a node going away mid-scan
                    pass
    return pids


def rss_kb(pid):
    try:
        with open('/proc/%d/status' % pid) as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1])
    except OSError:
        return None
    return None


def percentile(xs, q):
    return float(np.percentile(xs, q)) if xs else float('nan')


class LoadBurst:
    """Heavy work beside the soak for its first `minutes` of wall time: `hogs` processes
    spinning on a core each and a second ROS graph (the single-arm pick and place, looping,
    under its own master). `ended_in_cycle` is the soak cycle that was running when it
    stopped (None before): the cycles after it are judged as back to full function."""

    def __init__(self, minutes, hogs, log):
        self.seconds, self.n_hogs, self.log = 60.0 * minutes, hogs, log
        self.hogs, self.graph, self.master, self.timer = [], None, None, None
        self.ended_in_cycle = None
        self.cycle = lambda: None
        self._lock = threading.Lock()     # stop() runs on the timer's thread and the soak's

    def start(self, cycle):
        """cycle(): the soak's current cycle index."""
        if self.seconds <= 0:
            return
        from tools.bench.ros_processes import ros_master
        from tools.under_load import start_hogs
        self.cycle = cycle
        self.hogs = start_hogs(self.n_hogs)
        self.master = ros_master()
        env = self.master.__enter__()
        env = dict(env, ROS_LOG_DIR=tempfile.mkdtemp(prefix='soak_burst_logs_'))
        self.graph = subprocess.Popen(['roslaunch', 'leap_teleop', 'ur10_single.launch',
                                       'loop:=true'], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, start_new_session=True)
        self.log('[soak] load burst: %d CPU hogs and a second ROS graph (ur10_single, '
                 'looping) for %.1f wall minutes' % (self.n_hogs, self.seconds / 60.0))
        self.timer = threading.Timer(self.seconds, self.stop)
        self.timer.daemon = True
        self.timer.start()

    def stop(self):
        with self._lock:
            self._stop()

    def _stop(self):
        if self.timer is not None:
            self.timer.cancel()
        if self.graph is None and not self.hogs:
            return
        from tools.under_load import stop_hogs
        stop_hogs(self.hogs)
        self.hogs = []
        if self.graph is not None:
            try:
                os.killpg(self.graph.pid, signal.SIGINT)
                self.graph.wait(30)
            except (OSError, subprocess.TimeoutExpired):
                os.killpg(self.graph.pid, signal.SIGKILL)
            self.graph = None
            self.master.__exit__(None, None, None)
        if self.ended_in_cycle is None:
            self.ended_in_cycle = self.cycle()
            self.log('[soak] load burst over during cycle %d' % (self.ended_in_cycle + 1))

    def after(self, cycles):
        """The cycle indices that began after the burst ended (every one without a burst)."""
        if self.seconds <= 0:
            return list(range(cycles))
        if self.ended_in_cycle is None:
            return []
        return list(range(self.ended_in_cycle + 1, cycles))


def _per_consumer(by_status):
    """{consumer: count} from {diagnostic status name: count} (CONSUMERS' order)."""
    return {c: n for c in CONSUMERS for name, n in by_status.items()
            if name.startswith(c + ':')}


def scaled_timeouts(rtf, resubscribe_after):
    """The graph's timeouts in sim seconds for a real-time factor: {launch key: (table,
    its parameter, value)}, with the declared table that checks each."""
    from leap_teleop.control.stream_health import HAND_SUBSCRIPTION_PARAMS
    from leap_teleop.drone.pilot_params import PILOT_PARAMS
    from leap_teleop.ur10.teleop_params import TELEOP_PARAMS
    return {'input_timeout': (TELEOP_PARAMS, 'input_timeout', 0.2 * rtf),
            'disarm_after': (TELEOP_PARAMS, 'disarm_after', 1.0 * rtf),
            'max_age': (TELEOP_PARAMS, 'max_input_age', 0.25 * rtf),
            'hand_timeout': (PILOT_PARAMS, 'hand_timeout', 0.15 * rtf),
            'navdata_timeout': (PILOT_PARAMS, 'navdata_timeout', 0.5 * rtf),
            'land_after': (PILOT_PARAMS, 'land_after', 3.0 * rtf),
            'resubscribe_after': (HAND_SUBSCRIPTION_PARAMS, 'resubscribe_after', resubscribe_after * rtf),
            # longer than the pause between two cycles
            'resubscribe_silent_after': (HAND_SUBSCRIPTION_PARAMS, 'resubscribe_silent_after', 8.0 * rtf)}


def timeouts_problem(rtf, resubscribe_after):
    """One line naming a scaled timeout the nodes would refuse (None when all pass): the
    graph would not start."""
    for table, name, value in scaled_timeouts(rtf, resubscribe_after).values():
        try:
            table[name].check(name, value)
        except ValueError as e:
            return '--rtf %g gives %s' % (rtf, e)
    return None


def run(minutes, rtf, rate_hz=None, log=print, player_queue=2000, hand_queue=500,
        command_queue=50, joint_states_queue=100, burst_minutes=0.0, burst_hogs=2,
        resubscribe_after=0.5):
    """Run the soak; returns (figures, {figure: what it was measured on}). player_queue:
    the player's publisher queue per connection; hand_queue, command_queue,
    joint_states_queue, resubscribe_after: the nodes' ~hand_queue_size,
    ~command_queue_size (arm nodes), ~joint_states_queue_size (simulator) and the
    consumers' ~resubscribe_after (wall seconds); a load burst (LoadBurst) of
    burst_minutes with burst_hogs."""
    from leap_teleop.package_files import package_path
    from tools.bench.ros_processes import ros_master
    with ros_master() as env:
        os.environ.update({k: env[k] for k in ('ROS_MASTER_URI', 'ROS_IP', 'ROS_HOSTNAME')})
        log_dir = tempfile.mkdtemp(prefix='soak_logs_')
        env = dict(env, ROS_LOG_DIR=log_dir)
        with tempfile.NamedTemporaryFile('w', suffix='.launch', delete=False) as f:
            timeouts = {key: value for key, (_, _, value) in scaled_timeouts(rtf, resubscribe_after).items()}
            f.write(LAUNCH.format(rtf=rtf, **timeouts, hand_queue_size=hand_queue,
                                  command_queue_size=command_queue,
                                  joint_states_queue_size=joint_states_queue))
            launch_file = f.name
        subprocess.run(['rosparam', 'set', '/use_sim_time', 'true'], env=env, check=True)
        # To a file, not a pipe: the nodes share roslaunch's stderr (their warnings go
        # there even with output="log"), and a pipe nobody drains fills after 64 KiB and
        # then blocks every node at its next warning: a 30-minute soak froze all three
        # consumers that way in its last minutes.
        graph_err = open(os.path.join(log_dir, 'roslaunch-stderr.log'), 'w+b')
        graph = subprocess.Popen(['roslaunch', launch_file], env=env,
                                 stdout=subprocess.DEVNULL, stderr=graph_err,
                                 start_new_session=True)
        graph.err_path = graph_err.name
        graph_err.close()
        burst = LoadBurst(burst_minutes, burst_hogs, log)
        try:
            return _soak(env, minutes, rtf, rate_hz, log, package_path, graph, player_queue,
                         burst)
        finally:
            burst.stop()
            try:
                os.killpg(graph.pid, signal.SIGINT)
                graph.wait(30)
            except (OSError, subprocess.TimeoutExpired):
                os.killpg(graph.pid, signal.SIGKILL)
            os.unlink(launch_file)


def _soak(env, minutes, rtf, rate_hz, log, package_path, graph, player_queue, burst):
    import rospy
    from std_srvs.srv import Trigger

    from leap_teleop.msg import GestureEvent, Hand
    from leap_teleop.ros import hand_conversions
    from leap_teleop.ur10.config import load_config

    arm_topics = {side: {'leapcobot': '/leapmotion/data_%s' % side} for side in ('right', 'left')}
    drone_topics = {'right': {'hand': '/drone/leapmotion/hand_right',
                              'gesture': '/drone/leapmotion/gestures'}}
    session = render(package_path('config', 'gestures', 'ur10_pick_place_dual.yaml'),
                     ('leapcobot',), arm_topics, rate_hz)
    session += render(package_path('config', 'gestures', 'drone_flight.yaml'),
                      ('hand', 'gesture'), drone_topics, rate_hz)
    session.sort(key=lambda x: x[0])
    cycle_len = session[-1][0] + 4.0             # settle before the next reset
    cycles = max(1, int(round(minutes * 60.0 / cycle_len)))
    log('[soak] session %.1f s sim, %d messages; %d cycles = %.1f sim minutes at x%g'
        % (cycle_len, len(session), cycles, cycles * cycle_len / 60.0, rtf))

    rospy.init_node(PLAYER.lstrip('/'), disable_signals=True)
    types = {'/leapmotion/data_right': hand_conversions.LEAPCOBOT_TYPES['right'],
             '/leapmotion/data_left': hand_conversions.LEAPCOBOT_TYPES['left'],
             '/drone/leapmotion/hand_right': Hand, '/drone/leapmotion/gestures': GestureEvent}
    pubs = {t: rospy.Publisher(t, ty, queue_size=player_queue, tcp_nodelay=True)
            for t, ty in types.items()}
    mon = SoakMonitor({'arms': {s: arm_topics[s]['leapcobot'] for s in arm_topics},
                   'drone': drone_topics['right']['hand']})
    sent = {t: 0 for t in types}
    reset = rospy.ServiceProxy('/ur10_sim/reset', Trigger)
    reset.wait_for_service(120)
    # Every subscriber of the player's topics connected: a consumer (arm node, pilot) on
    # each, and the monitor on each but the gestures.
    wanted = {t: 1 if t == '/drone/leapmotion/gestures' else 2 for t in types}
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (
            all(pubs[t].get_num_connections() >= n for t, n in wanted.items())):
        time.sleep(0.2)
    while time.monotonic() < deadline and rospy.get_time() == 0:
        time.sleep(0.1)
    cell = load_config('ur10_dual_cell.yaml')
    master_uri = env['ROS_MASTER_URI']
    rss, placed, flights, missed_at_start = {}, [], 0, []
    wall0, sim0 = time.monotonic(), rospy.get_time()
    burst.start(lambda: mon.cycle)
    for cycle in range(cycles):
        mon.cycle = cycle
        with mon.lock:                  # as of each consumer's last /diagnostics (1 Hz)
            missed_at_start.append(_per_consumer(mon.consumer_missed))
        reset()
        t0 = rospy.get_time()
        for t, topic, msg in session:
            while True:
                ahead = t0 + t - rospy.get_time()
                if ahead <= 0:
                    break
                time.sleep(min(0.02, max(0.0005, 0.8 * ahead / rtf)))
            msg.header.stamp = rospy.Time.now()
            pubs[topic].publish(msg)
            sent[topic] += 1
        while rospy.get_time() < t0 + cycle_len:
            time.sleep(0.01)
        with mon.lock:
            cubes = dict(mon.cubes)
        ok, missed = 0, []
        for arm, (_, cube) in ARMS.items():
            pos = cubes.get(cube)
            tray = cell.arm(arm).tray
            off = np.linalg.norm(np.subtract(pos[:2], tray.xyz[:2])) if pos is not None else None
            if off is not None and off < 0.03:
                ok += 1
            else:
                # how far off says whether the grasp failed or the place was short
                missed.append('%s %s' % (arm, 'no cube pose' if off is None else
                                         '%.0f mm from the tray centre' % (1e3 * off)))
        placed.append(ok)
        with mon.lock:
            flights = sum(1 for c, s in mon.nav_states if s == 6)
        if cycle == 0 or cycle == cycles - 1 or cycle % 5 == 4:
            pids = node_pids(master_uri)
            gone = [n for n in NODES if n not in pids]
            if gone:
                raise SystemExit('[soak] nodes not running after cycle %d: %s'
                                 % (cycle + 1, ', '.join(gone)))
            sample = {n: rss_kb(p) for n, p in pids.items()}
            for n, kb in sample.items():
                if kb:
                    rss.setdefault(n, []).append((cycle, kb))
        wall, sim = time.monotonic() - wall0, rospy.get_time() - sim0
        log('[soak] cycle %d/%d: %d/2 cubes placed%s, %d takeoffs so far; %.1f sim min in %.1f '
            'wall min (x%.2f)' % (cycle + 1, cycles, ok, ' (missed: %s)' % ', '.join(missed)
                                   if missed else '', flights, sim / 60, wall / 60, sim / wall))
        if graph.poll() is not None:
            with open(graph.err_path, errors='replace') as err:
                raise SystemExit('[soak] the graph died: %s' % err.read()[-2000:])
    wall, sim = time.monotonic() - wall0, rospy.get_time() - sim0
    burst.stop()
    time.sleep(2.0)

    # -- figures ----------------------------------------------------------------------
    with mon.lock:
        received, gaps = dict(mon.received), dict(mon.gaps)
        status = dict(mon.status)
        lat = {k: list(v) for k, v in mon.lat.items()}
    lost_inputs = {t: sent[t] - received.get(t, 0) for t in ('/leapmotion/data_right',
                                                             '/leapmotion/data_left',
                                                             '/drone/leapmotion/hand_right')}
    rejected = {arm: int(s.rejected_inputs) for arm, s in status.items()}
    with mon.lock:
        rejected.update({n: v for n, v in mon.diag_rejected.items() if 'pilot' in n})
        got = dict(mon.consumer_received)
        resubscribed = dict(mon.resubscriptions)
        judged_afresh = dict(mon.judged_afresh)
    # What each consumer itself received from the player, against what the player sent on
    # its topic (a consumer that never reported counts as having received nothing).
    got = _per_consumer(got)
    lost_by_consumer = {c: sent[topic] - got.get(c, 0) for c, topic in CONSUMERS.items()}
    dropped = sum(lost_inputs.values()) + sum(gaps.values()) + sum(lost_by_consumer.values())
    # What the consumers saw missing in the player's numbering, and of it what went missing
    # after the load burst (from the start of the first cycle after it).
    with mon.lock:
        missed_msgs = _per_consumer(mon.consumer_missed)
        missed_reconnect = _per_consumer(mon.consumer_missed_reconnect)
    after = burst.after(cycles)
    baseline = missed_at_start[after[0]] if after else {}
    missed_after = ({c: n - baseline.get(c, 0) for c, n in missed_msgs.items()} if after
                    else {})
    growth = {}
    for n, samples in rss.items():
        if len(samples) >= 2 and samples[0][1] > 0:
            growth[n] = 100.0 * (samples[-1][1] - samples[0][1]) / samples[0][1]
    k = max(1, min(5, cycles // 3))

    def drift(key):
        xs = lat.get(key, [])
        first = [v for c, v in xs if c < k]
        last = [v for c, v in xs if c >= cycles - k]
        if not first or not last:
            return float('nan'), float('nan'), float('nan')
        return (1e3 * statistics.median(first), 1e3 * statistics.median(last),
                1e3 * (statistics.median(last) - statistics.median(first)))
    arm_first, arm_last, arm_drift = drift('arm')
    dr_first, dr_last, dr_drift = drift('drone')
    log('\n[soak] %.1f sim minutes in %.1f wall minutes: x%.2f' % (sim / 60, wall / 60,
                                                                    sim / wall))
    log('[soak] RSS growth per node (first cycle -> end):')
    for n in sorted(growth):
        log('  %-28s %7.0f kB -> %7.0f kB  %+6.2f %%' % (n, rss[n][0][1], rss[n][-1][1], growth[n]))
    log('[soak] hand -> arm command latency p50: first %d cycles %.2f ms, last %d %.2f ms '
        '(drift %+.2f ms); p99 overall %.2f ms' % (k, arm_first, k, arm_last, arm_drift,
                                                   1e3 * percentile([v for _, v in lat.get('arm', [])], 99)))
    log('[soak] hand -> cmd_vel latency p50: first %.2f ms, last %.2f ms (drift %+.2f ms)'
        % (dr_first, dr_last, dr_drift))
    log('[soak] lost inputs (the monitor) %s, lost per consumer (their own counts) %s, '
        'sequence gaps %s, rejected by the nodes %s, re-subscriptions %s, input judged '
        'afresh on its connection %s'
        % (lost_inputs, lost_by_consumer, gaps, rejected, resubscribed, judged_afresh))
    log('[soak] missed per consumer (gaps in the player\'s numbering, their own counts) %s; '
        'of them across their re-subscriptions %s; after the load burst %s'
        % (missed_msgs, missed_reconnect, missed_after))
    log('[soak] pick and place: %d/%d cubes placed; %d drone takeoffs in %d cycles'
        % (sum(placed), 2 * cycles, flights, cycles))
    # A cycle flew when the drone took off (the gesture topic) and the pilot steered it
    # from the hand (a moving cmd_vel after hand input; the hand topic is its own
    # connection, which can fail while the gestures still arrive).
    with mon.lock:
        flown = ({c for c, s in mon.nav_states if s == 6}
                 & {c for c, _ in lat.get('drone', [])})
    placed_after = sum(placed[c] for c in after)
    flown_after = sum(1 for c in after if c in flown)
    log('[soak] after the load burst (%d cycles): %d/%d cubes placed, %d/%d cycles flew'
        % (len(after), placed_after, 2 * len(after), flown_after, len(after)))
    figures = {
        'soak.rss_growth_pct': max(growth.values()) if growth else float('nan'),
        'soak.dropped_msgs': dropped,
        'soak.consumer_lost_msgs': sum(lost_by_consumer.values()),
        'soak.consumer_missed_msgs': sum(missed_msgs.values()),
        'soak.consumer_missed_after_burst_msgs': (sum(missed_after.values()) if after
                                                  else float('nan')),
        'soak.consumer_missed_across_resubscriptions_msgs': sum(missed_reconnect.values()),
        'soak.resubscriptions': sum(resubscribed.values()),
        'soak.judged_afresh': sum(judged_afresh.values()),
        'soak.rejected_inputs': sum(rejected.values()),
        'soak.sim_minutes': sim / 60.0,
        'soak.sim_wall_ratio': sim / wall,
        'soak.arm_latency_p50_ms': arm_last,
        'soak.arm_latency_drift_ms': arm_drift,
        'soak.drone_latency_drift_ms': dr_drift,
        'soak.pick_place_success_pct': 100.0 * sum(placed) / (2 * cycles),
        'soak.pick_place_after_burst_pct': (100.0 * placed_after / (2 * len(after))
                                            if after else float('nan')),
        'soak.flights_after_burst_pct': (100.0 * flown_after / len(after)
                                         if after else float('nan')),
    }
    run_of = ('%d cycles, %.1f sim minutes at x%.2f; player queue %d; load burst %s' % (
                  cycles, sim / 60.0, sim / wall, player_queue,
                  'of %.1f wall minutes' % (burst.seconds / 60.0) if burst.seconds > 0 else 'none'))
    nodes = ', '.join(sorted(growth)) or 'no node sampled twice'
    sources = {
        'soak.rss_growth_pct': 'VmRSS of each node after cycle 1 vs the end, the largest '
                               'growth (%s)' % nodes,
        'soak.dropped_msgs': 'hand messages sent minus received by the monitor %s and by '
                             'each consumer %s, plus sequence gaps %s'
                             % (lost_inputs, lost_by_consumer, gaps),
        'soak.consumer_lost_msgs': 'hand messages the player sent minus what each consumer '
                                   'counted from it (its /diagnostics) %s' % lost_by_consumer,
        'soak.consumer_missed_msgs': 'gaps in the header numbers of the player\'s hand '
                                     'messages, each consumer\'s own count (its /diagnostics) '
                                     '%s' % missed_msgs,
        'soak.consumer_missed_after_burst_msgs': 'the same, counted from the start of the '
                                                 'first cycle after the load burst (every '
                                                 'cycle without one) %s' % missed_after,
        'soak.consumer_missed_across_resubscriptions_msgs': 'of the consumers\' missed '
                                                            'messages, the gaps across a '
                                                            're-subscription (what the old '
                                                            'connection held and what was sent '
                                                            'while the new one formed) %s'
                                                            % missed_reconnect,
        'soak.resubscriptions': 'hand connections the consumers re-established %s'
                                % resubscribed,
        'soak.judged_afresh': 'times the consumers judged their late input afresh on its '
                              'connection %s' % judged_afresh,
        'soak.rejected_inputs': 'ArmStatus.rejected_inputs and the pilots\' diagnostics %s'
                                % rejected,
        'soak.sim_minutes': '/clock of the UR10 simulator',
        'soak.sim_wall_ratio': '/clock over monotonic wall time',
        'soak.arm_latency_p50_ms': 'the monitor\'s wall time from its latest hand message to '
                                   'each arm command (the arm\'s periodic ones too) within 0.5 '
                                   's of it, median of the last %d cycles (%d samples in all)'
                                   % (k, len(lat.get('arm', []))),
        'soak.arm_latency_drift_ms': 'arm latency median: last %d cycles minus first %d' % (k, k),
        'soak.drone_latency_drift_ms': 'the monitor\'s wall time from its latest hand message '
                                       'to each moving cmd_vel, median: last %d cycles minus '
                                       'first %d (%d samples)' % (k, k, len(lat.get('drone', []))),
        'soak.pick_place_success_pct': 'cubes in their trays after each cycle (%d/%d)'
                                       % (sum(placed), 2 * cycles),
        'soak.pick_place_after_burst_pct': 'cubes in their trays after each cycle that began '
                                           'after the load burst (%d/%d)'
                                           % (placed_after, 2 * len(after)),
        'soak.flights_after_burst_pct': 'cycles that began after the load burst with a '
                                        'takeoff and hand steering (%d/%d)'
                                        % (flown_after, len(after)),
    }
    return figures, {key: '%s; %s' % (text, run_of) for key, text in sources.items()}


def main(argv=None):
    from tools.bench.results import finite_figures, utc_now, write_results
    ap = argparse.ArgumentParser(prog='python -m tools.soak',
                                 description=__doc__.split('\n\n')[0])
    ap.add_argument('--minutes', type=float, default=30.0, help='simulated minutes')
    # Faster than real time, the graph alone keeps two cores near saturation (x1.2 of
    # the x1.5 asked): real time leaves it the margin a robot's computer would have.
    ap.add_argument('--rtf', type=float, default=1.0,
                    help='sim time / wall time target, 0.25-10 within the timeouts\' bounds (default real time)')
    ap.add_argument('--rate', type=float, default=None, help='hand frame rate, Hz '
                    '(default the scripts\' 120)')
    ap.add_argument('--player-queue', type=int, default=2000,
                    help='the player\'s publisher queue per connection (default 2000)')
    ap.add_argument('--hand-queue', type=int, default=500,
                    help='the consumers\' ~hand_queue_size (default 500, the nodes\' default)')
    ap.add_argument('--command-queue', type=int, default=50,
                    help='the arm nodes\' ~command_queue_size (default 50, their default)')
    ap.add_argument('--joint-states-queue', type=int, default=100,
                    help='the simulator\'s ~joint_states_queue_size (default 100, its default)')
    ap.add_argument('--burst-minutes', type=float, default=0.0,
                    help='load burst in the first wall minutes: CPU hogs and a second ROS '
                         'graph (default 0: none)')
    ap.add_argument('--burst-hogs', type=int, default=2, help='CPU hogs in the burst')
    ap.add_argument('--resubscribe-after', type=float, default=0.5,
                    help='the consumers\' ~resubscribe_after, wall s (default 0.5, the '
                         'nodes\' default; 0 = never)')
    ap.add_argument('--out', default='soak_results.json')
    args = ap.parse_args(argv)
    for name, value, lo, hi in (('--rtf', args.rtf, 0.25, 10.0),
                                ('--player-queue', args.player_queue, 1, 100000),
                                ('--hand-queue', args.hand_queue, 1, 2000),
                                ('--command-queue', args.command_queue, 1, 2000),
                                ('--joint-states-queue', args.joint_states_queue, 1, 2000),
                                ('--burst-minutes', args.burst_minutes, 0.0, 60.0),
                                ('--burst-hogs', args.burst_hogs, 0, 16),
                                ('--resubscribe-after', args.resubscribe_after, 0.0, 60.0)):
        if not lo <= value <= hi:
            ap.error('%s must be between %g and %g, not %g' % (name, lo, hi, value))
    # the graph's timeouts are sim seconds, scaled by --rtf: each within its node's bounds
    problem = timeouts_problem(args.rtf, args.resubscribe_after)
    if problem:
        ap.error(problem)
    run_info = {'started': utc_now(), 'minutes': args.minutes, 'rtf': args.rtf,
                'rate_hz': args.rate, 'player_queue': args.player_queue,
                'hand_queue': args.hand_queue, 'command_queue': args.command_queue,
                'joint_states_queue': args.joint_states_queue, 'burst_minutes': args.burst_minutes,
                'burst_hogs': args.burst_hogs, 'resubscribe_after': args.resubscribe_after}
    figures, sources, failed = {}, {}, {}
    # A plain kill ends the soak as Ctrl-C does: its graph and load burst are stopped.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    try:
        figures, sources = run(args.minutes, args.rtf, args.rate,
                               log=lambda s: print(s, flush=True),
                               player_queue=args.player_queue, hand_queue=args.hand_queue,
                               command_queue=args.command_queue,
                               joint_states_queue=args.joint_states_queue,
                               burst_minutes=args.burst_minutes, burst_hogs=args.burst_hogs,
                               resubscribe_after=args.resubscribe_after)
    except (Exception, SystemExit) as e:     # noqa: BLE001 - recorded in _failed, exit 1
        traceback.print_exc()
        failed['soak'] = '%s: %s' % (type(e).__name__, e)
    figures, not_measured = finite_figures(figures)
    failed.update(not_measured)
    sources = {key: sources[key] for key in figures}
    # A fresh file per run: a failed soak leaves no earlier run's figures behind.
    write_results(args.out, figures, sources, failed, run_info)
    print('[soak] wrote %s (%d figures from this run)' % (args.out, len(figures)), flush=True)
    if failed:
        print('[soak] failed: %s' % '; '.join('%s (%s)' % kv for kv in sorted(failed.items())),
              file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
