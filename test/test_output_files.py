"""Every tool that writes a file checks it before its work starts: an output that is one of
its inputs, a place that takes no file, or a file that is not the tool's own is refused
in one line, and nothing is overwritten or lost at the end."""
import os
import shutil

import numpy as np
import pytest

from leap_teleop.hands import classify_frames, record_frames
from leap_teleop.hands.gestures import record as record_gestures
from leap_teleop.hands.gestures import train as train_gestures
from leap_teleop.hands.gestures.datasets import HANDS_DATA
from leap_teleop.output_file import output_problem

SHARED_IMAGES = ('fist__asl__A11.jpg', 'fist__asl__A16.jpg')
UNWRITABLE_DIR = '/proc'        # root, too, cannot make a file there


def test_output_problem_names_each_case_and_changes_nothing(tmp_path):
    kept = tmp_path / 'kept.txt'
    kept.write_text('a take')
    os.utime(kept, (1e9, 1e9))
    link = tmp_path / 'link.txt'
    link.symlink_to(kept)
    assert output_problem(str(kept)) is None
    assert kept.read_text() == 'a take' and kept.stat().st_mtime == 1e9
    assert output_problem(str(tmp_path / 'new.txt')) is None
    assert not (tmp_path / 'new.txt').exists()          # the probe leaves nothing behind
    assert output_problem('') == 'name a file'
    assert output_problem(str(tmp_path)) == 'a folder: name a file'
    assert output_problem(str(tmp_path / 'no' / 'x')) == 'no folder %s' % (tmp_path / 'no')
    assert 'it is the input %s' % kept in output_problem(str(link), [None, '-', str(kept)])
    assert output_problem(str(tmp_path / ('x' * 300))).startswith('cannot write it')
    assert output_problem(os.path.join(UNWRITABLE_DIR, 'x.bag')).startswith('cannot write it')
    dangling = tmp_path / 'dangling.txt'
    dangling.symlink_to(tmp_path / 'made_later.txt')
    assert output_problem(str(dangling)) is None
    assert not (tmp_path / 'made_later.txt').exists()
    loop = tmp_path / 'loop.txt'
    loop.symlink_to(loop)
    assert output_problem(str(loop)).startswith('cannot write it')
    os.mkfifo(tmp_path / 'pipe')
    assert output_problem(str(tmp_path / 'pipe')) == 'a pipe that nothing reads'
    reader = os.open(tmp_path / 'pipe', os.O_RDONLY | os.O_NONBLOCK)
    try:
        assert output_problem(str(tmp_path / 'pipe')) is None     # e.g. >(gzip > f)
    finally:
        os.close(reader)
    if os.path.exists('/dev/null'):
        assert output_problem('/dev/null') is None


def test_recording_to_bag_never_writes_over_its_input_or_a_file_not_a_bag(
        tmp_path, leapjs_data, capsys):
    from leap_teleop.ros import recording_to_bag
    take = tmp_path / 'grab.json.lz'
    shutil.copy(os.path.join(leapjs_data, 'grab.json.lz'), take)
    before = take.read_bytes()
    notes = tmp_path / 'notes.csv'
    notes.write_text('a,b\n')
    for args, message in (([str(take), str(take)], 'name the bag file NAME.bag'),
                          (['--script', str(notes), str(notes)], 'name the bag file NAME.bag'),
                          ([str(take), str(tmp_path / ('x' * 300 + '.bag'))], 'cannot write it')):
        with pytest.raises(SystemExit) as stop:
            recording_to_bag.main(args)
        assert stop.value.code == 2
        assert message in capsys.readouterr().err.splitlines()[-1]
    assert take.read_bytes() == before and notes.read_text() == 'a,b\n'
    same = tmp_path / 'take.bag'         # a recording that happens to end in .bag
    same.write_bytes(before)
    with pytest.raises(SystemExit):
        recording_to_bag.main([str(same), str(same)])
    assert 'it is the input' in capsys.readouterr().err
    assert same.read_bytes() == before


def test_record_frames_refuses_its_own_input_before_recording(tmp_path, leapjs_data, capsys,
                                                              monkeypatch):
    monkeypatch.setattr(record_frames, 'record',
                        lambda *a, **k: pytest.fail('recorded before checking the output'))
    take = tmp_path / 'grab.json.lz'
    shutil.copy(os.path.join(leapjs_data, 'grab.json.lz'), take)
    before = take.read_bytes()
    assert record_frames.main([str(take), '--source', 'recording', '--recording', str(take),
                               '--realtime', '0', '--frames', '5']) == 2
    err = capsys.readouterr().err
    assert 'it is the input %s: it would be overwritten' % take in err and err.count('\n') == 1
    assert take.read_bytes() == before
    assert record_frames.main([os.path.join(UNWRITABLE_DIR, 'x.json'), '--source', 'recording',
                               '--recording', str(take)]) == 2
    assert 'cannot write it' in capsys.readouterr().err


def test_classify_frames_never_writes_over_an_image_it_reads(tmp_path, capsys):
    for name in SHARED_IMAGES:
        shutil.copy(os.path.join(HANDS_DATA, name), tmp_path / name)
    image = tmp_path / SHARED_IMAGES[1]
    before = image.read_bytes()
    for spec in (str(tmp_path), str(tmp_path / '*.jpg')):
        assert classify_frames.main([spec, '--out', str(image)]) == 2
        err = capsys.readouterr().err
        assert 'it is the input %s' % image in err and err.count('\n') == 1, err
    assert image.read_bytes() == before


@pytest.mark.parametrize('out, message', [
    (os.path.join(UNWRITABLE_DIR, 'two.jsonl'), 'cannot write it'),
    ('{tmp}/' + 'x' * 300 + '.jsonl', 'cannot write it'),
    ('{tmp}/folder.jsonl', 'a folder'),
    ('{tmp}/script.yaml.jsonl', 'it is the input'),
])
def test_record_gestures_checks_its_output_before_recording(tmp_path, monkeypatch, capsys,
                                                            out, message):
    monkeypatch.setattr(record_gestures, 'collect',
                        lambda *a, **k: pytest.fail('recorded before checking the output'))
    (tmp_path / 'folder.jsonl').mkdir()
    script = tmp_path / 'script.yaml.jsonl'     # an odd name, but the user's script
    script.write_text('rate_hz: 30\nhands:\n  right:\n  - {pose: open, duration: 1.0}\n')
    assert record_gestures.main(['--source', 'scripted', '--script', str(script),
                                 '--label', 'two', '--out', out.format(tmp=tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count('\n') == 1, err
    assert script.read_text().startswith('rate_hz: 30')


@pytest.mark.parametrize('name, suggestion', [('peace.csv', 'peace_2.csv'),
                                               ('two.jsonl.gz', 'two_2.jsonl.gz')])
def test_record_gestures_keeps_an_earlier_take(tmp_path, monkeypatch, capsys, name, suggestion):
    monkeypatch.setattr(record_gestures, 'collect',
                        lambda *a, **k: pytest.fail('recorded over an earlier take'))
    earlier = tmp_path / name
    earlier.write_text('a first session\n')
    source = (['--source', 'video', '--video', 'x.mp4'] if name.endswith('.csv')
              else ['--source', 'scripted', '--script', 'x.yaml'])
    assert record_gestures.main(source + ['--label', 'two', '--out', str(earlier)]) == 2
    err = capsys.readouterr().err
    assert err == ('record_gestures: --out %s: holds an earlier take; record to another file '
                   '(e.g. --out %s) or remove it\n' % (earlier, tmp_path / suggestion))
    assert earlier.read_text() == 'a first session\n'


def test_record_gestures_leaves_no_part_file_when_writing_fails(tmp_path):
    class Unwritable:
        def __iter__(self):
            raise OSError(28, 'No space left on device')
    with pytest.raises(OSError):
        record_gestures.write(str(tmp_path / 'two.jsonl'), 'leap', Unwritable())
    assert os.listdir(tmp_path) == []
    mask = os.umask(0o027)
    try:
        assert record_gestures.write(str(tmp_path / 'two.csv'), 'keypoints',
                                     [['me', 'two', 'two'] + [0] * 42]) == str(tmp_path / 'two.csv')
    finally:
        os.umask(mask)
    assert os.listdir(tmp_path) == ['two.csv']
    assert (tmp_path / 'two.csv').stat().st_mode & 0o777 == 0o640     # as any new file


def test_a_take_goes_beside_a_file_that_appeared_while_recording(tmp_path):
    first = tmp_path / 'two.jsonl.gz'
    first.write_text('another session, saved meanwhile\n')
    (tmp_path / 'two_2.jsonl.gz').write_text('and another\n')
    got = record_gestures.write(str(first), 'leap', [{'label': 'two'}])
    assert got == str(tmp_path / 'two_3.jsonl.gz')
    assert first.read_text() == 'another session, saved meanwhile\n'
    assert sorted(os.listdir(tmp_path)) == ['two.jsonl.gz', 'two_2.jsonl.gz', 'two_3.jsonl.gz']
    assert record_gestures.free_session_name(str(first)) == str(tmp_path / 'two_4.jsonl.gz')


def test_train_gestures_never_writes_over_a_file_that_is_no_model_or_card(
        tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(train_gestures, 'train',
                        lambda *a, **k: pytest.fail('fitted before checking the arguments'))
    samples = tmp_path / 'wave.jsonl'
    samples.write_text('{}\n')
    notes = tmp_path / 'notes.md'           # where the card of notes.npz would go
    notes.write_text('# my notes\n')
    archive = tmp_path / 'mydata.npz'
    np.savez(archive, a=np.arange(3))
    kept = archive.read_bytes()
    for out, message in ((tmp_path / 'notes.npz', '%s is no model card' % notes),
                         (archive, 'a file that is no pose model'),
                         (os.path.join(UNWRITABLE_DIR, 'm.npz'), 'cannot write it')):
        with pytest.raises(SystemExit) as stop:
            train_gestures.main(['--add', str(samples), '--label', 'wave', '--no-report',
                                 '--out', str(out)])
        assert stop.value.code == 2
        assert message in capsys.readouterr().err.splitlines()[-1]
    assert notes.read_text() == '# my notes\n' and archive.read_bytes() == kept


def test_a_model_and_its_card_may_be_written_over_by_a_retrain(tmp_path):
    from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS, load_model
    model = tmp_path / 'mine.npz'
    load_model(None, 'leap').save(str(model))
    (tmp_path / 'mine.md').write_text(train_gestures.CARD_TITLE + ': mine.npz\n')
    assert train_gestures.model_out_problem(str(model), []) is None
    # `make train` refits the shipped models, also when the features changed since
    for path in DEFAULT_MODELS.values():
        assert train_gestures.model_out_problem(path, []) is None
    with np.load(str(model)) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(mean=arrays['mean'][:-1], scale=arrays['scale'][:-1], w0=arrays['w0'][:-1])
    np.savez(str(model), **arrays)
    assert train_gestures.model_out_problem(str(model), []) is None

