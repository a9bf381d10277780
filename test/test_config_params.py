"""Parameters are declared once: the YAML files in config/ only set parameters their node
declares, with values the declarations accept, and a value that restates a default equals
it (or is one of the documented overrides below); the configuration dataclasses are
generated from the same declarations."""
import glob
import os

import pytest
import yaml

from leap_teleop.drone.pilot_params import PILOT_NODE_PARAMS, PILOT_PARAMS, PilotParams
from leap_teleop.params import ParamError
from leap_teleop.ros.nodes import ardrone_sim, drone_pilot, ur10_arm
from leap_teleop.ur10.teleop_params import ARM_NODE_PARAMS, TELEOP_PARAMS, ArmTeleopParams

CONFIG = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'config')

# config file -> {block: node module}; block None = the whole file is one node's namespace
# (the launch files load ur10_teleop.yaml inside each arm node, ardrone.yaml at the root).
NODE_FILES = {
    'ur10_teleop.yaml': {None: ur10_arm},
    'ardrone.yaml': {'ardrone_sim': ardrone_sim, 'drone_pilot': drone_pilot},
}
# Cell descriptions, not node parameters: ur10_sim reads them through ur10.config, which
# checks them (test_params.test_cell_config_scalars_are_checked).
NOT_NODE_PARAMS = {'ur10_cell.yaml', 'ur10_dual_cell.yaml', 'ur10_dual_rotated_cell.yaml'}
# (file, node, parameter): why the YAML differs from the declared default.
OVERRIDES = {
    ('ur10_teleop.yaml', 'ur10_arm', 'wrist_lower'): '-2 pi written to 4 decimals',
    ('ur10_teleop.yaml', 'ur10_arm', 'wrist_upper'): '2 pi written to 4 decimals',
    ('ardrone.yaml', 'ardrone_sim', 'control_yaw'): '100 deg/s written to 3 decimals',
}


def yaml_settings():
    """[(file, node name, module, {name: value})] of every node block in config/*.yaml."""
    out = []
    for name, blocks in sorted(NODE_FILES.items()):
        with open(os.path.join(CONFIG, name)) as f:
            data = yaml.safe_load(f)
        assert isinstance(data, dict), name
        for block, module in blocks.items():
            values = data if block is None else data[block]
            out.append((name, module.__name__.rsplit('.', 1)[1], module, values))
        if None not in blocks:
            assert set(data) == set(blocks), '%s: blocks of no known node: %s' % (
                name, sorted(set(data) - set(blocks)))
    return out


def test_every_config_file_is_known():
    found = {os.path.basename(p) for p in glob.glob(os.path.join(CONFIG, '*.yaml'))}
    assert found == set(NODE_FILES) | NOT_NODE_PARAMS, (
        'a config file that is neither a node parameter file nor a cell description')


@pytest.mark.parametrize('name, node, module, values', yaml_settings(),
                         ids=lambda x: x if isinstance(x, str) else '')
def test_yaml_sets_declared_parameters_inside_their_bounds(name, node, module, values):
    assert values, (name, node)
    for key, value in values.items():
        assert key in module.PARAMS, '%s: %s sets ~%s, which %s does not declare' % (
            name, node, key, node)
        p = module.PARAMS[key]
        try:
            checked = p.check(key, value)
        except ParamError as e:
            pytest.fail('%s: %s: %s' % (name, node, e))
        if (name, node, key) in OVERRIDES:
            assert checked != p.default, 'stale override entry: %s %s ~%s' % (name, node, key)
        else:
            assert checked == p.default, (
                '%s: %s ~%s = %r restates the default %r with another value; change one, or '
                'list it in OVERRIDES with the reason' % (name, node, key, value, p.default))


def test_every_override_names_a_yaml_setting():
    settings = {(name, node, key) for name, node, _, values in yaml_settings() for key in values}
    assert set(OVERRIDES) <= settings


def test_ur10_teleop_yaml_sets_every_teleop_parameter_but_the_expert_ones():
    with open(os.path.join(CONFIG, 'ur10_teleop.yaml')) as f:
        data = yaml.safe_load(f)
    # The file documents the teleop; these stay at their defaults, node wiring is
    # set by the launch files.
    assert set(TELEOP_PARAMS) - set(data) == {'max_input_age', 'joint_timeout', 'joint_loss_after'}


@pytest.mark.parametrize('cls, table', [(ArmTeleopParams, TELEOP_PARAMS),
                                        (PilotParams, PILOT_PARAMS)])
def test_the_config_classes_are_generated_from_the_declarations(cls, table):
    a, b = cls(), cls()
    assert list(vars(a)) == list(table)
    assert vars(a) == {name: p.default for name, p in table.items()}
    for name, p in table.items():
        if p.kind == 'list':
            assert getattr(a, name) is not getattr(b, name) is not p.default, name
    a.validate()
    assert vars(a) == vars(b)


@pytest.mark.parametrize('table, name', [(ARM_NODE_PARAMS, 'hand_topic'),
                                         (PILOT_NODE_PARAMS, 'hand_topic'),
                                         (PILOT_NODE_PARAMS, 'gesture_topic')])
def test_a_topic_parameter_wants_a_legal_ros_name(table, name):
    # before, rospy logged FATAL on subscribing and the node ran on with no input
    p = table[name]
    for good in ('leapmotion/data_right', '/ns/hand', '~hands'):
        assert p.check(name, good) == good
    for bad in ('bad topic!', 'a//b', 'hand/', '1hand', '/'):
        with pytest.raises(ParamError, match='not a legal ROS name; allowed: a ROS name'):
            p.check(name, bad)


def test_the_library_warnings_reach_rospy_once(monkeypatch):
    """A source's warning about bad frames went to the node's log file only: never on the
    console or /rosout."""
    import logging

    import rospy

    from leap_teleop.ros import node

    said = []
    for level in ('logerr', 'logwarn', 'loginfo', 'logdebug'):
        monkeypatch.setattr(rospy, level, lambda text, level=level: said.append((level, text)))
    logger = logging.getLogger('leap_teleop')
    monkeypatch.setattr(logger, 'handlers', [])
    monkeypatch.setattr(logger, 'propagate', True)
    monkeypatch.setattr(logger, 'level', logger.level)
    node.forward_library_logs()
    node.forward_library_logs()                       # twice: still one handler
    logging.getLogger('leap_teleop.hands.sources.recording').warning(
        'recording %s: skipped %d bad frame(s)', 'x.json', 100)
    logging.getLogger('leap_teleop.drone.sim').error('100% sure')
    assert said == [('logwarn', 'recording x.json: skipped 100 bad frame(s)'),
                    ('logerr', '100% sure')]
    assert logger.propagate is False and len(logger.handlers) == 1
    # a warning that comes once a frame reaches rospy once per 2 s, with a count
    source = logging.getLogger('leap_teleop.hands.sources.device_queue')
    for k in range(120):
        source.warning('frame %d could not be converted', k)
    assert said[2:] == [('logwarn', 'frame 0 could not be converted')]
    handler = logger.handlers[0]
    for entry in handler._limit._keys.values():                            # 10 s later
        entry[0] -= 10.0
    source.warning('frame %d could not be converted', 999)
    assert said[-1] == ('logwarn', 'frame 999 could not be converted (119 similar suppressed)')
