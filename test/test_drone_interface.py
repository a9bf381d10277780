"""The AR.Drone endpoint table in docs/robots.md is the node's (the rostest checks the node)."""
import os
import re

from leap_teleop.ros.ardrone_interface import DRIVER_ENDPOINTS, OPTIONAL_ENDPOINTS
from leap_teleop.ros.nodes.ardrone_sim import PARAMS

ROBOTS_DOC = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'docs',
                          'robots.md')


def documented_endpoints():
    with open(ROBOTS_DOC) as f:
        text = f.read()
    section = text.split('## The AR.Drone driver interface', 1)[1].split('\n## ', 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip('|').split('|')]
        if len(cells) >= 3 and cells[0].split(' ')[0] in ('publisher', 'subscriber', 'service'):
            rows.append((cells[0], re.findall(r'`([^`]+)`', cells[1])[0],
                         re.findall(r'`([^`]+)`', cells[2])[0]))
    return rows


def test_docs_table_lists_exactly_the_offered_endpoints():
    expected = [(k, n, t) for k, n, t, _ in DRIVER_ENDPOINTS]
    expected += [(k + ' (opt-in)', n, t) for k, n, t, _ in OPTIONAL_ENDPOINTS]
    assert documented_endpoints() == expected
    assert len(DRIVER_ENDPOINTS) == 23


def test_driver_types_differ_only_by_package():
    for _, _, ours, driver in DRIVER_ENDPOINTS + OPTIONAL_ENDPOINTS:
        assert ours.split('/')[1] == driver.split('/')[1]
        assert ours == driver or (ours.startswith('leap_teleop/')
                                  and driver.startswith('ardrone_autonomy/'))


def test_opt_in_and_camera_params_are_declared():
    assert PARAMS['enable_navdata_altitude'].default is False     # off, as in the driver
    assert PARAMS['front_rate'].default > 0 and PARAMS['bottom_rate'].default > 0
