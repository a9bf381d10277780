"""A bag recorded from the two-arm layout (leapcobotright on /leapmotion/data_right,
leapcobotleft on /leapmotion/data_left) replays into ur10_single.launch through
replay.launch's remap:, as the README shows, and the arm places its cube."""
import os

import pytest

from leap_teleop.sources.scripted import ScriptedSource
from leap_teleop.tools.to_bag import write_bag
from test_launch_smoke import GESTURES, run_launches


@pytest.mark.rostest
def test_two_arm_bag_remapped_into_the_single_arm(tmp_path):
    bag = str(tmp_path / 'two_arm.bag')
    # As rosbag record stores them: absolute names.
    topics = {side: {'leapcobot': '/leapmotion/data_' + side} for side in ('right', 'left')}
    write_bag(ScriptedSource(os.path.join(GESTURES, 'ur10_pick_place_single.yaml'), realtime=False),
              bag, ['right', 'left'], topics, kinds=('leapcobot',))
    import rosbag
    with rosbag.Bag(bag) as b:
        assert set(b.get_type_and_topic_info().topics) == {'/leapmotion/data_right',
                                                          '/leapmotion/data_left'}
    run_launches(tmp_path, [
        ['ur10_single.launch', 'sender:=false'],
        ['replay.launch', 'bag:=' + bag, 'topics:=/leapmotion/data_right',
         'remap_from:=/leapmotion/data_right', 'remap_to:=/leapmotion/data']],
        ['--cube', 'ur10_1:cube_red'], 120)
