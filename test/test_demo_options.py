"""make demo's options: refused before anything starts, and its folder keeps what is not its own."""
import pytest

from tools import demo


@pytest.mark.parametrize('tasks, why', [('drone_typo', 'no task drone_typo'), ('ur10,dron', 'no task dron'),
                                        ('', 'no task given'), (',', 'no task given')])
def test_unknown_or_no_tasks_are_refused_before_the_folder_or_the_graph(tasks, why, tmp_path, capsys,
                                                                       monkeypatch):
    out = tmp_path / 'out'
    out.mkdir()
    (out / 'summary.json').write_text('{}')
    monkeypatch.setattr(demo.subprocess, 'Popen', lambda *a, **k: pytest.fail('a graph started'))
    with pytest.raises(SystemExit) as stop:
        demo.main(['--tasks', tasks, '--out', str(out)])
    assert stop.value.code == 2
    assert why in capsys.readouterr().err
    assert (out / 'summary.json').read_text() == '{}'


def test_a_run_clears_only_its_own_earlier_outputs(tmp_path):
    own = ['summary.json', 'roslaunch.log', 'ur10.gif', 'drone.gif', 'ur10_000.png', 'ur10_1234.png',
           'drone_flight.png', 'rotated_grasp.png']
    others = ['bench_results.json', 'notes.log', 'my_picture.png', 'camera_view.png', 'ur10_x.png',
              'old_summary.json']
    for name in own + others:
        (tmp_path / name).write_text('x')
    demo.clear_earlier_outputs(str(tmp_path))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(others)
