"""At most one message per key and period, with a count of the ones left out: what every
rate-limited log line of the nodes and the library shares. No ROS, no clock of its own."""

# Keys can carry values (a refused parameter value, a reason with numbers): past this many,
# the oldest are forgotten, so the table stays bounded however long a node runs.
MAX_KEYS = 256


class RepeatLimit:
    def __init__(self, period=2.0):
        self.period = float(period)
        self._keys = {}             # key -> [time let through, repeats left out since]

    def take(self, key, now):
        """None when `key` was let through less than `period` ago (counted as left out),
        else the number left out since the last one let through (0 the first time)."""
        entry = self._keys.get(key)
        if entry is not None and 0.0 <= now - entry[0] < self.period:
            entry[1] += 1
            return None
        self._keys.pop(key, None)               # re-inserted: the newest come last
        self._keys[key] = [now, 0]
        if len(self._keys) > MAX_KEYS:
            for old in list(self._keys)[:len(self._keys) - MAX_KEYS // 2]:
                del self._keys[old]
        return entry[1] if entry is not None else 0

    @staticmethod
    def suffix(left_out):
        """The text a let-through message ends with."""
        return ' (%d similar suppressed)' % left_out if left_out else ''
