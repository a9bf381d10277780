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


def _keypoint_csv(path, ids, header=False):
    """A keypoint CSV of one row per id (the community's headerless form, or the shared
    form with a header, the id as the row's label)."""
    import numpy as np
    rng = np.random.default_rng(0)
    rows = ['person,label,source_label,' + ','.join('%s%d' % (a, i) for i in range(21) for a in 'xy')] if header else []
    for k, cls in enumerate(ids):
        values = ','.join('%.3f' % v for v in rng.uniform(-1, 1, 42))
        rows.append('me,%s,%s,%s' % (cls, cls, values) if header else '%s,%s' % (cls, values))
    path.write_text('\n'.join(rows) + '\n')
    return str(path)


def _pose_records(path, labels):
    import json

    from leap_teleop.hands.frame import Frame
    from leap_teleop.hands.rendered_hand import render_hand
    from leap_teleop.hands.sources import leapjs
    path.write_text(''.join(json.dumps({'person': 'me', 'label': lab, 'frame': leapjs.frame_to_dict(
        Frame(i, i / 60.0, [render_hand('right', 'two', (i, 200, 0))]))}) + '\n' for i, lab in enumerate(labels)))
    return str(path)


def test_a_file_of_several_classes_or_another_label_is_refused_with_label(tmp_path, monkeypatch, capsys):
    # --label relabelled every row: a community keypoint.csv (ids 0 open, 1 close, 2 pointer,
    # then the user's 3) turned every open hand and fist of it into the user's class.
    community = _keypoint_csv(tmp_path / 'keypoint.csv', ['0', '1', '2', '10', '3', '1', '0'])
    line = _refusal(tmp_path, monkeypatch, capsys, ['--add', community, '--label', 'peace'])
    assert line.endswith('error: --add %s holds rows of 5 classes (ids 0, 1, 2, 3, 10): --label peace '
                         'would make every one peace; give --id ID after --add to take the rows of one'
                         % community), line
    shared_form = _keypoint_csv(tmp_path / 'mine.csv', ['peace', 'fist'], header=True)
    line = _refusal(tmp_path, monkeypatch, capsys, ['--add', shared_form, '--label', 'peace'])
    assert '--add %s holds rows of 2 classes (labels fist, peace)' % shared_form in line, line
    # one label, not NAME: the rows say what they are
    other = _keypoint_csv(tmp_path / 'wave.csv', ['wave'] * 3, header=True)
    line = _refusal(tmp_path, monkeypatch, capsys, ['--add', other, '--label', 'peace'])
    assert line.endswith('error: --add %s labels its rows wave, not peace: give --label wave, or --id wave '
                         '--label peace to take them as peace' % other), line
    # a label no user class may take is not suggested (it is refused in turn)
    thumbs = _keypoint_csv(tmp_path / 'thumbs.csv', ['thumbs_up'] * 3, header=True)
    line = _refusal(tmp_path, monkeypatch, capsys, ['--add', thumbs, '--label', 'thumb'])
    assert line.endswith('error: --add %s labels its rows thumbs_up, not thumb: give --id thumbs_up '
                         '--label thumb to take them as thumb' % thumbs), line
    poses = _pose_records(tmp_path / 'two.jsonl', ['two', 'two', 'open'])
    line = _refusal(tmp_path, monkeypatch, capsys, ['--add', poses, '--label', 'two'])
    assert '--add %s holds rows of 2 classes (labels open, two)' % poses in line, line
    # an id no row has, and an --id before any --add
    line = _refusal(tmp_path, monkeypatch, capsys, ['--add', community, '--id', '7', '--label', 'peace'])
    assert line.endswith('error: --add %s --id 7: no row has that id (ids 0, 1, 2, 3, 10)' % community), line
    line = _refusal(tmp_path, monkeypatch, capsys, ['--id', '3', '--add', community, '--label', 'peace'])
    assert line.endswith('error: --id 3: give it after the --add FILE whose rows it picks'), line


def test_one_class_of_a_file_is_taken_with_id(tmp_path, monkeypatch):
    from leap_teleop.hands.gestures import training_set
    community = _keypoint_csv(tmp_path / 'keypoint.csv', ['0', '3', '1', '3', '3'])
    poses = _pose_records(tmp_path / 'two.jsonl', ['two', 'open', 'two'])
    fits = []
    monkeypatch.setattr(train_gestures, 'train', lambda family, data, adds, **k: fits.append(adds) or 1 / 0)
    with pytest.raises(ZeroDivisionError):      # the fit was reached
        train_gestures.main(['--add', community, '--label', 'peace', '--id', '3', '--out',
                             str(tmp_path / 'm.npz'), '--no-report'])
    with pytest.raises(ZeroDivisionError):
        train_gestures.main(['--add', poses, '--id', 'two', '--label', 'victory', '--out',
                             str(tmp_path / 'm.npz'), '--no-report'])
    assert fits == [[(community, 'peace', '3')], [(poses, 'victory', 'two')]]
    ds = training_set.Dataset('keypoints')
    training_set.add_keypoints(ds, community, label='peace', person='user:k', take='3')
    assert set(ds.y) == {'peace'} and len(ds.y) == 3 * 2 * 2       # 3 rows, a copy each, mirrored
    ds = training_set.Dataset('leap')
    training_set.add_leap_poses(ds, poses, label='victory', person='user:p', take='two')
    assert set(ds.y) == {'victory'} and ds.sources == ['two.jsonl (2 hands)']
