"""RepeatLimit: one message per key and period, with the count of those left out; its
table stays bounded however many keys come."""
from leap_teleop import repeat_limit
from leap_teleop.repeat_limit import RepeatLimit


def test_one_per_key_and_period_with_the_count_left_out():
    r = RepeatLimit(2.0)
    assert r.take('a', 10.0) == 0
    assert r.take('a', 10.5) is None and r.take('a', 11.9) is None
    assert r.take('b', 11.9) == 0                     # another key: its own period
    assert r.take('a', 12.0) == 2                     # two left out since
    assert r.take('a', 12.1) is None
    assert r.take('a', 11.0) == 1                     # a clock that went back: a new start
    assert RepeatLimit.suffix(2) == ' (2 similar suppressed)' and RepeatLimit.suffix(0) == ''


def test_the_table_forgets_its_oldest_keys_past_its_bound():
    # Keys carrying values (a refused parameter value, a reason with numbers) grew the
    # tables of the nodes' rate-limited logs without end.
    r = RepeatLimit(2.0)
    for k in range(10 * repeat_limit.MAX_KEYS):
        assert r.take(('refused', k), 1.0) == 0
    assert len(r._keys) <= repeat_limit.MAX_KEYS
    assert r.take(('refused', 10 * repeat_limit.MAX_KEYS - 1), 1.5) is None   # newest kept
