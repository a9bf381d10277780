"""Fit the pose models on people, judge them on people they never saw, and ship them as
arrays with a model card.

usage: python -m leap_teleop.hands.gestures.train [--family leap|keypoints|all]
           [--data DIR] [--add FILE [--id ID] --label NAME ...] [--out MODEL] [--no-report]
       rosrun leap_teleop train_gestures --add FILE [--id ID] --label NAME --out MODEL

Without --add it refits the shipped models (make train) from the shared, people-split
data: Leap frames of 12 people (static poses) and 2 people (dynamic takes) for the Leap
model, 8 people's webcam keypoints for the keypoint model. With --add FILE --label NAME
(repeatable) the user's samples join as one more person each file, class NAME: FILE is
record_gestures' output or a shared-format file (.jsonl[.gz] Leap poses, .csv keypoints)
or a community keypoint.csv whose rows are all NAME; the family follows FILE. A FILE whose
rows carry several classes (a community keypoint.csv's ids, or labels), or a label other
than NAME, is refused: --id ID after it takes the rows of that id (or label) alone.

Fitting is deterministic (fixed seed, one thread). Before the final fit it runs
leave-one-person-out (fit on all people but one, score that one, for each; a user's
retrain holds out each of their files and REPORT_SHARED_PEOPLE shared people) and writes
the figures, with the worst person, into the model's card.
"""
import argparse
import collections
import datetime
import gzip
import hashlib
import os
import sys
import time
import zlib

import numpy as np

from leap_teleop.hands.gestures import datasets as gd
from leap_teleop.hands.gestures.classifier import (
    BUILT_IN_CLASSES,
    DEFAULT_MODELS,
    PoseClassifier,
    class_name_problem,
    is_model_file,
)
from leap_teleop.hands.gestures.training_set import (
    JOINT_NOISE_MM,
    KEYPOINT_NOISE,
    SEED,
    Dataset,
    add_guinevere,
    add_keypoints,
    add_leap_poses,
    add_leap_views,
    add_leapjs_takes,
    add_photos,
    added_file_problem,
    data_terms,
    shared_label_problem,
)
from leap_teleop.output_file import output_problem

HIDDEN_UNITS = 64
L2 = 1e-3
# The keypoint model learns from few people (one to three a class): ten times the weight
# decay of the Leap model keeps it from fitting one person's habits (leave-one-person-out:
# thumbs-up 0.75 -> 0.80 with the landmark noise below, every false-positive rate <= 0.02).
KEYPOINT_L2 = 1e-2
L2_OF = {'leap': L2, 'keypoints': KEYPOINT_L2}
MAX_ITER = 80
# Consecutive frames of one pose are nearly the same: fitting on every other one halves the
# time and loses nothing measurable.
FIT_STRIDE = 2
CARD_TITLE = '# Pose model card'    # a card's first line: only such a file is rewritten
FOLD_WORKERS = 2        # leave-one-person-out folds fitted at once (this machine: 2 cores)
MIN_SCALE = 0.05        # features are unit vectors, cosines and palm widths
# The Guinevere thumbs takes' thumbs are the only real thumbs-up / down there are (two
# people, four takes each way, against thousands of frames of each static pose): each
# such frame counts THUMB_TAKE_REPEAT times in the fit.
THUMB_TAKE_REPEAT = 10


def strided(rows, groups, stride=FIT_STRIDE):
    """The rows of every stride-th group (Dataset.group: a recorded hand or row with its
    copies and mirror images, kept together) and those of group -1 (always fitted)."""
    rows = np.asarray(rows)
    g = np.asarray(groups)[rows]
    return rows[(g < 0) | (g % stride == 0)]


def fit_rows(labels, persons, rows):
    """`rows` (indices) with the thumbs takes' frames repeated (see THUMB_TAKE_REPEAT)."""
    thumbs = rows[np.isin(labels[rows], ('thumbs_up', 'thumbs_down'))
                  & np.char.startswith(persons[rows].astype(str), 'guinevere_')]
    return np.concatenate([rows] + [thumbs] * (THUMB_TAKE_REPEAT - 1))


def fit(x, y, seed=SEED, alpha=L2):
    """A PoseClassifier fitted on rows x with class names y (alpha: the L2 weight decay)."""
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.neural_network import MLPClassifier
    from threadpoolctl import threadpool_limits
    mean = x.mean(axis=0)
    # a floor on the spread: a feature nearly constant in the data (a tracker's fixed
    # proportions) must not turn a small difference elsewhere into a huge one
    scale = np.maximum(x.std(axis=0), MIN_SCALE)
    z = (x - mean) / scale
    with threadpool_limits(1), warnings.catch_warnings():
        warnings.simplefilter('ignore', ConvergenceWarning)
        m = MLPClassifier((HIDDEN_UNITS,), alpha=alpha, max_iter=MAX_ITER,
                          random_state=seed).fit(z, y)
    w1, b1 = m.coefs_[1], m.intercepts_[1]
    if len(m.classes_) == 2:    # one logistic output: the same as softmax over (0, z)
        w1 = np.hstack((np.zeros_like(w1), w1))
        b1 = np.concatenate(([0.0], b1))
    return PoseClassifier(m.classes_.tolist(), '', mean, scale, m.coefs_[0], m.intercepts_[0],
                          w1, b1)


_FOLD_DATA = None


def _fit_without(person):
    x, y, persons, labels, stride, alpha, groups = _FOLD_DATA
    rows = fit_rows(labels, persons, strided(np.where(persons != person)[0], groups, stride))
    return fit(x[rows], y[rows], alpha=alpha)


def models_without(x, y, persons, labels, held, stride=FIT_STRIDE, log=print, alpha=L2,
                   groups=None):
    """{person: model fitted on everyone else} for each held-out person, two folds at a
    time (one per core; each fit is seeded, so the result does not depend on the order).
    groups: Dataset.groups() (default: rows in pairs, a hand and its copy)."""
    groups = np.arange(len(y)) // 2 if groups is None else groups
    global _FOLD_DATA
    import multiprocessing

    # imported here, once, rather than by each forked worker again (seconds of CPU each)
    import sklearn.neural_network  # noqa: F401
    import threadpoolctl  # noqa: F401
    _FOLD_DATA = (x, y, persons, labels, stride, alpha, groups)
    held = sorted(held)
    out = {}
    try:
        ctx = multiprocessing.get_context('fork')
        with ctx.Pool(min(FOLD_WORKERS, len(held))) as pool:
            for person, model in zip(held, pool.imap(_fit_without, held)):
                out[person] = model
                log('  fitted without %s' % person)
    finally:
        _FOLD_DATA = None
    return out


def lopo(x, y, persons, labels, family, stride=FIT_STRIDE, log=print, clean=None, held=None,
         groups=None):
    """Leave-one-person-out: per class recall and false-positive rate per held-out person,
    their mean and worst, and the confusion of source labels into classes."""
    classes = sorted(set(y))
    per = {c: {} for c in classes}
    confusion = collections.defaultdict(collections.Counter)
    held = sorted(set(persons) if held is None else held)
    models = models_without(x, y, persons, labels, held, stride, log, alpha=L2_OF[family],
                            groups=groups)
    for person in held:
        test = persons == person
        model = models[person]
        if clean is not None:
            test = test & clean
        proba = model.proba(x[test])
        if family == 'keypoints':   # rows come in (image, mirror) pairs: score their mean
            proba = 0.5 * (proba[0::2] + proba[1::2])
            yt, lt = y[test][0::2], labels[test][0::2]
        else:
            yt, lt = y[test], labels[test]
        pred = np.array(model.classes)[proba.argmax(axis=1)]
        for c in classes:
            pos = yt == c
            per[c][person] = {'n': int(pos.sum()),
                              'recall': float((pred[pos] == c).mean()) if pos.any() else None,
                              'fpr': float((pred[~pos] == c).mean()) if (~pos).any() else None}
        for lab, p in zip(lt, pred):
            confusion[str(lab)][str(p)] += 1
        log('  held out %s: %s' % (person, ', '.join(
            '%s %.2f' % (c, per[c][person]['recall']) for c in classes
            if per[c][person].get('recall') is not None)))
    summary = {}
    for c in classes:
        rec = {p: v['recall'] for p, v in per[c].items() if v['recall'] is not None}
        fpr = {p: v['fpr'] for p, v in per[c].items() if v['fpr'] is not None}
        worst = min(rec, key=rec.get) if rec else None
        summary[c] = {'recall_mean': float(np.mean(list(rec.values()))) if rec else None,
                      'recall_worst': rec[worst] if rec else None, 'worst_person': worst,
                      'fpr_mean': float(np.mean(list(fpr.values()))) if fpr else None,
                      'fpr_worst': max(fpr.values()) if fpr else None,
                      'people': len(rec)}
    return {'per_class': summary, 'per_person': per,
            'confusion': {k: dict(v) for k, v in sorted(confusion.items())}}


def print_lopo(title, report):
    print(title)
    print('  %-11s %-22s %-16s %s' % ('class', 'recall mean / worst', 'worst person', 'FPR mean / worst'))
    for c, s in report['per_class'].items():
        if s['fpr_mean'] is None and s['recall_mean'] is None:
            continue
        rec = ('%.3f / %.3f          %-16s' % (s['recall_mean'], s['recall_worst'], s['worst_person'])
               if s['recall_mean'] is not None else '%-39s' % '- (no held-out person shows it)')
        fpr = ('%.4f / %.4f' % (s['fpr_mean'], s['fpr_worst']) if s['fpr_mean'] is not None
               else '- (no held-out person shows another pose)')
        print('  %-11s %s %s' % (c, rec, fpr))
    if report['confusion']:
        print('  confusion (source label -> share read as each class):')
    for lab, row in report['confusion'].items():
        tot = sum(row.values())
        print('    %-22s %s' % (lab, ', '.join('%s %.2f' % (k, v / tot) for k, v in
                                                sorted(row.items(), key=lambda kv: -kv[1]))))


# Shared people a user's retrain also holds out, evenly spread over the sorted names.
REPORT_SHARED_PEOPLE = 3


def report_people(shared):
    """The shared people a user's retrain holds out (REPORT_SHARED_PEOPLE of them)."""
    n = min(REPORT_SHARED_PEOPLE, len(shared))
    return [shared[i * len(shared) // n] for i in range(n)] if n else []


def training_dataset(family, data_dir, adds):
    """The Dataset of `family` from the shared data (when there) plus the user's files:
    adds, [(path, label)] or [(path, label, id)] (the file's rows of that id alone)."""
    adds = [tuple(add) + (None,) * (3 - len(add)) for add in adds]
    with gd.paused_gc():
        return _read_dataset(family, data_dir, adds)


def _read_dataset(family, data_dir, adds):
    ds = Dataset(family)
    if family == 'leap':
        gti = os.path.join(data_dir, 'leap_people', 'gti_dev.jsonl.gz')
        guin = os.path.join(data_dir, 'leap_people', 'guinevere')
        if os.path.isfile(gti):
            add_leap_poses(ds, gti)
        if os.path.isdir(guin):
            add_guinevere(ds, guin)
        if os.path.isdir(os.path.join(data_dir, 'leapjs')):
            add_leapjs_takes(ds, os.path.join(data_dir, 'leapjs'))
    else:
        folder = os.path.join(data_dir, 'keypoints')
        gti = os.path.join(data_dir, 'leap_people', 'gti_dev.jsonl.gz')
        if os.path.isfile(gti):
            add_leap_views(ds, gti)
        if os.path.isfile(os.path.join(data_dir, 'hands', 'hands.json')):
            add_photos(ds, os.path.join(data_dir, 'hands'))
        if os.path.isdir(folder):
            for name in sorted(os.listdir(folder)):
                if name.endswith('.csv'):
                    add_keypoints(ds, os.path.join(folder, name))
    # A user's new gesture that the shared people also recorded (a V sign is their 'two'
    # or 'peace', trained as none): their rows join the user's class instead of opposing it.
    # Only rows trained as none: a built-in class keeps its rows (and its guards).
    for _, label, _ in adds:
        for i, lab in enumerate(ds.label):
            if lab == label and ds.y[i] == 'none':
                ds.y[i] = label
    for (path, label, take), person in zip(adds, user_people([p for p, _, _ in adds])):
        before = len(ds.y)
        if file_family(path) == 'keypoints':
            add_keypoints(ds, path, label=label, person=person, take=take)
        else:
            add_leap_poses(ds, path, label=label, person=person, take=take)
        if len(ds.y) == before:
            raise gd.DataError('--add %s: no hand in it' % path)
    return ds


def user_people(paths):
    """The person each of a user's files stands for: 'user:' and its name without the
    extension, numbered when two files share a name (they are recorded apart)."""
    names = ['user:' + os.path.splitext(os.path.basename(p))[0] for p in paths]
    seen = collections.Counter()
    out = []
    for name in names:
        seen[name] += 1
        out.append(name if names.count(name) == 1 else '%s#%d' % (name, seen[name]))
    return out


def _content_digest(path):
    """A digest of a file's content, unpacked when gzipped (a take and its gzipped copy are
    one take), or None when it cannot be read (reading it for the fit says why)."""
    digest = hashlib.sha256()
    try:
        with open(path, 'rb') as f:
            packed = f.read(2) == b'\x1f\x8b'
        with gzip.open(path, 'rb') if packed else open(path, 'rb') as f:
            for block in iter(lambda: f.read(1 << 20), b''):
                digest.update(block)
    except (OSError, EOFError, zlib.error):
        return None
    return digest.digest()


def same_recording(paths):
    """(earlier, later): the first --add file that is, or holds the same content as, an
    earlier one, or None. Each file is one person held out in turn: a copy left in the
    fit would score that person on rows it was fitted on."""
    digests = []
    for k, path in enumerate(paths):
        digest = _content_digest(path)
        for earlier, seen in zip(paths[:k], digests):
            if os.path.samefile(path, earlier) or (digest is not None and digest == seen):
                return earlier, path
        digests.append(digest)
    return None


def file_family(path):
    return 'keypoints' if path.lower().endswith('.csv') else 'leap'


FAMILY_FILES = {'leap': 'Leap poses (.jsonl)', 'keypoints': 'keypoints (.csv)'}


def model_out_problem(out, adds):
    """Why a model cannot be written at `out` (its card goes beside it, NAME.md) without
    harm to the user's --add files or to anything that is no model or model card, or None."""
    if not out.strip():
        return 'name the model file (left out, the shipped model is refitted)'
    if os.path.isdir(out):
        return 'a folder: name the model file'
    if not out.lower().endswith('.npz'):
        return 'a model file ends in .npz'
    card = os.path.splitext(out)[0] + '.md'
    for path in (out, card):
        if os.path.exists(path) and not os.path.isfile(path):
            return '%s is no regular file' % path
        for add in adds:
            if os.path.exists(path) and os.path.samefile(path, add):
                return 'it would overwrite the --add file %s' % add
        problem = output_problem(path)
        if problem:
            return problem if path == out else '%s: %s' % (card, problem)
    if os.path.exists(out) and not is_model_file(out):
        return 'a file that is no pose model: it would be overwritten'
    if os.path.exists(card):
        with open(card, encoding='utf-8', errors='replace') as f:
            if not f.readline().startswith(CARD_TITLE):
                return '%s is no model card: it would be overwritten' % card
    return None


def train(family, data_dir, adds=(), report=True, log=print):
    """(model, card) fitted on every person, the card holding the LOPO figures."""
    t0 = time.time()
    adds = [tuple(add) + (None,) * (3 - len(add)) for add in adds]
    ds = training_dataset(family, data_dir, adds)
    x, y, persons, labels = ds.arrays()
    if len(set(y)) < 2:
        raise SystemExit('train_gestures: fewer than two classes of %s data (is the shared '
                         'data at %s?)' % (family, data_dir))
    missing = [c for c in BUILT_IN_CLASSES if c not in set(y.tolist())]
    if missing:
        # every consumer refuses a model without them (it reads every hand as a user's class)
        raise SystemExit('train_gestures: no %s rows of the built-in classes %s (is the shared '
                         'data at %s?)' % (family, ', '.join(missing), data_dir))
    card = {'family': family, 'fitted_on': ds.sources,
            'data_terms': data_terms(family, set(persons.tolist())),
            'people': sorted(set(persons.tolist())),
            'rows': int(len(y)), 'classes': sorted(set(y.tolist())),
            'model': 'standardised features, %d ReLU units, softmax (scikit-learn '
                     'MLPClassifier, alpha %g, %d iterations, seed %d; fitted on every %s '
                     'frame, %s)'
                     % (HIDDEN_UNITS, L2_OF[family], MAX_ITER, SEED, {1: '', 2: 'second'}.get(
                         FIT_STRIDE, '%dth' % FIT_STRIDE),
                        'each Leap hand also with %g mm of noise on every joint'
                        % JOINT_NOISE_MM if family == 'leap' else
                        'each row also as its mirror image, and turned with %g of '
                        'landmark noise' % KEYPOINT_NOISE),
            'command': 'python -m leap_teleop.hands.gestures.train --family %s%s' % (
                family, ''.join(' --add %s%s --label %s' % (path, '' if take is None else ' --id %s' % take,
                                                            label) for path, label, take in adds)),
            'date': datetime.date.today().isoformat()}
    users = sorted(p for p in set(persons.tolist()) if p.startswith('user:'))
    shared = sorted(p for p in set(persons.tolist()) if not p.startswith('user:'))
    if family == 'keypoints':
        # the Leap people's camera views are judged in tools.evaluation.people; the card holds the
        # webcam people
        shared = [p for p in shared if not p.startswith(('leap:', 'photo:'))]
    # the shipped models hold out every person; a user's retrain each of their own files
    # (their gesture's recall) and a few shared people (how often other people's poses
    # read as it), which keeps it within a minute
    held = users + report_people(shared) if adds else shared
    if report and len(set(persons)) > 1:
        log('%s: leave-one-person-out over %d of %d people (%d rows)'
            % (family, len(held), len(set(persons)), len(y)))
        if adds and len(users) < 2:
            log('  (one file of your own: while it is held out, the fit knows its gesture '
                'only where shared people show it; record a second session to judge it on '
                'data the fit never saw)')
        report = lopo(x, y, persons, labels, family, log=log, clean=ds.clean(), held=held,
                      groups=ds.groups())
        card['leave_one_person_out'] = report['per_class']
        card['confusion'] = report['confusion']
    mine = np.char.startswith(persons.astype(str), 'user:')
    rows = np.union1d(strided(np.where(~mine)[0], ds.groups()), np.where(mine)[0])
    rows = fit_rows(labels, persons, rows)
    model = fit(x[rows], y[rows], alpha=L2_OF[family])
    model.family = family
    model.card = card
    card['seconds'] = round(time.time() - t0, 1)
    return model, card


class _IdOfLastAdd(argparse.Action):
    """--id ID: {index of the --add it follows: ID}."""

    def __call__(self, parser, namespace, value, option_string=None):
        ids = dict(getattr(namespace, self.dest) or {})
        k = len(getattr(namespace, 'add', None) or []) - 1
        if k < 0:
            parser.error('--id %s: give it after the --add FILE whose rows it picks' % value)
        if k in ids:
            parser.error('--id %s: --add %s has its --id already' % (value, namespace.add[k]))
        ids[k] = value
        setattr(namespace, self.dest, ids)


def main(argv=None):
    ap = argparse.ArgumentParser(description=' '.join(__doc__.split('\n\n')[0].split()))
    ap.add_argument('--family', choices=('leap', 'keypoints', 'all'), default=None,
                    help='which model (default: all, or the family of the --add files)')
    ap.add_argument('--data', default=gd.SHARED_DATA,
                    help='the shared data folder (default %(default)s)')
    ap.add_argument('--add', action='append', default=[], metavar='FILE',
                    help="a user's samples (repeatable, each followed by --label)")
    ap.add_argument('--id', action=_IdOfLastAdd, default={}, metavar='ID', dest='ids',
                    help="after --add FILE: take only FILE's rows of this class id (a community "
                         'keypoint.csv) or label (a file with a header, pose records); a file of '
                         'several classes is refused without it')
    ap.add_argument('--label', action='append', default=[], metavar='NAME',
                    help='the class of the preceding --add file')
    ap.add_argument('--out', default=None,
                    help='model file (default, without --add only: the shipped one)')
    ap.add_argument('--no-report', action='store_true', help='skip leave-one-person-out')
    if argv is None:
        argv = [a for a in sys.argv[1:] if ':=' not in a]
    args = ap.parse_args(argv)
    if len(args.add) != len(args.label):
        ap.error('every --add FILE needs its --label NAME')
    if args.add and args.out is None:
        # a model with a user's samples is theirs: it must not replace the shipped one in place
        ap.error('--add needs --out MODEL (a file of your own; the shipped model stays as it is)')
    for path in args.add:
        if not os.path.isfile(path):
            ap.error('--add %s: %s' % (path, 'a folder: name a file' if os.path.isdir(path)
                                       else 'no such file'))
    same = same_recording(args.add)
    if same:
        ap.error('--add %s: the same recording as --add %s (give a second session)' % same[::-1])
    for label in args.label:
        problem = class_name_problem(label, new=True) or shared_label_problem(label)
        if problem:
            ap.error('--label %r: %s' % (label, problem))
    if args.out is not None:
        problem = model_out_problem(args.out, args.add)
        if problem:
            ap.error('--out %s: %s' % (args.out or "''", problem))
    adds = [(path, label, args.ids.get(k)) for k, (path, label) in enumerate(zip(args.add, args.label))]
    families = {file_family(p) for p in args.add}
    if len(families) > 1:
        ap.error('--add files of one family at a time (Leap .jsonl or keypoint .csv)')
    if families and args.family and args.family not in families:
        # the user's rows would join the other family's model and break its fit
        fam = next(iter(families))
        ap.error('--family %s: the --add files are %s; give --family %s or leave it out'
                 % (args.family, FAMILY_FILES[fam], fam))
    family = args.family or (families.pop() if families else 'all')
    todo = ('leap', 'keypoints') if family == 'all' else (family,)
    if args.out and len(todo) > 1:
        ap.error('--out names one model: give --family')
    # checked before the fit, which takes minutes
    for fam in todo if args.out is None else ():     # --out was checked above
        problem = model_out_problem(DEFAULT_MODELS[fam], args.add)
        if problem:
            ap.error('--out %s: %s' % (DEFAULT_MODELS[fam], problem))
    for path, label, take in adds:
        try:
            problem = added_file_problem(path, file_family(path), label, take)
        except gd.DataError as e:
            print('train_gestures: %s' % e, file=sys.stderr)
            return 2
        if problem:
            ap.error('--add %s' % problem)
    for fam in todo:
        try:
            model, card = train(fam, args.data, adds, report=not args.no_report)
        except gd.DataError as e:
            print('train_gestures: %s' % e, file=sys.stderr)
            return 2
        out = args.out or DEFAULT_MODELS[fam]
        # the card's command remakes this very file: copied without --out it would refit
        # the shipped model in place
        card['command'] += (' --out %s' % args.out if args.out else '') + (
            ' --no-report' if args.no_report else '')
        try:
            model.save(out)
            write_card(out, card)
        except OSError as e:
            print('train_gestures: cannot write %s: %s' % (out, e), file=sys.stderr)
            return 1
        if 'leave_one_person_out' in card:
            print_lopo('%s model, leave-one-person-out:' % fam,
                       {'per_class': card['leave_one_person_out'],
                        'confusion': card.get('confusion', {})})
        print('wrote %s (%d classes: %s) in %.0f s'
              % (out, len(model.classes), ', '.join(model.classes), card['seconds']))
    return 0


def write_card(model_path, card):
    """The model card beside the model, as Markdown."""
    lines = [CARD_TITLE + ': %s' % os.path.basename(model_path), '',
             '- family: %s' % card['family'],
             '- classes: %s' % ', '.join(card['classes']),
             '- fitted on: %s' % '; '.join(card['fitted_on']),
             '- data and terms: %s' % ('; '.join(card.get('data_terms', []))
                                       or 'none of the shared data (your own files only)'),
             '- people: %d (%s)' % (len(card['people']), ', '.join(card['people'])),
             '- rows: %d' % card['rows'], '- model: %s' % card['model'],
             '- made by: `%s` (%s, %s s)' % (card['command'], card['date'], card['seconds']), '']
    lo = card.get('leave_one_person_out')
    if lo:
        lines += ['## Leave-one-person-out (fit on all people but one, score that one)', '',
                  '| class | recall mean | recall worst (person) | FPR mean | FPR worst |',
                  '|---|---|---|---|---|']
        for c, s in lo.items():
            if s['fpr_mean'] is None and s['recall_mean'] is None:
                continue
            rec = ('%.3f | %.3f (%s)' % (s['recall_mean'], s['recall_worst'], s['worst_person'])
                   if s['recall_mean'] is not None else '- | - (no unseen person shows it)')
            fpr = ('%.4f | %.4f' % (s['fpr_mean'], s['fpr_worst']) if s['fpr_mean'] is not None
                   else '- | -')
            lines.append('| %s | %s | %s |' % (c, rec, fpr))
        lines.append('')
    with open(os.path.splitext(model_path)[0] + '.md', 'w') as f:
        f.write('\n'.join(lines))


if __name__ == '__main__':
    sys.exit(main())
