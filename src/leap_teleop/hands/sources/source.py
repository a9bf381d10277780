"""The one interface every hand source implements."""
import abc


class SourceError(RuntimeError):
    """A source cannot start or its input is unusable; the message names the fix."""


class HandSource(abc.ABC):
    """Yields leap_teleop.hands.frame.Frame objects, paced by the source itself.

    frames() blocks between frames as the device (or the recorded / scripted timing)
    does, and returns when the source is exhausted or stop() was called.
    """

    #: nominal frames per second, for rate checks; None when unknown
    rate_hz = None
    #: the pose model family that judges its hands when the source knows it better than
    #: its name does (a recording of camera hands: 'keypoints'); None: by its name
    hand_family = None

    @abc.abstractmethod
    def frames(self):
        """Iterate over frames until exhausted or stopped."""

    def stop(self):
        """Ask frames() to return soon; safe from any thread."""
        self._stopped = True

    @property
    def stopped(self):
        return getattr(self, '_stopped', False)
