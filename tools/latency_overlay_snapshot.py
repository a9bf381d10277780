"""Save the sender's annotated camera view with its latency lines, from a running graph.

A private master, the sender playing the shared clip of a fist then a thumbs-up through
MediaPipe (looping, at the clip's 25 frames/s, every frame processed, as ur10_single.launch
plays a video; with late frames dropped, one run at load 16 on 2 cores never armed the
arm), one ur10_arm and the UR10 simulator. The clip's thumbs-up arms the arm. Once
/diagnostics has the sender's capture -> published and the arm's capture -> command with numbers (the arm's over at
least MIN_COMMANDS commands, the first report WARM_S old) and the sender has had
SETTLE_S to hear them too, the next annotated image that shows the hand and at least
three latency lines is written as a PNG (palette colours, to keep it small).

usage: python -m tools.latency_overlay_snapshot OUT.png [--timeout S]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from leap_teleop.hands.camera_view import SIDE_COLOURS
from leap_teleop.hands.gestures.datasets import HANDS_DATA
from leap_teleop.package_files import package_path
from tools.bench import ros_processes

CLIP = 'clip_fist_then_thumbs_up__mps__gr_test_video.mp4'
IMAGE_TOPIC = '/camera/annotated'
HAND_TOPIC = '/leapmotion/data_right'       # the sender's default right-hand topic
SETTLE_S = 2.5              # the sender hears /diagnostics about once a second, as we do
MIN_HAND_PIXELS = 150       # skeleton and label in a side colour
MIN_TEXT_LINES = 3          # title, the sender's published, the arm's command
# The clip shows no rock, so the arm never tracks: it commands once or twice per pass of
# the clip, when the thumbs-up arms it; its row is a p50 / p99 of those few.
MIN_COMMANDS = 1
WARM_S = 12.0               # past the 10 s windows: MediaPipe's slow first frames left out


def _node(script, *args):
    return [sys.executable, package_path('scripts', script)] + list(args)


def graph_commands(clip):
    """The sender, arm and simulator command lines."""
    sender = _node('sender.py', '__name:=leap_sender', '_source:=video', '_video:=%s' % clip,
                   '_loop:=true', '_sides:=[right]',
                   '_wait_for_subscribers:=true',
                   '_annotated_image_topic:=%s' % IMAGE_TOPIC)
    # As camera_video_ur10.test: MediaPipe on a shared 2-core machine delivers some frames
    # later than the default max_input_age, and the thumbs-up must not be dropped.
    arm = _node('ur10_arm.py', '__name:=ur10_arm', '__ns:=ur10_1', '_hand:=right',
                '_hand_topic:=%s' % HAND_TOPIC, '_joint_prefix:=ur10_1_',
                '_max_joint_speed:=1.0', '_max_joint_accel:=3.14159', '_max_input_age:=1.0')
    sim = _node('ur10_sim.py', '__name:=ur10_sim')
    return [sim, arm, sender]


def latency_ready(rows, min_commands=MIN_COMMANDS):
    """True when the input-age rows [(name, stage, p50, p99, samples)] have the sender's
    published row and an arm's command row of at least `min_commands` samples, both with
    numbers."""
    def has(node, stage, n):
        return any(node in name and st == stage and p50 is not None and samples >= n
                   for name, st, p50, _, samples in rows)
    return has('leap_sender', 'published', 1) and has('ur10_arm', 'command', min_commands)


def hand_pixels(bgr, tol=12):
    """Pixels in a side's drawing colour (the hand's skeleton and label)."""
    img = bgr.astype(np.int16)
    return int(sum((np.abs(img - c).max(axis=2) <= tol).sum() for c in SIDE_COLOURS.values()))


def text_lines(bgr, rows=120):
    """Bands of white text rows bottom left of the image (the overlay's notes)."""
    h, w = bgr.shape[:2]
    white = (bgr[h - rows:, :w * 3 // 4] >= 200).all(axis=2).sum(axis=1) >= 3
    bands, inside, gap = 0, False, 0
    for row in white:
        if row:
            bands += not inside
            inside, gap = True, 0
        else:
            gap += 1
            inside = inside and gap < 6
    return bands


def capture(env, timeout):
    """Subscribe in this process on `env`'s master; the chosen BGR image, or None."""
    os.environ.update({k: env[k] for k in ('ROS_MASTER_URI', 'ROS_HOSTNAME', 'ROS_IP')})
    import rospy
    from sensor_msgs.msg import Image

    from leap_teleop.ros.latency_monitor import LatencyMonitor
    rospy.init_node('latency_overlay_snapshot', anonymous=True, disable_signals=True)
    monitor = LatencyMonitor()
    state = {'ready_at': None, 'image': None}
    first_heard = None

    def on_image(msg):
        if msg.encoding != 'bgr8' or state['image'] is not None:
            return
        ready = state['ready_at']
        if ready is None or time.monotonic() < ready + SETTLE_S:
            return
        img = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)[:, :msg.width * 3]
        img = img.reshape(msg.height, msg.width, 3)
        if hand_pixels(img) >= MIN_HAND_PIXELS and text_lines(img) >= MIN_TEXT_LINES:
            state['image'] = img.copy()

    rospy.Subscriber(IMAGE_TOPIC, Image, on_image, queue_size=2, buff_size=2 ** 22)
    deadline = time.monotonic() + timeout
    while state['image'] is None and time.monotonic() < deadline:
        rows = monitor.rows()
        if first_heard is None and rows:
            first_heard = time.monotonic()
        if (state['ready_at'] is None and first_heard is not None
                and time.monotonic() - first_heard >= WARM_S and latency_ready(rows)):
            state['ready_at'] = time.monotonic()
        time.sleep(0.1)
    rospy.signal_shutdown('done')
    if state['image'] is not None:
        print(monitor.table())      # what the overlay's lines were drawn from
    return state['image']


def save_png(bgr, path):
    from PIL import Image
    Image.fromarray(bgr[:, :, ::-1]).quantize(colors=128).save(path, optimize=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('out', help='PNG to write')
    ap.add_argument('--timeout', type=float, default=150.0,
                    help='s to wait for the picture once the graph is started')
    args = ap.parse_args(argv)
    clip = os.path.join(HANDS_DATA, CLIP)
    if not os.path.isfile(clip):
        print('latency_overlay_snapshot: shared clip %s absent (set HANDS_DATA)' % clip,
              file=sys.stderr)
        return 2
    with ros_processes.ros_master() as env, tempfile.TemporaryFile() as log:
        # The nodes' output goes to a file (a pipe nobody reads could fill and block them).
        procs = [subprocess.Popen(cmd, env=env, stdout=log, stderr=log)
                 for cmd in graph_commands(clip)]
        try:
            img = capture(env, args.timeout)
        finally:
            for p in reversed(procs):
                ros_processes.stop_spawned(p)
        if img is None:
            log.seek(0)
            sys.stderr.write(log.read()[-3000:].decode(errors='replace'))
    if img is None:
        print('latency_overlay_snapshot: no annotated image with the hand and the sender\'s '
              'and arm\'s latency lines within %.0f s' % args.timeout, file=sys.stderr)
        return 1
    save_png(img, args.out)
    print('latency_overlay_snapshot: wrote %s' % args.out)
    return 0


if __name__ == '__main__':
    sys.exit(main())
