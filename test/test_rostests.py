"""Runs every rostest (.test file in this folder) under its own private master."""
import glob
import os
import re
import subprocess
from xml.etree import ElementTree

import pytest

from leap_teleop.hands.gestures.datasets import HANDS_DATA, data_dir

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

HERE = os.path.dirname(os.path.abspath(__file__))
# Run elsewhere, on a bag recorded from the real sender (test_record_replay.py), and not
# a second time here on the checker's own bag: ur10_teleop_rotated.test runs that path on
# the same launch file and checker.
RUN_ON_A_RECORDED_BAG = ('ur10_teleop_dual.test',)
TESTS = sorted(t for t in glob.glob(os.path.join(HERE, '*.test'))
               if os.path.basename(t) not in RUN_ON_A_RECORDED_BAG)
TIMEOUT_S = 300


@pytest.mark.rostest
@pytest.mark.parametrize('test_file', TESTS, ids=[os.path.basename(t) for t in TESTS])
def test_rostest(test_file, tmp_path):
    env = dict(os.environ, ROS_LOG_DIR=str(tmp_path / 'log'))
    args = []
    with open(test_file) as f:
        if 'name="leapjs_data"' in f.read():      # it plays the shared recordings (and
            args.append('leapjs_data:=%s' % data_dir())   # fails when they are missing)
    if 'name="hands_data"' in open(test_file).read():   # real hand clips: fails if absent
        args.append('hands_data:=%s' % HANDS_DATA)
    proc = subprocess.run(
        # Not --text: with it rostest exits 0 even when a test fails.
        ['rostest', '--results-base-dir', str(tmp_path / 'results'), test_file] + args,
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env, timeout=TIMEOUT_S)
    output = proc.stdout.decode(errors='replace')
    assert proc.returncode == 0, 'rostest %s failed:\n%s' % (os.path.basename(test_file),
                                                           output[-8000:])
    check_every_test_passed(test_file, output)


def test_the_rostests_run_elsewhere_are_run_there():
    with open(os.path.join(HERE, 'test_record_replay.py')) as f:
        replay = f.read()
    for name in RUN_ON_A_RECORDED_BAG:
        assert os.path.exists(os.path.join(HERE, name)), name
        assert "'%s'" % name in replay, name


def check_every_test_passed(test_file, output):
    """rostest's summary says SUCCESS, and every <test> node of the file ran at least one
    test case that passed: a node that ran none (no test methods, a bad test-name) would
    still give SUCCESS."""
    assert re.search(r'RESULT: (\x1b\[\d+m)?SUCCESS', output), output[-8000:]
    names = [t.get('test-name') for t in ElementTree.parse(test_file).getroot().iter('test')]
    assert names, '%s has no <test>' % test_file
    for name in names:
        assert re.search(r'\[[\w.]+-%s/\w+\]\[passed\]' % re.escape(name), output), (
            'no passed test case of %s:\n%s' % (name, output[-8000:]))
    total = int(re.search(r'\* TESTS: (\d+)', output).group(1))
    assert total >= len(names), output[-8000:]
