"""Readers of the people-split gesture data: the shared folders' formats, which are also
what record_gestures writes and train_gestures reads.

- Leap static poses: JSON Lines `{"person", "label", "frame"}` (gzip or plain), frame a
  LeapJS frame dict with one hand (../shared/data/leap_people/gti_dev.jsonl.gz).
- Leap dynamic takes: `{"frames": N, "data": [frame, ...]}` (gzip or plain)
  (../shared/data/leap_people/guinevere/NN/GESTURE-K.json.gz).
- Webcam keypoints: CSV `person,label,source_label,x0,y0,...,x20,y20` with a header
  (../shared/data/keypoints/), or the community's keypoint.csv: a class id then 42
  numbers, no header.
"""
import contextlib
import csv
import gc
import gzip
import io
import json
import math
import os
import zlib

import numpy as np

try:                       # several times faster than the stdlib parser (tools/requirements.txt)
    import orjson as _orjson
except ImportError:        # pragma: no cover - the stdlib parser is the fallback
    _orjson = None

from leap_teleop.hands.gestures.features import MAX_KEYPOINT
from leap_teleop.hands.sources import leapjs

SHARED_DATA = os.environ.get('LEAP_TELEOP_SHARED_DATA') or os.path.normpath(
    os.path.join(os.path.dirname(os.path.realpath(__file__)), '..', '..', '..', '..', '..',
                 'shared', 'data'))
LEAP_PEOPLE = os.path.join(SHARED_DATA, 'leap_people')
# The shared LeapJS recordings ($LEAPJS_DATA overrides) and the hand photos and clips
# ($HANDS_DATA overrides).
DEFAULT_LEAPJS_DATA = os.environ.get('LEAPJS_DATA') or os.path.join(SHARED_DATA, 'leapjs')
HANDS_DATA = os.environ.get('HANDS_DATA') or os.path.join(SHARED_DATA, 'hands')
KEYPOINTS = os.path.join(SHARED_DATA, 'keypoints')
# The labelled photos (../hands: label__source__name): what each label is to the model.
PHOTO_LABELS = {'open_palm': 'open', 'flat_hand': 'open', 'fist': 'fist', 'thumbs_up': 'thumb',
                'thumbs_down': 'thumb', 'ok': 'pinch', 'pinch_o': 'pinch', 'pointing': 'none',
                'neg_half_curl': 'none', 'neg_pinky': 'none'}

# What each recorded pose label is to the recognizer. `thumb`: a fist with the thumb out
# (its direction, up or down, is judged apart from the model); `none`: a pose that is none
# of the gestures and must not read as one.
LEAP_LABELS = {'fist_moved': 'fist', 'five': 'open', 'palm': 'open', 'palm_m': 'open',
               'palm_u': 'open', 'ok': 'pinch', 'heavy': 'rock', 'up': 'thumb',
               'down': 'thumb', 'four': 'none', 'three': 'none', 'two': 'none',
               'index': 'none', 'L': 'none', 'hang': 'none', 'C': 'none'}
KEYPOINT_LABELS = {'open': 'open', 'fist': 'fist', 'thumb_up': 'thumb',
                   'thumb_down': 'thumb', 'ok': 'pinch', 'pointing': 'none',
                   'peace': 'none', 'other': 'none', 'rock': 'rock', 'horns': 'rock'}
# Classes of the shared keypoint files whose rows show another pose than their label says
# (plotted, every row alike): (person, source label) -> what the rows show. They are left
# out of the fit and of the recall / false-positive figures, and reported apart: fitting
# them under their label taught the model that four raised fingers are a fist and that a
# thumbs-up is an OK sign.
MISLABELLED_KEYPOINTS = {
    ('ASHISH74888', 'Close'): 'four fingers up (thumb folded or out), filed as fist',
    ('ASHISH74888', 'Ok'): 'a thumbs-up seen from the side (no thumb-index ring), filed as ok',
    ('CharlesCai7', 'Roll n Rock'): 'horns (index and pinky up), filed as other',
}


class DataError(ValueError):
    """A data file that cannot be read as its format."""


def open_text(path, errors='strict', newline=None):
    """A UTF-8 text stream of a file, gzipped or not (told by its magic bytes, not its
    name); errors and newline as for open()."""
    with open(path, 'rb') as f:
        head = f.read(2)
    if head == b'\x1f\x8b':
        return io.TextIOWrapper(gzip.open(path, 'rb'), encoding='utf-8-sig', errors=errors,
                                newline=newline)
    return open(path, encoding='utf-8-sig', errors=errors, newline=newline)


# A frame or pose record takes a few kB on its line: a line beyond this is no frame, and
# reading it whole could take the machine's memory (a few MB of gzip unpack to gigabytes).
MAX_LINE_CHARS = 16 << 20


def bounded_lines(stream, limit=MAX_LINE_CHARS):
    """The lines of a text stream, each read at most `limit` characters at a time; a
    longer line is skipped and given as None in its place."""
    while True:
        line = stream.readline(limit + 1)
        if not line:
            return
        if len(line) > limit and not line.endswith('\n'):
            while True:
                rest = stream.readline(limit)
                if not rest or rest.endswith('\n'):
                    break
            yield None
            continue
        yield line


# What reading a text file can raise besides its format's own errors: not UTF-8, a gzip
# stream cut short or with junk after it, a CSV field past the csv module's limit.
UNREADABLE = (UnicodeDecodeError, EOFError, gzip.BadGzipFile, zlib.error, csv.Error)


@contextlib.contextmanager
def paused_gc():
    """The cyclic garbage collector paused: reading and featurising the data sets builds
    millions of fresh containers, none in a cycle, and the collections they trigger walk
    every one already read, again and again (half the CPU of a pose file's read)."""
    paused = gc.isenabled()
    if paused:
        gc.disable()
    try:
        yield
    finally:
        if paused:
            gc.enable()


def _loads(text):
    """json.loads, through orjson when installed; what orjson refuses (NaN, huge integers,
    malformed text) goes to the stdlib parser, which reads it or raises as it always did."""
    if _orjson is not None:
        try:
            return _orjson.loads(text)
        except _orjson.JSONDecodeError:
            pass
    return json.loads(text)


def read_pose_lines(path):
    """[(person, label, frame dict)] of a JSON Lines pose file; malformed lines raise
    DataError naming the line."""
    with paused_gc():
        return _read_pose_lines(path)


def _read_pose_lines(path):
    rows = []
    try:
        with open_text(path) as f:
            _pose_rows(path, f, rows)
    except UNREADABLE as e:
        raise DataError('%s: cannot read on after %d pose records (%s)'
                        % (path, len(rows), e)) from None
    return rows


def _pose_rows(path, f, rows):
    for n, line in enumerate(bounded_lines(f), 1):
        if line is None:
            raise DataError('%s line %d: not a pose record (longer than %d characters)'
                            % (path, n, MAX_LINE_CHARS))
        line = line.strip()
        if not line:
            continue
        try:
            d = _loads(line)
            person, label, frame = str(d['person']), str(d['label']), d['frame']
            if not isinstance(frame, dict):
                raise TypeError('frame is not an object')
        except (ValueError, KeyError, TypeError) as e:
            raise DataError('%s line %d: not a pose record (%s)' % (path, n, e)) from None
        rows.append((person, label, frame))


def first_hand(frame_dict):
    """The first hand of a LeapJS frame dict as a Hand, or None."""
    try:
        frame = leapjs.frame_from_dict(frame_dict)
    except leapjs.FrameError:
        return None
    return frame.hands[0] if frame.hands else None


def read_take(path):
    """The LeapJS frame dicts of a dynamic take."""
    with open_text(path) as f, paused_gc():
        try:
            d = _loads(f.read())
        except UNREADABLE as e:
            raise DataError('%s: cannot read it (%s)' % (path, e)) from None
        except ValueError as e:
            raise DataError('%s: not JSON (%s)' % (path, e)) from None
    data = d.get('data') if isinstance(d, dict) else None
    if not isinstance(data, list):
        raise DataError('%s: no "data" list of frames' % path)
    return [f for f in data if isinstance(f, dict)]


def guinevere_takes(root=None):
    """[(person, gesture, path)] of the dynamic takes, sorted."""
    root = root or os.path.join(LEAP_PEOPLE, 'guinevere')
    out = []
    for person in sorted(os.listdir(root)):
        folder = os.path.join(root, person)
        if not os.path.isdir(folder):
            continue
        for name in sorted(os.listdir(folder)):
            if name.endswith('.json.gz') or name.endswith('.json'):
                gesture = name.split('.json')[0].rsplit('-', 1)[0]
                out.append((person, gesture, os.path.join(folder, name)))
    return out


def read_keypoints(path, label=None, person=None, sources=None):
    """(persons, labels, xy (n, 21, 2)) of a keypoint CSV in either form (iter_keypoints).
    `sources`, a list, receives each row's source label (the id in the headerless form)."""
    persons, labels, rows = [], [], []
    for p, lab, src, xy in iter_keypoints(path, label, person):
        persons.append(p)
        labels.append(lab)
        rows.append(xy)
        if sources is not None:
            sources.append(src)
    return persons, labels, np.array(rows).reshape(-1, 21, 2)


def iter_keypoints(path, label=None, person=None):
    """(person, label, source label, xy (21, 2)) per row of a keypoint CSV in either form,
    read as it goes (the rows before a cut or a bad row are yielded; then DataError). The
    community's headerless form has a class id per row: its label is `label` when given
    (the whole file is that gesture), else the id as text; its person is `person` or the
    file's name."""
    default_person = person or os.path.splitext(os.path.basename(path))[0]
    n_rows = 0
    try:
        with open_text(path, newline='') as f:
            header = None
            for n, row in enumerate(csv.reader(f), 1):
                if not row or not ''.join(row).strip():
                    continue
                # the header: the first row that is not blank (an editor may add blank lines)
                if header is None and n_rows == 0 and _is_keypoint_header(row):
                    header = row
                    continue
                p, lab, src, xy = _keypoint_row(path, n, row, header is not None, default_person)
                n_rows += 1
                yield person or p, label if label is not None else lab, src, xy
    except UNREADABLE as e:
        raise DataError('%s: cannot read on after %d keypoint rows (%s)'
                        % (path, n_rows, e)) from None


def _is_keypoint_header(row):
    return row[0].strip() == 'person'


def keypoint_labels_named(path):
    """Whether a keypoint CSV is the shared form, whose header names a label column, rather
    than the community's headerless one (a class id per row)."""
    try:
        with open_text(path, newline='') as f:
            for row in csv.reader(f):
                if row and ''.join(row).strip():
                    return _is_keypoint_header(row)
    except UNREADABLE as e:
        raise DataError('%s: cannot read it (%s)' % (path, e)) from None
    return False


def _keypoint_row(path, n, row, with_header, default_person):
    """(person, label, source label, xy) of row `n`, or DataError."""
    try:
        if with_header:
            if len(row) != 45:
                raise ValueError('%d columns, not 45' % len(row))
            p, lab, src, values = row[0], row[1], row[2], row[3:]
        else:
            if len(row) != 43:
                raise ValueError('%d columns, not 43' % len(row))
            p, lab, values = default_person, row[0].strip(), row[1:]
            src = lab
        if any('_' in v for v in values):    # float() would read 1_0 as 10
            raise ValueError('a number with _')
        xy = np.array([float(v) for v in values]).reshape(21, 2)
    except ValueError as e:
        raise DataError('%s row %d: not a keypoint row (%s)' % (path, n, e)) from None
    if not np.isfinite(xy).all():
        raise DataError('%s row %d: a keypoint is not finite' % (path, n))
    if np.abs(xy).max() > MAX_KEYPOINT:
        raise DataError('%s row %d: a keypoint beyond %g (neither pixels nor normalised)'
                        % (path, n, MAX_KEYPOINT))
    return p, lab, src, xy


def mislabelled_keypoints(person, source_label):
    """What a keypoint row shows instead of its label (MISLABELLED_KEYPOINTS), or None."""
    return MISLABELLED_KEYPOINTS.get((person, source_label))


def photo_hands(folder=None):
    """[(source, label, (21, 2) pixel landmarks)] of the labelled photos' hands, from the
    folder's hands.json (what MediaPipe found in each photo)."""
    folder = folder or HANDS_DATA
    with open(os.path.join(folder, 'hands.json'), encoding='utf-8') as f:
        images = json.load(f)['images']
    out = []
    for name, entry in sorted(images.items()):
        parts = name.split('__')
        if len(parts) < 3:
            continue
        for h in entry['hands']:
            xy = np.asarray(h['landmarks'], dtype=float)[:, :2] * (entry['width'], entry['height'])
            out.append((parts[1], parts[0], xy))
    return out


# -- the shared LeapJS takes' labelled frames -----------------------------------------
# Nobody labelled the recordings frame by frame, so the labels below are frame ranges read
# once off each take (its title / description and its raw data: the SDK's grab and pinch
# strength, fingertip positions), fixed here, and never moved to suit a recognizer. Frames
# in transitions (a hand closing or opening) are left unlabelled: what they "are" is a
# matter of opinion. Per take:
#
# - grab (right hand, open <-> fist cycles): fist where the SDK grab strength sits on its
#   plateau (>= 0.6, all fingers folded: frames 52-118, 246-334); open where grab is 0 and
#   the fingers are straight (0-22, 160-206, 350-373). Also negatives: no pinch and no
#   thumb-up in any of those frames (a fist is not a pinch).
# - pinch (right, pinch ramp with grab 0): pinch on the plateau where the SDK's pinch
#   strength is >= 0.9 (frames 128-234); not a pinch where it is 0 (0-60, 266-306). In this
#   take nothing but the pinch moves, so the SDK strength is a fair witness here.
# - gun (right, thumb + index extended): every frame is not fist, not pinch, not thumb-up,
#   not open.
# - HandSplay-110fps (right, open hand spread / closed flat): every frame open; not fist,
#   not pinch, not thumb-up.
# - three-claps (both hands, open hands clapping): every frame open; not fist, not pinch,
#   not thumb-up.
# - test-paddle-rightwards (right): thumb out of a closed fist (grab >= 0.9 with the thumb
#   tip clear of the fist: frames 28-74, 148-186, 290-318) -> not fist; thumb_up where the
#   SDK's own thumb direction points up (within 45 deg of +y), unlabelled where it leans
#   further (THUMB_UP_BY_DIRECTION: the thumb side of these hands stays turned up, and real
#   people's thumbs-ups lean as far: a Guinevere take's thumb 75..80 deg off vertical by the
#   SDK's direction, so "sideways" here is no longer a label that can be defended); a fist
#   with the thumb tucked (262-282) -> fist, not thumb-up; open hand (84-100, 200-236,
#   344-366) -> open.

ALL = range(0, 10 ** 6)


def _r(a, b):
    return range(a, b + 1)


# A thumb-out-of-a-fist frame is a thumbs-up when the SDK's thumb direction is within 45
# deg of +y; beyond, unlabelled (see the paddle take above).
UP = 'up'
THUMB_UP_BY_DIRECTION = math.cos(math.radians(45.0))


def expected(want, hand):
    """The label's bool for this hand, or None (unlabelled)."""
    if want != UP:
        return want
    try:
        y = float(hand.fingers[0].direction[1])
    except (TypeError, ValueError, IndexError, AttributeError):
        return None
    return True if y >= THUMB_UP_BY_DIRECTION else None


# take -> list of (side, frame range, {gesture: expected bool or UP})
LEAPJS_LABELS = {
    'grab': [
        ('right', _r(52, 118), {'fist': True, 'open': False, 'pinch': False, 'thumb_up': False}),
        ('right', _r(246, 334), {'fist': True, 'open': False, 'pinch': False, 'thumb_up': False}),
        ('right', _r(0, 22), {'open': True, 'fist': False, 'pinch': False, 'thumb_up': False}),
        ('right', _r(160, 206), {'open': True, 'fist': False, 'pinch': False, 'thumb_up': False}),
        ('right', _r(350, 373), {'open': True, 'fist': False, 'pinch': False, 'thumb_up': False}),
    ],
    'pinch': [
        ('right', _r(128, 234), {'pinch': True, 'fist': False, 'thumb_up': False}),
        ('right', _r(0, 60), {'pinch': False, 'fist': False, 'thumb_up': False}),
        ('right', _r(266, 306), {'pinch': False, 'fist': False, 'thumb_up': False}),
    ],
    'gun': [('right', ALL, {'fist': False, 'pinch': False, 'thumb_up': False, 'open': False})],
    'HandSplay-110fps': [
        ('right', ALL, {'open': True, 'fist': False, 'pinch': False, 'thumb_up': False})],
    'three-claps': [
        (side, ALL, {'open': True, 'fist': False, 'pinch': False, 'thumb_up': False})
        for side in ('right', 'left')],
    'test-paddle-rightwards': [
        ('right', _r(28, 74), {'thumb_up': UP, 'fist': False, 'open': False, 'pinch': False}),
        ('right', _r(148, 186), {'thumb_up': UP, 'fist': False, 'open': False, 'pinch': False}),
        ('right', _r(290, 318), {'thumb_up': UP, 'fist': False, 'open': False, 'pinch': False}),
        ('right', _r(262, 282), {'fist': True, 'thumb_up': False, 'open': False}),
        ('right', _r(84, 100), {'open': True, 'fist': False, 'thumb_up': False, 'pinch': False}),
        ('right', _r(200, 236), {'open': True, 'fist': False, 'thumb_up': False, 'pinch': False}),
        ('right', _r(344, 366), {'open': True, 'fist': False, 'thumb_up': False, 'pinch': False}),
    ],
}


def find_take(data_dir, take):
    """The file of a shared LeapJS take (any of its encodings), or None."""
    for name in (take + '.json.gz', 'decoded/%s.json.gz' % take, take + '.json.lz',
                 take + '.json'):
        path = os.path.join(data_dir, name)
        if os.path.exists(path):
            return path
    return None


_TAKES = {}


def take_frames(path):
    """The take's frame dicts, read once per process (training and evaluation read each
    take many times)."""
    if path not in _TAKES:
        _TAKES[path] = leapjs.load(path)[1]
    return _TAKES[path]


def data_dir():
    """The folder of the shared LeapJS recordings: $LEAPJS_DATA when set (read now), else
    the repository's sibling shared/data/leapjs."""
    return os.environ.get('LEAPJS_DATA') or DEFAULT_LEAPJS_DATA
