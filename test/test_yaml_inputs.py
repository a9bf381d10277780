"""The YAML a user hands in (gesture scripts, gesture bindings, cell configs): nesting
thousands deep and integers of hundreds of digits are one clear error, not a
RecursionError or OverflowError traceback."""
import pytest

from leap_teleop.hands.gestures.bindings import BindingError, load_bindings
from leap_teleop.hands.sources import SourceError
from leap_teleop.hands.sources.scripted import GestureScript
from leap_teleop.params import Param, ParamError
from leap_teleop.ur10.config import CellConfigError, config_path, read_cell_config

DEEP = 'a: ' + '[' * 5000 + ']' * 5000 + '\n'
HUGE = '1' + '0' * 400


@pytest.mark.parametrize('load, error', [
    (GestureScript.load, SourceError), (load_bindings, BindingError),
    (read_cell_config, CellConfigError)])
def test_yaml_nested_thousands_deep_is_one_error(load, error, tmp_path):
    path = tmp_path / 'deep.yaml'
    path.write_text(DEEP)
    with pytest.raises(error, match='nested too deeply'):
        load(str(path))


def test_integers_of_hundreds_of_digits_are_refused_by_name(tmp_path):
    script = tmp_path / 'script.yaml'
    script.write_text('hands:\n  right:\n    - {pose: open, palm: [%s, 0, 0], duration: 1}\n' % HUGE)
    with pytest.raises(SourceError, match=r'palm must be a list of 3 numbers'):
        GestureScript.load(str(script))
    with pytest.raises(ParamError, match='not finite'):
        Param(1.0, 'a float').check('x', int(HUGE))
    cell = tmp_path / 'cell.yaml'
    base = open(config_path('ur10_cell.yaml')).read()
    assert 'base_xyz: [0.0, 0.0, 0.75]' in base
    cell.write_text(base.replace('base_xyz: [0.0, 0.0, 0.75]', 'base_xyz: [%s, 0.0, 0.75]' % HUGE))
    with pytest.raises(CellConfigError, match='base_xyz must be 3 numbers'):
        read_cell_config(str(cell))
