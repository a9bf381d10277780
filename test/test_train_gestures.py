"""train_gestures' checks of its --add files before the fit (which takes minutes)."""
import gzip
import shutil

import pytest

from leap_teleop.hands.gestures import train as train_gestures


def _refusal(tmp_path, monkeypatch, capsys, args):
    monkeypatch.setattr(train_gestures, 'train',
                        lambda *a, **k: pytest.fail('fitted before checking the arguments'))
    with pytest.raises(SystemExit) as stop:
        train_gestures.main(args + ['--out', str(tmp_path / 'm.npz'), '--no-report'])
    assert stop.value.code == 2
    return capsys.readouterr().err.strip().splitlines()[-1]


@pytest.mark.parametrize('how', ['the same path', 'a link', 'a copy', 'a gzipped copy'])
def test_the_same_recording_given_twice_is_refused(tmp_path, monkeypatch, capsys, how):
    # Each --add file is one person, held out in turn: a copy of it left in the fit scored
    # that person on the very rows it was fitted on.
    first = tmp_path / 'two.jsonl'
    first.write_text('{"person": "me", "label": "two", "frame": {}}\n' * 3)
    (tmp_path / 'session2').mkdir()
    second = tmp_path / 'session2' / 'two.jsonl'
    if how == 'the same path':
        second = first
    elif how == 'a link':
        second.symlink_to(first)
    elif how == 'a copy':
        shutil.copy(first, second)
    else:
        second = tmp_path / 'session2' / 'two.jsonl.gz'
        second.write_bytes(gzip.compress(first.read_bytes()))
    line = _refusal(tmp_path, monkeypatch, capsys,
                    ['--add', str(first), '--label', 'two', '--add', str(second), '--label', 'two'])
    assert line.endswith('error: --add %s: the same recording as --add %s (give a second session)'
                         % (second, first)), line


def test_two_sessions_of_one_gesture_pass_the_check(tmp_path):
    a, b = tmp_path / 'a.jsonl', tmp_path / 'b.jsonl'
    a.write_text('{"person": "me", "label": "two", "frame": {"id": 1}}\n')
    b.write_text('{"person": "me", "label": "two", "frame": {"id": 2}}\n')
    assert train_gestures.same_recording([str(a), str(b)]) is None


@pytest.mark.parametrize('labels', [['two'], ['two', 'gun'], ['two', 'gun', 'wave']])
def test_no_shared_data_is_refused_whatever_the_number_of_labels(tmp_path, capsys, labels):
    # With two labels of a user's own, the fit went on and wrote a model of their classes
    # alone, which every consumer refuses.
    import json

    from leap_teleop.hands.frame import Frame
    from leap_teleop.hands.rendered_hand import render_hand
    from leap_teleop.hands.sources import leapjs
    args = []
    for label in labels:
        path = tmp_path / (label + '.jsonl')
        path.write_text(''.join(json.dumps({'person': 'me', 'label': label, 'frame': leapjs.frame_to_dict(
            Frame(i, i / 60.0, [render_hand('right', 'two', (i, 200, 0))]))}) + '\n' for i in range(20)))
        args += ['--add', str(path), '--label', label]
    (tmp_path / 'empty').mkdir()
    with pytest.raises(SystemExit) as stop:
        train_gestures.main(['--data', str(tmp_path / 'empty')] + args
                            + ['--out', str(tmp_path / 'm.npz'), '--no-report'])
    assert 'is the shared data at %s?' % (tmp_path / 'empty') in str(stop.value.code)
    assert not (tmp_path / 'm.npz').exists()


def test_your_own_samples_need_an_out_of_your_own(tmp_path, capsys, monkeypatch):
    # Without --out a retrain with --add rewrote the shipped model the sender loads.
    monkeypatch.setattr(train_gestures, 'train', lambda *a, **k: pytest.fail('fitted'))
    samples = tmp_path / 'two.jsonl'
    samples.write_text('{"person": "me", "label": "two", "frame": {"id": 1}}\n')
    with pytest.raises(SystemExit) as stop:
        train_gestures.main(['--add', str(samples), '--label', 'two', '--no-report'])
    assert stop.value.code == 2
    assert '--add needs --out MODEL' in capsys.readouterr().err
