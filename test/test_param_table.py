"""README's parameter tables are what the declarations say."""
import os

from tools import param_table
README = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'README.md')
SCRIPTS = os.path.join(os.path.dirname(README), 'scripts')


def test_readme_parameter_tables_match_the_declarations():
    assert param_table.readme_copy(README) == param_table.markdown(), (
        'README.md is out of date: python -m tools.param_table')
    assert param_table.main(['--check', README]) == 0


def test_every_table_names_an_installed_script_and_every_parameter():
    text = param_table.markdown()
    for module, script, params in param_table.node_tables():
        assert os.path.exists(os.path.join(SCRIPTS, script)), script
        for name, p in params.items():
            assert '| `~%s` |' % name in text and p.allowed().replace('<', '&lt;') in text


def test_check_fails_on_a_stale_copy(tmp_path):
    stale = tmp_path / 'README.md'
    stale.write_text(open(README).read().replace('| `~hand_timeout` |', '| `~hand_timeoutx` |'))
    assert param_table.main(['--check', str(stale)]) == 1
