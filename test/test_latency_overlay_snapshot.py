"""tools.latency_overlay_snapshot: when it takes the picture, how it tells the overlay's
lines and the hand are drawn, and (integration) the documented command on a real graph."""
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from tools.latency_overlay_snapshot import MIN_HAND_PIXELS, MIN_TEXT_LINES, hand_pixels, latency_ready, text_lines

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC_PICTURE = os.path.join(ROOT, 'docs', 'camera_latency.png')
SENDER = ('leap_sender: hand stages', 'published', 25.0, 80.0, 250)
ARM = ('ur10_1/ur10_arm: teleop', 'command', 40.0, 48.0, 2)


def _bgr(path):
    return np.asarray(Image.open(path).convert('RGB'))[:, :, ::-1]


def test_ready_needs_the_senders_and_an_arms_row_with_numbers():
    recognized = ('leap_sender: hand stages', 'recognized', 20.0, 70.0, 250)
    assert latency_ready([recognized, SENDER, ARM])
    assert not latency_ready([recognized, SENDER])
    assert not latency_ready([ARM])
    assert not latency_ready([SENDER, ARM[:2] + (None, None, 0)])       # arm: no samples
    assert not latency_ready([SENDER, ARM], min_commands=3)
    assert not latency_ready([SENDER, ('drone_pilot: pilot',) + ARM[1:]])


def test_the_doc_picture_has_the_hand_and_the_latency_lines():
    img = _bgr(DOC_PICTURE)
    assert img.shape == (480, 640, 3)
    assert os.path.getsize(DOC_PICTURE) < 150_000
    assert text_lines(img) >= MIN_TEXT_LINES
    assert hand_pixels(img) >= MIN_HAND_PIXELS
    # The criterion can fail: the camera view without latency lines has none, and a
    # blank image neither lines nor a hand.
    assert text_lines(_bgr(os.path.join(ROOT, 'docs', 'camera_view.png'))) == 0
    blank = np.zeros_like(img)
    assert text_lines(blank) == 0 and hand_pixels(blank) == 0


@pytest.mark.integration
def test_the_command_writes_the_overlay_picture(tmp_path):
    """The documented command on a real graph (fails when the shared clip is absent)."""
    out = tmp_path / 'camera_latency.png'
    run = subprocess.run([sys.executable, '-m', 'tools.latency_overlay_snapshot', str(out),
                          '--timeout', '120'], cwd=ROOT, capture_output=True, text=True,
                         timeout=240)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-3000:]
    assert 'ur10_1/ur10_arm: teleop' in run.stdout and 'published' in run.stdout, run.stdout
    img = _bgr(out)
    assert img.shape == (480, 640, 3) and out.stat().st_size > 20_000
    assert text_lines(img) >= MIN_TEXT_LINES and hand_pixels(img) >= MIN_HAND_PIXELS
    assert img.std() > 20          # a camera picture, not a flat fill
