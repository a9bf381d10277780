"""Where the UR10's six arm joints are in a joint_states name list."""
from leap_teleop.ur10.kinematics import JOINT_NAMES


class JointStateIndex:
    """The arm joints' positions (and velocities) in JOINT_NAMES order from a joint_states
    message's names and values. A name matches a joint exactly or with a prefix ending in '_' or '/'
    (ur10_1_shoulder_pan_joint); the first match wins. The lookup is kept while the list's
    length stays the same."""

    def __init__(self):
        self._index = None
        self._count = None

    def positions(self, names, positions):
        """The six positions; KeyError (its argument the joint's name) when one is missing."""
        return [positions[i] for i in self._lookup(names)]

    def velocities(self, names, velocities):
        """The six velocities, or None when the message carries none (velocity may be
        empty); KeyError as positions()."""
        index = self._lookup(names)
        return [velocities[i] for i in index] if len(velocities) == len(names) else None

    def _lookup(self, names):
        if self._index is None or len(names) != self._count:
            index = []
            for joint in JOINT_NAMES:
                match = [i for i, n in enumerate(names)
                         if n == joint or n.endswith('_' + joint) or n.endswith('/' + joint)]
                if not match:
                    raise KeyError(joint)
                index.append(match[0])
            self._index, self._count = index, len(names)
        return self._index
