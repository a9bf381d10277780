"""The sender's Ctrl-C paths (no master: rospy's state is set in-process): a shutdown while
it waits for ~camera_info_topic or while its source runs is a clean stop, not a bad
parameter or 'source ended'."""
import threading

import pytest
import rospy

from leap_teleop.hands.sources import SourceError
from leap_teleop.ros.camera_topics import camera_model

P = {'camera_info_topic': '/camera/camera_info'}


def waiting_for_camera_info(monkeypatch, error):
    def wait_for_message(*_args):
        raise error
    monkeypatch.setattr(rospy, 'wait_for_message', wait_for_message)


def test_ctrl_c_while_waiting_for_the_camera_info_is_a_clean_exit(monkeypatch):
    # rospy raises ROSInterruptException (a ROSException) on shutdown: once a FATAL
    # "bad parameter: no sensor_msgs/CameraInfo ... within 10 s", status 1
    waiting_for_camera_info(monkeypatch, rospy.ROSInterruptException('rospy shutdown'))
    with pytest.raises(SystemExit) as stop:
        camera_model(P)
    assert stop.value.code == 0


def test_a_camera_info_that_does_not_come_is_still_a_bad_parameter(monkeypatch):
    waiting_for_camera_info(monkeypatch, rospy.ROSException('timeout exceeded'))
    with pytest.raises(SourceError, match='no sensor_msgs/CameraInfo on /camera/camera_info within 10 s'):
        camera_model(P)
    monkeypatch.setattr(rospy.core, 'is_shutdown_requested', lambda: True)
    with pytest.raises(SystemExit) as stop:        # the timeout raced a Ctrl-C
        camera_model(P)
    assert stop.value.code == 0


class Interface:
    def __init__(self, finished):
        self.finished = threading.Event()
        if finished:
            self.finished.set()


def test_a_source_stopped_by_ctrl_c_did_not_end_by_itself(monkeypatch):
    # Ctrl-C: rospy's shutdown runs the on_shutdown hook (interface.stop, which sets
    # finished) while is_shutdown() is still False; that logged 'source ended after N frames'
    from leap_teleop.ros.nodes.sender import ended_by_itself
    monkeypatch.setattr(rospy.core, 'is_shutdown_requested', lambda: True)
    monkeypatch.setattr(rospy, 'is_shutdown', lambda: False)
    assert not ended_by_itself(Interface(finished=True))
    monkeypatch.setattr(rospy.core, 'is_shutdown_requested', lambda: False)
    assert ended_by_itself(Interface(finished=True))
    assert not ended_by_itself(Interface(finished=False))
