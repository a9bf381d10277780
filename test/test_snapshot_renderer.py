"""UR10 snapshots are drawn outside the simulator: the physics keeps stepping meanwhile."""
import os
import threading
import time

import numpy as np
import pytest

from leap_teleop.ur10.cell import UR10Cell
from leap_teleop.ur10.snapshot import RENDER_NICENESS, SnapshotRenderer

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


def test_found_snapshot_renders_outside_the_physics_thread(tmp_path):
    # Before: ~snapshot rendered in the simulator's process under its lock; PyBullet keeps
    # the interpreter lock while it renders, so even a render on another thread stalled
    # joint_states for the whole picture (~0.2-0.8 s here).
    cell = UR10Cell()
    renderer = SnapshotRenderer(cell.config)
    try:
        cell.move_to('ur10_1', np.array(cell.joint_state('ur10_1')[0]) + 0.3, 0.5)
        cell.run(0.6)
        renderer.render(cell.pose_state(), str(tmp_path / 'warm.png'), 64, 48)  # start it
        out = {}

        def snap():
            t = time.monotonic()
            out['path'] = renderer.render(cell.pose_state(), str(tmp_path / 'cell.png'),
                                          640, 480)
            out['s'] = time.monotonic() - t
        th = threading.Thread(target=snap)
        gaps, last = [], time.monotonic()
        th.start()
        while th.is_alive():
            cell.step()
            now = time.monotonic()
            gaps.append(now - last)
            last = now
        th.join()
        assert out['path'] == str(tmp_path / 'cell.png')
        assert (tmp_path / 'cell.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
        # The physics kept stepping: no stall near the render's duration.
        assert len(gaps) > 20 and max(gaps) < max(0.1, 0.5 * out['s']), (max(gaps), out)
    finally:
        renderer.close()
        cell.close()


def test_render_only_cell_takes_the_copied_poses():
    a, b = UR10Cell(), UR10Cell()
    try:
        a.move_to('ur10_1', np.array(a.joint_state('ur10_1')[0]) - 0.4, 0.3)
        a.run(0.5)
        b.set_pose_state(a.pose_state())
        np.testing.assert_allclose(b.joint_state('ur10_1')[0], a.joint_state('ur10_1')[0])
        for name, pose in a.object_poses().items():
            np.testing.assert_allclose(b.object_poses()[name][0], pose[0], atol=1e-9)
    finally:
        a.close()
        b.close()


def test_the_renderer_yields_the_cpu_to_the_simulation(tmp_path):
    """On a loaded machine a picture waits, not the physics and the nodes driving it: the
    renderer process runs at a low priority."""
    cell = UR10Cell()
    renderer = SnapshotRenderer(cell.config)
    try:
        renderer.render(cell.pose_state(), str(tmp_path / 'a.png'), 64, 48)
        pid = renderer._proc.pid
        assert os.getpriority(os.PRIO_PROCESS, pid) == RENDER_NICENESS > 0
        assert os.getpriority(os.PRIO_PROCESS, os.getpid()) < RENDER_NICENESS   # only it
    finally:
        renderer.close()
        cell.close()


def test_ctrl_c_leaves_the_renderer_to_its_simulator(tmp_path):
    """Ctrl-C reaches the whole process group; the renderer lives on (no traceback in the
    launch's log) until its simulator closes the pipe."""
    import signal
    cell = UR10Cell()
    renderer = SnapshotRenderer(cell.config)
    try:
        renderer.render(cell.pose_state(), str(tmp_path / 'a.png'), 64, 48)
        proc = renderer._proc
        proc.send_signal(signal.SIGINT)
        time.sleep(0.5)
        assert proc.poll() is None
        assert renderer.render(cell.pose_state(), str(tmp_path / 'b.png'), 64, 48)
        renderer.close()
        assert proc.returncode == 0
    finally:
        renderer.close()
        cell.close()
