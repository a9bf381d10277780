"""The drone's cameras: the AR.Drone 2.0's geometry, rendered views that show motion."""
import math
import os

import numpy as np
import pytest

from leap_teleop.drone import cameras
from leap_teleop.drone.cameras import BOTTOM, FRONT


def test_camera_geometry_is_the_ar_drone_2s():
    assert (FRONT.width, FRONT.height) == (640, 360)
    assert (BOTTOM.width, BOTTOM.height) == (320, 240)
    for spec, fov in ((FRONT, 92.0), (BOTTOM, 64.0)):
        half_diag = math.hypot(spec.width, spec.height) / 2
        assert math.degrees(2 * math.atan(half_diag / spec.focal_px)) == pytest.approx(fov)
        k, p = spec.intrinsics()
        assert k[0] == k[4] == p[0] == p[5] == pytest.approx(spec.focal_px)


@pytest.fixture(scope='module')
def renderer():
    r = cameras.SceneRenderer()
    yield r
    r.close()


def _yaw_quat(yaw):
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def test_front_camera_sees_the_horizon_and_moves_with_the_drone(renderer):
    a = renderer.render('front', (0.0, 0.0, 1.0), _yaw_quat(0.0))
    assert a.shape == (360, 640, 3)
    # Sky above, ground below: the top rows are blue-ish, the bottom rows green-ish.
    top, bottom = a[:20].reshape(-1, 3).mean(0), a[-20:].reshape(-1, 3).mean(0)
    assert top[2] > top[1] and bottom[1] > bottom[2]
    b = renderer.render('front', (0.5, 0.0, 1.0), _yaw_quat(0.0))      # 0.5 m forward
    c = renderer.render('front', (0.0, 0.0, 1.0), _yaw_quat(0.5))      # turned left
    for other in (b, c):
        assert np.abs(a.astype(int) - other).mean() > 3.0


def test_bottom_camera_looks_down_at_the_gridded_field(renderer):
    a = renderer.render('bottom', (0.3, 0.3, 1.0), _yaw_quat(0.0))
    assert a.shape == (240, 320, 3)
    assert a[:, :, 1].mean() > a[:, :, 2].mean()        # ground, no sky
    assert a.std() > 10                                 # grid lines / checker, not flat
    b = renderer.render('bottom', (0.6, 0.3, 1.0), _yaw_quat(0.0))
    assert np.abs(a.astype(int) - b).mean() > 3.0


def test_renderer_process_matches_in_process_rendering(renderer):
    proc = cameras.RendererProcess()
    try:
        pose = ((1.0, -0.5, 1.2), _yaw_quat(0.3))
        out = proc.render(*pose, ['front', 'bottom'])
    finally:
        proc.close()
    assert proc.proc is None
    for name in ('front', 'bottom'):
        np.testing.assert_array_equal(out[name], renderer.render(name, *pose))


def test_camera_loop_keeps_its_rate_delivers_and_stops():
    got = []
    pose = ((0.0, 0.0, 1.0), _yaw_quat(0.0), 'ctx')
    loop = cameras.CameraLoop({'bottom': 4.0, 'front': 0.0}, lambda: pose,
                              lambda name, rgb, ctx: got.append((name, rgb.shape, ctx)))
    loop.start()
    try:
        assert loop.ready.wait(60.0)
        n0 = loop.frames['bottom']
        import time
        time.sleep(2.0)
        n = loop.frames['bottom'] - n0
    finally:
        loop.stop()
    assert 'front' not in loop.frames                      # rate 0: never rendered
    assert 2 <= n <= 9, n                                  # ~4 Hz, never a burst
    assert got and all(g == ('bottom', (240, 320, 3), 'ctx') for g in got)
    assert not loop.thread.is_alive() and loop.renderer.proc is None


def test_camera_loop_replaces_a_dead_renderer():
    errors, got = [], []
    loop = cameras.CameraLoop({'bottom': 5.0}, lambda: ((0.0, 0.0, 1.0), _yaw_quat(0.0), None),
                              lambda name, rgb, ctx: got.append(name), errors.append)
    loop.start()
    try:
        assert loop.ready.wait(60.0)
        first = loop.renderer
        first.proc.kill()                                   # the renderer process dies
        import time
        deadline = time.monotonic() + 30.0
        n = len(got)
        while time.monotonic() < deadline and not (errors and len(got) > n + 1):
            time.sleep(0.1)
    finally:
        loop.stop()
    assert errors and loop.renderer is not first and len(got) > n + 1


def test_camera_loop_stops_at_once_with_its_renderer_stuck():
    # A renderer stuck (or still starting: its first frame may take 30 s) held the stop
    # for its whole timeout and then 5 s more: past roslaunch's 15 s before SIGTERM.
    import signal
    import time
    loop = cameras.CameraLoop({'bottom': 20.0}, lambda: ((0.0, 0.0, 1.0), _yaw_quat(0.0), None),
                              lambda name, rgb, ctx: None)
    loop.start()
    try:
        assert loop.ready.wait(60.0)
        proc = loop.renderer.proc
        os.kill(proc.pid, signal.SIGSTOP)
        time.sleep(0.5)                                   # a frame is asked for and waits
    finally:
        started = time.monotonic()
        loop.stop()
        took = time.monotonic() - started
    assert took < 3.0 and not loop.thread.is_alive() and proc.poll() is not None, took


def test_chase_snapshots_close_at_once_with_a_picture_under_way():
    # close() waited for the lock a stuck take held for its whole timeout (30 s in the
    # simulator): past roslaunch's 15 s between Ctrl-C and SIGTERM.
    import signal
    import threading
    import time
    shots = cameras.ChaseSnapshots(timeout=30.0)
    pose = ((0.0, 0.0, 1.0), _yaw_quat(0.0))
    assert shots.take(*pose, width=64, height=48).shape == (48, 64, 3)
    proc = shots.renderer.proc
    os.kill(proc.pid, signal.SIGSTOP)
    failed = []

    def take():
        try:
            shots.take(*pose, width=64, height=48)
        except RuntimeError as e:
            failed.append(e)
    taker = threading.Thread(target=take)
    taker.start()
    time.sleep(0.3)                                   # the picture is asked for and waits
    started = time.monotonic()
    shots.close()
    took = time.monotonic() - started
    taker.join(5.0)
    assert took < 3.0 and failed and not taker.is_alive() and proc.poll() is not None, took
    with pytest.raises(RuntimeError, match='shutting down'):
        shots.take(*pose)                              # no renderer started after close


def test_chase_snapshots_closed_while_their_renderer_starts_stop_at_once(monkeypatch):
    # close() came while take() was still making its renderer: nothing was there to kill,
    # and close() waited the take's whole timeout.
    import threading
    import time
    made = []

    class SlowToStart(cameras.RendererProcess):
        def __init__(self):
            time.sleep(0.5)
            super().__init__()
            made.append(self)
    monkeypatch.setattr(cameras, 'RendererProcess', SlowToStart)
    shots = cameras.ChaseSnapshots(timeout=30.0)
    failed = []
    taker = threading.Thread(target=lambda: failed.append(
        pytest.raises(RuntimeError, shots.take, (0.0, 0.0, 1.0), _yaw_quat(0.0), None, 64, 48)))
    taker.start()
    time.sleep(0.2)
    started = time.monotonic()
    shots.close()
    took = time.monotonic() - started
    taker.join(5.0)
    assert took < 3.0 and failed and 'shutting down' in str(failed[0].value), took
    assert made and made[0].proc is None and shots.renderer is None


CAMERA_SHAPES = {n: (c.height, c.width, 3) for n, c in cameras.CAMERAS.items()}


class _LateFirstRenderer:
    """A stand-in renderer process whose first answer (scene set-up) comes too late: the
    request times out and its answer is read as the answer to the next request."""
    made, timeouts = [], []

    def __init__(self):
        self.pending = None                 # the late answer still in the pipe
        self.proc = object()
        _LateFirstRenderer.made.append(self)

    def render(self, pos, quat, names, timeout=10.0):
        shows = pos[0]
        _LateFirstRenderer.timeouts.append(timeout)
        if len(_LateFirstRenderer.made) == 1 and self.pending is None:
            self.pending = shows
            raise RuntimeError('camera renderer did not answer in %.0f s' % timeout)
        if self.pending is not None:
            shows, self.pending = self.pending, shows
        return {n: np.full(CAMERA_SHAPES[n], int(shows), np.uint8) for n in names}   # shows its pose

    def close(self, wait=5.0):
        self.proc = None


def test_camera_loop_replaces_a_renderer_whose_first_frame_timed_out(monkeypatch):
    # The first answer, late, paired with the second request: every image after it showed
    # the pose of the request before, under the newer pose's stamp, for the whole run.
    _LateFirstRenderer.made.clear()
    _LateFirstRenderer.timeouts.clear()
    monkeypatch.setattr(cameras, 'RendererProcess', _LateFirstRenderer)
    monkeypatch.setattr(cameras.CameraLoop, 'RESTART_WAIT', 0.0, raising=False)
    asked, got, errors = [0], [], []

    def pose():
        asked[0] += 1
        return (float(asked[0]), 0.0, 1.0), _yaw_quat(0.0), asked[0]
    loop = cameras.CameraLoop({'bottom': 20.0}, pose,
                              lambda name, rgb, ctx: got.append((ctx, int(rgb[0, 0, 0]))),
                              errors.append)
    loop.start()
    try:
        assert loop.ready.wait(10.0)
        import time
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline and len(got) < 3:
            time.sleep(0.02)
    finally:
        loop.stop()
    assert len(errors) == 1 and len(got) >= 3
    assert all(stamp == shows for stamp, shows in got), got
    assert len(_LateFirstRenderer.made) == 2 and _LateFirstRenderer.made[0].proc is None
    # each renderer's first answer is given its start-up time, the others a frame's
    start, frame = cameras.CameraLoop.START_TIMEOUT, cameras.CameraLoop.FRAME_TIMEOUT
    assert _LateFirstRenderer.timeouts[:3] == [start, start, frame]
