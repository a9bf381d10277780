"""classify_frames CLI: recordings, JSON Lines, malformed input, schema."""
import json
import os
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from leap_teleop.hands import classify_frames
from leap_teleop.hands.classify_frames import FrameClassifier
from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures.datasets import data_dir
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.sources import leapjs

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

DATA = data_dir()
KEYS = ['type', 'fist', 'thumb_up', 'pinch', 'pinch_value', 'rock', 'open', 'thumb_down',
        'events']


def run_cli(args, stdin=None):
    p = subprocess.run([sys.executable, '-m', 'leap_teleop.hands.classify_frames'] + args,
                       input=stdin, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    return [json.loads(line) for line in p.stdout.splitlines()]


def run_main(args, capsys):
    """The same command in this process (its main, as `python -m` runs it): for the tests
    that run it many times; the ones above and below keep the real subprocess."""
    capsys.readouterr()
    assert classify_frames.main(args) == 0
    return [json.loads(line) for line in capsys.readouterr().out.splitlines()]


def check_line(line):
    assert set(line) >= {'id', 'timestamp', 'hands'}
    for h in line['hands']:
        assert list(h) == KEYS and h['type'] in ('left', 'right')
        assert 0.0 <= h['pinch_value'] <= 0.8
        assert all(isinstance(h[k], bool) for k in ('fist', 'thumb_up', 'pinch', 'rock', 'open', 'thumb_down'))


def _dicts(poses):
    return [leapjs.frame_to_dict(Frame(i, i / 100.0, [render_hand('right', p, (0, 200, 0), pinch_value=0.5)]))
            for i, p in enumerate(poses)]


def test_json_lines_on_stdin_stream_and_stateless(tmp_path):
    # 10 ms apart: a fist held 0.4 s, then open (an unfold once open has held 0.15 s)
    frames = _dicts(['fist'] * 40 + ['open'] * 30)
    text = '\n'.join(json.dumps(f) for f in frames) + '\n'
    out = run_cli([], stdin=text)
    assert len(out) == 70 and [o['id'] for o in out] == list(range(70))
    for o in out:
        check_line(o)
    assert out[39]['hands'][0]['fist'] and out[69]['hands'][0]['open']
    events = [e for o in out for e in o['hands'][0]['events']]
    assert events == ['fist', 'open', 'unfold']
    out = run_cli(['--stateless'], stdin=text)
    assert out[0]['hands'][0]['fist'] and out[40]['hands'][0]['open']
    assert all(o['hands'][0]['events'] == [] for o in out)


def test_recording_file_and_json_lines_file(tmp_path):
    frames = _dicts(['pinch'] * 5)
    rec = str(tmp_path / 'r.json.gz')
    leapjs.save(rec, frames)
    jl = tmp_path / 'f.jsonl'
    jl.write_text('\n'.join(json.dumps(f) for f in frames))
    a, b = run_cli([rec]), run_cli([str(jl)])
    assert a == b and len(a) == 5 and a[-1]['hands'][0]['pinch']
    assert a[-1]['hands'][0]['pinch_value'] == pytest.approx(0.5)


def test_stamps_that_do_not_advance_are_spaced_as_the_sender_does(tmp_path, capsys):
    # Every interval was 0: no hold grew, so no fold or unfold, where the sender's recording
    # source spaces such a take by its frame rate (with a warning) and sees them.
    frames = _dicts(['fist'] * 40 + ['open'] * 30 + ['fist'] * 40)
    capsys.readouterr()
    timed = run_main([str(_save_lines(tmp_path / 'timed.jsonl', frames))], capsys)   # 10 ms apart
    assert [e for o in timed for e in o['hands'][0]['events'] if 'fold' in e] == ['unfold', 'fold']
    stalled = [dict(f, timestamp=1400000000) for f in frames]
    rec = str(tmp_path / 'stalled.json')
    leapjs.save(rec, stalled, {'frameRate': 100})
    assert classify_frames.main([rec]) == 0
    captured = capsys.readouterr()
    out = [json.loads(line) for line in captured.out.splitlines()]
    assert [o['hands'] for o in out] == [o['hands'] for o in timed]
    assert [o['timestamp'] for o in out] == [k * 10000 for k in range(110)]
    assert captured.err == ('classify_frames: recording %s: its timestamps do not advance (109 of 109 '
                            'steps between frames are not forward in time); played at 100 frames/s '
                            '(its metadata.frameRate)\n' % rec)
    # JSON Lines keep their stamps: a frame written twice with its stamp is no time passing,
    # as for the sender (judged 10 ms on, it came after the next frame of a 115 Hz Leap,
    # a stamp going back that ended the fist before the unfold)
    fast = [dict(f, timestamp=round(k * 1e6 / 115)) for k, f in enumerate(frames[:70])]
    fast.insert(41, dict(fast[40]))
    out = run_main([str(_save_lines(tmp_path / 'repeated.jsonl', fast))], capsys)
    assert [e for o in out for e in o['hands'][0]['events'] if 'fold' in e] == ['unfold']


def _save_lines(path, dicts):
    path.write_text(''.join(json.dumps(d) + '\n' for d in dicts))
    return path


def test_garbage_lines_never_stop_the_run():
    text = 'not json\n[1, 2]\n{"id": 3}\n{"id": 4, "hands": [{"type": "left"}], "pointables": "x"}\n' \
           '{"id": 5, "timestamp": 9, "hands": [{"type": "right", "palmPosition": [1, null, 2]}]}\n'
    out = run_cli([], stdin=text)
    assert len(out) == 5
    assert 'error' in out[0] and 'error' in out[1] and out[2]['hands'] == []
    assert out[4]['hands'][0]['type'] == 'right' and not out[4]['hands'][0]['open']


@pytest.mark.usefixtures('leapjs_data')     # fails without the shared recordings
def test_every_shared_recording_classifies(capsys):
    takes = sorted(n for n in os.listdir(DATA) if n.endswith('.json.lz'))
    assert len(takes) == 13, takes          # the loop below checks every one of them
    for name in takes:
        out = run_main([os.path.join(DATA, name)], capsys)
        assert len(out) > 50
        assert any(h for o in out for h in o['hands']), name      # hands were classified
        for o in out:
            check_line(o)


json_values = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(), st.text(max_size=5),
                                     st.floats(allow_nan=True, allow_infinity=True)),
                           lambda c: st.one_of(st.lists(c, max_size=4),
                                               st.dictionaries(st.text(max_size=8), c, max_size=4)),
                           max_leaves=20)
vec = st.one_of(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=3, max_size=3),
                json_values)
hand = st.fixed_dictionaries({'type': st.sampled_from(['left', 'right', 'up']), 'id': st.integers(0, 3)},
                             optional={'palmPosition': vec, 'palmNormal': vec, 'direction': vec,
                                       'grabStrength': json_values, 'pinchStrength': json_values,
                                       'confidence': json_values})
pointable = st.fixed_dictionaries({'handId': st.integers(0, 3), 'type': st.integers(-1, 6)},
                                  optional={'tipPosition': vec, 'dipPosition': vec, 'pipPosition': vec,
                                            'mcpPosition': vec, 'direction': vec, 'extended': json_values})
frame = st.fixed_dictionaries({}, optional={'id': json_values, 'timestamp': json_values,
                                            'hands': st.one_of(st.lists(hand, max_size=3), json_values),
                                            'pointables': st.one_of(st.lists(pointable, max_size=8), json_values),
                                            'gestures': json_values})


@settings(max_examples=200, deadline=None)
@given(st.lists(st.one_of(frame, json_values), min_size=1, max_size=6), st.booleans())
def test_frame_parsing_never_raises(frames, stateless):
    c = FrameClassifier(stateless=stateless)
    for d in frames:
        if not isinstance(d, dict):
            continue
        line = c.classify(d)
        json.dumps(line, allow_nan=False)
        check_line(line)


KEYPOINTS = os.path.join(os.path.dirname(DATA), 'keypoints')


def test_keypoints_in_both_csv_forms_give_one_line_per_row(tmp_path, capsys):
    from leap_teleop.hands.gestures import datasets as gesture_data
    path = os.path.join(KEYPOINTS, 'Harikumar4.csv')
    if not os.path.isfile(path):
        pytest.fail('the shared keypoint files are not at %s' % KEYPOINTS)
    _, labels, xy = gesture_data.read_keypoints(path)
    # the community's own form: a class id, then 42 numbers, no header
    community = tmp_path / 'keypoint.csv'
    community.write_text(''.join('7,' + ','.join('%.4f' % v for v in row.ravel()) + '\n'
                                 for row in xy[:20]))
    a = run_main(['--keypoints', str(community)], capsys)
    b_all = run_main(['--keypoints', path], capsys)
    assert len(b_all) == len(xy) and [o['id'] for o in b_all] == list(range(len(xy)))
    b = b_all[:20]
    assert len(a) == 20 and [o['id'] for o in a] == list(range(20))
    for line in a:
        h, = line['hands']
        assert h['type'] is None and set(h) == set(KEYS)
    # the class id is ignored: both forms judge the same rows alike (4-decimal rounding)
    assert [o['hands'] for o in a] == [o['hands'] for o in b]


@pytest.mark.parametrize('before', ['\n', '\r\n\n', ' \n,,\n', '\ufeff\n'])
def test_blank_lines_before_the_header_are_skipped(tmp_path, capsys, before):
    # the header was told only on the file's first line: the next one was 'not a keypoint
    # row (45 columns, not 43)' and the run stopped
    from leap_teleop.hands.gestures import datasets as gesture_data
    with open(os.path.join(KEYPOINTS, 'Harikumar4.csv'), encoding='utf-8') as f:
        head = ''.join(f.readline() for _ in range(6))
    plain, blank = tmp_path / 'plain.csv', tmp_path / 'blank.csv'
    plain.write_text(head, encoding='utf-8')
    blank.write_text(before + head, encoding='utf-8', newline='')
    want = run_main(['--keypoints', str(plain)], capsys)
    assert len(want) == 5 and run_main(['--keypoints', str(blank)], capsys) == want
    persons, labels, xy = gesture_data.read_keypoints(str(blank))
    assert persons == ['Harikumar4'] * 5 and len(xy) == 5
    # a header after a row is still no row
    late = tmp_path / 'late.csv'
    late.write_text('7,' + ','.join(['0.5'] * 42) + '\n' + head, encoding='utf-8')
    with pytest.raises(gesture_data.DataError, match='row 2: not a keypoint row'):
        gesture_data.read_keypoints(str(late))


def test_keypoints_mirror_image_reads_the_same(tmp_path, capsys):
    from leap_teleop.hands.gestures import datasets as gesture_data
    _, _, xy = gesture_data.read_keypoints(os.path.join(KEYPOINTS, 'Kazuhito00.csv'))
    rows = xy[::200]
    mirrored = rows.copy()
    mirrored[:, :, 0] *= -1
    paths = []
    for name, data in (('a.csv', rows), ('b.csv', mirrored)):
        p = tmp_path / name
        p.write_text(''.join('0,' + ','.join(repr(float(v)) for v in r.ravel()) + '\n' for r in data))
        paths.append(str(p))
    a, b = (run_main(['--keypoints', p], capsys) for p in paths)
    assert [o['hands'] for o in a] == [o['hands'] for o in b]
    # and they are judged, not all false: Kazuhito00 shows open hands and fists
    assert sum(o['hands'][0]['open'] for o in a) >= 3 and sum(o['hands'][0]['fist'] for o in a) >= 3


def test_malformed_keypoint_file_is_one_clear_error(tmp_path):
    bad = tmp_path / 'bad.csv'
    bad.write_text('1,0.0,0.0,0.5\n')
    p = subprocess.run([sys.executable, '-m', 'leap_teleop.hands.classify_frames', '--keypoints',
                        str(bad)], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and 'row 1' in p.stderr and 'Traceback' not in p.stderr


def test_pose_records_and_quantumleap_takes_classify_as_their_frames(tmp_path, capsys):
    """The shared data's own forms (pose records, plain or gzipped, as the shared static
    poses and record_gestures write them; QuantumLeap's {"frames": N, "data": [...]}
    takes) give the lines their bare frames give."""
    import gzip
    frames = _dicts(['fist'] * 5 + ['open'] * 5 + ['pinch'] * 5)
    bare = tmp_path / 'bare.jsonl'
    bare.write_text(''.join(json.dumps(f) + '\n' for f in frames))
    records = ''.join(json.dumps({'person': 'me', 'label': 'x', 'frame': f}) + '\n' for f in frames)
    plain, packed = tmp_path / 'poses.jsonl', tmp_path / 'poses.jsonl.gz'
    plain.write_text(records)
    with gzip.open(packed, 'wt') as f:
        f.write(records)
    take = tmp_path / 'take.json.gz'
    with gzip.open(take, 'wt') as f:
        json.dump({'frames': len(frames), 'data': frames}, f)
    want = run_main(['--stateless', str(bare)], capsys)
    assert [o['hands'][0]['fist'] for o in want] == [True] * 5 + [False] * 10
    assert [o['hands'][0]['open'] for o in want] == [False] * 5 + [True] * 5 + [False] * 5
    for path in (plain, packed, take):
        assert run_main(['--stateless', str(path)], capsys) == want, path
    assert leapjs.load(str(take))[1] == frames


def test_the_shared_people_files_classify(capsys):
    """The shared static poses (gzipped pose records, the documented command) and a shared
    dynamic take read as hands, the poses as they were recorded (fails without the shared
    data)."""
    import gzip
    people = os.path.join(os.path.dirname(DATA), 'leap_people')
    poses = os.path.join(people, 'gti_dev.jsonl.gz')
    take = os.path.join(people, 'guinevere', '01', 'thumbs_up-1.json.gz')
    for path in (poses, take):
        if not os.path.isfile(path):
            pytest.fail('the shared Leap people are not at %s' % people)
    with gzip.open(poses, 'rt') as f:
        labels = [json.loads(line)['label'] for line in f]
    out = run_main(['--stateless', poses], capsys)
    assert len(out) == len(labels) == 30675 and all(len(o['hands']) == 1 for o in out)
    five = [o['hands'][0]['open'] for o, lab in zip(out, labels) if lab == 'five']
    assert len(five) > 1000 and sum(five) >= 0.9 * len(five)
    out = run_main([take], capsys)
    assert len(out) > 30 and all(len(o['hands']) == 1 for o in out)
    assert sum(o['hands'][0]['thumb_up'] for o in out) >= 0.5 * len(out)


def test_a_truncated_gzip_is_one_clear_error_after_the_frames_it_held(tmp_path):
    import gzip
    # open hands all over the place: frames that do not compress to a few bytes
    frames = [leapjs.frame_to_dict(Frame(i, i / 100.0, [render_hand(
        'right', 'open', (i * 0.37 % 100, 200 + i * 0.11 % 50, i * 0.53 % 80))]))
        for i in range(400)]
    whole = gzip.compress(''.join(json.dumps({'person': 'me', 'label': 'x', 'frame': f}) + '\n'
                                  for f in frames).encode())
    cut = tmp_path / 'cut.jsonl.gz'
    cut.write_bytes(whole[:len(whole) // 2])
    p = subprocess.run([sys.executable, '-m', 'leap_teleop.hands.classify_frames', '--stateless',
                        str(cut)], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and 'Traceback' not in p.stderr
    assert 'cannot read on after' in p.stderr and str(cut) in p.stderr
    lines = [json.loads(line) for line in p.stdout.splitlines()]
    assert 0 < len(lines) < 400 and all(o['hands'][0]['open'] for o in lines)


@pytest.mark.parametrize('layout', ['one line, long metadata', 'pretty-printed', 'bare list'])
def test_a_recording_is_told_from_json_lines_by_its_shape(tmp_path, capsys, layout):
    import gzip
    frames = _dicts(['fist'] * 3 + ['open'] * 3)
    if layout == 'bare list':
        text = json.dumps(frames)
    else:
        doc = {'metadata': {'note': 'x' * 70000 if layout.startswith('one') else 'short'},
               'frames': frames}
        text = json.dumps(doc, indent=None if layout.startswith('one') else 2)
    path = tmp_path / 'take.json.gz'
    with gzip.open(path, 'wt') as f:
        f.write(text)
    out = run_main(['--stateless', str(path)], capsys)
    assert [o['hands'][0]['open'] for o in out] == [False] * 3 + [True] * 3


def _model_arrays():
    import numpy as np

    from leap_teleop.hands.gestures.classifier import DEFAULT_MODELS
    with np.load(DEFAULT_MODELS['leap']) as z:
        return {k: z[k] for k in z.files}


@pytest.mark.parametrize('spoil, message', [
    ('empty', 'cannot read a pose model'),
    ('one array', 'one array, not a .npz'),
    ('card a list', 'its card is not a JSON object'),
    ('106 features', 'a leap model takes 107 features, not 106'),
    ('a class named type', "class 'type': the name of a built-in"),
    ('a class named twice', 'a class named twice'),
    # a model of a user's classes alone read every hand as one of them (the fist never stopped)
    ('none of the built-in classes', 'of the classes gun, two, wave, hi, bye, peace lacks the built-in '
                                     'ones fist, none, open, pinch, rock, thumb'),
    ('scalar mean', 'inconsistent model arrays'),
    ('a zero scale', 'inconsistent model arrays'),     # numpy's warnings were two more lines
    ('weights near the float limit', 'weights beyond 1e+06: not a fitted model'),
    # numpy allocated what the header said before reading: terabytes
    ('a header declaring 10**12 numbers', 'mean.npy declares 8000000000000 bytes in'),
    # numpy reads format 3.0 too: the check skipped it and numpy asked for 7 TB
    ('a 3.0 header declaring 10**12 numbers', 'mean.npy declares 8000000000000 bytes in'),
    ('a header of a format numpy does not write', 'mean.npy is .npy format 9.0'),
    # json's RecursionError was a traceback
    ('a card nested 100000 deep', 'cannot read a pose model (maximum recursion depth'),
    # zipfile's and zlib's own errors were tracebacks (or blamed the input file)
    ('a compression zipfile does not read', 'cannot read a pose model (That compression method'),
    ('compressed data damaged', 'cannot read a pose model ('),
    ('a password-protected member', 'cannot read a pose model ('),
    ('LZMA data damaged (a model re-zipped by hand)', 'cannot read a pose model ('),
])
def test_a_bad_model_file_is_one_clear_error_before_any_frame(tmp_path, spoil, message):
    import numpy as np
    bad = tmp_path / 'bad.npz'
    arrays = _model_arrays()
    if spoil == 'empty':
        bad.write_bytes(b'')
    elif spoil == 'one array':
        with open(bad, 'wb') as f:
            np.save(f, arrays['w0'])
    else:
        if spoil == 'card a list':
            arrays['card'] = np.array('[1, 2]')
        elif spoil == '106 features':
            arrays.update(mean=arrays['mean'][:106], scale=arrays['scale'][:106],
                          w0=arrays['w0'][:106])
        elif spoil == 'a class named type':
            arrays['classes'] = np.array(['type' if c == 'rock' else c for c in arrays['classes']])
        elif spoil == 'none of the built-in classes':
            arrays['classes'] = np.array(['gun', 'two', 'wave', 'hi', 'bye', 'peace'])
        elif spoil == 'a class named twice':
            arrays['classes'] = np.array(['fist' if c == 'rock' else c for c in arrays['classes']])
        elif spoil == 'scalar mean':
            arrays['mean'] = np.array(0.0)
        elif spoil == 'a zero scale':
            arrays['scale'] = arrays['scale'] * 0.0
        elif spoil == 'weights near the float limit':
            arrays['w0'] = arrays['w0'] * 1e200      # finite, but the folding overflows
            arrays['scale'] = arrays['scale'] * 1e-120
        elif spoil == 'a card nested 100000 deep':
            arrays['card'] = np.array('[' * 100000 + ']' * 100000)
        (np.savez_compressed if 'compressed' in spoil else np.savez)(bad, **arrays)
        data = bytearray(bad.read_bytes())
        central = data.rfind(b'PK\x01\x02')          # the last member's central directory entry
        if spoil == 'a compression zipfile does not read':
            data[central + 10] = 9                      # its method: deflate64
        elif spoil == 'compressed data damaged':
            data[400] ^= 0xff
        elif spoil == 'a password-protected member':
            data[central + 8] |= 1                      # its flags: encrypted
        bad.write_bytes(bytes(data))
        if 'LZMA' in spoil:
            import zipfile
            with zipfile.ZipFile(bad) as z:
                members = {n: z.read(n) for n in z.namelist()}
            with zipfile.ZipFile(bad, 'w', zipfile.ZIP_LZMA) as z:
                for n, data in members.items():
                    z.writestr(n, data)
            data = bytearray(bad.read_bytes())
            data[400] ^= 0x55
            bad.write_bytes(bytes(data))
        if 'header' in spoil:
            import io
            import zipfile
            with zipfile.ZipFile(bad) as z:
                members = {n: z.read(n) for n in z.namelist()}
            head = io.BytesIO()
            write = (np.lib.format.write_array_header_2_0 if '3.0' in spoil
                     else np.lib.format.write_array_header_1_0)
            write(head, {'descr': '<f8', 'fortran_order': False, 'shape': (10 ** 12,)})
            head = bytearray(head.getvalue())
            if '3.0' in spoil:
                head[6:8] = b'\x03\x00'       # 3.0: 2.0's layout, the header in UTF-8
            elif 'format' in spoil:
                head[6:8] = b'\x09\x00'
            members['mean.npy'] = bytes(head) + arrays['mean'].astype('<f8').tobytes()
            with zipfile.ZipFile(bad, 'w') as z:
                for n, data in members.items():
                    z.writestr(n, data)
    frames = tmp_path / 'f.jsonl'
    frames.write_text(''.join(json.dumps(d) + '\n' for d in _dicts(['fist'] * 3)))
    p = subprocess.run([sys.executable, '-m', 'leap_teleop.hands.classify_frames', str(frames),
                        '--model', str(bad)], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and p.stdout == '' and 'Traceback' not in p.stderr, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('classify_frames: %s: ' % bad), p.stderr
    assert message in lines[0]


def test_the_output_never_overwrites_the_input_and_a_full_disk_is_a_write_error(tmp_path):
    frames = tmp_path / 'f.jsonl'
    text = ''.join(json.dumps(d) + '\n' for d in _dicts(['fist'] * 3))
    frames.write_text(text)
    cmd = [sys.executable, '-m', 'leap_teleop.hands.classify_frames', str(frames), '--out']
    p = subprocess.run(cmd + [str(frames)], capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and 'it would be overwritten' in p.stderr
    assert frames.read_text() == text
    for out, why in (('', 'name a file'), (str(tmp_path), 'a folder'),
                     (str(tmp_path / 'no' / 'x.jsonl'), 'no folder')):
        p = subprocess.run(cmd + [out], capture_output=True, text=True, timeout=60)
        assert p.returncode == 2 and why in p.stderr and 'Traceback' not in p.stderr
    if os.path.exists('/dev/full'):
        p = subprocess.run(cmd + ['/dev/full'], capture_output=True, text=True, timeout=60)
        assert p.returncode == 1 and 'cannot write /dev/full' in p.stderr, p.stderr
        assert 'cannot read' not in p.stderr


def test_unhashable_ids_and_a_recording_on_stdin_are_no_crash(tmp_path):
    d = _dicts(['fist'])[0]
    d['hands'][0]['id'] = [1]
    d['pointables'][0]['handId'] = {'a': 1}
    line = run_cli(['--stateless'], stdin=json.dumps(d) + '\n')
    assert len(line) == 1 and line[0]['hands'][0]['type'] == 'right'
    recording = json.dumps({'metadata': {'formatVersion': 1}, 'frames': _dicts(['fist'] * 3)})
    line = run_cli([], stdin=recording + '\n')
    assert line == [{'id': None, 'timestamp': None, 'hands': [],
                     'error': 'a whole recording on one line: give its file as INPUT'}]


@pytest.mark.parametrize('where', ['in its first 64 KiB', 'past them'])
def test_a_corrupt_gzip_is_one_clear_error(tmp_path, where):
    import gzip
    text = ''.join(json.dumps({'id': i, 'hands': [], 'n': i * 7919 % 10007}) + '\n'
                   for i in range(20000)).encode()
    data = bytearray(gzip.compress(text, mtime=0))
    start = 200 if where == 'in its first 64 KiB' else len(data) // 2
    for k in range(start, start + 50):
        data[k] ^= 0x55
    bad = tmp_path / 'bad.jsonl.gz'
    bad.write_bytes(bytes(data))
    p = subprocess.run([sys.executable, '-m', 'leap_teleop.hands.classify_frames', '--stateless',
                        str(bad), '--out', str(tmp_path / 'o.jsonl')],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and 'Traceback' not in p.stderr, p.stderr
    assert p.stderr.strip().splitlines()[-1].startswith('classify_frames: %s: ' % bad)


@pytest.mark.parametrize('args, message', [
    (['frames.jsonl', '--keypoints', 'k.csv'], 'give INPUT or --keypoints, not both'),
    (['--keypoints', ''], '--keypoints: name a file'),
    (['--model', ' ', 'frames.jsonl'], '--model: name a file'),
    (['--keypoint-model', '', 'frames.jsonl'], '--keypoint-model: name a file'),
])
def test_classify_frames_refuses_inputs_it_would_ignore_or_guess(args, message, capsys):
    with pytest.raises(SystemExit) as stop:
        classify_frames.main(args)
    assert stop.value.code == 2
    assert message in capsys.readouterr().err.splitlines()[-1]


@pytest.mark.parametrize('content', [b'', b'person,label,source_label\n', b'\xef\xbb\xbf'])
def test_classify_frames_says_when_a_keypoint_file_holds_no_row(tmp_path, capsys, content):
    empty = tmp_path / 'empty.csv'
    empty.write_bytes(content)
    assert classify_frames.main(['--keypoints', str(empty)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ''
    assert captured.err == 'classify_frames: %s: no keypoint row in it\n' % empty


def test_a_cut_keypoint_file_keeps_the_rows_before_the_cut(tmp_path, capsys):
    import gzip
    rows = ''.join('%d,' % (i % 3) + ','.join('%.3f' % (0.01 * ((i * 7 + k) % 50)) for k in range(42))
                   + '\n' for i in range(400))
    packed = gzip.compress(rows.encode())
    cut = tmp_path / 'cut.csv'
    cut.write_bytes(packed[:len(packed) // 2])
    bad_row = tmp_path / 'bad_row.csv'
    bad_row.write_text(rows[:rows.index('\n', 1000) + 1] + '1,0.0\n')
    for path in (cut, bad_row):
        assert classify_frames.main(['--keypoints', str(path)]) == 2
        captured = capsys.readouterr()
        lines = [json.loads(line) for line in captured.out.splitlines()]
        assert lines and [d['id'] for d in lines] == list(range(len(lines)))
        if path == bad_row:                            # every row before the bad one
            assert len(lines) == rows[:rows.index('\n', 1000) + 1].count('\n')
        err = captured.err.splitlines()
        assert len(err) == 1 and err[0].startswith('classify_frames: %s' % path), err
        if path == cut:
            assert 'cannot read on after %d keypoint rows' % len(lines) in err[0]


def test_a_line_too_long_to_be_a_frame_is_one_error_line_not_all_the_memory(tmp_path):
    # A few MB of gzip can hold a line of gigabytes: read whole, it took the machine's memory.
    import gzip
    import io

    from leap_teleop.hands.gestures import datasets as gesture_data
    lines = list(gesture_data.bounded_lines(io.StringIO('ab\n' + 'x' * 25 + '\ncd\n' + 'y' * 11), 10))
    assert lines == ['ab\n', None, 'cd\n', None]
    assert list(gesture_data.bounded_lines(io.StringIO('0123456789\n'), 10)) == ['0123456789\n']
    frames = [json.dumps(d) for d in _dicts(['fist'] * 2)]
    path = tmp_path / 'long.jsonl.gz'
    with gzip.open(path, 'wt') as f:
        f.write(frames[0] + '\n' + ' ' * (gesture_data.MAX_LINE_CHARS + 5) + 'x\n' + frames[1] + '\n')
    p = subprocess.run([sys.executable, '-m', 'leap_teleop.hands.classify_frames', '--stateless',
                        str(path)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and 'Traceback' not in p.stderr, p.stderr
    out = [json.loads(line) for line in p.stdout.splitlines()]
    assert len(out) == 3 and out[0]['hands'][0]['fist'] and out[2]['hands'][0]['fist']
    assert out[1]['error'] == 'a line longer than %d characters' % gesture_data.MAX_LINE_CHARS
    poses = tmp_path / 'long_poses.jsonl.gz'
    with gzip.open(poses, 'wt') as f:
        f.write(json.dumps({'person': 'p', 'label': 'fist', 'frame': _dicts(['fist'])[0]}) + '\n'
                + ' ' * (gesture_data.MAX_LINE_CHARS + 5) + 'x\n')
    with pytest.raises(gesture_data.DataError, match='line 2: not a pose record .longer than'):
        gesture_data.read_pose_lines(str(poses))


@pytest.mark.parametrize('content', ['', '  \n\n'])
def test_a_file_with_no_frame_says_so(tmp_path, capsys, content):
    # Before: status 0 and no output at all, as if every frame had been classified.
    path = tmp_path / 'take.jsonl'
    path.write_text(content)
    assert classify_frames.main([str(path)]) == 2
    assert capsys.readouterr().err == 'classify_frames: %s: no frame in it\n' % path


def test_a_model_made_before_the_yaml_word_rule_still_loads(tmp_path):
    # a class named like a YAML boolean cannot be a new label, but a model that has one (a
    # binding names it quoted) kept loading: the rule refused it at every start
    import numpy as np

    from leap_teleop.hands.gestures.classifier import load_model
    arrays = _model_arrays()
    arrays['classes'] = np.append(arrays['classes'], 'yes')
    arrays['w1'] = np.hstack([arrays['w1'], arrays['w1'][:, :1]])
    arrays['b1'] = np.append(arrays['b1'], arrays['b1'][0] - 10.0)
    np.savez(tmp_path / 'old.npz', **arrays)
    assert 'yes' in load_model(str(tmp_path / 'old.npz'), 'leap').classes


def _one_side_frames(kind):
    """Right hands only, 120 frames at 120 Hz. 'swap': id 1 (fist) for 0.5 s, then at once
    another hand, id 7 (open). 'order': two hands typed right, id 1 a steady fist and id 2
    a steady open hand, listed in the other order from 0.5 s on."""
    frames = []
    for i in range(120):
        if kind == 'swap':
            hands = [render_hand('right', 'fist', (0, 200, 0), hand_id=1) if i < 60 else
                     render_hand('right', 'open', (120, 200, 0), hand_id=7)]
        else:
            a = render_hand('right', 'fist', (0, 200, 0), hand_id=1)
            b = render_hand('right', 'open', (150, 200, 0), hand_id=2)
            hands = [a, b] if i < 60 else [b, a]
        frames.append(Frame(i + 1, 1.0 + i / 120.0, hands))
    return frames


@pytest.mark.parametrize('kind', ['swap', 'order'])
def test_a_side_follows_one_hand_by_its_id_as_the_sender_does(kind):
    # One recognizer per side fed whichever hand came first: one hand's fist and another's
    # open hand made an unfold that neither hand made (and the sender does not report).
    from leap_teleop.hands.leap_interface import LeapInterface
    classifier, live = FrameClassifier(), LeapInterface(source=None)
    for frame in _one_side_frames(kind):
        out = classifier.classify_frame(frame, frame.id, None)
        state = live.on_frame(frame)['right']
        assert not any(e in ('fold', 'unfold') for h in out['hands'] for e in h['events'])
        by_id = dict(zip((h.id for h in frame.hands), out['hands']))
        if kind == 'order':         # id 1 is followed throughout; id 2 judged on its own
            assert by_id[2]['open'] and not by_id[2]['fist']
            assert by_id[1]['fist'] == state.fist and state.fist == (frame.id >= 3)
        elif frame.id == 61:        # the new hand is judged from the next frame on
            assert not by_id[7]['open'] and not by_id[7]['fist'] and not state.present
        elif frame.id > 61:
            assert by_id[7]['open'] == (frame.id >= 64)


def test_a_hand_that_cannot_be_placed_counts_as_gone_as_in_the_sender():
    # classify_frames judged it anyway, so a fist, one frame with a NaN palm, then an open
    # hand made an unfold there that the sender (which reports the hand lost) never sends.
    import dataclasses

    from leap_teleop.hands.leap_interface import LeapInterface
    classifier, live = FrameClassifier(), LeapInterface(source=None)
    for i in range(180):
        pose = 'fist' if i < 90 else 'open'
        hand = render_hand('right', pose, (0, 200, 0), hand_id=1)
        if i == 90:
            hand = dataclasses.replace(hand, palm_position=(float('nan'), 200.0, 0.0))
        frame = Frame(i + 1, 1.0 + i / 120.0, [hand])
        out = classifier.classify_frame(frame, frame.id, None)['hands'][0]
        state = live.on_frame(frame)['right']
        assert not any(e.gesture in ('fold', 'unfold') for e in state.events)
        assert not any(e in ('fold', 'unfold') for e in out['events']), i
        if i == 90:
            assert not state.present and not any(out[k] for k in ('fist', 'open', 'pinch', 'rock'))
    assert out['open'] and state.open


def test_a_keypoint_row_s_pinch_value_is_measured_from_its_landmarks(tmp_path, capsys):
    # A row holds no pinch strength: the dataclass default 0.0 was taken as one, and every
    # OK sign read pinch_value 0.0 ("barely pinching").
    import numpy as np

    from leap_teleop.hands.gestures import datasets as gesture_data
    from leap_teleop.hands.gestures.pose import image_pinch_strength
    path = os.path.join(KEYPOINTS, 'kinivi.csv')
    _, labels, xy = gesture_data.read_keypoints(path)
    lines = run_main(['--keypoints', path], capsys)
    pinches = [(o['hands'][0]['pinch_value'], row) for o, row in zip(lines, xy) if o['hands'][0]['pinch']]
    assert len(pinches) >= 100
    values = np.array([v for v, _ in pinches])
    assert values.min() > 0.5 and values.max() <= 0.8     # tips touching: a firm pinch
    for value, row in pinches[:20]:
        assert value == pytest.approx(min(max(image_pinch_strength(row) - 0.2, 0.0), 0.8), abs=1e-4)
    # tips apart read as no strength; what cannot be measured as a pinch (as before)
    apart = np.array(xy[0], float)
    apart[4] = apart[0] + 5 * (apart[9] - apart[0])
    assert image_pinch_strength(apart) == 0.0
    assert image_pinch_strength(np.zeros((21, 2))) == 1.0


def test_camera_footage_is_letterboxed_as_the_sender_does(tmp_path, detector_sizes, capsys):
    # Before: images went to the detector as they came (here 1280x720), while the sender
    # letterboxes to its ~width x ~height (640x480): a photo read as a fist here and as no
    # hand in the sender.
    import cv2
    import numpy as np

    from leap_teleop.hands.sources.camera_params import CAMERA_PARAMS
    path = str(tmp_path / 'wide.png')
    cv2.imwrite(path, np.zeros((720, 1280, 3), np.uint8))
    assert classify_frames.main([path]) == 0
    assert json.loads(capsys.readouterr().out)['hands'] == []
    size = (CAMERA_PARAMS['height'].default, CAMERA_PARAMS['width'].default, 3)
    assert detector_sizes == [size] == [(480, 640, 3)]


def test_a_side_whose_hand_cannot_be_placed_is_lost_not_given_to_the_other_hand():
    # classify_frames chose among the placeable hands only: one frame with a NaN palm on
    # the followed hand (id 1, the more confident) gave the side to the other (id 2) for
    # good, while the sender reports the side lost and follows id 1 again, whose unfold
    # (a takeoff with the drone bindings) classify_frames then missed.
    import dataclasses

    from leap_teleop.hands.leap_interface import LeapInterface
    classifier, live = FrameClassifier(), LeapInterface(source=None)
    sent, classified = [], []
    for i in range(200):
        a = dataclasses.replace(render_hand('right', 'fist' if i < 100 else 'open', (0, 200, 0), hand_id=1),
                                confidence=0.9)
        if i == 50:
            a = dataclasses.replace(a, palm_position=(float('nan'), 200.0, 0.0))
        b = dataclasses.replace(render_hand('right', 'open', (150, 200, 0), hand_id=2), confidence=0.5)
        frame = Frame(i + 1, 1.0 + i / 120.0, [a, b])
        out = classifier.classify_frame(frame, frame.id, None)['hands']
        state = live.on_frame(frame)['right']
        sent += [(i, e.gesture) for e in state.events if e.active and e.gesture in ('fold', 'unfold')]
        classified += [(i, e) for e in out[0]['events'] if e in ('fold', 'unfold')]
        assert (out[0]['fist'], out[0]['open']) == (state.fist, state.open), i
        assert classifier.followed.get('right') == live._trackers['right'].hand_id, i
    assert classified == sent == [(120, 'unfold')]
