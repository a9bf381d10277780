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


BAD_FILES = [(None, 'cannot read (No such file or directory)'),
             (b'\xff\xfe hands: {}', 'not UTF-8 text'),
             (b'a: [1,\n', 'not valid YAML (line 2: '),
             (DEEP.encode(), 'nested too deeply'),
             # PyYAML kept the last one: the first was dropped without a word
             (b'a: 1\nb:\n  c: 2\n  c: 3\n', "'c' given twice (lines 3 and 4)")]


@pytest.mark.parametrize('load, error, what', [
    (GestureScript.load, SourceError, 'gesture script'),
    (load_bindings, BindingError, 'gesture bindings'),
    (read_cell_config, CellConfigError, 'cell config')])
@pytest.mark.parametrize('data, why', BAD_FILES, ids=[b[1].split(' (')[0] for b in BAD_FILES])
def test_every_yaml_file_a_user_hands_in_fails_the_same_one_line_way(load, error, what, data,
                                                                     why, tmp_path):
    path = tmp_path / 'bad.yaml'
    if data is not None:
        path.write_bytes(data)
    with pytest.raises(error) as e:
        load(str(path))
    line = str(e.value)
    assert line.startswith('%s %s: %s' % (what, path, why)) and '\n' not in line, line


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


@pytest.mark.parametrize('text, line', [
    # a section widened at the top, then the docs' example form appended lower down
    ('arm:\n  stop: [fist, open]\ndrone:\n  hover: open\narm: {arm: rock, origin: []}\n',
     "'arm' given twice (lines 1 and 5)"),
    ('arm:\n  stop: [fist, open]\n  gripper: pinch\n  stop: fist\n', "'stop' given twice (lines 2 and 4)"),
])
def test_a_bindings_yaml_naming_a_section_or_action_twice_is_refused(tmp_path, text, line):
    path = tmp_path / 'mine.yaml'
    path.write_text(text)
    with pytest.raises(BindingError) as e:
        load_bindings(str(path))
    assert str(e.value) == 'gesture bindings %s: %s' % (path, line)


def test_a_merge_key_may_still_be_overridden(tmp_path):
    path = tmp_path / 'mine.yaml'
    path.write_text('base: &b {stop: fist, gripper: pinch}\narm:\n  <<: *b\n  stop: [fist, open]\n')
    from leap_teleop.yaml_file import load_yaml_file
    assert load_yaml_file(str(path), 'x')['arm'] == {'stop': ['fist', 'open'], 'gripper': 'pinch'}


@pytest.mark.parametrize('text, want', [
    # a merge source that overrides a merged key itself, used by a mapping read first
    ('a: &a {x: 1, y: 2}\ndefs:\n  b: &b\n    <<: *a\n    x: 5\nuse:\n  <<: *b\n',
     {'a': {'x': 1, 'y': 2}, 'defs': {'b': {'x': 5, 'y': 2}}, 'use': {'x': 5, 'y': 2}}),
    ('common: &c\n  stop: fist\n  gripper: pinch\nprofiles:\n  careful: &k\n    <<: *c\n    stop: [fist, open]\n'
     'arm:\n  <<: *k\n  arm: rock\n',
     {'common': {'stop': 'fist', 'gripper': 'pinch'},
      'profiles': {'careful': {'stop': ['fist', 'open'], 'gripper': 'pinch'}},
      'arm': {'stop': ['fist', 'open'], 'gripper': 'pinch', 'arm': 'rock'}}),
])
def test_a_merge_override_reads_as_pyyaml_reads_it_wherever_its_source_sits(tmp_path, text, want):
    # The duplicate check ran on a source PyYAML had already rewritten with its merged keys,
    # and refused a key the file gives once.
    from leap_teleop.yaml_file import load_yaml_file
    path = tmp_path / 'mine.yaml'
    path.write_text(text)
    assert load_yaml_file(str(path), 'x') == want


def test_a_key_given_twice_inside_a_merge_source_is_still_refused(tmp_path):
    from leap_teleop.yaml_file import YamlFileError, load_yaml_file
    path = tmp_path / 'mine.yaml'
    path.write_text('a: &a {x: 1, x: 2}\nb: {<<: *a}\n')
    with pytest.raises(YamlFileError, match="'x' given twice"):
        load_yaml_file(str(path), 'x')
