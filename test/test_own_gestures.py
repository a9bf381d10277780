"""Your own gestures, end to end: record samples from a scripted source, retrain with
them, bind the new gesture to an action, and the sender's side and the arm logic act on
it; plus bad input to each step. Needs the shared data (../shared/data): fails without."""
import contextlib
import csv
import fcntl
import gzip
import json
import os
import re
import time

import numpy as np
import pytest
import yaml

from leap_teleop.hands import classify_frames
from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures import GestureRecognizer, training_set
from leap_teleop.hands.gestures import datasets as gesture_data
from leap_teleop.hands.gestures import record as record_gestures
from leap_teleop.hands.gestures import train as train_gestures
from leap_teleop.hands.gestures.bindings import Bindings
from leap_teleop.hands.gestures.classifier import PoseClassifier
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.sources import SourceError, make_source
from leap_teleop.hands.sources.source import HandSource
from leap_teleop.ros import hand_conversions
from leap_teleop.ur10 import kinematics as kin
from leap_teleop.ur10.teleop import ARMED, DISARMED, ArmInput, ArmTeleop

# needs a ROS master, a simulator, a subprocess or a build: not in make check
pytestmark = pytest.mark.integration

RETRAIN_CPU_S = 60.0        # the bound for retraining with a user's samples


def gti_path():
    path = os.path.join(gesture_data.LEAP_PEOPLE, 'gti_dev.jsonl.gz')
    assert os.path.isfile(path), 'shared data missing: %s' % path
    return path


def write_script(path, pose, seconds, rate=60):
    """A scripted hand holding `pose`, moving and turning a little, as a user would."""
    third = seconds / 3.0
    path.write_text(yaml.safe_dump({'rate_hz': rate, 'noise_mm': 3.0, 'seed': 1, 'hands': {
        'right': [{'pose': pose, 'palm': [0, 200, 0], 'duration': third},
                  {'pose': pose, 'palm': [30, 230, -20], 'rpy': [10, 15, -10], 'duration': third},
                  {'pose': pose, 'palm': [-30, 190, 20], 'rpy': [-10, -10, 15],
                   'duration': third}]}}))
    return str(path)


@contextlib.contextmanager
def run_wide_folder(tmp_path_factory, name):
    """A folder of this test run, held by one process at a time: under make test's
    workers, the one that every worker of the run sees (the rostests below are work units
    of their own, often on the other worker, and would retrain again); alone, this
    process's own."""
    root = tmp_path_factory.getbasetemp()
    if os.environ.get('PYTEST_XDIST_WORKER'):
        root = root.parent          # the run's folder; each worker's is one inside it
        name += '_' + os.environ.get('PYTEST_XDIST_TESTRUNUID', '')
    folder = root / name
    folder.mkdir(exist_ok=True)
    with open(root / (name + '.lock'), 'w') as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield folder
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


@pytest.fixture(scope='module')
def trained(tmp_path_factory):
    """(samples file, model path, CPU seconds of the retrain): 'two' (V sign), which the
    shipped model reads as none, recorded from the scripted source and added. Done once
    per test run; the tests only read what it wrote."""
    gti_path()
    with run_wide_folder(tmp_path_factory, 'own_gestures_trained') as tmp:
        samples, model, done = str(tmp / 'two.jsonl'), str(tmp / 'mine.npz'), tmp / 'cpu.json'
        if not done.exists():
            rc = record_gestures.main(['--source', 'scripted', '--script',
                                       write_script(tmp / 'two.yaml', 'two', 6.0), '--label',
                                       'two', '--seconds', '5', '--realtime', '0', '--out',
                                       samples, '--person', 'tester'])
            assert rc == 0
            t0 = time.process_time()
            rc = train_gestures.main(['--add', samples, '--label', 'two', '--out', model,
                                      '--no-report'])
            cpu = time.process_time() - t0
            assert rc == 0
            done.write_text(json.dumps(cpu))
        return samples, model, json.loads(done.read_text())


def test_recorded_samples_are_the_shared_pose_format(trained):
    samples = trained[0]
    rows = gesture_data.read_pose_lines(samples)
    assert len(rows) == 300                       # 5 s at 60 Hz, one hand each
    assert {(p, lab) for p, lab, _ in rows} == {('tester', 'two')}
    hands = [gesture_data.first_hand(f) for _, _, f in rows]
    assert all(h is not None and h.side == 'right' and len(h.fingers) == 5 for h in hands)
    assert len({tuple(np.round(h.palm_position, 1)) for h in hands}) > 250    # it moved


def test_retrain_is_quick_and_adds_the_new_gesture_as_a_class(trained):
    _, model, cpu = trained
    assert cpu <= RETRAIN_CPU_S, 'retraining took %.1f CPU s' % cpu
    m = PoseClassifier.load(model, 'leap')
    assert 'two' in m.classes and {'fist', 'open', 'pinch', 'rock', 'none'} <= set(m.classes)
    card = open(os.path.splitext(model)[0] + '.md').read()
    assert 'two.jsonl (300 hands)' in card and '--out %s --no-report`' % model in card


def session(path, rate=60):
    """Frames of a scripted session: an open hand 1 s, then the V sign 1.5 s."""
    path.write_text(yaml.safe_dump({'rate_hz': rate, 'noise_mm': 1.0, 'seed': 7, 'hands': {
        'right': [{'pose': 'open', 'palm': [0, 200, 0], 'duration': 1.0},
                  {'pose': 'two', 'palm': [10, 210, -10], 'rpy': [5, 10, 0],
                   'duration': 1.5}]}}))
    return list(make_source('scripted', script=str(path), realtime=False).frames())


def drive_arm(li, frames):
    """The sender's side (LeapInterface -> leapcobot message) into the arm's logic (message
    -> ArmInput -> ArmTeleop), as the nodes do; the arm's state after each frame."""
    arm = ArmTeleop()
    arm.on_joints(kin.HOME_Q.copy(), frames[0].timestamp)
    out = []
    for frame in frames:
        state = li.on_frame(frame)['right']
        msg = hand_conversions.to_leapcobot(state)
        hand = ArmInput.from_leapcobot_dict(hand_conversions.from_leapcobot(msg))
        arm.on_hand(hand, frame.timestamp)
        arm.on_joints(arm._q, frame.timestamp)
        arm.step(frame.timestamp)
        out.append(arm.status.state)
    return out


def test_a_bound_new_gesture_arms_the_arm(trained, tmp_path):
    _, model, _ = trained
    frames = session(tmp_path / 'session.yaml')
    bindings = Bindings({'arm': {'arm': 'two'}})
    # the shipped model: the V sign is no gesture, so it cannot even be bound
    with pytest.raises(ValueError, match="unknown gesture 'two'"):
        LeapInterface(sides=['right'], bindings=bindings)
    shipped = drive_arm(LeapInterface(sides=['right']), frames)
    assert set(shipped) == {DISARMED}
    mine = LeapInterface(sides=['right'], bindings=bindings,
                         recognizer_factory=lambda: GestureRecognizer(model=model))
    states = drive_arm(mine, frames)
    assert set(states[:60]) == {DISARMED}               # the open hand arms nothing
    first = states.index(ARMED)
    # armed during the V sign, after the arm's 0.3 s hold (and the filter's few frames)
    assert 60 + 0.3 * 60 <= first <= 60 + 0.6 * 60, first
    assert states[-1] == ARMED
    snapshot = mine.snapshot('right')
    assert snapshot.thumb_up and not snapshot.fist


def test_a_bound_new_gesture_takes_a_drone_off(trained, tmp_path):
    """The drone side: 'two' bound to takeoff emits the pilot's takeoff event (unfold)
    once, at the gesture's start; the raw unfold stays bound to nothing."""
    _, model, _ = trained
    frames = session(tmp_path / 'session.yaml')
    li = LeapInterface(sides=['right'], recognizer_factory=lambda: GestureRecognizer(model=model),
                       bindings=Bindings({'drone': {'takeoff': 'two', 'land': []}}))
    events = [(f.id, e.gesture) for f in frames for e in li.on_frame(f)['right'].events]
    names = [name for _, name in events]
    assert names.count('unfold') == 1 and names.index('unfold') == names.index('two') + 1
    assert events[names.index('two')][0] >= 60


def test_classify_frames_reports_the_new_gesture(trained, tmp_path, capsys):
    _, model, _ = trained
    frames = [leapjs_dict(i, pose) for i, pose in enumerate(['open'] * 10 + ['two'] * 10)]
    path = tmp_path / 'frames.jsonl'
    path.write_text(''.join(json.dumps(f) + '\n' for f in frames))
    assert classify_frames.main([str(path), '--model', model]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    two = [line['hands'][0]['two'] for line in lines]
    assert two[:10] == [False] * 10 and all(two[13:]), two
    assert classify_frames.main([str(path)]) == 0        # the shipped model: no such key
    assert all('two' not in json.loads(x)['hands'][0]
               for x in capsys.readouterr().out.splitlines())
    assert classify_frames.main([str(path), '--model', str(tmp_path / 'none.npz')]) == 2
    assert 'cannot read a pose model' in capsys.readouterr().err
    # the recorder's own file, as the docs show it: pose records, each judged alone
    samples, _, _ = trained
    assert classify_frames.main([samples, '--stateless', '--model', model]) == 0
    two = [json.loads(x)['hands'][0]['two'] for x in capsys.readouterr().out.splitlines()]
    assert len(two) == 300 and sum(two) >= 270, sum(two)


def leapjs_dict(i, pose):
    from leap_teleop.hands.sources import leapjs
    return leapjs.frame_to_dict(Frame(i, 100.0 + i / 60.0,
                                      [render_hand('right', pose, (0, 200, 0))]))


def test_default_retrain_includes_the_leave_one_person_out_report(tmp_path, trained, capsys):
    """Without --no-report the card holds leave-one-person-out figures (on a small slice
    of the shared poses, to keep the test short), the user's own gesture among them: its
    recall on their held-out file and how often shared people it never saw read as it."""
    keep, seen = [], {}
    with gzip.open(gti_path(), 'rt') as f:
        for line in f:
            person = json.loads(line)['person']
            n = seen[person] = seen.get(person, 0) + 1
            if len(seen) > 3:
                break
            if n % 10 == 0:             # every 10th pose of the first three people
                keep.append(line)
    data = tmp_path / 'data' / 'leap_people'
    data.mkdir(parents=True)
    with gzip.open(data / 'gti_dev.jsonl.gz', 'wt') as f:
        f.writelines(keep)
    model = str(tmp_path / 'small.npz')
    assert train_gestures.main(['--data', str(tmp_path / 'data'), '--add', trained[0],
                                '--label', 'two', '--out', model]) == 0
    out = capsys.readouterr().out
    assert 'leave-one-person-out' in out and 'user:two' in out
    assert re.search(r'^  two +\d\.\d{3} / \d\.\d{3} .* \d\.\d{4} / \d\.\d{4}$', out, re.M), out
    # the confusion is printed under its heading (it was a heading alone)
    assert re.search(r'^  confusion .*\n    \S+ +\w+ \d\.\d\d', out, re.M), out
    assert re.search(r'^    two +two \d\.\d\d', out, re.M), out
    card = open(os.path.splitext(model)[0] + '.md').read()
    assert '## Leave-one-person-out' in card
    assert '--label two --out %s` (' % model in card       # the command remakes this file
    assert re.search(r'^\| two \| \d\.\d{3} \| \d\.\d{3} \(.*\) \| \d\.\d{4} \| \d\.\d{4} \|$', card, re.M)
    # Found: the card named the terms of every shared source, used or not.
    assert [t.split(' ')[0] for t in PoseClassifier.load(model, 'leap').card['data_terms']] \
        == ['GTI-UPM']
    two = PoseClassifier.load(model, 'leap').card['leave_one_person_out']['two']
    # the user's file and the three shared people (their V signs are the class too)
    assert two['people'] == 4 and two['fpr_mean'] is not None


def test_a_card_names_the_terms_of_the_shared_sources_it_used_only():
    assert training_set.data_terms('leap', {'user:two', 'user:wave'}) == []
    assert len(training_set.data_terms('leap', {'user_03', 'guinevere_01', 'leapjs_takes'})) == 3
    terms = training_set.data_terms('keypoints', {'kinivi', 'photo:mps', 'user:ok'})
    assert [t.split(' ')[0] for t in terms] == ['hand', 'the']
    with pytest.raises(ValueError, match="no data terms for the leap data of 'someone'"):
        training_set.data_terms('leap', {'user_01', 'someone'})


@pytest.mark.parametrize('shared, held', [
    (['a', 'b', 'c', 'd', 'e', 'f', 'g'], ['a', 'c', 'e']),
    (['a', 'b'], ['a', 'b']),
    ([], []),
])
def test_a_retrain_holds_out_a_few_shared_people_spread_over_them(shared, held):
    assert train_gestures.report_people(shared) == held


# -- bad input ------------------------------------------------------------------------

@pytest.mark.parametrize('args, message', [
    (['--source', 'scripted', '--label', 'two'], 'needs --script'),
    (['--source', 'scripted', '--script', 'x.yaml', '--label', 'thumb_up'],
     'the name of a built-in gesture'),
    (['--source', 'scripted', '--script', 'x.yaml', '--label', 'my sign'],
     'letters, digits and _ only'),
    (['--source', 'scripted', '--script', 'x.yaml', '--label', 'two', '--seconds', '0'],
     '--seconds 0'),
    (['--source', 'scripted', '--script', 'x.yaml', '--label', 'two', '--out', 'two.csv'],
     'name it .jsonl'),
    (['--source', 'video', '--video', 'x.mp4', '--label', 'two', '--out', 'two.jsonl'],
     'name it .csv'),
    (['--source', 'scripted', '--script', 'x.yaml', '--label', 'two', '--out',
      '/no/such/dir/two.jsonl'], 'no folder'),
    (['--source', 'scripted', '--script', '/no/such.yaml', '--label', 'two'], 'such.yaml'),
])
def test_record_gestures_bad_arguments(args, message, capsys):
    assert record_gestures.main(args) == 2
    err = capsys.readouterr().err
    assert message in err and err.count('\n') == 1, err


def record_one_second_of(pose, tmp_path, out, *more):
    """record_gestures' exit code for a 30 Hz scripted right hand held in `pose` for 1 s."""
    script = tmp_path / ('%s.yaml' % pose)
    script.write_text(yaml.safe_dump({'rate_hz': 30, 'hands': {
        'right': [{'pose': pose, 'duration': 1.0}]}}))
    return record_gestures.main(['--source', 'scripted', '--script', str(script), '--label',
                                 'two', '--realtime', '0', '--out', str(out)] + list(more))


def test_record_gestures_refuses_a_label_the_shared_data_gives_a_built_in_class(tmp_path, capsys):
    assert record_one_second_of('thumbs_up', tmp_path, tmp_path / 'x.jsonl', '--label', 'up') == 2
    assert "--label 'up': the shared data's name for its built-in class 'thumb'" in capsys.readouterr().err


def test_a_new_class_takes_only_shared_rows_that_were_none(tmp_path, leapjs_data):
    # a user's class named like a shared take moved that take's fists and open hands into it
    from leap_teleop.hands.gestures.train import training_dataset
    data = tmp_path / 'data'
    data.mkdir()
    (data / 'leapjs').symlink_to(os.path.abspath(leapjs_data))
    out = tmp_path / 'grab.jsonl'
    assert record_one_second_of('two', tmp_path, out) == 0
    before = training_dataset('leap', str(data), [])
    grab = {c for c, lab in zip(before.y, before.label) if lab == 'grab'}
    assert grab >= {'fist', 'open'}
    after = training_dataset('leap', str(data), [(str(out), 'grab')])
    assert {c for c, lab in zip(after.y, after.label) if lab == 'grab'} >= grab


def test_record_gestures_without_a_hand_writes_nothing(tmp_path, capsys):
    out = tmp_path / 'x.jsonl'
    assert record_one_second_of('absent', tmp_path, out) == 1
    assert 'no hand in 30 frames: nothing written' in capsys.readouterr().err
    assert not out.exists()


def test_record_gestures_says_when_the_source_ends_before_the_time_asked(tmp_path, capsys):
    """A short take is written, and said to be short (it was silent before)."""
    out = tmp_path / 'two.jsonl'
    assert record_one_second_of('open', tmp_path, out) == 0
    captured = capsys.readouterr()
    assert 'the source ended after 1.0 of the 10 s asked' in captured.err, captured.err
    assert 'wrote 30 hand poses' in captured.out and out.exists()
    # the whole time asked (0.5 s, or the script's whole 1 s): no such line
    for seconds, name in (('0.5', 'two_b.jsonl'), ('1', 'two_c.jsonl')):
        assert record_one_second_of('open', tmp_path, tmp_path / name, '--seconds', seconds) == 0
        assert 'ended' not in capsys.readouterr().err


def record_with_the_other_hand_resting(tmp_path, name, rest_s, *more):
    """record_gestures' exit code for 1 s of a 30 Hz right hand in a V sign, the left hand
    resting open beside it for the first `rest_s` seconds."""
    script = tmp_path / (name + '.yaml')
    script.write_text(yaml.safe_dump({'rate_hz': 30, 'hands': {
        'right': [{'pose': 'two', 'palm': [80, 200, 0], 'duration': 1.0}],
        'left': [{'pose': 'open', 'palm': [-80, 200, 0], 'duration': rest_s}]}}))
    return record_gestures.main(['--source', 'scripted', '--script', str(script), '--label',
                                 'two', '--realtime', '0', '--seconds', '1', '--out',
                                 str(tmp_path / (name + '.jsonl'))] + list(more))


def test_record_gestures_writes_no_take_of_two_hands_unless_a_side_is_given(tmp_path, capsys):
    # With the default --side any, the resting left hand was written as 'two' too: retrained,
    # the user's open hand read as their class. Skipping only the frames that show both
    # kept those where the gesture's hand was lost: the resting hand's alone.
    for name, rest_s in (('half', 0.5), ('whole', 1.0)):
        assert record_with_the_other_hand_resting(tmp_path, name, rest_s) == 1
        err = capsys.readouterr().err
        assert err.splitlines()[-1] == (
            'record_gestures: the take showed more than one hand (%d of the 30 frames showed two '
            'hands): nothing written; give --side right|left to record the hand showing the '
            'gesture' % round(30 * rest_s)), err
        assert not (tmp_path / (name + '.jsonl')).exists()
    # --side right records the gesture's hand on every frame, without a word about the other
    assert record_with_the_other_hand_resting(tmp_path, 'right', 1.0, '--side', 'right') == 0
    captured = capsys.readouterr()
    assert 'wrote 30 hand poses' in captured.out and 'showed two' not in captured.err
    rows = gesture_data.read_pose_lines(str(tmp_path / 'right.jsonl'))
    assert {gesture_data.first_hand(f).side for _, _, f in rows} == {'right'}


class TwoOfASide(HandSource):
    """A right hand in a V, then a left hand alone (the V's hand lost), then two hands
    both typed right (a tracker's mistake): 10 frames each at 30 Hz."""

    def frames(self):
        v = render_hand('right', 'two', (60, 200, 0), hand_id=1)
        rest = render_hand('left', 'open', (-80, 200, 0), hand_id=2)
        rest_typed_right = render_hand('right', 'open', (-80, 200, 0), hand_id=2)
        for i in range(30):
            hands = [[v], [rest], [v, rest_typed_right]][i // 10]
            yield Frame(i + 1, 100.0 + i / 30.0, hands)


def test_record_gestures_refuses_a_take_of_both_sides_and_skips_two_hands_of_one(
        tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(record_gestures, 'source_from_args', lambda args: TwoOfASide())
    base = ['--source', 'scripted', '--script', str(tmp_path / 's.yaml'), '--label', 'two',
            '--seconds', '5']
    # any: the left hand of the frames where the V was lost would be written as 'two'
    assert record_gestures.main(base + ['--out', str(tmp_path / 'any.jsonl')]) == 1
    assert 'more than one hand (10 of the 30 frames showed two hands)' in capsys.readouterr().err
    # right: the frames with two right hands are skipped and said so; the left one is not kept
    assert record_gestures.main(base + ['--side', 'right', '--out', str(tmp_path / 'r.jsonl')]) == 0
    captured = capsys.readouterr()
    assert 'wrote 10 hand poses' in captured.out, captured.out
    assert 'record_gestures: 10 of the 30 frames showed two right hands and were skipped' in captured.err
    rows = gesture_data.read_pose_lines(str(tmp_path / 'r.jsonl'))
    assert {gesture_data.first_hand(f).id for _, _, f in rows} == {1}


class FailsNearTheEnd(HandSource):
    """9 s of a right hand at 30 Hz, then the SourceError of an unplugged webcam."""

    def frames(self):
        for i in range(270):
            yield Frame(i + 1, 100.0 + i / 30.0, [render_hand('right', 'open', (0, 200, 0))])
        raise SourceError('camera 0 stopped delivering frames (unplugged?)')


def test_record_gestures_keeps_the_take_when_the_source_fails(tmp_path, monkeypatch, capsys):
    # The failure threw away the 9 s already recorded of a 10 s take.
    monkeypatch.setattr(record_gestures, 'source_from_args', lambda args: FailsNearTheEnd())
    out = tmp_path / 'wave.jsonl'
    assert record_gestures.main(['--source', 'scripted', '--script', str(tmp_path / 's.yaml'),
                                 '--label', 'wave', '--out', str(out)]) == 1
    captured = capsys.readouterr()
    assert ('the scripted source failed after 9.0 of the 10 s asked: camera 0 stopped '
            'delivering frames (unplugged?)') in captured.err, captured.err
    assert 'wrote 270 hand poses' in captured.out
    records = [json.loads(line) for line in out.read_text().splitlines()]
    assert len(records) == 270 and records[-1]['label'] == 'wave'


class FailsAtOnce(HandSource):
    def frames(self):
        raise SourceError('leapc source: cannot connect to the hand-tracking service')
        yield


def test_a_source_that_fails_before_any_frame_is_one_line(tmp_path, monkeypatch, capsys):
    # The failure was followed by 'no hand in 0 frames: nothing written', as if the take
    # had been recorded and held no hand.
    monkeypatch.setattr(record_gestures, 'source_from_args', lambda args: FailsAtOnce())
    out = tmp_path / 'wave.jsonl'
    assert record_gestures.main(['--source', 'scripted', '--script', str(tmp_path / 's.yaml'),
                                 '--label', 'wave', '--out', str(out)]) == 1
    err = [line for line in capsys.readouterr().err.splitlines() if 'recording' not in line]
    assert err == ['record_gestures: the scripted source failed after 0.0 of the 10 s asked: '
                   'leapc source: cannot connect to the hand-tracking service'], err
    assert not out.exists()


class CameraHands(HandSource):
    """Hands as a camera source gives them: with image landmarks (pixels)."""

    def __init__(self, landmarks):
        self.landmarks = landmarks

    def frames(self):
        for i, xy in enumerate(self.landmarks):
            hands = []
            if xy is not None:
                hand = render_hand('left', 'open', (0, 200, 0))
                hand.image_landmarks = np.asarray(xy, dtype=float)
                hands = [hand]
            yield Frame(i, 10.0 + i / 30.0, hands)


def test_a_recorded_camera_take_gives_keypoint_rows(tmp_path, capsys):
    # --source recording was always taken for Leap hands: a camera take recorded with
    # record_frames (its hands keep their picture's landmarks) gave pose records the
    # keypoint model that judges such hands never learns from.
    from leap_teleop.hands.sources import leapjs
    rng = np.random.default_rng(1)
    frames = list(CameraHands([rng.uniform(100, 400, (21, 2)) for _ in range(6)]).frames())
    take = tmp_path / 'cam.json'
    leapjs.save(str(take), [leapjs.frame_to_dict(f) for f in frames], {})
    out = tmp_path / 'peace.csv'
    assert record_gestures.main(['--source', 'recording', '--recording', str(take), '--realtime', '0',
                                 '--label', 'peace', '--seconds', '0.2', '--out', str(out)]) == 0
    assert 'wrote 6 keypoint rows' in capsys.readouterr().out
    persons, labels, xy = gesture_data.read_keypoints(str(out))
    assert labels == ['peace'] * 6 and len(xy) == 6
    # asked for a .jsonl, it says the take holds camera hands
    assert record_gestures.main(['--source', 'recording', '--recording', str(take), '--label', 'peace',
                                 '--out', str(tmp_path / 'peace.jsonl')]) == 2
    assert '.csv' in capsys.readouterr().err


def test_camera_hands_become_community_normalised_keypoint_rows(tmp_path):
    rng = np.random.default_rng(0)
    pts = [rng.uniform(100, 400, (21, 2)) for _ in range(4)]
    take = record_gestures.collect(
        CameraHands([pts[0], None, pts[1], pts[2], np.full((21, 2), 50.0), pts[3]]),
        'keypoints', 'peace', 'ann', 10.0)
    assert (len(take.rows), take.seen, take.missing) == (4, 6, 2)  # no hand; a degenerate one
    # six frames of a 30 Hz source: it ended long before the 10 s asked
    assert take.ended == 'source ended' and take.seconds == pytest.approx(6 / 30.0)
    # six frames are a whole 0.2 s take, the last one standing for its period
    whole = record_gestures.collect(CameraHands(pts + pts[:2]), 'keypoints', 'peace', 'ann',
                                    0.2)
    assert whole.ended == 'time' and whole.seconds == 0.2 and whole.seen == 6
    rows = take.rows
    path = str(tmp_path / 'peace.csv')
    record_gestures.write(path, 'keypoints', rows)
    with open(path) as f:
        assert next(csv.reader(f))[:5] == ['person', 'label', 'source_label', 'x0', 'y0']
    persons, labels, xy = gesture_data.read_keypoints(path)
    assert persons == ['ann'] * 4 and labels == ['peace'] * 4
    for got, raw in zip(xy, pts):
        want = (raw - raw[0]) / np.abs(raw - raw[0]).max()
        np.testing.assert_allclose(got, want, atol=5e-5)
        assert got[0].tolist() == [0.0, 0.0] and np.abs(got).max() == pytest.approx(1.0)
    # and seconds of source time end it
    take = record_gestures.collect(CameraHands(pts * 10), 'keypoints', 'peace', 'ann', 0.5)
    assert take.seen == 15 and len(take.rows) == 15
    assert take.ended == 'time' and take.seconds == 0.5


def test_train_gestures_names_a_malformed_file(tmp_path, capsys):
    bad = tmp_path / 'bad.jsonl'
    bad.write_text('{"person": "me", "label": "two", "frame": {}}\n{"person": "me"\n')
    assert train_gestures.main(['--data', str(tmp_path), '--add', str(bad), '--label', 'two',
                                '--out', str(tmp_path / 'm.npz')]) == 2
    assert 'bad.jsonl line 2: not a pose record' in capsys.readouterr().err
    bad_csv = tmp_path / 'bad.csv'
    bad_csv.write_text('0,1,2,3\n')
    assert train_gestures.main(['--data', str(tmp_path), '--add', str(bad_csv), '--label',
                                'two', '--out', str(tmp_path / 'm.npz')]) == 2
    assert 'bad.csv row 1: not a keypoint row' in capsys.readouterr().err


@pytest.mark.parametrize('args, message', [
    (['--out', '{tmp}/no_dir/m.npz'], '--out {tmp}/no_dir/m.npz: no folder {tmp}/no_dir'),
    (['--out', '{tmp}'], '--out {tmp}: a folder'),
    (['--family', 'keypoints', '--out', '{tmp}/m.npz'],
     '--family keypoints: the --add files are Leap poses'),
    (['--family', 'all', '--out', '{tmp}/m.npz'], '--family all: the --add files are Leap poses'),
    # an empty --out once meant "the shipped model", refitted over without a word
    (['--out', ''], "--out '': name the model file"),
    (['--out', '{tmp}/m.md'], "--out {tmp}/m.md: a model file ends in .npz"),
    (['--out', '{tmp}/dev.npz'], "--out {tmp}/dev.npz: {tmp}/dev.md is no regular file"),
    (['--label', 'type', '--out', '{tmp}/m.npz'], "--label 'type': the name of a built-in"),
    (['--label', 'thumb_up', '--out', '{tmp}/m.npz'], "--label 'thumb_up': the name of a built-in"),
    (['--label', 'hover', '--out', '{tmp}/m.npz'], "--label 'hover': the name of a built-in"),
    (['--label', 'yes', '--out', '{tmp}/m.npz'], "--label 'yes': a bindings YAML reads it as a boolean"),
    # the shared data's names of built-in classes: the real thumbs-ups left the guarded
    # class for an unguarded one, the OK signs left pinch
    (['--label', 'thumbs_up', '--out', '{tmp}/m.npz'],
     "--label 'thumbs_up': the shared data's name for its built-in class 'thumb'"),
    (['--label', 'ok', '--out', '{tmp}/m.npz'], "--label 'ok': the shared data's name for its "
                                                "built-in class 'pinch': add to that class with --label pinch"),
    (['--label', 'caf\u00e9', '--out', '{tmp}/m.npz'], "--label 'caf\u00e9': letters, digits and _ only"),
    (['--label', 'a' * 65, '--out', '{tmp}/m.npz'], "--label '%s': at most 64 characters" % ('a' * 65)),
])
def test_train_gestures_refuses_bad_arguments_before_the_fit(tmp_path, monkeypatch, capsys,
                                                             args, message):
    """The fit takes minutes: a bad --out or a --family that is not the files' is refused
    before it, in one line."""
    monkeypatch.setattr(train_gestures, 'train',
                        lambda *a, **k: pytest.fail('fitted before checking the arguments'))
    samples = tmp_path / 'wave.jsonl'
    samples.write_text('{}\n')
    (tmp_path / 'dev.md').mkdir()       # where the card of {tmp}/dev.npz would go
    label = ['--label', 'fist'] if '--label' not in args else []
    with pytest.raises(SystemExit) as stop:
        train_gestures.main(['--add', str(samples)] + label + ['--no-report']
                            + [a.format(tmp=tmp_path) for a in args])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert ': error: ' + message.format(tmp=tmp_path) in err.splitlines()[-1], err


def test_train_gestures_never_writes_over_its_own_input(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(train_gestures, 'train',
                        lambda *a, **k: pytest.fail('fitted before checking the arguments'))
    samples = tmp_path / 'two.npz'          # a user's file, whatever its name
    samples.write_text('{}\n')
    with pytest.raises(SystemExit):
        train_gestures.main(['--add', str(samples), '--label', 'two', '--out', str(samples)])
    assert 'would overwrite the --add file' in capsys.readouterr().err
    assert samples.read_text() == '{}\n'


def test_train_gestures_refuses_a_file_with_no_hand_and_keeps_same_named_files_apart(
        tmp_path, capsys):
    empty = tmp_path / 'wave.jsonl'
    empty.write_text('')
    assert train_gestures.main(['--data', str(tmp_path), '--add', str(empty), '--label', 'wave',
                                '--out', str(tmp_path / 'm.npz'), '--no-report']) == 2
    assert '--add %s: no hand in it' % empty in capsys.readouterr().err
    assert not (tmp_path / 'm.npz').exists()
    assert train_gestures.user_people(['a/two.jsonl', 'b/two.jsonl', 'c/peace.csv']) == [
        'user:two#1', 'user:two#2', 'user:peace']


@pytest.mark.parametrize('content, message', [
    (b'\xff\xfe not text\n', 'cannot read on after 0 pose records'),
    (gzip.compress(b'{"person": "a", "label": "b", "frame": {}}\n' * 2000, mtime=0)[:300],
     'cannot read on after'),
    (b'{"person": "a", "label": "wave", "frame": {"hands": [{"type": "right", "id": [1], '
     b'"grabStrength": 1' + b'0' * 400 + b'}], "pointables": [{"handId": {"a": 1}}]}}\n',
     'no hand in it'),
], ids=['not UTF-8', 'a gzip cut short', 'unhashable ids and a 400-digit integer'])
def test_train_gestures_names_an_unreadable_file_in_one_line(tmp_path, capsys, content, message):
    bad = tmp_path / 'bad.jsonl'
    bad.write_bytes(content)
    assert train_gestures.main(['--data', str(tmp_path), '--add', str(bad), '--label', 'wave',
                                '--out', str(tmp_path / 'm.npz'), '--no-report']) == 2
    err = capsys.readouterr().err
    assert message in err and 'Traceback' not in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize('tool, sentence_end', [
    (record_gestures, 'for train_gestures --add FILE --label NAME.'),
    (train_gestures, 'and ship them as arrays with a model card.'),
])
def test_help_gives_the_whole_first_paragraph(tool, sentence_end, capsys):
    with pytest.raises(SystemExit) as stop:
        tool.main(['--help'])
    assert stop.value.code == 0
    assert sentence_end in ' '.join(capsys.readouterr().out.split())


def test_record_gestures_usage_shows_seconds_as_optional(capsys):
    assert '--label NAME [--seconds N]' in record_gestures.__doc__
    with pytest.raises(SystemExit):
        record_gestures.main(['--help'])
    usage = ' '.join(capsys.readouterr().out.split())
    assert '--label NAME' in usage and '[--seconds N]' in usage


@pytest.mark.rostest
def test_the_nodes_arm_on_a_bound_new_gesture(trained, tmp_path):
    """The real graph: sender (the user's model and bindings, a scripted V sign) ->
    ur10_arm (unchanged) on the simulated UR10: the arm node reports armed."""
    from test_launch_smoke import run_launches
    _, model, _ = trained
    script = tmp_path / 'session.yaml'
    script.write_text(yaml.safe_dump({'rate_hz': 60, 'noise_mm': 1.0, 'seed': 7, 'hands': {
        'right': [{'pose': 'open', 'palm': [0, 200, 0], 'duration': 1.5},
                  {'pose': 'two', 'palm': [10, 210, -10], 'duration': 3.0}]}}))
    bindings = tmp_path / 'mine.yaml'
    bindings.write_text('arm: {arm: two}\n')
    run_launches(tmp_path, [['ur10_sim.launch'], ['ur10_arm.launch', 'max_joint_speed:=1.0'],
                            ['sender.launch', 'script:=%s' % script, 'sides:=[right]',
                             'wait_for_subscribers:=true', 'gesture_model:=%s' % model,
                             'gesture_bindings:=%s' % bindings]],
                 ['--armed', 'ur10_1'], 90)


def test_record_gestures_from_a_leap_recording(tmp_path, capsys):
    """A recording (here a shared LeapJS take of a hand making an L / gun) is a source
    too: one pose record per hand per frame, gzip by the name."""
    from leap_teleop.hands.gestures.datasets import data_dir
    take = os.path.join(data_dir(), 'gun.json.lz')
    assert os.path.isfile(take), 'shared data missing: %s' % take
    out = tmp_path / 'gun.jsonl.gz'
    assert record_gestures.main(['--source', 'recording', '--recording', take, '--label', 'gun',
                                 '--seconds', '2', '--realtime', '0', '--side', 'right',
                                 '--out', str(out)]) == 0
    summary = capsys.readouterr().out
    rows = gesture_data.read_pose_lines(str(out))
    assert rows and {lab for _, lab, _ in rows} == {'gun'}
    stamps = [f['timestamp'] for _, _, f in rows]
    assert stamps == sorted(stamps) and stamps[-1] - stamps[0] < 2.0e6 and len(rows) > 50
    assert all(len(f['hands']) == 1 and f['hands'][0]['type'] == 'right' for _, _, f in rows)
    assert 'wrote %d hand poses' % len(rows) in summary


@pytest.mark.rostest
def test_the_nodes_fly_a_drone_on_bound_gestures(trained, tmp_path):
    """The real graph: sender (the user's model; takeoff bound to the V sign, land to a
    fist held) -> drone_pilot (unchanged) -> simulated AR.Drone: it takes off,
    flies and lands again, while the hand is still there (a lost hand lands only after
    the check's time limit)."""
    from test_launch_smoke import run_launches
    _, model, _ = trained
    script = tmp_path / 'flight.yaml'
    script.write_text(yaml.safe_dump({'rate_hz': 60, 'noise_mm': 1.0, 'seed': 7, 'hands': {
        'right': [{'pose': 'absent', 'duration': 3.0},
                  {'pose': 'open', 'palm': [0, 200, 0], 'duration': 1.0},
                  {'pose': 'two', 'duration': 1.5},            # takeoff
                  {'pose': 'open', 'duration': 4.0},           # climb, hover
                  {'pose': 'fist', 'duration': 1.0},           # land
                  {'pose': 'open', 'duration': 120.0}]}}))
    bindings = tmp_path / 'mine.yaml'
    bindings.write_text('drone: {takeoff: two, land: fist}\n')
    run_launches(tmp_path, [['ardrone.launch', 'sender:=false'],
                            ['sender.launch', 'script:=%s' % script, 'sides:=[right]',
                             'wait_for_subscribers:=true',
                             'wait_topics:=[leapmotion/hand_right, leapmotion/gestures, '
                             'ardrone/takeoff]',
                             'gesture_model:=%s' % model, 'gesture_bindings:=%s' % bindings]],
                 ['--drone'], 100)


def test_keypoint_files_gzipped_or_with_a_bom_read_and_absurd_values_are_refused(tmp_path):
    row = '3,' + ','.join('%.3f' % (0.01 * i) for i in range(42)) + '\n'
    (tmp_path / 'bom.csv').write_bytes(b'\xef\xbb\xbf' + row.encode())
    (tmp_path / 'gz.csv').write_bytes(gzip.compress(row.encode() * 2))
    assert len(gesture_data.read_keypoints(str(tmp_path / 'bom.csv'))[2]) == 1
    assert len(gesture_data.read_keypoints(str(tmp_path / 'gz.csv'))[2]) == 2
    (tmp_path / 'huge.csv').write_text(row.replace('0.010', '1e300'))
    with pytest.raises(gesture_data.DataError, match='row 1: a keypoint beyond'):
        gesture_data.read_keypoints(str(tmp_path / 'huge.csv'))
    (tmp_path / 'underscore.csv').write_text(row.replace('0.010', '1_0'))   # float(): 10.0
    with pytest.raises(gesture_data.DataError, match='row 1: not a keypoint row'):
        gesture_data.read_keypoints(str(tmp_path / 'underscore.csv'))
    (tmp_path / 'latin1.csv').write_bytes(row.encode() + b'3,\xe9\n')
    with pytest.raises(gesture_data.DataError, match=r'cannot read on after \d+ keypoint rows .*decode'):
        gesture_data.read_keypoints(str(tmp_path / 'latin1.csv'))


def test_the_card_counts_the_samples_fitted_and_a_file_of_no_hand_is_refused(tmp_path, capsys):
    # Before: 30 hands without joints were counted in the card's '(60 hands)', and three
    # keypoint rows with every landmark on one spot trained a class on their noisy copies.
    from leap_teleop.hands.sources import leapjs
    good = [leapjs_dict(i, 'two') for i in range(30)]
    broken = []
    for i in range(30):
        d = leapjs_dict(100 + i, 'two')
        d['pointables'] = [{k: v for k, v in p.items() if k not in ('mcpPosition', 'pipPosition',
                                                                    'dipPosition')}
                           for p in d['pointables']]
        assert leapjs.frame_from_dict(d).hands       # a hand, without its joints
        broken.append(d)
    mixed = tmp_path / 'mixed.jsonl'
    mixed.write_text(''.join(json.dumps({'person': 'me', 'label': 'two', 'frame': f}) + '\n'
                             for f in good + broken))
    nodata = tmp_path / 'nodata'
    nodata.mkdir()
    opens = tmp_path / 'opens.jsonl'
    opens.write_text(''.join(json.dumps({'person': 'me', 'label': 'open', 'frame': leapjs_dict(i, 'open')})
                             + '\n' for i in range(30)))
    # a few shared poses: a model without the built-in classes is refused
    shared = tmp_path / 'shared' / 'leap_people'
    shared.mkdir(parents=True)
    with gzip.open(gti_path(), 'rt') as f, gzip.open(shared / 'gti_dev.jsonl.gz', 'wt') as out:
        for k, line in enumerate(f):
            if k >= 3000:
                break
            if k % 10 == 0:
                out.write(line)
    model = tmp_path / 'm.npz'
    # the open hands, labelled open, taken as wave with --id (a label of their own: refused)
    assert train_gestures.main(['--data', str(shared.parent), '--add', str(mixed), '--label', 'two',
                                '--add', str(opens), '--id', 'open', '--label', 'wave', '--out', str(model),
                                '--no-report']) == 0
    card = open(tmp_path / 'm.md').read()
    assert 'mixed.jsonl (30 hands)' in card and 'opens.jsonl (30 hands)' in card
    assert '--add %s --id open --label wave --out' % opens in card
    # keypoints: a file whose rows hold no hand is refused by name, not fitted on noise
    rows = [','.join(['1'] + ['%.3f' % v for v in np.random.default_rng(k).uniform(0, 1, 42)])
            for k in range(20)]
    (tmp_path / 'some.csv').write_text('\n'.join(rows) + '\n')
    (tmp_path / 'zeros.csv').write_text(('0,' + ','.join(['0.5'] * 42) + '\n') * 3)
    capsys.readouterr()
    assert train_gestures.main(['--data', str(nodata), '--add', str(tmp_path / 'some.csv'),
                                '--label', 'foo', '--add', str(tmp_path / 'zeros.csv'), '--label',
                                'bar', '--out', str(tmp_path / 'k.npz'), '--no-report']) == 2
    assert '--add %s: no hand in it' % (tmp_path / 'zeros.csv') in capsys.readouterr().err
