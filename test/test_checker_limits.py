"""The rostest checkers' limits are data: every <test> of ours in test/*.test gives its
checker a `limits` mapping that fits the checker's table (no key missing, none unknown,
each value in range), and a bad one is refused naming the key. No master needed."""
import glob
import importlib
import os
from xml.etree import ElementTree

import pytest
import yaml

from check_helpers import LimitsError, check_limits, limit, state_limit

HERE = os.path.dirname(os.path.abspath(__file__))
TESTS = sorted(glob.glob(os.path.join(HERE, '*.test')) + glob.glob(os.path.join(HERE, 'replay', '*.test')))


def checker_nodes():
    """(.test name, <test> element) for each test node that runs one of our checkers."""
    nodes = []
    for path in TESTS:
        for node in ElementTree.parse(path).getroot().iter('test'):
            if node.get('pkg') == 'leap_teleop':
                nodes.append((os.path.basename(path), node))
    return nodes


NODES = checker_nodes()


def table_for(node):
    module = importlib.import_module(node.get('type')[:-len('.py')])
    scenario = next((p.get('value') for p in node.iter('param') if p.get('name') == 'scenario'),
                    None)
    if hasattr(module, 'SCENARIO_LIMITS'):
        return module.SCENARIO_LIMITS[scenario]
    return module.LIMITS


def limits_yaml(node):
    blocks = [r.text for r in node.iter('rosparam') if r.get('param') == 'limits']
    assert len(blocks) == 1, '%d <rosparam param="limits"> blocks' % len(blocks)
    return yaml.safe_load(blocks[0])


def test_every_checker_is_run_by_a_test_file():
    assert len(NODES) >= 20
    run = {node.get('type') for _, node in NODES}
    checkers = {os.path.basename(p) for p in glob.glob(os.path.join(HERE, '*_check.py'))}
    assert checkers - {'launch_check.py'} <= run


@pytest.mark.parametrize('test_file,node', NODES, ids=[n.get('test-name') for _, n in NODES])
def test_limits_fit_the_checker(test_file, node):
    check_limits(table_for(node), limits_yaml(node), '%s: %s' % (test_file, node.get('name')))


TABLE = {'timeout_s': limit('wait', 's', gt=0),
         'count': limit('at least', kind='int', ge=0),
         'state': state_limit('the state'),
         'optional_m': limit('checked when given', 'm', default=0.0, ge=0)}


def test_check_limits_accepts_and_converts():
    got = check_limits(TABLE, {'timeout_s': 5, 'count': 3, 'state': 'taking off'}, 'x')
    assert (got.timeout_s, got.count, got.state, got.optional_m) == (5.0, 3, 'taking off', 0.0)
    assert isinstance(got.timeout_s, float)


@pytest.mark.parametrize('raw,message', [
    (None, 'x: missing'),
    ([1, 2], 'x: not a mapping'),
    ({'count': 3, 'state': 'landed'}, 'x/timeout_s: missing'),
    ({'timeout_s': 5, 'count': 3, 'state': 'landed', 'timout_s': 5}, 'unknown key timout_s'),
    ({'timeout_s': -1, 'count': 3, 'state': 'landed'}, 'x/timeout_s: .*out of range'),
    ({'timeout_s': 'soon', 'count': 3, 'state': 'landed'}, 'x/timeout_s: .*not a number'),
    ({'timeout_s': 5, 'count': 2.5, 'state': 'landed'}, 'x/count: .*not an integer'),
    ({'timeout_s': 5, 'count': 3, 'state': 'airborne'}, 'x/state: .*not one of'),
])
def test_bad_limits_are_refused_naming_the_key(raw, message):
    with pytest.raises(LimitsError, match=message):
        check_limits(TABLE, raw, 'x')
