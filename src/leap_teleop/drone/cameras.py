"""The AR.Drone 2.0's cameras, rendered by PyBullet's CPU renderer (no GPU needed).

Front camera 640x360 with a ~92 degree (diagonal) field of view looking forward, bottom
camera 320x240 with ~64 degrees looking down, image top toward the nose. A camera is
rendered from a drone pose (position, quaternion) in a PyBullet client that holds only
the scene (`scene.add_bodies`), so rendering never touches the physics client.
`RendererProcess` runs that client in a process of its own: PyBullet holds the GIL while
it renders, so a renderer thread would stall the physics loop for tens of milliseconds.

Also here: `chase_view`, the picture a person reads (a camera behind and above the
drone looking along its heading, ground texture and horizon in view), and
`ChaseSnapshots`, which has a renderer process draw it (with the drone's body) from a
copied pose, so a snapshot never holds the simulator.
"""
import math
import os
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from multiprocessing.connection import Connection

import numpy as np
import pybullet as pb

from leap_teleop.drone import scene


@dataclass(frozen=True)
class CameraSpec:
    name: str
    width: int
    height: int
    fov_diag_deg: float            # diagonal field of view
    mount: tuple                   # optical centre in the body frame, m
    forward: tuple                 # viewing direction in the body frame
    up: tuple                      # image "up" in the body frame
    near: float = 0.05
    far: float = 120.0

    @property
    def focal_px(self):
        """Pinhole focal length (px) giving the diagonal field of view."""
        half_diag = 0.5 * math.hypot(self.width, self.height)
        return half_diag / math.tan(math.radians(self.fov_diag_deg) / 2)

    @property
    def fov_vertical_deg(self):
        return math.degrees(2 * math.atan(0.5 * self.height / self.focal_px))

    def intrinsics(self):
        """(K row-major 3x3, P row-major 3x4) of the ideal, distortion-free pinhole."""
        f, cx, cy = self.focal_px, (self.width - 1) / 2.0, (self.height - 1) / 2.0
        return ((f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0),
                (f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0))


FRONT = CameraSpec('front', 640, 360, 92.0, (0.21, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0))
BOTTOM = CameraSpec('bottom', 320, 240, 64.0, (0.0, -0.02, 0.0), (0.0, 0.0, -1.0),
                    (1.0, 0.0, 0.0))
CAMERAS = {c.name: c for c in (FRONT, BOTTOM)}


def _rotate(rot, v):
    return (rot[0] * v[0] + rot[1] * v[1] + rot[2] * v[2],
            rot[3] * v[0] + rot[4] * v[1] + rot[5] * v[2],
            rot[6] * v[0] + rot[7] * v[1] + rot[8] * v[2])


def render(client, spec, pos, quat):
    """The camera's RGB image (height, width, 3) uint8 seen from a drone pose."""
    rot = pb.getMatrixFromQuaternion(quat, physicsClientId=client)
    eye = np.add(pos, _rotate(rot, spec.mount))
    target = eye + np.asarray(_rotate(rot, spec.forward))
    view = pb.computeViewMatrix(eye.tolist(), target.tolist(), _rotate(rot, spec.up),
                                physicsClientId=client)
    proj = pb.computeProjectionMatrixFOV(spec.fov_vertical_deg, spec.width / float(spec.height),
                                         spec.near, spec.far, physicsClientId=client)
    return _rgb(client, spec.width, spec.height, view, proj)


def chase_view(client, pos, yaw, width=480, height=360, behind=2.2, above=1.0, fov=60.0):
    """A picture of the drone from behind and above it, looking along its heading."""
    fwd = (math.cos(yaw), math.sin(yaw))
    eye = (pos[0] - behind * fwd[0], pos[1] - behind * fwd[1], max(pos[2], 0.0) + above)
    target = (pos[0] + 1.5 * fwd[0], pos[1] + 1.5 * fwd[1], max(pos[2], 0.0) - 0.1)
    view = pb.computeViewMatrix(eye, target, (0, 0, 1), physicsClientId=client)
    proj = pb.computeProjectionMatrixFOV(fov, width / float(height), 0.05, 200.0,
                                         physicsClientId=client)
    return _rgb(client, width, height, view, proj)


SKY_TOP, SKY_HORIZON = (110, 160, 225), (200, 222, 245)


def _rgb(client, width, height, view, proj):
    # No shadow pass: it doubles the cost.
    _, _, rgba, depth, _ = pb.getCameraImage(width, height, view, proj,
                                             renderer=pb.ER_TINY_RENDERER,
                                             flags=pb.ER_NO_SEGMENTATION_MASK,
                                             shadow=0, physicsClientId=client)
    img = np.array(np.reshape(np.asarray(rgba, dtype=np.uint8), (height, width, 4))[:, :, :3])
    # The renderer leaves empty pixels white: paint a sky there, darker toward the top.
    sky = np.reshape(np.asarray(depth, dtype=np.float32), (height, width)) >= 0.99999
    if sky.any():
        frac = np.linspace(0.0, 1.0, height)[:, None]
        grad = (np.asarray(SKY_TOP) * (1 - frac) + np.asarray(SKY_HORIZON) * frac)
        colours = np.broadcast_to(grad[:, None, :], (height, width, 3)).astype(np.uint8)
        img[sky] = colours[sky]
    return img


HIDDEN = (0.0, 0.0, -1000.0)     # where the drawn drone waits: beyond every camera's far plane


class SceneRenderer:
    """A PyBullet client holding the scene, rendering the drone's cameras, and the chase
    view with a drawn drone (a visual-only body, placed for that picture only: the drone's
    own cameras do not see its hull)."""

    def __init__(self):
        self.client = pb.connect(pb.DIRECT)
        scene.add_bodies(self.client)
        self._drone, self._drone_arm = None, None

    def render(self, name, pos, quat):
        return render(self.client, CAMERAS[name], pos, quat)

    def chase(self, pos, quat, width, height, arm):
        c = self.client
        if self._drone_arm != arm:
            if self._drone is not None:
                pb.removeBody(self._drone, physicsClientId=c)
            self._drone = pb.createMultiBody(0, -1, scene.body_visual(c, arm), HIDDEN,
                                             physicsClientId=c)
            self._drone_arm = arm
        pb.resetBasePositionAndOrientation(self._drone, pos, quat, physicsClientId=c)
        try:
            rot = pb.getMatrixFromQuaternion(quat, physicsClientId=c)
            return chase_view(c, pos, math.atan2(rot[3], rot[0]), width, height)
        finally:
            pb.resetBasePositionAndOrientation(self._drone, HIDDEN, (0, 0, 0, 1),
                                               physicsClientId=c)

    def close(self):
        if self.client is not None:
            pb.disconnect(self.client)
            self.client = None


def _serve(conn):
    """The renderer process; None stops it. Requests:
    ('cameras', pos, quat, names) -> [(name, rgb bytes)];
    ('chase', pos, quat, width, height, arm, path) -> ('ok', rgb bytes) or ('error', text),
    the PNG written to `path` when it is not None."""
    renderer = SceneRenderer()
    try:
        while True:
            try:
                req = conn.recv()
            except EOFError:
                return
            if req is None:
                return
            if req[0] == 'cameras':
                _, pos, quat, names = req
                conn.send([(n, renderer.render(n, pos, quat).tobytes()) for n in names])
                continue
            _, pos, quat, width, height, arm, path = req
            try:
                img = renderer.chase(pos, quat, width, height, arm)
                if path:
                    from PIL import Image
                    Image.fromarray(img).save(path)
                reply = ('ok', img.tobytes())
            except Exception as e:      # answered; the renderer lives on
                reply = ('error', '%s: %s' % (type(e).__name__, e))
            conn.send(reply)
    finally:
        renderer.close()


class PictureError(RuntimeError):
    """The renderer process could not draw or write a picture (and is still serving)."""


class RendererProcess:
    """Camera rendering in a child process (its own PyBullet client and its own GIL).

    One request at a time, from one thread: `render(pos, quat, names)` blocks that thread
    (never the physics loop) until the images are back. The child is `python -m
    leap_teleop.drone.cameras`, talking over its stdin / stdout."""

    def __init__(self):
        self.proc = subprocess.Popen([sys.executable, '-m', 'leap_teleop.drone.cameras'],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self._out = Connection(os.dup(self.proc.stdin.fileno()), readable=False)
        self._in = Connection(os.dup(self.proc.stdout.fileno()), writable=False)
        self.proc.stdin.close()
        self.proc.stdout.close()

    def render(self, pos, quat, names, timeout=10.0):
        """{name: (height, width, 3) uint8} for the cameras named."""
        self._out.send(('cameras', tuple(pos), tuple(quat), tuple(names)))
        if not self._in.poll(timeout):
            raise RuntimeError('camera renderer did not answer in %.0f s' % timeout)
        out = {}
        for name, data in self._in.recv():
            spec = CAMERAS[name]
            out[name] = np.frombuffer(data, np.uint8).reshape(spec.height, spec.width, 3)
        return out

    def chase(self, pos, quat, width, height, arm, path=None, timeout=10.0):
        """The chase view (height, width, 3) uint8 with the drone drawn at (pos, quat);
        also a PNG at `path` when given. PictureError when the renderer answers that it
        could not draw or write it; RuntimeError when it does not answer within `timeout`
        (close it then: its late answer would pair with the next request)."""
        width, height = int(width), int(height)
        self._out.send(('chase', tuple(pos), tuple(quat), width, height, float(arm), path))
        if not self._in.poll(timeout):
            raise RuntimeError('snapshot renderer did not answer in %.1f s' % timeout)
        status, value = self._in.recv()
        if status != 'ok':
            raise PictureError(value)
        return np.frombuffer(value, np.uint8).reshape(height, width, 3)

    def kill(self):
        """End the process at once, from any thread: a request under way then fails with
        EOFError instead of waiting out its timeout."""
        proc = self.proc
        if proc is not None:
            proc.kill()

    def close(self, wait=5.0):
        """Stop the process: asked to, killed after `wait` s (0 = at once, e.g. while it
        is still busy with a picture nobody waits for)."""
        if self.proc is None:
            return
        try:
            self._out.send(None)
        except OSError:
            pass
        try:
            self.proc.wait(wait)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)
        self._out.close()
        self._in.close()
        self.proc = None


class ChaseSnapshots:
    """Chase-view snapshots drawn by a renderer process of their own, from a pose the
    caller copied (under its lock): PyBullet holds the GIL while it renders, so a snapshot
    drawn in the simulator's process stalls its physics for the whole picture.

    `take(pos, quat, path, width, height, arm)` blocks only the calling thread. The
    process starts on the first snapshot and is replaced after a failure or a timeout."""

    def __init__(self, timeout=20.0):
        self.timeout = timeout
        self.renderer = None
        self._closed = False
        self._lock = threading.Lock()   # one snapshot at a time (service threads)

    def take(self, pos, quat, path=None, width=640, height=480, arm=0.18):
        """The picture (height, width, 3) uint8, written to `path` as a PNG when given;
        RuntimeError (with the reason) when it cannot be drawn in `timeout` s."""
        with self._lock:
            if self._closed:
                raise RuntimeError('the simulator is shutting down')
            try:
                if self.renderer is None:
                    self.renderer = RendererProcess()
                    if self._closed:    # closed while it started: close() saw no renderer
                        self._drop()
                        raise RuntimeError('the simulator is shutting down')
                return self.renderer.chase(pos, quat, width, height, arm, path,
                                           timeout=self.timeout)
            except PictureError:
                raise
            except RuntimeError:                # no answer in time
                self._drop()
                raise
            except (OSError, EOFError) as e:    # the process died
                self._drop()
                raise RuntimeError('snapshot renderer failed: %r' % e)

    def _drop(self):
        if self.renderer is not None:
            self.renderer.close(wait=0.0)
            self.renderer = None

    def close(self):
        # A snapshot under way holds the lock for up to `timeout`: its renderer is killed
        # first (the take then fails at once), and no later take starts one.
        self._closed = True
        renderer = self.renderer
        if renderer is not None:
            renderer.kill()
        with self._lock:
            if self.renderer is not None:
                self.renderer.close()
                self.renderer = None


class CameraLoop:
    """Renders the cameras at their rates (wall clock) in a thread of its own.

    `get_pose()` returns (pos, quat, context) and is where the caller copies the drone
    pose under its lock; `deliver(name, rgb, context)` receives each image. A camera whose
    rate is 0 is never rendered; a late frame is not made up for (no bursts). The
    renderer works at most `max_duty` of the time (after a render of d seconds it rests
    d * (1 / max_duty - 1)): on a loaded machine the rates drop instead of the cameras
    taking a whole core from the flight and everything else.

    A renderer that fails or does not answer in time is replaced: its late answer would
    pair with the next request (no request ids), each image then showing the pose before."""

    # A renderer's first answer also waits for its start (importing PyBullet, building the
    # scene: seconds on a loaded machine).
    START_TIMEOUT, FRAME_TIMEOUT = 30.0, 10.0
    RESTART_WAIT = 1.0                 # s between a failed renderer and the next
    # A frame under way may finish within this at stop; a renderer still starting (its
    # first answer may take START_TIMEOUT) or stuck is killed: roslaunch's Ctrl-C waits
    # 15 s before it escalates.
    STOP_WAIT = 1.0

    def __init__(self, rates, get_pose, deliver, on_error=None, max_duty=0.5):
        self.max_duty = max_duty
        self.rates = {name: float(r) for name, r in rates.items() if r > 0}
        self.get_pose, self.deliver, self.on_error = get_pose, deliver, on_error
        self.frames = {name: 0 for name in self.rates}
        self.renderer = None
        self._answered = False             # the renderer has answered once (it is up)
        self.thread = None
        self.ready = threading.Event()     # set once the renderer has drawn a first frame
        self._stop = threading.Event()

    def start(self):
        if not self.rates:
            return
        self.renderer = RendererProcess()
        self.thread = threading.Thread(target=self._run, name='drone_cameras', daemon=True)
        self.thread.start()

    def stop(self):
        self._stop.set()
        if self.thread is not None:
            self.thread.join(self.STOP_WAIT)
            if self.thread.is_alive() and self.renderer is not None:
                self.renderer.kill()
                self.thread.join(5.0)
        if self.renderer is not None:
            self.renderer.close()

    @property
    def stopping(self):
        return self._stop.is_set()

    def _render(self, pos, quat, names):
        """The images, or None when the renderer failed (reported, then replaced)."""
        timeout = self.FRAME_TIMEOUT if self._answered else self.START_TIMEOUT
        try:
            images = self.renderer.render(pos, quat, names, timeout=timeout)
        except (RuntimeError, OSError, EOFError) as e:
            if self._stop.is_set():
                return None
            if self.on_error is not None:
                self.on_error(e)
            self.renderer.close()
            if not self._stop.wait(self.RESTART_WAIT):
                self.renderer = RendererProcess()
                self._answered = False
            return None
        self._answered = True
        return images

    def _run(self):
        pos, quat, _ = self.get_pose()
        self._render(pos, quat, list(self.rates))     # sets the renderer up: not counted
        self.ready.set()
        due = {name: time.monotonic() for name in self.rates}
        while not self._stop.is_set():
            now = time.monotonic()
            names = [n for n, t in due.items() if t <= now]
            if not names:
                self._stop.wait(min(due.values()) - now)
                continue
            for n in names:
                due[n] = max(due[n] + 1.0 / self.rates[n], now)
            pos, quat, context = self.get_pose()
            started = time.monotonic()
            images = self._render(pos, quat, names)
            if images is None:
                continue
            for name, rgb in images.items():
                self.frames[name] += 1
                self.deliver(name, rgb, context)
            busy = time.monotonic() - started
            rest_until = time.monotonic() + busy * (1.0 / self.max_duty - 1.0)
            for n in due:
                due[n] = max(due[n], rest_until)


def _child_main():
    # The protocol owns the original stdout; anything printed (PyBullet's C code prints
    # to fd 1) goes to stderr instead.
    out_fd = os.dup(1)
    os.dup2(2, 1)
    # Ctrl-C reaches the whole process group: the parent stops this process (None or EOF).
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _serve(_Duplex(Connection(0, writable=False), Connection(out_fd, readable=False)))


class _Duplex:
    def __init__(self, rx, tx):
        self.recv, self.send = rx.recv, tx.send


if __name__ == '__main__':
    _child_main()
