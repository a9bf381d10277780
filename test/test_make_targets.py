"""make lint and make check as a user runs them (this checkout, set up by make setup)."""
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# runs make in this checkout: not in make check (which would run itself)
pytestmark = [pytest.mark.checkout, pytest.mark.integration]


def make(*args):
    return subprocess.run(['make', '-C', ROOT] + list(args), capture_output=True, text=True,
                          timeout=600)


def test_make_lint_is_clean():
    p = make('lint')
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    assert 'All checks passed' in p.stdout


def test_make_check_runs_the_unit_tests_only():
    p = make('check', "PYTEST_ARGS=-k 'layout or params' -rN")
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-3000:]
    # the fuzzing of every node's parameters is marked slow, the rest of test_params runs
    assert ' passed' in p.stdout and ' deselected' in p.stdout, p.stdout[-2000:]
