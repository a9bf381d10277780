"""The AR.Drone 2.0's cameras, rendered by PyBullet's CPU renderer (no GPU needed).

Front camera 640x360 with a ~92 degree (diagonal) field of view looking forward, bottom
camera 320x240 with ~64 degrees looking down, image top toward the nose. A camera is
rendered from a drone pose (position, quaternion) in a PyBullet client that holds only
the scene (`scene.build`), so rendering never touches the physics client.
`RendererProcess` runs that client in a process of its own: PyBullet holds the GIL while
it renders, so a renderer thread would stall the physics loop for tens of milliseconds.

Also here: `chase_view`, the picture a person reads (a camera behind and above the
drone looking along its heading, ground texture and horizon in view).
"""
import math
import os
import signal
import subprocess
import sys
import threading
import time
from multiprocessing.connection import Connection
from dataclasses import dataclass

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


class SceneRenderer:
    """A PyBullet client holding the scene, rendering the drone's cameras."""

    def __init__(self):
        self.client = pb.connect(pb.DIRECT)
        scene.build(self.client)

    def render(self, name, pos, quat):
        return render(self.client, CAMERAS[name], pos, quat)

    def close(self):
        if self.client is not None:
            pb.disconnect(self.client)
            self.client = None


def _serve(conn):
    """The renderer process: (pos, quat, names) in, [(name, rgb bytes)] out; None stops."""
    renderer = SceneRenderer()
    try:
        while True:
            try:
                req = conn.recv()
            except EOFError:
                return
            if req is None:
                return
            pos, quat, names = req
            conn.send([(n, renderer.render(n, pos, quat).tobytes()) for n in names])
    finally:
        renderer.close()


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
        self._out.send((tuple(pos), tuple(quat), tuple(names)))
        if not self._in.poll(timeout):
            raise RuntimeError('camera renderer did not answer in %.0f s' % timeout)
        out = {}
        for name, data in self._in.recv():
            spec = CAMERAS[name]
            out[name] = np.frombuffer(data, np.uint8).reshape(spec.height, spec.width, 3)
        return out

    def close(self):
        if self.proc is None:
            return
        try:
            self._out.send(None)
        except OSError:
            pass
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)
        self._out.close()
        self._in.close()
        self.proc = None


class CameraLoop:
    """Renders the cameras at their rates (wall clock) in a thread of its own.

    `get_pose()` returns (pos, quat, context) and is where the caller copies the drone
    pose under its lock; `deliver(name, rgb, context)` receives each image. A camera whose
    rate is 0 is never rendered; a late frame is not made up for (no bursts). The
    renderer works at most `max_duty` of the time (after a render of d seconds it rests
    d * (1 / max_duty - 1)): on a loaded machine the rates drop instead of the cameras
    taking a whole core from the flight and everything else."""

    def __init__(self, rates, get_pose, deliver, on_error=None, max_duty=0.5):
        self.max_duty = max_duty
        self.rates = {name: float(r) for name, r in rates.items() if r > 0}
        self.get_pose, self.deliver, self.on_error = get_pose, deliver, on_error
        self.frames = {name: 0 for name in self.rates}
        self.renderer = None
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
            self.thread.join(15.0)
        if self.renderer is not None:
            self.renderer.close()

    @property
    def stopping(self):
        return self._stop.is_set()

    def _run(self):
        pos, quat, _ = self.get_pose()
        try:                           # the first frame sets the renderer up: not counted
            self.renderer.render(pos, quat, list(self.rates))
        except (RuntimeError, OSError, EOFError) as e:
            if self.on_error is not None and not self._stop.is_set():
                self.on_error(e)
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
            try:
                images = self.renderer.render(pos, quat, names)
            except (RuntimeError, OSError, EOFError) as e:
                if self._stop.is_set():
                    return
                if self.on_error is not None:
                    self.on_error(e)
                # A late answer would pair with the next request: start a fresh renderer.
                self.renderer.close()
                self._stop.wait(1.0)
                self.renderer = RendererProcess()
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
