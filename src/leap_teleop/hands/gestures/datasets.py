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
import csv
import gzip
import io
import json
import os

import numpy as np

from leap_teleop.hands.sources import leapjs

SHARED_DATA = os.environ.get('LEAP_TELEOP_SHARED_DATA') or os.path.normpath(
    os.path.join(os.path.dirname(os.path.realpath(__file__)), '..', '..', '..', '..', '..',
                 'shared', 'data'))
LEAP_PEOPLE = os.path.join(SHARED_DATA, 'leap_people')
KEYPOINTS = os.path.join(SHARED_DATA, 'keypoints')
STROKES = os.path.join(SHARED_DATA, 'strokes')
HANDS = os.path.join(SHARED_DATA, 'hands')
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


class DataError(ValueError):
    """A data file that cannot be read as its format."""


def _open_text(path):
    with open(path, 'rb') as f:
        head = f.read(2)
    if head == b'\x1f\x8b':
        return io.TextIOWrapper(gzip.open(path, 'rb'), encoding='utf-8')
    return open(path, encoding='utf-8')


def read_pose_lines(path):
    """[(person, label, frame dict)] of a JSON Lines pose file; malformed lines raise
    DataError naming the line."""
    rows = []
    with _open_text(path) as f:
        for n, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                d = json.loads(line)
                person, label, frame = str(d['person']), str(d['label']), d['frame']
                if not isinstance(frame, dict):
                    raise TypeError('frame is not an object')
            except (ValueError, KeyError, TypeError) as e:
                raise DataError('%s line %d: not a pose record (%s)' % (path, n, e)) from None
            rows.append((person, label, frame))
    return rows


def first_hand(frame_dict):
    """The first hand of a LeapJS frame dict as a Hand, or None."""
    try:
        frame = leapjs.frame_from_dict(frame_dict)
    except leapjs.FrameError:
        return None
    return frame.hands[0] if frame.hands else None


def read_take(path):
    """The LeapJS frame dicts of a dynamic take."""
    with _open_text(path) as f:
        try:
            d = json.load(f)
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


def read_keypoints(path, label=None, person=None):
    """(persons, labels, xy (n, 21, 2)) of a keypoint CSV in either form. The community's
    headerless form has a class id per row: its label is `label` when given (the whole file
    is that gesture), else the id as text; its person is `person` or the file's name."""
    persons, labels, rows = [], [], []
    default_person = person or os.path.splitext(os.path.basename(path))[0]
    with open(path, newline='', encoding='utf-8') as f:
        reader = csv.reader(f)
        header = None
        for n, row in enumerate(reader, 1):
            if not row or not ''.join(row).strip():
                continue
            if n == 1 and row[0].strip() == 'person':
                header = row
                continue
            try:
                if header is not None:
                    if len(row) != 45:
                        raise ValueError('%d columns, not 45' % len(row))
                    p, lab, values = row[0], row[1], row[3:]
                else:
                    if len(row) != 43:
                        raise ValueError('%d columns, not 43' % len(row))
                    p, lab, values = default_person, row[0].strip(), row[1:]
                xy = np.array([float(v) for v in values]).reshape(21, 2)
            except ValueError as e:
                raise DataError('%s row %d: not a keypoint row (%s)' % (path, n, e)) from None
            if not np.isfinite(xy).all():
                raise DataError('%s row %d: a keypoint is not finite' % (path, n))
            persons.append(person or p)
            labels.append(label if label is not None else lab)
            rows.append(xy)
    return persons, labels, np.array(rows).reshape(-1, 21, 2)


def photo_hands(folder=None):
    """[(source, label, (21, 2) pixel landmarks)] of the labelled photos' hands, from the
    folder's hands.json (what MediaPipe found in each photo)."""
    folder = folder or HANDS
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
