"""test_rviz_screenshot's retry when RViz crashes, without RViz."""
import pytest
from test_rviz_screenshot import RvizDied, _retry_once_if_rviz_died, _rviz_death


def test_an_rviz_crash_is_retried_once_and_a_second_fails(tmp_path):
    log = tmp_path / 'roslaunch.log'
    log.write_bytes(b'[rviz-4]: started with pid [27301]\n')
    assert _rviz_death(log) is None
    log.write_bytes(b'\x1b[31m[rviz-4] process has died [pid 27301, exit code -11, cmd '
                    b'/usr/lib/rviz/rviz -d ur10.rviz].\nlog file: rviz-4*.log\x1b[0m\n')
    assert 'exit code -11' in _rviz_death(log)
    attempts = []

    def crashes_once(directory):
        attempts.append(directory)
        if len(attempts) == 1:
            raise RvizDied('exit code -11')
        return 'drawn'
    assert _retry_once_if_rviz_died(tmp_path / 'a', crashes_once) == 'drawn'
    assert [d.name for d in attempts] == ['first', 'second']

    def always_crashes(directory):
        raise RvizDied('exit code -11')
    with pytest.raises(pytest.fail.Exception, match='both attempts'):
        _retry_once_if_rviz_died(tmp_path / 'b', always_crashes)
