"""The typed parameter declarations: what they accept, refuse and say."""
import math

import pytest

from leap_teleop.params import Param, ParamError, check_params

TABLE = {
    'rate': Param(125.0, 'loop rate', unit='Hz', gt=0.0),
    'count': Param(3, 'items', ge=0, le=10),
    'mode': Param('tilt', 'mode', choices=('tilt', 'paper')),
    'xyz': Param([0.0, 0.0, 0.0], 'position', unit='m', length=3),
    'flag': Param(False, 'a switch'),
    'topic': Param('a/b', 'topic', empty_ok=False),
}


def test_defaults_pass_and_ints_become_floats():
    p = check_params(TABLE, {'rate': 50})
    assert p['rate'] == 50.0 and isinstance(p['rate'], float)
    assert p['count'] == 3 and p['mode'] == 'tilt' and p['xyz'] == [0.0, 0.0, 0.0]


@pytest.mark.parametrize('name, value', [
    ('rate', 0.0), ('rate', -1), ('rate', math.nan), ('rate', math.inf), ('rate', 'fast'),
    ('rate', True), ('count', 2.5), ('count', 11), ('count', -1), ('mode', 'loop'),
    ('xyz', [1.0, 2.0]), ('xyz', [1.0, math.nan, 0.0]), ('xyz', 'origin'), ('flag', 1),
    ('topic', ''), ('topic', 5),
])
def test_bad_values_are_refused_with_one_line_naming_the_parameter(name, value):
    with pytest.raises(ParamError) as e:
        check_params(TABLE, {name: value})
    msg = str(e.value)
    assert '\n' not in msg and msg.startswith('~%s = ' % name) and 'allowed: ' in msg


def test_allowed_text():
    assert TABLE['rate'].allowed() == 'a finite number > 0 (Hz)'
    assert TABLE['count'].allowed() == 'an integer >= 0 and <= 10'
    assert TABLE['mode'].allowed() == 'one of: tilt, paper'
    assert TABLE['xyz'].allowed() == 'a list of 3 finite numbers (m)'
