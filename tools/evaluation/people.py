"""Gesture recognition judged on people it never saw: leave-one-person-out.

usage: python -m tools.evaluation.people [--data DIR] [--family leap|keypoints|all]
           [--out FILE]

For every person of the shared, people-split data: fit the pose model on all the others
(hands/gestures/train.py, same settings as the shipped model), then run that person's hands
through the recognizer's per-frame decisions (model + guards) and, for the dynamic takes,
through the whole stream recognizer (temporal filter, events). Reported per gesture:
recall (mean over people and the worst person), false-positive rate (pooled over every
person's other poses, and the worst person's), a confusion
table (which recorded pose reads as which gesture), and for the takes: thumbs-up takes
that arm (thumbs-up held arm_hold_s), thumbs-down takes that arm, and takes with a false
fold / unfold or circle (none of the takes draws a circle or folds a hand).

What each recorded label must read as (anything else: every gesture false):
Leap static poses: fist_moved -> fist; five, palm, palm_m, palm_u -> open; ok -> pinch;
heavy -> rock; up, down (a fist with the thumb out, pointing forward) and two, three,
four, index, L, hang, C -> nothing. Dynamic takes: thumbs_up -> thumb_up, thumbs_down ->
thumb_down, open_hand_* -> open, other takes' frames are unlabelled (they only count for
false thumbs-ups and false events). The shared LeapJS takes (one more person, an older
tracker): their labelled frames (hands.gestures.datasets.LEAPJS_LABELS; a thumb out of a fist
is a thumbs-up where the SDK's thumb points up, nothing where it points sideways). Webcam
keypoints: open, fist, thumb_up, thumb_down, ok -> pinch; pointing, peace, other ->
nothing (classes whose rows show another pose, hands.gestures.datasets.MISLABELLED_KEYPOINTS,
are left out and reported apart); the Leap people seen as a camera would
(hands.gestures.training_set.projected_landmarks) score horns (heavy -> rock) and are reported
apart, and so are the labelled photos, one photo source held out at a time.
"""
import argparse
import collections
import os
import sys
import time

import numpy as np

from leap_teleop.hands.frame import TrackedHand
from leap_teleop.hands.gestures import GestureRecognizer, training_set
from leap_teleop.hands.gestures import datasets as gd
from leap_teleop.hands.gestures import train as tg
from leap_teleop.hands.gestures.geometry import hand_geometry
from leap_teleop.hands.gestures.pose import MIN_P, classify_pose
from leap_teleop.hands.gestures.temporal import HELD_GESTURES
from leap_teleop.ur10.teleop_params import TELEOP_PARAMS
from tools.evaluation.results_file import write_json

ARM_HOLD_S = TELEOP_PARAMS['arm_hold_s'].default     # the arm's own default
LEAP_EXPECT = {'fist_moved': 'fist', 'five': 'open', 'palm': 'open', 'palm_m': 'open',
               'palm_u': 'open', 'ok': 'pinch', 'heavy': 'rock', 'thumbs_up': 'thumb_up',
               'thumbs_down': 'thumb_down', 'open_hand_up': 'open', 'open_hand_down': 'open',
               'open_hand_left': 'open', 'open_hand_right': 'open'}
KEYPOINT_EXPECT = {'open': 'open', 'fist': 'fist', 'thumb_up': 'thumb_up',
                   'thumb_down': 'thumb_down', 'ok': 'pinch', 'heavy': 'rock'}
PHOTO_EXPECT = {'open_palm': 'open', 'flat_hand': 'open', 'fist': 'fist', 'thumbs_up': 'thumb_up',
                'thumbs_down': 'thumb_down', 'ok': 'pinch', 'pinch_o': 'pinch'}
GESTURES = ('fist', 'open', 'pinch', 'rock', 'thumb_up', 'thumb_down')
MODEL_CLASS = {'thumb_up': 'thumb', 'thumb_down': 'thumb'}   # else the gesture's own name


def _read(s):
    """What a decision dict says: the one gesture on, or 'nothing'."""
    on = [g for g in HELD_GESTURES if s.get(g)]
    return on[0] if on else 'nothing'


def why_missed(s, want):
    """Why a decision dict misses the gesture `want`: the model chose another class
    ('model: CLASS'), its class was below MIN_P ('below MIN_P'), or a guard said no
    ('guard': the thumb's measured direction or THUMB_UP_MIN_P); 'no joints' when the hand
    could not be judged."""
    label = s.get('label') or ''
    if not label:
        return 'no joints'
    if label != MODEL_CLASS.get(want, want):
        return 'model: ' + label
    return 'below MIN_P' if s.get('probability', 0.0) < MIN_P else 'guard'


class Tally:
    """Per person, per gesture: positives found, negatives read as it; confusion."""

    def __init__(self):
        self.pos = collections.defaultdict(lambda: collections.defaultdict(lambda: [0, 0]))
        self.neg = collections.defaultdict(lambda: collections.defaultdict(lambda: [0, 0]))
        self.confusion = collections.defaultdict(collections.Counter)
        self.missed = collections.defaultdict(collections.Counter)

    def add(self, person, label, want, read, why=None):
        """`why`: why_missed's cause when a positive is missed (counted per gesture)."""
        for g in GESTURES:
            if want == g:
                self.pos[g][person][0] += read == g
                self.pos[g][person][1] += 1
                if read != g and why is not None:
                    self.missed[g][why] += 1
            else:
                self.neg[g][person][0] += read == g
                self.neg[g][person][1] += 1
        self.confusion[label][read] += 1

    def add_negative(self, person, gesture, label, read):
        """A frame that is no `gesture` and nothing else known (an unlabelled take's):
        counted against that gesture alone."""
        self.neg[gesture][person][0] += read == gesture
        self.neg[gesture][person][1] += 1
        self.confusion[label][read] += 1

    def summary(self):
        out = {}
        for g in GESTURES:
            rec = {p: a / n for p, (a, n) in self.pos[g].items() if n}
            fpr = {p: a / n for p, (a, n) in self.neg[g].items() if n}
            pooled = sum(a for a, _ in self.neg[g].values()), sum(n for _, n in self.neg[g].values())
            worst = min(rec, key=rec.get) if rec else None
            out[g] = {'recall_mean': float(np.mean(list(rec.values()))) if rec else None,
                      'recall_worst': rec[worst] if rec else None, 'worst_person': worst,
                      'recall_per_person': {p: round(v, 4) for p, v in sorted(rec.items())},
                      'positives': int(sum(n for _, n in self.pos[g].values())),
                      'fpr_pooled': pooled[0] / pooled[1] if pooled[1] else None,
                      'fpr_worst': max(fpr.values()) if fpr else None,
                      'fpr_worst_person': max(fpr, key=fpr.get) if fpr else None,
                      'missed_because': dict(self.missed[g].most_common())}
        return {'per_gesture': out,
                'confusion': {k: dict(v) for k, v in sorted(self.confusion.items())}}


def _decide(hand, model):
    return classify_pose(hand, hand_geometry(hand), model)


def take_outcome(frames, model):
    """Stream a take through the recognizer: did a thumbs-up arm (held ARM_HOLD_S), did
    a thumbs-down hold as long, which events fired."""
    rec = GestureRecognizer(model=model)
    since = {'thumb_up': None, 'thumb_down': None}
    armed = {'thumb_up': False, 'thumb_down': False}
    events = collections.Counter()
    for d in frames:
        hand = gd.first_hand(d)
        t = (d.get('timestamp') or 0) * 1e-6
        if hand is None:
            rec.reset()
            since = {k: None for k in since}
            continue
        s = rec.update(hand, t)
        for e in s.events:
            if e.active:
                events[e.gesture] += 1
        for k in since:
            if getattr(s, k):
                since[k] = t if since[k] is None else since[k]
                armed[k] = armed[k] or t - since[k] >= ARM_HOLD_S - 1e-9
            else:
                since[k] = None
    return armed, events


def leap_people(data_dir, log=print):
    ds = tg.training_dataset('leap', data_dir, [])
    x, y, persons, labels = ds.arrays()
    gti = gd.read_pose_lines(os.path.join(data_dir, 'leap_people', 'gti_dev.jsonl.gz'))
    takes = gd.guinevere_takes(os.path.join(data_dir, 'leap_people', 'guinevere'))
    tally = Tally()
    take_rows = []
    models = tg.models_without(x, y, persons, labels, set(persons), log=log, groups=ds.groups())
    for person in sorted(models):
        t0 = time.time()
        model = models[person]
        model.family = 'leap'
        if person.startswith('guinevere_'):
            subject = person[len('guinevere_'):]
            for p, gesture, path in takes:
                if p != subject:
                    continue
                frames = gd.read_take(path)
                want = LEAP_EXPECT.get(gesture)
                thumb_up_frames = 0
                for d in frames:
                    hand = gd.first_hand(d)
                    if hand is not None:
                        decision = _decide(hand, model)
                        read = _read(decision)
                        thumb_up_frames += read == 'thumb_up'
                        if want is not None:
                            tally.add(person, gesture, want, read, why_missed(decision, want))
                        else:       # an unlabelled take (knob turns, swipes): no thumbs-up
                            tally.add_negative(person, 'thumb_up', gesture, read)
                armed, events = take_outcome(frames, model)
                take_rows.append({'person': person, 'take': os.path.basename(path),
                                  'gesture': gesture, 'thumb_up_armed': armed['thumb_up'],
                                  'thumb_down_held': armed['thumb_down'],
                                  'thumb_up_frames': thumb_up_frames,
                                  'events': dict(events)})
        elif person == training_set.LEAPJS_PERSON:
            from leap_teleop.hands.gestures.datasets import UP, expected
            folder = os.path.join(data_dir, 'leapjs')
            for take, hand, cls, want in training_set.leapjs_take_hands(folder):
                if cls == 'thumb':
                    up = expected(UP, hand)
                    if up is None:
                        continue
                    goal = 'thumb_up' if up else 'nothing'
                else:
                    goal = {'none': 'nothing'}.get(cls, cls)
                decision = _decide(hand, model)
                tally.add(person, take + ':' + cls, goal, _read(decision),
                          why_missed(decision, goal))
        else:
            for p, label, frame in gti:
                if p != person:
                    continue
                hand = gd.first_hand(frame)
                if hand is not None:
                    want = LEAP_EXPECT.get(label, 'nothing')
                    decision = _decide(hand, model)
                    tally.add(person, label, want, _read(decision), why_missed(decision, want))
        log('  leap: scored %s (%.0f s)' % (person, time.time() - t0))
    out = tally.summary()
    out['takes'] = take_summary(take_rows)
    return out


def take_summary(rows):
    up = [r for r in rows if r['gesture'] == 'thumbs_up']
    down = [r for r in rows if r['gesture'] == 'thumbs_down']
    fold = [r for r in rows if r['events'].get('fold') or r['events'].get('unfold')]
    circle = [r for r in rows if any(k.startswith('circle') for k in r['events'])]
    return {'takes': len(rows),
            'thumbs_up_takes_armed': [sum(r['thumb_up_armed'] for r in up), len(up)],
            # a thumbs-up take that did not arm: lost per frame (no frame read thumbs-up)
            # or by the temporal filter and the hold (some did)
            'thumbs_up_takes_not_armed': {'%s/%s' % (r['person'], r['take']):
                                          r.get('thumb_up_frames', 0)
                                          for r in up if not r['thumb_up_armed']},
            'thumbs_down_takes_armed': sum(r['thumb_up_armed'] for r in down),
            'thumbs_down_takes_held': [sum(r['thumb_down_held'] for r in down), len(down)],
            'takes_armed_not_thumbs_up': sorted(r['take'] for r in rows
                                                if r['thumb_up_armed'] and r['gesture'] != 'thumbs_up'),
            'takes_with_fold_or_unfold': sorted('%s/%s' % (r['person'], r['take']) for r in fold),
            'fold_unfold_rate': len(fold) / len(rows) if rows else None,
            'takes_with_circle': sorted('%s/%s' % (r['person'], r['take']) for r in circle),
            'circle_rate': len(circle) / len(rows) if rows else None,
            'per_take': rows}


def keypoint_people(data_dir, log=print):
    ds = tg.training_dataset('keypoints', data_dir, [])
    x, y, persons, labels = ds.arrays()
    folder = os.path.join(data_dir, 'keypoints')
    real = {}
    for name in sorted(os.listdir(folder)):
        if name.endswith('.csv'):
            sources = []
            ps, labs, xy = gd.read_keypoints(os.path.join(folder, name), sources=sources)
            for p, lab, src, pts in zip(ps, labs, sources, xy):
                real.setdefault(p, []).append((lab, src, pts))
    tally, views, photos = Tally(), Tally(), Tally()
    mislabelled = collections.defaultdict(collections.Counter)
    photo_hands = gd.photo_hands(os.path.join(data_dir, 'hands')) \
        if os.path.isfile(os.path.join(data_dir, 'hands', 'hands.json')) else []
    models = tg.models_without(x, y, persons, labels, set(persons), log=log,
                               alpha=tg.L2_OF['keypoints'], groups=ds.groups())
    for person in sorted(models):
        t0 = time.time()
        model = models[person]
        model.family = 'keypoints'
        if person in real:
            for lab, src, pts in real[person]:
                hand = TrackedHand(side='right', image_landmarks=pts)
                decision = classify_pose(hand, None, model)
                read = _read(decision)
                if gd.mislabelled_keypoints(person, src):
                    mislabelled['%s %s' % (person, src)][read] += 1
                    continue
                want = KEYPOINT_EXPECT.get(lab, 'nothing')
                tally.add(person, lab, want, read, why_missed(decision, want))
        elif person.startswith('photo:'):
            for source, lab, xy in photo_hands:
                if 'photo:' + source == person and lab in gd.PHOTO_LABELS:
                    hand = TrackedHand(side='right', image_landmarks=xy)
                    photos.add(person, lab, PHOTO_EXPECT.get(lab, 'nothing'),
                               _read(classify_pose(hand, None, model)))
        else:   # a Leap person seen as a camera would: judge it on its views
            idx = np.where(persons == person)[0][0::2]
            for i in idx:
                p = model.proba(x[i]) * 0.5 + model.proba(x[i + 1]) * 0.5
                best = model.classes[int(p.argmax())]
                read = best if best in GESTURES and p.max() >= 0.5 else (
                    'thumb' if best == 'thumb' else 'nothing')
                views.add(person, labels[i], {'fist_moved': 'fist', 'heavy': 'rock', 'ok': 'pinch',
                                              'five': 'open', 'palm': 'open', 'palm_m': 'open',
                                              'palm_u': 'open'}.get(labels[i], 'nothing'), read)
        log('  keypoints: scored %s (%.0f s)' % (person, time.time() - t0))
    out = tally.summary()
    # rows whose pictures show another pose than their label (datasets.MISLABELLED_KEYPOINTS):
    # in no figure above; what they read as
    out['mislabelled_rows_read_as'] = {k: dict(v) for k, v in sorted(mislabelled.items())}
    out['leap_people_seen_by_a_camera'] = views.summary()
    out['photos_by_source'] = photos.summary()
    return out


def print_people(title, r):
    print(title)
    print('  %-11s %-26s %-22s %s' % ('gesture', 'recall mean / worst (n)', 'worst person',
                                      'FPR pooled / worst person'))
    for g, s in r['per_gesture'].items():
        if s['recall_mean'] is None and s['fpr_pooled'] is None:
            continue
        rec = ('%.3f / %.3f (%d)' % (s['recall_mean'], s['recall_worst'], s['positives'])
               if s['recall_mean'] is not None else '-')
        print('  %-11s %-26s %-22s %.4f / %.4f (%s)' % (
            g, rec, s['worst_person'] or '-', s['fpr_pooled'], s['fpr_worst'],
            s['fpr_worst_person']))
    missed = ['%s: %s' % (g, ', '.join('%s %d' % kv for kv in s['missed_because'].items()))
              for g, s in r['per_gesture'].items() if s.get('missed_because')]
    if missed:
        print('  missed frames, because (the model chose another class, was below MIN_P, '
              'or a guard said no):')
        for line in missed:
            print('    ' + line)
    print('  confusion (recorded label -> share read as):')
    for lab, row in r['confusion'].items():
        tot = sum(row.values())
        print('    %-20s %s' % (lab, ', '.join('%s %.2f' % (k, v / tot) for k, v in
                                              sorted(row.items(), key=lambda kv: -kv[1]))))
    for lab, row in r.get('mislabelled_rows_read_as', {}).items():
        tot = sum(row.values())
        print('    left out (%s) %s: %s' % (
            gd.mislabelled_keypoints(*lab.split(' ', 1)), lab, ', '.join(
                '%s %.2f' % (k, v / tot) for k, v in sorted(row.items(), key=lambda kv: -kv[1]))))
    t = r.get('takes')
    if t:
        print('  takes: thumbs-up takes that arm %d of %d; thumbs-down takes that arm %d; '
              'takes with a false fold/unfold %d of %d (%.1f %%); with a circle %d'
              % (t['thumbs_up_takes_armed'][0], t['thumbs_up_takes_armed'][1],
                 t['thumbs_down_takes_armed'], len(t['takes_with_fold_or_unfold']), t['takes'],
                 100.0 * t['fold_unfold_rate'], len(t['takes_with_circle'])))
        for take, n in t['thumbs_up_takes_not_armed'].items():
            print('  thumbs-up take %s did not arm: %d of its frames read thumbs-up' % (take, n))


def run(data_dir, families=('leap', 'keypoints'), log=print):
    results = {}
    if 'leap' in families:
        results['leap'] = leap_people(data_dir, log)
    if 'keypoints' in families:
        results['keypoints'] = keypoint_people(data_dir, log)
    return results


def print_tables(results):
    if 'leap' in results:
        print_people('Leap, leave-one-person-out (12 + 2 people):', results['leap'])
    if 'keypoints' in results:
        print_people('Webcam keypoints, leave-one-person-out (8 people):', results['keypoints'])
        print_people('Leap people seen as a camera would (keypoint model):',
                     results['keypoints']['leap_people_seen_by_a_camera'])
        print_people('Labelled photos, leave one photo source out (keypoint model):',
                     results['keypoints']['photos_by_source'])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--data', default=gd.SHARED_DATA, help='shared data folder (default %(default)s)')
    ap.add_argument('--family', choices=('leap', 'keypoints', 'all'), default='all')
    ap.add_argument('--out', default='people_results.json')
    args = ap.parse_args(argv)
    for sub in ('leap_people', 'keypoints'):
        if not os.path.isdir(os.path.join(args.data, sub)):
            print('evaluate_people: no %s folder in %s' % (sub, args.data), file=sys.stderr)
            return 2
    fams = ('leap', 'keypoints') if args.family == 'all' else (args.family,)
    results = run(args.data, fams)
    print_tables(results)
    write_json(args.out, results)
    return 0


if __name__ == '__main__':
    sys.exit(main())
