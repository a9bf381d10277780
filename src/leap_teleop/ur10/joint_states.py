"""Where the UR10's six arm joints are in a joint_states name list."""
from leap_teleop.ur10.kinematics import JOINT_NAMES


class JointStateIndex:
    """The arm joints' positions (and velocities) in JOINT_NAMES order from a joint_states
    message's names and values. A name matches a joint exactly or with a prefix ending in '_' or '/'
    (ur10_1_shoulder_pan_joint); the first match wins. The lookup is kept while the names
    stay the same."""

    def __init__(self):
        self._index = None
        self._names = None

    def positions(self, names, positions):
        """The six positions; KeyError (its argument the joint's name) when one is missing,
        ValueError when there are not as many positions as names."""
        if len(positions) != len(names):
            raise ValueError('%d names but %d positions' % (len(names), len(positions)))
        return [positions[i] for i in self._lookup(names)]

    def state(self, names, positions, velocities):
        """(positions, velocities or None) of the six joints; ValueError saying what is
        wrong with the message."""
        try:
            return self.positions(names, positions), self.velocities(names, velocities)
        except KeyError as e:
            raise ValueError('it lacks %s' % e.args[0]) from None

    def velocities(self, names, velocities):
        """The six velocities, or None when the message carries none or not one per name
        (velocity may be empty); KeyError as positions()."""
        index = self._lookup(names)
        return [velocities[i] for i in index] if len(velocities) == len(names) else None

    def _lookup(self, names):
        # by the names themselves: two publishers on joint_states (an arm's, a gripper's)
        # may send lists of the same length
        if self._index is None or names != self._names:
            index = []
            for joint in JOINT_NAMES:
                match = [i for i, n in enumerate(names)
                         if n == joint or n.endswith('_' + joint) or n.endswith('/' + joint)]
                if not match:
                    raise KeyError(joint)
                index.append(match[0])
            self._index, self._names = index, list(names)
        return self._index
