"""ros/diagnostics.py without a master: a node's /diagnostics updates."""
import pytest


def test_a_diagnostics_update_racing_the_shutdown_is_quiet(monkeypatch):
    """The diagnostics timer's last update can find /diagnostics closed by the shutdown
    (seen once as a traceback at the end of demo.launch): quiet then, raised otherwise."""
    import rospy

    from leap_teleop.ros.diagnostics import update

    class ClosedTopic:
        calls = 0

        def update(self):
            self.calls += 1
            raise rospy.ROSException('publish() to a closed topic')
    updater = ClosedTopic()
    monkeypatch.setattr(rospy.core, 'is_shutdown_requested', lambda: True)
    update(updater)
    monkeypatch.setattr(rospy.core, 'is_shutdown_requested', lambda: False)
    with pytest.raises(rospy.ROSException):
        update(updater)
    assert updater.calls == 2
