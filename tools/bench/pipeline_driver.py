"""Benchmark driver for capture-to-command latency (run as its own process, beside one
gated sender, one ur10_arm node and the UR10 simulator under a private master).

Records the arm's ArmStatus stream (status time, input_stamp, state) and the measured
sender's Hand stamps, and gets the arm tracking on the measured hands. Arming is the only
input it makes up: with --inject-thumbs-up it holds a thumbs-up on the arm's hand topic
before the sender starts (a take without one); whenever the arm is armed on the sender's
hands it sends a short rock at the latest measured palm, so the origin is set where the
hand is (no shared take or clip shows a rock). Then it opens the sender's gate (subscribes
--gate: the sender waits for that) and records for --duration s from --warmup s after the
arm first tracks. Writes JSON.
"""
import argparse
import json
import threading
import time

import rospy
from geometry_msgs.msg import Point

from leap_teleop.msg import ArmStatus, Hand, leapcobotright
from leap_teleop.ros.signals import init_node

INJECT_HZ = 100.0
ROCK_MESSAGES = 5
ROCK_RETRY_S = 0.5             # wait this long for the arm to track before another rock
FRESH_HAND_S = 0.2             # a measured hand this recent counts as the hand now


class DriverRecord:
    """What the callbacks saw (they run on rospy's threads)."""

    def __init__(self):
        self.since = time.time()   # the latched status of an earlier round is older
        self.lock = threading.Lock()
        self.status = []           # (status stamp, input_stamp, state)
        self.hands = []            # (stamp, receipt, present)
        self.state = None
        self.first_tracking = None
        self.last_hand = None      # (receipt, present, palm mm)

    def on_status(self, msg):
        row = (msg.header.stamp.to_sec(), msg.input_stamp.to_sec(), msg.state)
        if row[0] < self.since:
            return
        with self.lock:
            self.status.append(row)
            self.state = msg.state
            if msg.state == 'tracking' and self.first_tracking is None:
                self.first_tracking = row[0]

    def on_hand(self, msg):
        now = time.time()
        p = msg.palm_position
        with self.lock:
            self.hands.append((msg.header.stamp.to_sec(), now, bool(msg.present)))
            self.last_hand = (now, bool(msg.present), (1000.0 * p.x, 1000.0 * p.y, 1000.0 * p.z))


def _cobot(palm_mm, **flags):
    msg = leapcobotright(is_right_hand=True)
    msg.right_hand_palmpos = Point(*palm_mm)
    for k, v in flags.items():
        setattr(msg, 'right_hand_' + k, v)
    msg.header.stamp = rospy.Time.now()
    return msg


def _wait(cond, timeout, what):
    deadline = time.monotonic() + timeout
    while not cond():
        if rospy.is_shutdown() or time.monotonic() > deadline:
            raise SystemExit('pipeline driver: %s within %.0f s' % (what, timeout))
        time.sleep(0.005)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--status-topic', default='/ur10_1/ur10_arm/status')
    ap.add_argument('--hand-topic', default='/leapmotion/hand_right',
                    help='the measured sender\'s Hand topic (its stamps are the inputs)')
    ap.add_argument('--cobot-topic', default='/leapmotion/data_right',
                    help='the arm\'s hand topic (arming input goes there)')
    ap.add_argument('--gate', default='/bench/pipeline_go')
    ap.add_argument('--inject-thumbs-up', action='store_true')
    ap.add_argument('--duration', type=float, default=20.0)
    ap.add_argument('--warmup', type=float, default=1.0)
    ap.add_argument('--timeout', type=float, default=60.0,
                    help='s for the graph to come up and for the arm to track')
    ap.add_argument('--out', required=True)
    args = ap.parse_args(rospy.myargv()[1:])
    init_node('pipeline_bench_driver')
    rec = DriverRecord()
    rospy.Subscriber(args.status_topic, ArmStatus, rec.on_status, queue_size=1000,
                     tcp_nodelay=True)
    rospy.Subscriber(args.hand_topic, Hand, rec.on_hand, queue_size=1000, tcp_nodelay=True)
    pub = rospy.Publisher(args.cobot_topic, leapcobotright, queue_size=10, tcp_nodelay=True)
    _wait(lambda: pub.get_num_connections() > 0, args.timeout,
          'the arm node did not subscribe %s' % args.cobot_topic)
    time.sleep(0.5)
    home = (0.0, 250.0, 0.0)
    if args.inject_thumbs_up:
        # Held past arm_hold_s; on until the sender's first hand arrives (no gap in input).
        deadline = time.monotonic() + args.timeout
        while rec.state != 'armed':
            if time.monotonic() > deadline:
                raise SystemExit('pipeline driver: the injected thumbs-up did not arm the arm '
                                 '(state %s)' % rec.state)
            pub.publish(_cobot(home, thumb_up=True))
            time.sleep(1.0 / INJECT_HZ)
    gate = rospy.Subscriber(args.gate, rospy.AnyMsg)     # noqa: F841 (the sender starts)
    if args.inject_thumbs_up:
        deadline = time.monotonic() + args.timeout
        while rec.last_hand is None:
            if time.monotonic() > deadline:
                raise SystemExit('pipeline driver: no hand from the sender on %s'
                                 % args.hand_topic)
            pub.publish(_cobot(home))
            time.sleep(1.0 / INJECT_HZ)
    rocks = 0
    last_rock = -1e9
    deadline = time.monotonic() + args.timeout
    window = None
    while not rospy.is_shutdown():
        now = time.time()
        with rec.lock:
            state, hand, first = rec.state, rec.last_hand, rec.first_tracking
        if window is None:
            if first is not None:
                window = (first + args.warmup, first + args.warmup + args.duration)
            elif time.monotonic() > deadline:
                raise SystemExit('pipeline driver: the arm never tracked (last state %s, %d '
                                 'rocks sent)' % (state, rocks))
        elif now > window[1]:
            break
        if (state == 'armed' and hand is not None and hand[1] and now - hand[0] < FRESH_HAND_S
                and time.monotonic() - last_rock > ROCK_RETRY_S):
            for _ in range(ROCK_MESSAGES):
                pub.publish(_cobot(hand[2], set_origin_frame_detected=True))
                time.sleep(1.0 / INJECT_HZ)
            rocks += 1
            last_rock = time.monotonic()
        time.sleep(0.005)
    if window is None:
        raise SystemExit('pipeline driver: shut down before the arm tracked')
    with rec.lock:
        status = [r for r in rec.status if window[0] <= r[0] <= window[1]]
        hands = list(rec.hands)
    with open(args.out, 'w') as f:
        json.dump({'status': status, 'hands': hands, 'window': window, 'rocks': rocks,
                   'duration': args.duration}, f)
    rospy.signal_shutdown('done')


if __name__ == '__main__':
    main()
