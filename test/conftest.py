"""pytest set-up shared by every test."""
import os

import pytest
from hypothesis import settings

# CI replays the same generated cases every run (reproducible results); local runs keep
# exploring new ones. A counterexample found locally belongs in a regression test.
settings.register_profile('ci', derandomize=True, deadline=None)
if os.environ.get('CI'):
    settings.load_profile('ci')


@pytest.fixture(scope='session')
def leapjs_data():
    """The shared LeapJS recordings ($LEAPJS_DATA, else ../shared/data/leapjs next to the
    repository). A test that needs them fails without them: CI always has them, and a
    skip would let a run without the data pass."""
    from leap_teleop.hands.gestures.datasets import data_dir
    path = data_dir()
    if not os.path.isdir(path):
        pytest.fail('the shared LeapJS recordings are not at %s: set $LEAPJS_DATA' % path)
    return path


@pytest.hookimpl(tryfirst=True)
@pytest.fixture
def detector_sizes(monkeypatch):
    """The camera sources' MediaPipe HandDetector replaced by one that finds no hand and
    notes the shape of each image it is given: the list of those shapes."""
    import types

    from leap_teleop.hands.sources import camera
    seen = []
    monkeypatch.setattr(camera, 'HandDetector', lambda **kwargs: types.SimpleNamespace(
        detect=lambda rgb: seen.append(rgb.shape) or [], close=lambda: None))
    return seen


def pytest_collection_modifyitems(config, items):
    """Work units for `make test`'s two workers (`--dist loadgroup`): a test file is one
    unit, so its module fixtures are built once, except the rostests, each a unit of its
    own, so the two workers share them; the longest units are handed out first."""
    if not getattr(config.option, 'loadgroup', False):   # set on the workers
        return
    for item in items:
        rostest = item.get_closest_marker('rostest') is not None
        item.add_marker(pytest.mark.xdist_group(item.name if rostest else item.path.name))
    # Longest first, keeping each file's tests together and in order: the minutes-long
    # fits, builds and simulations, then the rostests, then the rest; the whole demo
    # last, beside the short unit tests rather than beside another ROS graph.
    def rank(item):
        if item.get_closest_marker('last') is not None:
            return 4
        if item.get_closest_marker('slow') is not None:
            return 0
        if item.get_closest_marker('rostest') is not None:
            return 1
        return 2 if item.get_closest_marker('integration') is not None else 3
    order = {}
    for i, item in enumerate(items):
        r, first = order.get(item.path, (4, i))
        order[item.path] = (min(r, rank(item)), first)
    items.sort(key=lambda item: order[item.path])
