"""Source stamps on the caller's clock: the recorded or device timing in real time, shifted
only by how far a faster clock (a simulator under /use_sim_time) runs ahead of it."""
import time

import numpy as np

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.sources import leapjs, make_source


def _recording(tmp_path, n, dt):
    frames = [leapjs.frame_to_dict(Frame(i, 5.0 + i * dt, [render_hand('right', 'open', (i, 200, 0))]))
              for i in range(n)]
    path = str(tmp_path / 'r.json')
    leapjs.save(path, frames)
    return path


def test_a_recording_in_real_time_keeps_its_recorded_timing_and_a_stalls_lateness(tmp_path):
    # Stamped at release instead, the stamps carried the pacing's jitter, and the backlog
    # after a consumer stall came stamped microseconds apart: speeds from the stamps read
    # 7-20 m/s and the arm's lateness guard saw fresh frames.
    path = _recording(tmp_path, 40, 0.01)
    stamps, lags = [], []
    for k, f in enumerate(make_source('recording', path=path, realtime=True, clock=time.time).frames()):
        stamps.append(f.timestamp)
        lags.append(time.time() - f.timestamp)
        if k == 10:
            time.sleep(0.25)                  # the consumer stalls once
    assert len(stamps) == 40
    np.testing.assert_allclose(np.diff(stamps), 0.01, atol=1e-6)
    # the frames held back by the stall reach the consumer late, and read late
    assert min(lags[11:20]) > 0.15 and max(lags[:10]) < 0.05
