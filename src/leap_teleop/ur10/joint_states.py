"""Where the UR10's six arm joints are in a joint_states name list."""
from leap_teleop.ur10.kinematics import JOINT_NAMES


class JointStateIndex:
    """The arm joints' positions (and velocities) in JOINT_NAMES order from a joint_states
    message's names and values. With a `prefix` (the arm's joint_prefix, ur10_1_) a joint
    is prefix + its name, or its bare name (a driver that publishes those); without one, its
    name exactly or after any prefix ending in '_' or '/', and a list holding the joint of
    two arms is refused (which is this one's?). The lookup is kept while the names stay the
    same."""

    def __init__(self, prefix=''):
        self.prefix = prefix
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
                if self.prefix:
                    match = ([i for i, n in enumerate(names) if n == self.prefix + joint]
                             or [i for i, n in enumerate(names) if n == joint])
                else:
                    match = [i for i, n in enumerate(names)
                             if n == joint or n.endswith('_' + joint) or n.endswith('/' + joint)]
                if not match:
                    raise KeyError(joint)
                if len(match) > 1:
                    raise ValueError('%s comes %d times (%s): set ~joint_prefix'
                                     % (joint, len(match), ', '.join(names[i] for i in match)))
                index.append(match[0])
            self._index, self._names = index, list(names)
        return self._index
