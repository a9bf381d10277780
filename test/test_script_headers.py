"""Every hand script's header names the files that use it ("# Used by: ..."), and that list
stays true: each named file exists and mentions the script, and every file of the
repository's code, launch files and tests that mentions the script is named."""
import glob
import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPTS = sorted(glob.glob(os.path.join(ROOT, 'config', 'gestures', '*.yaml')))
# Where a user of a script can be: tests, launch files, the library and the tooling.
USER_GLOBS = ('test/*.test', 'test/*.py', 'launch/*.launch', 'src/**/*.py', 'tools/**/*.py',
              'scripts/*', 'Makefile')


def used_by(path):
    """The files named by the header's "# Used by:" line (continued on lines starting '#  ')."""
    names, in_list = [], False
    with open(path) as f:
        for line in f:
            if not line.startswith('#'):
                break
            if line.startswith('# Used by:'):
                in_list, line = True, line[len('# Used by:'):]
            elif not (in_list and line.startswith('#  ')):
                in_list = False
                continue
            names += [n.strip() for n in line.lstrip('#').split(',') if n.strip()]
    return names


def mentions(path, script):
    with open(path, errors='replace') as f:
        return re.search(r'(?<![\w-])%s\b' % re.escape(script), f.read()) is not None


def users(script):
    found = set()
    for pattern in USER_GLOBS:
        for path in glob.glob(os.path.join(ROOT, pattern), recursive=True):
            if os.path.isfile(path) and mentions(path, script):
                found.add(os.path.relpath(path, ROOT))
    return found


def test_scripts_found():
    assert len(SCRIPTS) >= 10, SCRIPTS


@pytest.mark.parametrize('path', SCRIPTS, ids=[os.path.basename(p) for p in SCRIPTS])
def test_header_names_the_files_that_use_the_script(path):
    script = os.path.basename(path)
    named = used_by(path)
    assert named, '%s: no "# Used by:" line in the header' % script
    for name in named:
        full = os.path.join(ROOT, name)
        assert os.path.isfile(full), '%s names %s, which does not exist' % (script, name)
        assert mentions(full, script), '%s names %s, which does not use it' % (script, name)
    missing = sorted(users(script) - set(named))
    assert not missing, '%s: used by %s, not named in its header' % (script, missing)


def test_used_by_parses_continued_lines(tmp_path):
    p = tmp_path / 's.yaml'
    p.write_text('# About.\n# Used by: test/a.test,\n#   test/b.py, launch/c.launch\n'
                 '# More about.\n#  indented, not a list\nrate_hz: 120\n')
    assert used_by(str(p)) == ['test/a.test', 'test/b.py', 'launch/c.launch']
