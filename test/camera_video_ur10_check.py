#!/usr/bin/env python3
"""rostest node: a clip of a real person drives a simulated UR10 through the video source:
the hand messages show the raised fist, then the thumbs-up, which arms the arm; the armed
arm commands the gripper, the clip's end trips the arm's input watchdog, and the
annotated view is out. (Under heavy load a gap in the camera's frames can also trip the
watchdog mid-clip: the checks do not depend on the disarms in between.)"""
import os
import sys
import threading
import unittest

import rospy
import rostest
from sensor_msgs.msg import Image
from trajectory_msgs.msg import JointTrajectory

from leap_teleop.msg import ArmStatus, leapcobotright

from check_helpers import limit, read_limits

LIMITS = {
    'timeout_s': limit('wait this long for the clip to end', 's', gt=0),
    'ended_after_s': limit('the clip has ended once no hand message came for this long', 's',
                           gt=0),
    'min_hand_frames': limit('more right-hand messages than this', kind='int', ge=0),
    'image_size': limit('the annotated view\'s width, height', 'px', kind='list', item='int',
                        length=2),
    'image_encoding': limit('the annotated view\'s encoding', kind='str'),
}


class CameraDrivesUr10(unittest.TestCase):
    def test_thumbs_up_from_video_arms_the_arm(self):
        lim = read_limits(LIMITS)
        video = rospy.get_param('~video')
        self.assertTrue(os.path.exists(video), 'clip %s absent' % video)
        lock = threading.Lock()
        status, grips, images, hands = [], [], [], []

        def on_status(msg):
            with lock:
                if not status or status[-1][1:] != (msg.state, msg.reason):
                    status.append((rospy.get_time(), msg.state, msg.reason))

        def on_grip(msg):
            with lock:
                grips.append(rospy.get_time())

        rospy.Subscriber('/ur10_1/ur10_arm/status', ArmStatus, on_status, queue_size=100)
        grip_sub = rospy.Subscriber('/ur10_1/gripper/command', JointTrajectory, on_grip,
                                    queue_size=100)
        hand_sub = rospy.Subscriber('/leapmotion/data_right', leapcobotright,
                                    lambda m: hands.append((rospy.get_time(), m)),
                                    queue_size=1000)
        deadline = rospy.get_time() + lim.timeout_s
        # The sender starts the clip once the annotated view has a subscriber (the .test
        # sets its wait_topics): subscribe to that only once the hand stream is
        # connected, so a slow start cannot miss the clip's first frames (the fist).
        # The gripper command goes out once, on arming, unlatched: connected first too.
        while ((hand_sub.get_num_connections() == 0 or grip_sub.get_num_connections() == 0)
               and rospy.get_time() < deadline):
            rospy.sleep(0.05)
        rospy.Subscriber('/camera/annotated', Image, images.append, queue_size=5)
        # The clip lasts 7.8 s (longer under load): done once its messages have stopped
        # for a while, so the watchdog has had its say.
        while rospy.get_time() < deadline and not rospy.is_shutdown():
            with lock:
                ended = hands and rospy.get_time() - hands[-1][0] > lim.ended_after_s
            if ended:
                break
            rospy.sleep(0.2)
        timeline = '\n'.join('%.2f %s: %s' % (t - status[0][0], s, r) for t, s, r in status)
        armed = [t for t, s, r in status if s == 'armed' and 'thumbs-up' in r]
        fist = [t for t, m in hands if m.is_right_hand and m.right_hand_fist]
        self.assertTrue(armed, 'never armed:\n' + timeline)
        self.assertTrue(fist, 'no fist in the hand messages')
        self.assertGreater(armed[-1], fist[0], 'no thumbs-up after the fist:\n' + timeline)
        self.assertIn('watchdog', status[-1][2], 'the clip\'s end did not disarm:\n' + timeline)
        # Armed, the arm drives the gripper (sent once: open, no pinch in the clip), from
        # the step after the one that armed it. Command and status come on two
        # connections, so under load the command can be heard first: 0.2 s allowed, less
        # than the thumbs-up's hold (arm_hold_s 0.3 s) during which nothing may be sent.
        self.assertTrue(grips, 'no gripper command once armed:\n' + timeline)
        self.assertGreater(grips[0], armed[0] - 0.2, 'a gripper command before arming:\n'
                           + timeline)
        present = [m for _, m in hands if m.is_right_hand]
        self.assertGreater(len(present), lim.min_hand_frames)
        self.assertTrue(any(m.right_hand_thumb_up for m in present))
        self.assertTrue(images, 'no annotated camera view')
        self.assertEqual((images[0].width, images[0].height, images[0].encoding),
                         (*lim.image_size, lim.image_encoding))


if __name__ == '__main__':
    rospy.init_node('camera_video_ur10_check')
    rostest.rosrun('leap_teleop', 'camera_video_ur10_check', CameraDrivesUr10, sys.argv)
