"""Bags of the original systems replay into ur10_single.launch through replay.launch as the
docs/usage.md shows, and the arm places its cube: the one-arm layout (leapcobotright on
/leapmotion/data) as recorded, the two-arm layout (leapcobotright on /leapmotion/data_right,
leapcobotleft on /leapmotion/data_left) through remap_from / remap_to."""
import os

import pytest
from test_launch_smoke import GESTURES, run_launches

from leap_teleop.hands.sources.scripted import ScriptedSource
from leap_teleop.ros.recording_to_bag import write_bag

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

LAYOUTS = {
    'one_arm': ({'right': '/leapmotion/data'}, ['topics:=/leapmotion/data']),
    'two_arm': ({'right': '/leapmotion/data_right', 'left': '/leapmotion/data_left'},
                ['topics:=/leapmotion/data_right', 'remap_from:=/leapmotion/data_right',
                 'remap_to:=/leapmotion/data']),
}


@pytest.mark.rostest
@pytest.mark.parametrize('layout', sorted(LAYOUTS))
def test_original_bag_replays_into_the_single_arm(layout, tmp_path):
    recorded, replay_args = LAYOUTS[layout]
    bag = str(tmp_path / (layout + '.bag'))
    # As rosbag record stores them: absolute names.
    write_bag(ScriptedSource(os.path.join(GESTURES, 'ur10_pick_place_single.yaml'), realtime=False),
              bag, list(recorded), {side: {'leapcobot': t} for side, t in recorded.items()},
              kinds=('leapcobot',))
    import rosbag
    with rosbag.Bag(bag) as b:
        assert set(b.get_type_and_topic_info().topics) == set(recorded.values())
    run_launches(tmp_path, [['ur10_single.launch', 'sender:=false'],
                            ['replay.launch', 'bag:=' + bag] + replay_args],
                 ['--cube', 'ur10_1:cube_red'], 120)
