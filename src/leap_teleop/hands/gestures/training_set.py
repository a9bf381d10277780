"""What the pose models are fitted on: the shared, people-split data (and a user's own
files) as feature rows with their class, person and source label, plus the copies that
teach invariance (tracker noise on Leap joints, turned and noisy keypoints, Leap hands
seen as a webcam would). Each source adds whole people, so the fit can be judged on
people it never saw (train)."""
import collections
import dataclasses
import os

import numpy as np

from leap_teleop.hands.frame import Finger
from leap_teleop.hands.gestures import datasets as gd
from leap_teleop.hands.gestures.features import (
    hand_landmarks,
    keypoint_features_rows,
    leap_features,
    rotate_keypoints,
)
from leap_teleop.hands.sources import leapjs

SEED = 0                # the noisy copies' draws, and the fit's (train)
JOINT_NOISE_MM = 3.0    # tracker noise on the Leap hands' noisy copies

# Guinevere takes whose every frame shows one pose: the thumbs takes (a fist with the thumb
# out, judged up or down apart from the model) and the open-hand moves.
TAKE_LABELS = {'thumbs_up': 'thumb', 'thumbs_down': 'thumb', 'open_hand_up': 'open',
               'open_hand_down': 'open', 'open_hand_left': 'open', 'open_hand_right': 'open'}



def shared_label_problem(label):
    """Why a user's class may not be named `label` because the shared data files rows of
    that name under a built-in class (a user's `thumbs_up` would take the real thumbs-ups
    from the guarded `thumb`), or None."""
    for labels in (gd.LEAP_LABELS, gd.KEYPOINT_LABELS, gd.PHOTO_LABELS, TAKE_LABELS):
        cls = labels.get(label)
        if cls not in (None, 'none', label):      # fist, open, rock add to their class
            return ('the shared data\'s name for its built-in class %r: add to that class '
                    'with --label %s, or choose another name' % (cls, cls))
    return None


# Where the fitted data comes from and under what terms (the data folders' READMEs), by
LEAPJS_PERSON = 'leapjs_takes'       # the person of the shared LeapJS takes (one tracker, one name)
# the prefix of the people each source adds ('' for the webcam keypoint files' people).
DATA_TERMS = {
    'leap': [('user_', 'GTI-UPM multi-modal Leap Motion hand-gesture dataset (Universidad Politecnica '
                       'de Madrid, Grupo de Tratamiento de Imagenes; Mantecon et al.), users 01-12, as '
                       'redistributed in sluyters/QuantumLeap: published by its authors for research, '
                       'no licence file'),
             ('guinevere_', 'Guinevere dynamic gestures (QuantumLeap), subjects 01-02: published for '
                            'research, no licence file'),
             (LEAPJS_PERSON, 'LeapJS recordings (leapjs-playback / leapjs-plugins): Apache-2.0')],
    'keypoints': [('', 'hand keypoints (keypoint.csv) of Kazuhito00, kinivi, CharlesCai7, '
                       'ASHISH74888, 6kumaran, Alexamakans, Harikumar4, Completed-Spoon-6 '
                       '(their hand-gesture-recognition repositories): Apache-2.0'),
                  ('leap:', 'GTI-UPM Leap captures seen as a camera would (see the Leap model)'),
                  ('photo:', 'the labelled hand photos of ../shared/data/hands (each under its source '
                             "repository's licence; see that README)")],
}
_OTHER_SOURCES = ('user:', 'leap:', 'photo:')


def data_terms(family, persons):
    """The terms of the shared data sources that people of `persons` come from (a user's
    own files, 'user:...', carry none); ValueError for a person of no known source (a
    source added without its terms)."""
    def source(person):
        if person.startswith('user:'):
            return None
        if family == 'keypoints' and not person.startswith(_OTHER_SOURCES):
            return ''
        prefix = next((prefix for prefix, _ in DATA_TERMS[family]
                       if prefix and person.startswith(prefix)), None)
        if prefix is None:
            raise ValueError('no data terms for the %s data of %r' % (family, person))
        return prefix
    used = {source(p) for p in persons}
    return [text for prefix, text in DATA_TERMS[family] if prefix in used]


class Dataset:
    """Feature rows with their class, person and source label; `augmented` marks the
    noisy copies (fitted on, never scored); `group` the recorded row or hand each row
    comes from (its copies and mirror images share it; the fit keeps or strides a group
    whole), or -1 for one always fitted."""

    def __init__(self, family, seed=SEED):
        self.family = family
        self.x, self.y, self.person, self.label, self.augmented = [], [], [], [], []
        self.group = []
        self.sources = []
        self.rng = np.random.default_rng(seed)
        self._groups = 0

    def new_group(self):
        self._groups += 1
        return self._groups - 1

    def add(self, x, cls, person, label, augmented=False, group=-1):
        if x is not None:
            self.x.append(x)
            self.y.append(cls)
            self.person.append(person)
            self.label.append(label)
            self.augmented.append(augmented)
            self.group.append(group)

    def add_hand(self, hand, cls, person, label):
        """A Leap-family hand, and a copy with JOINT_NOISE_MM of tracker noise on every
        joint (a model fitted on one tracker's exact proportions reads a fist as
        something else once its joints move by a millimetre). False for a hand without
        features (joints missing): nothing added."""
        x = leap_features(hand)
        if x is None:
            return False
        group = self.new_group()
        self.add(x, cls, person, label, group=group)
        self.add(leap_features(noisy_hand(hand, JOINT_NOISE_MM, self.rng)), cls, person, label,
                 augmented=True, group=group)
        return True

    def arrays(self):
        return (np.array(self.x), np.array(self.y), np.array(self.person),
                np.array(self.label))

    def clean(self):
        return ~np.array(self.augmented, dtype=bool)

    def groups(self):
        return np.array(self.group, dtype=int)


def noisy_hand(hand, sigma, rng):
    """A copy of a Hand with Gaussian noise (mm) on every joint."""
    jointed = [f.mcp is not None and f.pip is not None and f.dip is not None
               for f in hand.fingers]
    # one draw for the whole hand: the same numbers, in the same order (tip, mcp, pip,
    # dip of each jointed finger), as one draw per joint
    noise = iter(rng.normal(0.0, sigma, (sum(jointed), 4, 3)))
    fingers = []
    for f, j in zip(hand.fingers, jointed):
        if j:
            n = next(noise)
            f = Finger(f.tip + n[0], f.direction, f.extended, f.mcp + n[1], f.pip + n[2],
                       f.dip + n[3])
        fingers.append(f)
    return dataclasses.replace(hand, fingers=tuple(fingers))


def add_leap_poses(ds, path, label_map=None, label=None, person=None, take=None):
    """Rows of a Leap pose file; `label` overrides every row's (a user's file); `take`, when
    given, keeps only the rows the file labels so."""
    n = 0
    for p, lab, frame in gd.read_pose_lines(path):
        if take is not None and lab != take:
            continue
        hand = gd.first_hand(frame)
        cls = label if label is not None else (label_map or gd.LEAP_LABELS).get(lab)
        if hand is None or cls is None:
            continue
        n += ds.add_hand(hand, cls, person or p, lab)
    ds.sources.append('%s (%d hands)' % (os.path.basename(path), n))


def take_class(want, hand):
    """The pose class of a labelled frame of the shared LeapJS takes, or None."""
    if want.get('fist') is True:
        return 'fist'
    if want.get('open') is True:
        return 'open'
    if want.get('pinch') is True:
        return 'pinch'
    if want.get('thumb_up') == gd.UP:
        return 'thumb'          # a thumb out of a fist, up or sideways: the guard decides
    if all(v is False for v in want.values()) and len(want) == 4:
        return 'none'           # the gun (thumb and index out)
    return None


def leapjs_take_hands(folder):
    """(take, hand, pose class, labels) of every labelled hand of the shared LeapJS takes
    (labels: datasets.LEAPJS_LABELS)."""
    for take, spans in sorted(gd.LEAPJS_LABELS.items()):
        path = gd.find_take(folder, take)
        if path is None:
            continue
        dicts = gd.take_frames(path)
        for side, frames, want in spans:
            for k in frames if frames is not gd.ALL else range(len(dicts)):
                if k >= len(dicts) or dicts[k] is None:
                    continue
                try:
                    frame = leapjs.frame_from_dict(dicts[k])
                except leapjs.FrameError:
                    continue
                hand = frame.hand(side)
                cls = take_class(want, hand) if hand is not None else None
                if cls is not None:
                    yield take, hand, cls, want


def add_leapjs_takes(ds, folder):
    """The labelled frames of the shared LeapJS takes (an older tracker's hand model:
    fists curled at the middle joints, knuckles straight) as one more person."""
    n = 0
    for take, hand, cls, _ in leapjs_take_hands(folder):
        ds.add_hand(hand, cls, LEAPJS_PERSON, take)
        n += 1
    ds.sources.append('the LeapJS takes of ../leapjs (%d labelled hands)' % n)


def add_guinevere(ds, root):
    n = 0
    for person, gesture, path in gd.guinevere_takes(root):
        cls = TAKE_LABELS.get(gesture)
        if cls is None:
            continue
        for frame in gd.read_take(path):
            hand = gd.first_hand(frame)
            if hand is not None:
                ds.add_hand(hand, cls, 'guinevere_' + person, gesture)
                n += 1
    ds.sources.append('guinevere takes (%d hands of %s)' % (n, ', '.join(sorted(TAKE_LABELS))))


def keypoint_copies(ds, pts, cls, person, label, copies=1, group=None):
    """A keypoint row's copies for add_keypoint_rows, in one group (default a new one):
    the first as recorded, further copies turned in the picture by up to TURN_RAD with
    KEYPOINT_NOISE on every landmark."""
    group = ds.new_group() if group is None else group
    out = []
    for k in range(copies):
        q = pts if k == 0 else rotate_keypoints(pts, ds.rng.uniform(-TURN_RAD, TURN_RAD))
        if k:
            q = q + ds.rng.normal(0.0, KEYPOINT_NOISE, q.shape)
        out.append((q, cls, person, label, k > 0, group))
    return out


def add_keypoint_rows(ds, rows):
    """Keypoint rows [(landmarks, class, person, label, augmented, group)], each followed by
    its mirror image (a left hand is a mirrored right one); their features computed at once."""
    if not rows:
        return
    xy = np.repeat(np.array([np.reshape(q, (21, 2)) for q, *_ in rows], dtype=float), 2, axis=0)
    xy[1::2, :, 0] = -xy[1::2, :, 0]
    x, ok = keypoint_features_rows(xy)
    for i, (_, cls, person, label, augmented, group) in enumerate(rows):
        for j in (2 * i, 2 * i + 1):
            ds.add(x[j] if ok[j] else None, cls, person, label, augmented=augmented, group=group)


def add_keypoints(ds, path, label=None, person=None, take=None):
    """Rows of a keypoint CSV; `label` overrides every row's (a user's file); `take`, when
    given, keeps only the rows of that class id (headerless form) or label (header form)."""
    sources = []
    persons, labels, xy = gd.read_keypoints(path, label=label if take is None else None,
                                            person=person, sources=sources)
    if take is not None:
        kept = [i for i, lab in enumerate(labels) if lab == take]
        persons, sources, xy = [persons[i] for i in kept], [sources[i] for i in kept], xy[kept]
        labels = [labels[i] if label is None else label for i in kept]
    # a row without features (all its landmarks on one spot) is no hand; its noisy copies
    # would have features, of noise alone
    _, whole = keypoint_features_rows(np.reshape(np.asarray(xy, dtype=float), (-1, 21, 2)))
    n = skipped = no_hand = 0
    rows = []
    for p, lab, src, pts, ok in zip(persons, labels, sources, xy, whole):
        cls = label if label is not None else gd.KEYPOINT_LABELS.get(lab)
        if cls is None:
            continue
        if not ok:
            no_hand += 1
            continue
        if label is None and gd.mislabelled_keypoints(p, src):
            skipped += 1
            continue
        # the rarer gestures (few people recorded a thumb or an OK sign) count more
        rows += keypoint_copies(ds, pts, cls, p, lab,
                                RARE_KEYPOINT_COPIES if cls in ('thumb', 'pinch') else 2)
        n += 1
    add_keypoint_rows(ds, rows)
    ds.sources.append('%s (%d rows%s%s)' % (
        os.path.basename(path), n, ', %d mislabelled left out' % skipped if skipped else '',
        ', %d without a hand left out' % no_hand if no_hand else ''))


def file_classes(path, family):
    """(Counter of the classes a user's file gives its rows, whether they are names): the
    label of each pose record or of each row of a keypoint CSV with the shared header, the
    class id of each row of the community's headerless keypoint.csv. DataError for a file
    that cannot be read."""
    if family == 'keypoints':
        counts = collections.Counter(lab for _, lab, _, _ in gd.iter_keypoints(path))
        return counts, gd.keypoint_labels_named(path)
    return collections.Counter(lab for _, lab, _ in gd.read_pose_lines(path)), True


def _short(text, most=24):
    return text if len(text) <= most else text[:most - 3] + '...'


def _listed(classes, named, most=8):
    # ids in numeric order (by length, then digits), names after them
    def key(c):
        number = c.isascii() and c.isdigit()
        return (not number, len(c) if number else 0, c)
    shown = sorted(classes, key=key)
    text = ', '.join(_short(c) for c in shown[:most])
    return '%s %s%s' % ('labels' if named else 'ids', text, ', ...' if len(shown) > most else '')


def added_file_problem(path, family, label, take=None):
    """Why the rows of a user's file (`take`'s rows alone, when given) cannot be taken as
    class `label`, or None: `label` relabels every row, so a file of several classes (a
    community keypoint.csv holds its open hands and fists beside a new gesture), or one
    that names another, would put other poses into it. DataError for a file that cannot be
    read."""
    counts, named = file_classes(path, family)
    if take is not None:
        if take not in counts:
            return '%s --id %s: no row has that %s (%s)' % (
                path, take, 'label' if named else 'id', _listed(counts, named))
        return None
    if len(counts) > 1:
        return ('%s holds rows of %d classes (%s): --label %s would make every one %s; give '
                '--id ID after --add to take the rows of one' % (
                    path, len(counts), _listed(counts, named), label, label))
    if named and counts and label not in counts:
        found = _short(next(iter(counts)))
        take_as = '--id %s --label %s to take them as %s' % (found, label, label)
        if shared_label_problem(found):      # not a name a user's class may take
            return '%s labels its rows %s, not %s: give %s' % (path, found, label, take_as)
        return ('%s labels its rows %s, not %s: give --label %s, or %s'
                % (path, found, label, found, take_as))
    return None


# The keypoint model also learns from the Leap people seen as a webcam sees a hand: their
# 3-D landmarks turned palm to the camera, then about the fingers' axis by up to
# VIEW_YAW_DEG (side views: a thumbs-up shows the side of the fist) and about the
# thumbward axis by up to VIEW_PITCH_DEG, and flattened. They bring the poses the
# keypoint files lack (horns, and OK signs and thumbs of more people).
VIEW_YAW_DEG = 80.0
VIEW_PITCH_DEG = 35.0
VIEW_STRIDE = 2

# Keypoint rows are also fitted turned in the picture by up to this (rad, ~26 deg), and
# the thumbs and OK signs (three and two people of eight) in RARE_KEYPOINT_COPIES copies.
TURN_RAD = 0.45
RARE_KEYPOINT_COPIES = 4

# Landmark noise on those copies, in the keypoint files' units (the largest coordinate is 1)
KEYPOINT_NOISE = 0.015
PHOTO_COPIES = 10       # a photo is one hand against hundreds of rows of each keypoint file


def projected_landmarks(landmarks, yaw, pitch):
    """(21, 2) image positions (y down) of hand-frame landmarks seen palm-on after
    turning them by yaw (about the hand direction) and pitch (about thumbward)."""
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cp, -sp], [0.0, sp, cp]])
    q = landmarks @ (rx @ rz).T
    return np.stack((q[:, 0], -q[:, 2]), axis=1)


def add_leap_views(ds, path, seed=SEED):
    rng = np.random.default_rng(seed)
    n = 0
    rows = []
    for i, (p, lab, frame) in enumerate(gd.read_pose_lines(path)):
        cls = gd.LEAP_LABELS.get(lab)
        # their thumbs point ahead along the fingers, unlike a webcam's thumbs-up
        if i % VIEW_STRIDE or cls is None or cls == 'thumb':
            continue
        hand = gd.first_hand(frame)
        lm = hand_landmarks(hand) if hand is not None else None
        if lm is None:
            continue
        yaw, pitch = np.radians(rng.uniform(-1, 1, 2) * (VIEW_YAW_DEG, VIEW_PITCH_DEG))
        xy = rotate_keypoints(projected_landmarks(lm, yaw, pitch), rng.uniform(-TURN_RAD, TURN_RAD))
        rows.append((xy, cls, 'leap:' + p, lab, False, ds.new_group()))
        n += 1
    add_keypoint_rows(ds, rows)
    ds.sources.append('%s seen as a webcam would (%d views)' % (os.path.basename(path), n))


def add_photos(ds, folder):
    """The labelled photos' hands, one person per photo source (a few photos each, from
    other people than the keypoint files): PHOTO_COPIES turned copies each, every one
    fitted (no stride: each photo is a hand of its own)."""
    n = 0
    rows = []
    for source, label, xy in gd.photo_hands(folder):
        cls = gd.PHOTO_LABELS.get(label)
        if cls is not None:
            rows += keypoint_copies(ds, xy, cls, 'photo:' + source, label, PHOTO_COPIES, group=-1)
            n += 1
    add_keypoint_rows(ds, rows)
    ds.sources.append('the labelled photos of ../hands (%d hands)' % n)
