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
