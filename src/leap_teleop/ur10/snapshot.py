"""Render the work cell in a separate process, so a slow render never holds the physics.

PyBullet keeps Python's global lock while it renders: a render on another thread of the
simulator still stalls its physics loop for the whole picture. The renderer process owns a
render-only UR10Cell (same config, never stepped); the simulator copies the poses under
its lock (UR10Cell.pose_state) and sends them here. The renderer runs at a low CPU
priority: on a busy machine a picture waits, not the physics and the nodes driving it.
"""
import os
import pickle
import select
import signal
import subprocess
import sys

RENDER_NICENESS = 10     # a picture is for people; the simulation it shows comes first


def serve(inp, out):
    """The renderer process: a config, then (state, path, w, h) jobs, until EOF."""
    os.nice(max(0, RENDER_NICENESS - os.nice(0)))
    config = pickle.load(inp)
    from leap_teleop.ur10.cell import UR10Cell
    cell = UR10Cell(config)
    while True:
        try:
            job = pickle.load(inp)
        except EOFError:
            break
        state, path, width, height = job
        try:
            cell.set_pose_state(state)
            cell.snapshot(path, width, height)
            reply = ('ok', path)
        except Exception as e:       # reported to the caller, the renderer lives on
            reply = ('error', '%s: %s' % (type(e).__name__, e))
        pickle.dump(reply, out)
        out.flush()
    cell.close()


class SnapshotRenderer:
    """render(state, path, w, h, timeout): the PNG's path; RuntimeError on a failed render,
    TimeoutError (and a fresh renderer next time) when it takes longer than `timeout`."""

    def __init__(self, config):
        self.config = config
        self._proc = None

    def _start(self):
        self._proc = subprocess.Popen([sys.executable, '-m', 'leap_teleop.ur10.snapshot'],
                                      stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        pickle.dump(self.config, self._proc.stdin)
        self._proc.stdin.flush()

    def render(self, state, path, width, height, timeout=30.0):
        if self._proc is None or self._proc.poll() is not None:
            self._start()
        try:
            pickle.dump((state, path, int(width), int(height)), self._proc.stdin)
            self._proc.stdin.flush()
        except OSError as e:
            self.close()
            raise RuntimeError('renderer gone: %s' % e)
        ready, _, _ = select.select([self._proc.stdout], [], [], timeout)
        if not ready:
            self.close()
            raise TimeoutError('no picture after %.1f s' % timeout)
        try:
            status, value = pickle.load(self._proc.stdout)
        except (EOFError, pickle.UnpicklingError) as e:
            self.close()
            raise RuntimeError('renderer failed: %r' % e)
        if status != 'ok':
            raise RuntimeError(value)
        return value

    def close(self):
        if self._proc is not None:
            try:
                self._proc.stdin.close()
                self._proc.wait(2.0)
            except (OSError, subprocess.TimeoutExpired):
                self._proc.kill()
                try:
                    self._proc.wait(2.0)
                except subprocess.TimeoutExpired:    # killed; reaped by the next wait
                    pass
            self._proc = None


if __name__ == '__main__':
    # Ctrl-C reaches the whole process group: the simulator ends its renderer by closing
    # the pipe (EOF, also when it dies), so the renderer ignores SIGINT instead of dying
    # mid-picture with a traceback in the launch's log.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # Replies go on the original stdout; anything the C libraries print goes to stderr.
    reply_fd = os.dup(1)
    os.dup2(2, 1)
    serve(sys.stdin.buffer, os.fdopen(reply_fd, 'wb'))
