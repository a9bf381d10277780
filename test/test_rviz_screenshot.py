"""RViz draws the UR10: rviz/ur10.rviz under Xvfb, screenshot, robot pixels counted (and,
last, the leap_motion driver's hand markers in rviz/leap_motion.rviz the same way).

Two RViz windows on two virtual screens watch the same private-master graph
(launch/ur10_sim.launch): one started by the launch file's rviz:=true with the shipped
config, one with the same config but the RobotModel display disabled. Inside the 3D
view, the pixels that differ between the two are what the robot model drew; they must
cover a robot-sized area near the view's centre and include the UR10's blue joint caps,
while the reference view has none of those. rviz, Xvfb and Pillow with XCB come with
make setup: without them the test fails (a skip would let a broken setup pass).
"""
import contextlib
import os
import re
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest
import yaml

from tools.bench.ros_processes import free_port

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))
CONFIG = os.path.join(HERE, '..', 'rviz', 'ur10.rviz')
SCREEN = (1280, 900)
BACKGROUND = np.array([48, 48, 48])   # the config's Background Color
MIN_ROBOT_PIXELS = 3000               # ~0.5 % of the 3D view; the arm covers ~7600
MIN_BLUE_PIXELS = 150                 # the UR10's light-blue joint caps
DEADLINE_S = 45.0


def _need(tool, package):
    assert shutil.which(tool), ('%s not found: install the Debian package %s (tools/setup.sh '
                                'does)' % (tool, package))


def _start_xvfb():
    """An Xvfb on a free display number; returns (process, ':N')."""
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen(['Xvfb', '-displayfd', str(write_fd), '-screen', '0',
                             '%dx%dx24' % SCREEN, '-nolisten', 'tcp'],
                            pass_fds=(write_fd,), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    os.close(write_fd)
    with os.fdopen(read_fd) as f:
        number = f.readline().strip()
    if not number:
        proc.kill()
        pytest.fail('Xvfb did not start')
    return proc, ':' + number


def _grab(display):
    from PIL import ImageGrab
    return np.asarray(ImageGrab.grab(xdisplay=display).convert('RGB')).astype(np.int16)


def _view_box(img):
    """Rows / columns of RViz's 3D view: where the background colour dominates."""
    bg = np.abs(img - BACKGROUND).sum(axis=2) <= 6
    rows, cols = np.nonzero(bg.mean(axis=1) > 0.3)[0], np.nonzero(bg.mean(axis=0) > 0.3)[0]
    if len(rows) < 200 or len(cols) < 200:
        return None
    return rows[0], rows[-1] + 1, cols[0], cols[-1] + 1


def _bluish(img):
    """The UR10 caps' steel blue (r < g < b); not TF's pure blue axes (r == g)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (b > r + 25) & (g > r + 12) & (b > 70)


def measure(robot_img, ref_img):
    """Robot pixels in the 3D view (robot_img vs the no-robot reference) and where."""
    box = _view_box(ref_img)
    if box is None or _view_box(robot_img) is None:
        return None
    r0, r1, c0, c1 = box
    robot, ref = robot_img[r0:r1, c0:c1], ref_img[r0:r1, c0:c1]
    drawn = np.abs(robot - ref).sum(axis=2) > 60
    ys, xs = np.nonzero(drawn)
    h, w = drawn.shape
    return {'box': box, 'pixels': int(drawn.sum()),
            'blue': int((drawn & _bluish(robot)).sum()),
            'ref_blue': int(_bluish(ref).sum()),   # must stay ~0: no robot there
            'centre': ((xs.mean() / w, ys.mean() / h) if len(xs) else (None, None))}


def robot_drawn(m):
    if m is None or m['pixels'] < MIN_ROBOT_PIXELS or m['blue'] < MIN_BLUE_PIXELS:
        return False
    cx, cy = m['centre']
    return abs(cx - 0.5) < 0.25 and abs(cy - 0.5) < 0.25


def _stop(proc, sig=signal.SIGINT, wait=15):
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, sig)
        proc.wait(wait)
    except (subprocess.TimeoutExpired, ProcessLookupError):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(5)


def _reference_config(config, display_class, path):
    """`config` with every display of `display_class` disabled, written to `path`; returns
    those displays."""
    with open(config) as f:
        cfg = yaml.safe_load(f)
    displays = [d for d in cfg['Visualization Manager']['Displays']
                if d['Class'] == display_class]
    for d in displays:
        d['Enabled'] = False
    path.write_text(yaml.safe_dump(cfg))
    return displays


class RvizDied(Exception):
    """An RViz process ended by itself (under Xvfb's software GL it now and then crashes
    while it starts)."""


def _rviz_death(log_path):
    """roslaunch's line saying its rviz process died, or None."""
    with open(log_path, 'rb') as f:
        found = re.search(rb'\[rviz[^\]]*\] process has died[^\n]*', f.read())
    return found.group(0).decode(errors='replace') if found else None


def _retry_once_if_rviz_died(tmp_path, run):
    """run(directory) once more, in a fresh directory, if an RViz process crashed: the test
    is about what the shipped config draws, not about RViz's start-up. A second crash
    fails."""
    first = tmp_path / 'first'
    first.mkdir(parents=True)
    try:
        return run(first)
    except RvizDied as e:
        print('RViz died on the first attempt, trying once more: %s' % e)
    second = tmp_path / 'second'
    second.mkdir()
    try:
        return run(second)
    except RvizDied as e:
        pytest.fail('RViz died on both attempts (logs in %s): %s' % (tmp_path, e))


@contextlib.contextmanager
def _launch_beside_reference(tmp_path, launch_args, ref_config):
    """`roslaunch leap_teleop LAUNCH_ARGS` (its RViz on one Xvfb screen) and an RViz with
    `ref_config` on another, on a private master; yields grab() -> (the launched RViz's
    screen, the reference's), which fails once either has ended. Everything stops after."""
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI='http://127.0.0.1:%d' % port,
               ROS_LOG_DIR=str(tmp_path / 'log'), ROS_HOME=str(tmp_path),
               LIBGL_ALWAYS_SOFTWARE='1', XDG_RUNTIME_DIR=str(tmp_path))
    procs = []
    launch = ref = log = None
    try:
        xa, display_a = _start_xvfb()
        procs.append(xa)
        xb, display_b = _start_xvfb()
        procs.append(xb)
        log = open(tmp_path / 'roslaunch.log', 'wb')
        launch = subprocess.Popen(['roslaunch', '-p', str(port), 'leap_teleop'] + launch_args,
                                  env=dict(env, DISPLAY=display_a), stdout=log,
                                  stderr=subprocess.STDOUT, start_new_session=True)
        ref = subprocess.Popen(['rviz', '-d', str(ref_config)], env=dict(env, DISPLAY=display_b),
                               stdout=log, stderr=subprocess.STDOUT, start_new_session=True)

        def grab():
            assert launch.poll() is None, 'roslaunch ended: see %s' % (tmp_path / 'roslaunch.log')
            died = _rviz_death(tmp_path / 'roslaunch.log')
            if died or ref.poll() is not None:
                raise RvizDied(died or 'the reference rviz ended (%s)' % ref.returncode)
            return _grab(display_a), _grab(display_b)
        yield grab
    finally:
        _stop(ref, signal.SIGTERM)
        _stop(launch)
        for p in procs:
            _stop(p, signal.SIGTERM, 5)
        if log is not None:
            log.close()


def test_rviz_draws_the_ur10(tmp_path):
    _need('rviz', 'rviz')
    _need('Xvfb', 'xvfb')
    from PIL import features  # Pillow is pinned in tools/requirements.txt
    assert features.check('xcb'), 'Pillow was built without XCB: no X screenshots'

    ref_path = tmp_path / 'no_robot.rviz'
    assert _reference_config(CONFIG, 'rviz/RobotModel', ref_path), \
        'rviz/ur10.rviz has no RobotModel display'

    def run(directory):
        with _launch_beside_reference(directory, ['ur10_sim.launch', 'rviz:=true'],
                                      ref_path) as grab:
            start, m = time.monotonic(), None
            while time.monotonic() - start < DEADLINE_S:
                time.sleep(2.0)
                robot_img, ref_img = grab()
                m = measure(robot_img, ref_img)
                if robot_drawn(m):
                    break
        from PIL import Image
        Image.fromarray(robot_img.astype(np.uint8)).save(directory / 'rviz_ur10.png')
        Image.fromarray(ref_img.astype(np.uint8)).save(directory / 'rviz_no_robot.png')
        print('screenshots in %s: %r after %.1f s' % (directory, m, time.monotonic() - start))
        return m, ref_img

    m, ref_img = _retry_once_if_rviz_died(tmp_path, run)
    assert m is not None, 'no RViz 3D view found on the screen (screenshots under %s)' % tmp_path
    assert robot_drawn(m), 'robot not drawn: %r (screenshots under %s)' % (m, tmp_path)
    # The criterion can fail: the reference view has no robot-blue in it, and
    # compared with itself shows nothing drawn.
    assert not robot_drawn(measure(ref_img, ref_img))
    assert m['ref_blue'] < MIN_BLUE_PIXELS / 3, m

DRIVER_CONFIG = os.path.join(HERE, '..', 'rviz', 'leap_motion.rviz')
MIN_HAND_PIXELS = 400                 # bones, joints and palm of one hand at 0.8 m
MIN_RED_PIXELS = 40                   # the joint spheres


def _red(img):
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 150) & (g < 90) & (b < 90)


def test_rviz_draws_the_leap_motion_driver_markers(tmp_path):
    """leap_motion.launch rviz:=true: the driver visualizer's markers (the scripted hand)
    show in the shipped config, against the same config with the MarkerArray off."""
    _need('rviz', 'rviz')
    _need('Xvfb', 'xvfb')
    ref_path = tmp_path / 'no_markers.rviz'
    arrays = _reference_config(DRIVER_CONFIG, 'rviz/MarkerArray', ref_path)
    assert [d['Marker Topic'] for d in arrays] == ['/leap_motion/visualization_marker_array']

    def run(directory):
        with _launch_beside_reference(directory, ['leap_motion.launch', 'rviz:=true',
                                                  'loop:=true'], ref_path) as grab:
            start, best = time.monotonic(), None
            while time.monotonic() - start < DEADLINE_S:
                time.sleep(2.0)
                hand_img, ref_img = grab()
                box = _view_box(ref_img)
                if box is None or _view_box(hand_img) is None:
                    continue
                r0, r1, c0, c1 = box
                drawn = np.abs(hand_img[r0:r1, c0:c1] - ref_img[r0:r1, c0:c1]).sum(axis=2) > 60
                m = {'pixels': int(drawn.sum()),
                     'red': int((drawn & _red(hand_img[r0:r1, c0:c1])).sum()),
                     'ref_red': int(_red(ref_img[r0:r1, c0:c1]).sum())}   # TF's x axes only
                if best is None or m['pixels'] > best['pixels']:
                    best = m
                if m['pixels'] >= MIN_HAND_PIXELS and m['red'] >= MIN_RED_PIXELS:
                    break
        from PIL import Image
        Image.fromarray(hand_img.astype(np.uint8)).save(directory / 'rviz_hand.png')
        Image.fromarray(ref_img.astype(np.uint8)).save(directory / 'rviz_no_hand.png')
        return best

    best = _retry_once_if_rviz_died(tmp_path, run)
    assert best is not None, 'no RViz 3D view found (screenshots under %s)' % tmp_path
    assert best['pixels'] >= MIN_HAND_PIXELS and best['red'] >= MIN_RED_PIXELS, (
        'hand not drawn: %r (screenshots under %s)' % (best, tmp_path))
    assert best['ref_red'] < best['red'] / 3, best      # the red is the hand's joints
