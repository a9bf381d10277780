"""The typed parameter declarations: what they accept, refuse and say."""
import math

import pytest

from leap_teleop.params import Param, ParamError, check_params, unknown_param_warnings

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


def test_an_unknown_parameter_is_named_with_the_closest_declared_ones():
    declared = ['dead_zone', 'scale', 'rate', 'hand_topic']
    assert unknown_param_warnings('ur10_arm', declared, ['deadzone_mm', 'scale', 'rate']) == [
        '~deadzone_mm is not a parameter of ur10_arm (did you mean ~dead_zone?); ignored']
    # Nothing close: no guess; several close: all of them, best first; sorted by name.
    assert unknown_param_warnings('pilot', ['dead_zone', 'z_dead_zone', 'max_cmd'],
                                  ['zzz', 'deadzone']) == [
        '~deadzone is not a parameter of pilot (did you mean ~dead_zone or ~z_dead_zone?); '
        'ignored',
        '~zzz is not a parameter of pilot; ignored']
    assert unknown_param_warnings('x', declared, declared) == []


def test_allowed_text():
    assert TABLE['rate'].allowed() == 'a finite number > 0 (Hz)'
    assert TABLE['count'].allowed() == 'an integer >= 0 and <= 10'
    assert TABLE['mode'].allowed() == 'one of: tilt, paper'
    assert TABLE['xyz'].allowed() == 'a list of 3 finite numbers (m)'


# -- every node's table: declarations, bad values, bounds of the safety functions ----------

from leap_teleop.hands.sources.camera_params import DeviceParam  # noqa: E402
from tools.param_table import node_tables  # noqa: E402

TABLES = {module: params for module, _, params in node_tables()}
EVERY_PARAM = [(m, n) for m, params in sorted(TABLES.items()) for n in params]
NOT_NUMBERS = [None, 'fast', [1.0], {'a': 1}, True]


def test_every_node_declares_its_parameters():
    assert set(TABLES) >= {'sender', 'ur10_arm', 'ur10_sim', 'drone_pilot', 'ardrone_sim',
                           'hand_markers'}
    for module, params in TABLES.items():
        # the defaults pass, unchanged
        assert check_params(params, {}) == {n: p.default for n, p in params.items()}, module
        for name, p in params.items():
            assert p.doc.strip(), (module, name)
            if p.kind in ('int', 'float') or (p.kind == 'list' and p.item in ('int', 'float')):
                # Every number has a finite range on both sides (or a fixed set of choices).
                assert p.choices or ((p.gt is not None or p.ge is not None)
                                     and (p.lt is not None or p.le is not None)), (module, name)


def _scalar_bad(p, kind):
    """Values the declaration `p` must refuse for a scalar of `kind`."""
    if kind == 'bool':
        return [1, 0, 'yes', None, 1.0]
    if kind == 'str':
        # ~device also takes an index as an integer (YAML reads `1` as one), not a negative one
        out = [-1 if isinstance(p, DeviceParam) else 5, None, 2.5, True]
        if p.choices is not None:
            out.append('no-such-choice')
        if not p.empty_ok:
            out.append('')
        return out
    out = list(NOT_NUMBERS)
    if kind == 'float':
        out += [math.nan, math.inf, -math.inf]
    else:
        out += [2.5, math.nan]
    lo = p.gt if p.gt is not None else p.ge
    hi = p.lt if p.lt is not None else p.le
    if p.gt is not None:
        out.append(p.gt)
    if p.ge is not None:
        out.append(p.ge - (1 if kind == 'int' else max(1e-6, abs(p.ge) * 1e-3)))
    if p.lt is not None:
        out.append(p.lt)
    if p.le is not None:
        out.append(p.le + (1 if kind == 'int' else max(1e-6, abs(p.le) * 1e-3)))
    if lo is not None:
        out += [lo - 1e9, -1e300] if kind == 'float' else [int(lo) - 10 ** 9]
    if hi is not None:
        out += [hi + 1e9, 1e300] if kind == 'float' else [int(hi) + 10 ** 9]
    return out


def bad_values(p):
    if p.kind != 'list':
        return _scalar_bad(p, p.kind)
    good = list(p.default)
    out = [3, None, 2.5, {'x': 1}]
    if p.item != 'str':
        out.append('text')
    if p.length is not None:
        out += [good[:-1], good + good[-1:], []]
    if p.min_length:
        out.append([])
    item = p.item if isinstance(p.item, Param) else None
    bad_items = bad_values(item) if item else _scalar_bad(p, p.item)
    for i in range(len(good)):
        out += [good[:i] + [b] + good[i + 1:] for b in bad_items]
    return out


def test_the_device_takes_an_index_given_as_an_integer():
    """`_device:=1` or `device: 1` in a camera_config: YAML gives an int, once refused as
    'not a string'."""
    from leap_teleop.hands.sender_params import SENDER_PARAMS
    assert check_params(SENDER_PARAMS, {'device': 1})['device'] == '1'
    assert check_params(SENDER_PARAMS, {'device': 0})['device'] == '0'
    assert check_params(SENDER_PARAMS, {'device': '/dev/video2'})['device'] == '/dev/video2'
    for bad in (-1, True, 1.0, ''):
        with pytest.raises(ParamError, match='~device = '):
            check_params(SENDER_PARAMS, {'device': bad})


def test_every_bad_value_of_every_parameter_is_refused_in_one_line():
    """Each listed bad value of each parameter: refused, in one line naming the parameter
    and what it allows."""
    n = 0
    for module, name in EVERY_PARAM:
        for value in bad_values(TABLES[module][name]):
            with pytest.raises(ParamError) as e:
                check_params(TABLES[module], {name: value})
            msg = str(e.value)
            assert msg.startswith('~%s = ' % name) and 'allowed: ' in msg and '\n' not in msg
            n += 1
    assert n > 1000


# -- the library configurations share the declarations ------------------------------------
from leap_teleop.drone.pilot import PILOT_PARAMS, DronePilot, PilotParams  # noqa: E402
from leap_teleop.ur10.teleop import TELEOP_PARAMS, ArmTeleop, ArmTeleopParams  # noqa: E402


def test_every_config_field_is_declared():
    from dataclasses import fields
    assert {f.name for f in fields(PilotParams)} == set(PILOT_PARAMS)
    assert {f.name for f in fields(ArmTeleopParams)} == set(TELEOP_PARAMS)


@pytest.mark.parametrize('table, make', [
    (PILOT_PARAMS, lambda values: PilotParams().update(values)),
    (TELEOP_PARAMS, lambda values: ArmTeleopParams.from_dict(values)),
])
def test_library_configs_refuse_every_bad_value(table, make):
    for name, p in table.items():
        for value in bad_values(p):
            with pytest.raises(ValueError):
                make({name: value})


def test_found_nan_timeouts_no_longer_disable_the_pilot_or_arm_watchdogs():
    # Before: PilotParams.update turned 'nan' into float('nan') and the watchdog compared
    # with NaN (never lost, never landed); the dataclasses built directly took anything.
    for key in ('hand_timeout', 'land_after', 'navdata_timeout'):
        for value in ('nan', math.nan, math.inf, 0.0, -1.0, 1e6):
            with pytest.raises(ValueError):
                PilotParams().update({key: value})
            with pytest.raises(ValueError):
                DronePilot(PilotParams(**{key: value}))
    for key in ('input_timeout', 'joint_timeout', 'max_input_age', 'dead_zone'):
        for value in (math.nan, math.inf, 0.0, -5.0):
            with pytest.raises(ValueError):
                ArmTeleop(ArmTeleopParams(**{key: value}))


@pytest.mark.parametrize('key, value', [('physics_hz', 0), ('physics_hz', math.nan),
                                        ('physics_hz', 'fast'), ('cube_size', -0.05),
                                        ('cube_mass', math.inf)])
def test_cell_config_scalars_are_checked(key, value):
    # A physics rate of 0 divided by zero when the cell started; NaN corrupted the physics.
    import yaml

    from leap_teleop.ur10.config import config_path, load_config, parse_config
    with open(config_path('ur10_cell.yaml')) as f:
        data = yaml.safe_load(f)
    assert load_config('ur10_cell.yaml').physics_hz == data['physics_hz']
    data[key] = value
    with pytest.raises(ValueError) as e:
        parse_config(data, 'cell.yaml')
    assert ('%s = ' % key) in str(e.value) and 'allowed' in str(e.value)


@pytest.mark.parametrize('spoil, message', [
    (lambda d: d['arms'][0].update(name='bad arm!'), "arms[0].name must be a ROS name"),
    # misspelt keys were ignored: the arm stood at its default place
    (lambda d: d['arms'][0].update(base_xzy=d['arms'][0].pop('base_xyz')),
     "arms[0]: unknown key 'base_xzy' (did you mean base_xyz?) (arm keys: name, base_xyz"),
    (lambda d: d['arms'][0]['tray'].update(wal=[0.01, 0.04]), "arms[0].tray: unknown key 'wal' (did you mean wall?)"),
    (lambda d: d['cubes'][0].update(colour=[1, 0, 0, 1]), "cubes[0]: unknown key 'colour'"),
    (lambda d: d.update(physics=500), "unknown key 'physics' (did you mean physics_hz?) (cell keys"),
    (lambda d: d['table'].update(hieght=0.8), "table: unknown key 'hieght' (did you mean height?)"),
    (lambda d: d['camera'].update(fovy=40), "camera: unknown key 'fovy' (did you mean fov?)"),
    (lambda d: d['arms'][0].update(home=[100] * 6), 'ur10_1 home (rad) must be 6 numbers'),
    (lambda d: d['arms'][0]['tray'].update(inner=['abc', 0.2]), 'ur10_1 tray inner must be'),
    (lambda d: d['arms'][0]['tray'].update(wall=[-0.01, -0.04]), 'ur10_1 tray wall must be'),
    (lambda d: d['table'].update(size=[math.nan, 1.4]), 'table size must be 2 numbers'),
    (lambda d: d['table'].update(center=[0.45]), 'table center must be 2 numbers'),
    (lambda d: d['cubes'][0].update(yaw=math.nan), 'cubes[0].yaw must be'),
    (lambda d: d['cubes'][0].update(rgba=[0.85]), 'cubes[0].rgba must be 4 numbers'),
    (lambda d: d['cubes'][0].update(arm='nosucharm'), "cubes[0].arm: no arm 'nosucharm'"),
    (lambda d: d['camera'].update(fov=math.nan), 'camera.fov must be'),
    (lambda d: d['arms'].append(5), 'cell config cell.yaml: an entry of the wrong shape'),
])
def test_cell_config_fields_are_checked_and_named(spoil, message):
    # Each of these was taken silently (NaN cube poses, a home of 95.8 rad, a cube for no
    # arm) or ended in a message that named no field.
    import yaml

    from leap_teleop.ur10.config import config_path, parse_config
    with open(config_path('ur10_cell.yaml')) as f:
        data = yaml.safe_load(f)
    spoil(data)
    with pytest.raises(ValueError) as e:
        parse_config(data, 'cell.yaml')
    assert str(e.value).startswith('cell config cell.yaml: ') and message in str(e.value), e.value


def test_an_empty_topic_list_given_as_an_empty_string_is_no_topic():
    # _wait_topics:='' (or an empty launch arg) was [''], which rospy resolves to '/': the
    # sender then waited for ever for subscribers on '/'.
    from leap_teleop.hands.sender_params import SENDER_PARAMS
    wait = SENDER_PARAMS['wait_topics']
    assert wait.check('wait_topics', '') == []
    assert wait.check('wait_topics', 'leapmotion/data_right') == ['leapmotion/data_right']
    with pytest.raises(ParamError, match='an empty name'):
        wait.check('wait_topics', ['leapmotion/data_right', ''])


@pytest.mark.parametrize('frame', ['leap-hands', 'leap.hands', '2nd_leap', 'leap_hands'])
def test_every_frame_the_sender_may_stamp_is_one_a_consumer_may_ask_for(frame):
    # A frame id the sender took (leap-hands) was refused as ~hand_frame, though the
    # consumers' warning advised setting it so.
    from leap_teleop.control.stream_health import HAND_SUBSCRIPTION_PARAMS
    from leap_teleop.hands.sender_params import SENDER_PARAMS
    assert SENDER_PARAMS['frame_id'].check('frame_id', frame) == frame
    assert HAND_SUBSCRIPTION_PARAMS['hand_frame'].check('hand_frame', frame) == frame


def test_two_field_limits_name_the_axis_and_the_values():
    with pytest.raises(ValueError, match=r'workspace_min \[0.3, 0.9, 0.1\] must be below '
                                         r'workspace_max \[0.9, 0.5, 1.0\] .*\(not on y\)'):
        ArmTeleopParams.from_dict({'workspace_min': [0.3, 0.9, 0.1], 'workspace_max': [0.9, 0.5, 1.0]})
    with pytest.raises(ValueError, match=r'\(not for wrist 3\)'):
        ArmTeleopParams.from_dict({'wrist_lower': [-1.0, -1.0, 1.0], 'wrist_upper': [1.0, 1.0, 1.0]})


def test_a_misspelt_pilot_parameter_is_refused_by_name():
    with pytest.raises(ParamError, match='unknown pilot parameters: dead_zon'):
        PilotParams().update({'dead_zon': 0.2})


def test_a_relative_path_is_read_from_where_the_command_ran(tmp_path, monkeypatch):
    # roslaunch starts nodes in ROS_HOME: video:=clip.mp4 given beside the clip was looked
    # for there, and the cell config fell back to config/ under the same name
    from leap_teleop.package_files import user_path
    shell, ros_home = tmp_path / 'shell', tmp_path / 'ros_home'
    (shell / 'frames').mkdir(parents=True)
    ros_home.mkdir()
    (shell / 'clip.mp4').write_bytes(b'')
    (shell / 'frames' / 'a.png').write_bytes(b'')
    (ros_home / 'only_here.yaml').write_text('')
    monkeypatch.chdir(ros_home)
    monkeypatch.setenv('PWD', str(shell))
    assert user_path('clip.mp4') == str(shell / 'clip.mp4')
    assert user_path('frames/*.png') == str(shell / 'frames/*.png')
    # what is not there keeps its name: a file of config/, or one beside the node
    for name in ('ur10_dual_cell.yaml', 'only_here.yaml', 'frames/*.jpg', '', '/abs/x.yaml'):
        assert user_path(name) == name
    monkeypatch.setenv('PWD', 'relative/nonsense')
    assert user_path('clip.mp4') == 'clip.mp4'


def test_every_file_parameter_is_declared_a_path():
    from leap_teleop.hands.sender_params import SENDER_PARAMS
    from leap_teleop.ur10.cell_runner import RUNNER_PARAMS
    files = {'script', 'recording', 'video', 'gesture_model', 'keypoint_model', 'gesture_bindings'}
    assert {n for n, p in SENDER_PARAMS.items() if p.path} == files
    assert RUNNER_PARAMS['config'].path
    assert 'a path (a relative one from where it was launched)' in SENDER_PARAMS['video'].allowed()


def test_a_silence_shorter_than_two_checks_is_refused_and_0_still_means_never():
    # 0.005 s re-made a healthy 120 Hz stream's connection 4 times a second
    from leap_teleop.control.stream_health import HAND_SUBSCRIPTION_PARAMS
    p = HAND_SUBSCRIPTION_PARAMS['resubscribe_silent_after']
    assert p.check('resubscribe_silent_after', 0) == 0.0
    assert p.check('resubscribe_silent_after', 0.5) == 0.5
    for bad in (0.005, 0.25, -1.0):
        with pytest.raises(ParamError, match=r'allowed: 0 or a finite number >= 0.5 and <= 60 \(s\)'):
            p.check('resubscribe_silent_after', bad)
