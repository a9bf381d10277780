"""Cell configs the physics cannot run soundly are refused at start-up with one line: a
physics rate below where grasps and the table hold, a cube that starts inside an arm or a
tray."""
import copy

import pytest

from leap_teleop.ur10.config import config_path, load_config, parse_config
from leap_teleop.yaml_file import load_yaml_file

SHIPPED = ('ur10_cell.yaml', 'ur10_dual_cell.yaml', 'ur10_dual_rotated_cell.yaml')


def cell_data(name='ur10_cell.yaml'):
    return copy.deepcopy(load_yaml_file(config_path(name), 'cell config'))


@pytest.mark.parametrize('hz', [60, 100, 119.9])
def test_a_physics_rate_below_120_hz_is_refused_naming_the_key_and_range(hz):
    # At 60-90 Hz a closing gripper sank into the cube and dropped it in a lift; at
    # 60-100 Hz a dropped cube fell through the table top.
    data = cell_data()
    data['physics_hz'] = hz
    with pytest.raises(ValueError) as e:
        parse_config(data, 'cell.yaml')
    line = str(e.value)
    assert '\n' not in line
    assert line.startswith('cell config cell.yaml: physics_hz = %g: out of range' % hz)
    assert '>= 120 and <= 2000 (Hz)' in line


@pytest.mark.parametrize('hz', [120, 2000])
def test_physics_rates_from_120_hz_are_accepted(hz):
    data = cell_data()
    data['physics_hz'] = hz
    assert parse_config(data, 'cell.yaml').physics_hz == hz


@pytest.mark.parametrize('name', SHIPPED)
def test_the_shipped_cells_run_at_a_rate_inside_the_range(name):
    assert 120 <= load_config(name).physics_hz <= 2000
