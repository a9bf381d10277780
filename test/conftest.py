"""pytest set-up shared by every test."""
import os

from hypothesis import settings

# CI replays the same generated cases every run (reproducible results); local runs keep
# exploring new ones. A counterexample found locally belongs in a regression test.
settings.register_profile('ci', derandomize=True, deadline=None)
if os.environ.get('CI'):
    settings.load_profile('ci')
