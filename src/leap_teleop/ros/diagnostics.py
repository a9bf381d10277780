"""A node's /diagnostics: one diagnostic_updater task filled from a report of plain values."""
import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus

from leap_teleop.params import Param
from leap_teleop.ros.signals import closed_at_shutdown

# diagnostic_updater's own parameter, declared and checked at start-up like the nodes'
# (its default is the library's).
DIAGNOSTIC_PARAMS = {
    'diagnostic_period': Param(1.0, 'seconds between two /diagnostics reports (read at start-up)',
                               unit='s', gt=0.0, le=60.0),
}
LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN, 'error': DiagnosticStatus.ERROR}


def diagnostics_updater(hardware_id, task, report, input_age=None):
    """A diagnostic_updater.Updater (its update() publishes at most every ~diagnostic_period)
    with one task named `task`: report() gives (level 'ok' | 'warn' | 'error', summary,
    [(key, value)]); the age of the input behind the commands (an InputAgeWindow, or the
    sender's StageAges: anything with diagnostic_values(now), read on the thread that
    calls update()) follows those values."""
    def run(stat):
        level, summary, values = report()
        stat.summary(LEVELS[level], summary)
        if input_age is not None:
            values = values + input_age.diagnostic_values(rospy.get_time())
        for key, value in values:
            stat.add(key, value)
        return stat

    updater = FixedPeriodUpdater(rospy.get_param('~diagnostic_period',
                                                 DIAGNOSTIC_PARAMS['diagnostic_period'].default))
    updater.setHardwareID(hardware_id)
    updater.add(task, run)
    return updater


class FixedPeriodUpdater(diagnostic_updater.Updater):
    """An Updater whose period is the one checked at start-up, and that reports on after
    ROS time jumps back. The library's re-reads ~diagnostic_period four times a second on
    the caller's thread (a control loop, the pilot's watchdog): a master call there, and a
    bad value set later raised out of it."""

    def __init__(self, period_s):
        super().__init__()
        self.period = float(period_s)

    def _check_diagnostic_period(self):
        pass

    def update(self):
        """Publishes once ~diagnostic_period has passed since the last report, and at once
        when ROS time went back before it: the library's waited for /clock to pass the last
        report again (never, with a looped bag)."""
        if rospy.Time.now() < self.last_time:
            self.force_update()     # also restarts the period from now
        else:
            super().update()


def update_every(updater, period_s=0.25):
    """A rospy.Timer calling updater.update() (which publishes once per ~diagnostic_period)
    every period_s, for a node whose own loop is a hot path that should not carry it (the
    sender); keep the timer referenced."""
    # reset: a /clock that jumps back (a looped bag) would otherwise end the timer's thread
    return rospy.Timer(rospy.Duration.from_sec(period_s), lambda _event: update(updater), reset=True)


def update(updater):
    """updater.update(), quiet when the node is shutting down: a timer's last call can race
    the shutdown that closes /diagnostics ("publish() to a closed topic")."""
    with closed_at_shutdown():
        updater.update()
