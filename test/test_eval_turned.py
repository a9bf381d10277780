"""tools.evaluation.turned: the real turned hands are judged by a model that never saw them."""
import pytest

from tools.evaluation import turned

pytestmark = pytest.mark.slow          # fits a pose model (~15 s)


def test_turned_hands_are_judged_by_a_model_fitted_without_them(leapjs_data):
    model = turned.model_without_the_takes(leapjs_data)
    unseen = turned.real(leapjs_data, model)
    shipped = turned.real(leapjs_data)
    assert set(unseen) == set(shipped) and len(unseen) >= 3
    for key, (right, total) in unseen.items():
        assert total == shipped[key][1] and total > 500, key
        assert right / total >= 0.85, (key, right, total)
    # fitted on them, the shipped model scores higher: the two are not the same model
    assert sum(r for r, _ in unseen.values()) < sum(r for r, _ in shipped.values())


def test_an_empty_turn_bin_prints_no_fraction(monkeypatch, capsys):
    monkeypatch.setattr(turned, 'model_without_the_takes', lambda data: None)
    monkeypatch.setattr(turned, 'real', lambda data, model: {'20-40 deg': (3, 4)})
    monkeypatch.setattr(turned, 'synthetic', lambda: {})
    assert turned.main(['--data', 'unused']) == 0
    lines = {line.split()[0]: line.split() for line in capsys.readouterr().out.splitlines()
             if line.startswith('  ') and 'deg' in line}
    assert lines['0-20'][-1] == '-' and lines['20-40'][-1] == '0.7500'
