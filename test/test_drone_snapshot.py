"""ardrone/snapshot is drawn by a renderer process: the drone's physics keeps stepping."""
import threading
import time

import numpy as np
import pybullet as pb
import pytest

from leap_teleop.drone import scene
from leap_teleop.drone.cameras import ChaseSnapshots, chase_view
from leap_teleop.drone.sim import ArDroneSim

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


@pytest.fixture
def flying():
    sim = ArDroneSim()
    sim.takeoff()
    sim.advance(3.0)
    sim.set_cmd_vel(0.3, 0.0, 0.0, 0.0, 0.0, 0.4)
    sim.advance(1.0)
    yield sim
    sim.close()


def test_snapshot_renders_outside_the_physics_thread(flying, tmp_path):
    # Before: the node drew the chase view in the physics client under the simulator's
    # lock; PyBullet keeps the interpreter lock while it renders, so physics and navdata
    # stopped for the whole picture.
    sim, lock = flying, threading.Lock()
    snaps = ChaseSnapshots()
    try:
        snaps.take(sim.pos, sim.quat, None, 32, 24)        # starts the renderer
        out = {}

        def snap():                  # what the node's service does
            with lock:
                pos, quat = sim.pos, sim.quat
            t = time.monotonic()
            out['img'] = snaps.take(pos, quat, str(tmp_path / 'drone.png'), 640, 480,
                                    sim.p.arm)
            out['s'] = time.monotonic() - t
        th = threading.Thread(target=snap)
        gaps, last = [], time.monotonic()
        th.start()
        while th.is_alive():
            with lock:
                sim.step()
            now = time.monotonic()
            gaps.append(now - last)
            last = now
        th.join()
        assert out['img'].shape == (480, 640, 3)
        assert (tmp_path / 'drone.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
        # The physics kept stepping: no stall near the render's duration.
        assert len(gaps) > 20 and max(gaps) < max(0.1, 0.5 * out['s']), (max(gaps), out['s'])
    finally:
        snaps.close()


def test_renderer_draws_what_the_simulator_draws(flying):
    # Same scene, same drone body at the copied pose: the in-process chase view.
    sim = flying
    snaps = ChaseSnapshots()
    try:
        theirs = snaps.take(sim.pos, sim.quat, None, 160, 120, sim.p.arm)
        mine = sim.snapshot(None, 160, 120)
        diff = np.abs(theirs.astype(int) - mine.astype(int))
        assert diff.mean() < 2.0 and (diff.max(axis=2) > 30).mean() < 0.01, diff.mean()
        # The drone is in it: the same view of the scene alone differs where it is drawn.
        client = pb.connect(pb.DIRECT)
        try:
            scene.add_bodies(client)
            empty = chase_view(client, sim.pos, sim.yaw, 160, 120)
        finally:
            pb.disconnect(client)
        changed = np.abs(theirs.astype(int) - empty.astype(int)).max(axis=2) > 40
        assert changed.sum() > 30 and changed[50:90, 60:100].sum() > 0.8 * changed.sum()
    finally:
        snaps.close()


def test_failures_are_answered_and_the_renderer_recovers(flying, tmp_path):
    sim = flying
    snaps = ChaseSnapshots(timeout=0.001)
    try:
        with pytest.raises(RuntimeError, match='did not answer'):
            snaps.take(sim.pos, sim.quat, None, 640, 480)
        assert snaps.renderer is None             # dropped: a late answer pairs with nothing
        snaps.timeout = 20.0
        with pytest.raises(RuntimeError, match='No such file|FileNotFoundError'):
            snaps.take(sim.pos, sim.quat, str(tmp_path / 'missing' / 'x.png'), 32, 24)
        assert snaps.take(sim.pos, sim.quat, None, 32, 24).shape == (24, 32, 3)
    finally:
        snaps.close()
