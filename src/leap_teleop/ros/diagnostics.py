"""A node's /diagnostics: one diagnostic_updater task filled from a report of plain values."""
import diagnostic_updater
import rospy
from diagnostic_msgs.msg import DiagnosticStatus

from leap_teleop.ros.signals import closed_at_shutdown

DEFAULT_PERIOD_S = 1.0     # diagnostic_updater's own default
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

    # The updater re-reads ~diagnostic_period four times a second through rospy's param
    # cache, which keeps only parameters that exist: unset, each read is a master call.
    if not rospy.has_param('~diagnostic_period'):
        rospy.set_param('~diagnostic_period', DEFAULT_PERIOD_S)
    updater = diagnostic_updater.Updater()
    updater.setHardwareID(hardware_id)
    updater.add(task, run)
    return updater


def update_every(updater, period_s=0.25):
    """A rospy.Timer calling updater.update() (which publishes once per ~diagnostic_period)
    every period_s, for a node whose own loop is a hot path that should not carry it (the
    sender); keep the timer referenced."""
    return rospy.Timer(rospy.Duration.from_sec(period_s), lambda _event: update(updater))


def update(updater):
    """updater.update(), quiet when the node is shutting down: a timer's last call can race
    the shutdown that closes /diagnostics ("publish() to a closed topic")."""
    with closed_at_shutdown():
        updater.update()
