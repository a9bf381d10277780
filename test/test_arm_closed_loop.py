"""The arm teleop logic closes the loop on the simulated cell: the scripted person's
pick-and-place sessions put each arm's cube in its tray (no ROS; simulated time)."""
import numpy as np
import pytest

from leap_teleop.ur10.config import config_path
from leap_teleop.ur10.teleop import DISARMED, TRACKING
from tools.closed_loop import run_session, sim_params

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration


def tray_error(cell, cube, arm):
    tray = cell.config.arm(arm).tray.xyz
    return float(np.linalg.norm(cell.object_poses()[cube][0][:2] - np.asarray(tray[:2])))


@pytest.mark.parametrize('session, cell_file, arms', [
    ('ur10_pick_place_single.yaml', 'ur10_cell.yaml', {'ur10_1': ('right', 'cube_red')}),
    ('ur10_pick_place_dual.yaml', 'ur10_dual_cell.yaml',
     {'ur10_1': ('right', 'cube_red'), 'ur10_2': ('left', 'cube_yellow')}),
])
def test_scripted_sessions_pick_and_place(session, cell_file, arms):
    cell, runs = run_session(config_path('gestures/' + session), cell_file,
                             {arm: side for arm, (side, _) in arms.items()}, sim_params())
    try:
        for arm, (_, cube) in arms.items():
            states = [s for _, s in runs[arm].states]
            assert states[:4] == [DISARMED, 'armed', TRACKING, DISARMED], states
            assert cell.in_tray(cube, arm), cell.object_poses()[cube]
            assert tray_error(cell, cube, arm) < 0.03
            assert cell.grasped(arm) is None
            # Motion bounded by the configured joint speed (with the controller's overshoot).
            assert runs[arm].max_joint_speed_seen < 1.0 * 1.2
        moved = [c.name for c in cell.config.cubes
                 if np.linalg.norm(cell.object_poses()[c.name][0][:2] - c.xyz[:2]) > 0.01]
        assert sorted(moved) == sorted(cube for _, cube in arms.values())
    finally:
        cell.close()


def test_generated_sessions_are_up_to_date():
    from tools.make_sessions import main
    assert main(['--check']) == 0


# 'full' here; 'yaw', the same session in the same closed loop, is the demo's rotated-cube
# task, which test_demo.py holds to the same states, placement and squareness.
@pytest.mark.parametrize('orientation', ['full'])
def test_rotated_cubes_are_grasped_across_the_faces_and_placed_square(orientation):
    """Each arm picks a cube lying at 30 / 60 deg: the hand turns, the tool turns with it,
    the jaws close across the faces and the cube lands square in the tray."""
    import math
    arms = {'ur10_1': ('right', 'cube_red'), 'ur10_2': ('left', 'cube_yellow')}
    cell, runs = run_session(config_path('gestures/ur10_pick_place_rotated.yaml'),
                             'ur10_dual_rotated_cell.yaml',
                             {arm: side for arm, (side, _) in arms.items()},
                             sim_params(orientation=orientation))
    try:
        for arm, (_, cube) in arms.items():
            states = [s for _, s in runs[arm].states]
            assert states == [DISARMED, 'armed', TRACKING, DISARMED], states
            assert cell.in_tray(cube, arm), cell.object_poses()[cube]
            assert tray_error(cell, cube, arm) < 0.02
            assert math.degrees(cell.cube_yaw_error(cube)) < 5.0
    finally:
        cell.close()
