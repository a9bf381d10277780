"""The parameter tables in docs/nodes.md are what the declarations say."""
import os

from tools import param_table

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NODES_DOC = os.path.join(ROOT, 'docs', 'nodes.md')
SCRIPTS = os.path.join(ROOT, 'scripts')


def test_docs_parameter_tables_match_the_declarations():
    assert param_table.docs_copy(NODES_DOC) == param_table.markdown(), (
        'docs/nodes.md is out of date: python -m tools.param_table --write '
        'docs/nodes.md')
    assert param_table.main(['--check', NODES_DOC]) == 0


def test_every_table_names_an_installed_script_and_every_parameter():
    text = param_table.markdown()
    for module, script, params in param_table.node_tables():
        assert os.path.exists(os.path.join(SCRIPTS, script)), script
        for name, p in params.items():
            assert '| `~%s` |' % name in text and p.allowed().replace('<', '&lt;') in text


def test_check_fails_on_a_stale_copy(tmp_path):
    stale = tmp_path / 'nodes.md'
    stale.write_text(open(NODES_DOC).read().replace('| `~hand_timeout` |', '| `~hand_timeoutx` |'))
    assert param_table.main(['--check', str(stale)]) == 1


def test_write_regenerates_a_stale_copy_and_keeps_the_rest(tmp_path):
    original = open(NODES_DOC).read()
    stale = tmp_path / 'nodes.md'
    stale.write_text(original.replace('| `~hand_timeout` |', '| `~hand_timeoutx` |'))
    assert param_table.main(['--write', str(stale)]) == 0
    assert stale.read_text() == original
    assert param_table.main(['--check', str(stale)]) == 0


def test_write_and_check_refuse_a_file_without_the_markers(tmp_path, capsys):
    other = tmp_path / 'other.md'
    other.write_text('# no table here\n')
    assert param_table.main(['--write', str(other)]) == 1
    assert other.read_text() == '# no table here\n'
    assert param_table.main(['--check', str(other)]) == 1
    assert 'markers' in capsys.readouterr().err
