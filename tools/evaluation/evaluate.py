"""Evaluate the gesture recognizer: on people it never saw, on the real Leap takes, under
invariance stress and on the labelled photos.

usage: python -m tools.evaluation.evaluate [--data DIR] [--out eval_results.json]
           [--no-people] [--no-photos]

The leave-one-person-out figures (tools/evaluation/people.py) come first: they are the
result. The shared LeapJS takes below are a secondary check against the original
system's rules: the pose model is fitted on their labelled frames too (one more person),
so their figures are no result on their own.

The labelled frames of the takes are datasets.LEAPJS_LABELS (see there).

- Waiting-110fps and flapping: the SDK's own circle gestures, counted beside the circle
  events (see circle_agreement; reported, not a target: nobody draws a circle in these
  takes, the SDK's circles are loops of flapping thumbs and pinkies): 10 SDK circles, each reported by the SDK once its
  fingertip has swept >= 270 deg (its start event, progress 0.76..0.95 turns).
  Recall counts only the SDK circles whose arc lies inside the recording: an SDK circle
  whose start event comes less than CIRCLE_MIN_LEAD_S after the hand's first recorded
  frame (or that is already under way in the first frame) was mostly drawn before the
  capture began, so nothing in the file shows it. That excludes 5 of the 10 (Waiting's
  first, which the first frame shows 81 ms into the gesture, and flapping's four that
  start 0.03..0.22 s in; their fingertips move 2..14 mm in the recorded frames before the
  start, along no circle). A circle event agrees with an SDK circle of the same hand
  and the same sense (the SDK's: clockwise when its normal points along the finger)
  when it falls within the SDK circle's span widened by CIRCLE_TOLERANCE_S and is that
  circle (same_place: the same finger, centre within the SDK's radius, at least 10 mm;
  the SDK's circles belong to one pointable). Without the place check, hand + sense +
  time credited two loops the SDK did not report, a middle/ring loop 130 mm from the
  pinky circle the SDK reported meanwhile and a thumb loop drawn after the SDK's circle
  ended, 49 mm from its centre. Precision counts events agreeing with any SDK circle,
  excluded ones included.

The same circle matching also runs over every shared take (EVERY_TAKE); the target there
is no circle event at all, since none of the takes draws one.

No take shows the rock (horns) pose, so rock has no real-data row; it is covered by the
synthetic-hand tests.

The recognizer runs as a stream over every frame of a take (temporal filter on, so its
latency counts against it); OriginalRules is applied to the same frames. Per gesture:
precision and recall over the labelled frames, n = labelled frames.
"""
import argparse
import os
import sys

from leap_teleop.hands.gestures import FINGER_NAMES
from leap_teleop.hands.gestures.datasets import (
    DEFAULT_LEAPJS_DATA,
    HANDS_DATA,
    LEAPJS_LABELS,
    SHARED_DATA,
    data_dir,
    expected,
    find_take,
    take_frames,
)
from tools.evaluation.original_rules import OriginalRules
from tools.evaluation.results_file import write_json
from tools.evaluation.take_stream import EVERY_TAKE, recognize_take

GESTURES = ('fist', 'thumb_up', 'pinch', 'open')

# Takes whose frames must show neither pinch nor fist (none of them holds one: a hard
# requirement, not a rate).
NO_PINCH_NO_FIST = ('gun', 'HandSplay-110fps', 'three-claps')
CIRCLE_TAKES = ('Waiting-110fps', 'flapping')
# An event matches an SDK circle of the same hand and the same sense when it falls within
# the SDK circle's span (start .. stop event) widened by this much on each side: the SDK
# reports the start at 270 deg, the recognizer fires at 300 deg, inside the span; the
# tolerance covers a circle the recognizer closes a little before or after the SDK.
CIRCLE_TOLERANCE_S = 0.15
# ... and when it is that circle, not another loop the hand made meanwhile (same_place).
CIRCLE_PLACE_MM = 10.0
# The SDK's circles on these takes turn at <= ~3 turns/s (its progress updates: 1.8..3.2),
# so the 270 deg before its start event take >= 0.25 s of recorded hand.
CIRCLE_MIN_LEAD_S = 0.25


class Row(tuple):
    """(frame index, side, recognizer state, original state, timestamp); .hand: the Hand
    judged (the labels' thumb direction reads it)."""
    hand = None


def run_take(path):
    """Per frame: a Row (index, side, recognizer state, original state, timestamp; .hand)
    for every hand, plus the SDK circle gestures: {id: SdkCircle}."""
    dicts = take_frames(path)
    original = OriginalRules()
    rows = []
    sdk_circles = {}
    first_seen = {}                  # side -> timestamp of its first frame
    for k, frame, judged in recognize_take(dicts):
        d = dicts[k]
        sides_by_id = {h.id: h.side for h in frame.hands}
        for hand, state in judged:
            first_seen.setdefault(hand.side, frame.timestamp)
            row = Row((k, hand.side, state, original.classify(hand), frame.timestamp))
            row.hand = hand
            rows.append(row)
        pointables = {p.get('id'): p for p in d.get('pointables') or [] if isinstance(p, dict)}
        for g in frame.gestures:
            if g.get('type') != 'circle':
                continue
            t = frame.timestamp
            c = sdk_circles.get(g.get('id'))
            if c is None:
                ids = g.get('handIds') or []
                side = sides_by_id.get(ids[0]) if ids else None
                c = sdk_circles[g.get('id')] = SdkCircle(side, t, t, _sdk_clockwise(g, pointables))
                lead = t - first_seen.get(side, t)
                under_way = g.get('state') != 'start' or (g.get('duration') or 0) > 0
                c.in_recording = not under_way and lead >= CIRCLE_MIN_LEAD_S
                p = pointables.get((g.get('pointableIds') or [None])[0]) or {}
                c.finger = FINGER_NAMES[p['type']] if p.get('type') in range(5) else None
            c.t_last = t
            try:        # the SDK refines its centre and radius over the updates: keep each
                c.places.append(([float(x) for x in g['center'][:3]], float(g['radius'])))
            except (KeyError, TypeError, ValueError, IndexError):
                pass
    return rows, sdk_circles


class SdkCircle:
    def __init__(self, side, t_first, t_last, clockwise):
        self.side, self.t_first, self.t_last, self.clockwise = side, t_first, t_last, clockwise
        self.in_recording = True
        self.finger = None
        self.places = []            # (centre [x, y, z] mm, radius mm) per report


def _sdk_clockwise(g, pointables):
    """The SDK's sense: clockwise when the circle's normal points along the finger."""
    p = pointables.get((g.get('pointableIds') or [None])[0])
    try:
        n, d = g['normal'], p['direction']
        return n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0
    except (TypeError, KeyError, IndexError):
        return None


def _ratio(num, den):
    """num / den to 4 places; None when there is nothing to divide (no frame to score is
    not a perfect score)."""
    return round(num / den, 4) if den else None


def _score(tp, fp, fn, n):
    return {'precision': _ratio(tp, tp + fp), 'recall': _ratio(tp, tp + fn), 'n': n}


def circle_agreement(rows, sdk_circles):
    """(matched SDK circles in the recording, SDK circles in the recording, circle events
    that match any SDK circle, circle events)."""
    events = [(r[1], r[4], e) for r in rows for e in r[2].events if e.gesture.startswith('circle')]
    tol = CIRCLE_TOLERANCE_S

    def near(ev, c):
        side, t, e = ev
        return (c.side in (None, side) and c.clockwise in (None, e.gesture == 'circle_cw')
                and c.t_first - tol <= t <= c.t_last + tol and same_place(e, c))
    judged = [c for c in sdk_circles.values() if c.in_recording]
    matched_sdk = sum(1 for c in judged if any(near(ev, c) for ev in events))
    matched_ev = sum(1 for ev in events if any(near(ev, c) for c in sdk_circles.values()))
    return matched_sdk, len(judged), matched_ev, len(events)


def same_place(event, c):
    """Whether a fingertip circle event is the SDK circle `c` itself, not another loop of
    the same hand at the same time: traced by the same finger, centred within the SDK
    circle's radius (at least CIRCLE_PLACE_MM) of a centre the SDK reported for it. A palm
    circle moves every fingertip around its own centre, so it is placed by hand and time
    only; an event or SDK circle that does not say where it is is not held against it."""
    if event.source in ('', 'palm') or event.center is None or not c.places:
        return True
    if c.finger is not None and event.source != c.finger:
        return False
    e = event.center
    return any(sum((a - b) ** 2 for a, b in zip(e, centre)) ** 0.5 <= max(radius, CIRCLE_PLACE_MM)
               for centre, radius in c.places)


def score_take(take, rows):
    """{'recognizer' / 'original': {gesture: [tp, fp, fn, n]}, 'forbidden': {who: frames
    with a pinch or fist on a NO_PINCH_NO_FIST take}} over the take's labelled frames."""
    counts = {who: {g: [0, 0, 0, 0] for g in GESTURES} for who in ('recognizer', 'original')}
    forbidden = {'recognizer': 0, 'original': 0}
    labels = LEAPJS_LABELS.get(take, ())
    for row in rows:
        k, side, rec, orig, _ = row
        hand = row.hand
        for lside, frames, expect in labels:
            if lside != side or k not in frames:
                continue
            for who, st in (('recognizer', rec), ('original', orig)):
                for g, want in expect.items():
                    want = expected(want, hand)
                    if want is None:
                        continue
                    got = bool(getattr(st, g))
                    c = counts[who][g]
                    c[3] += 1
                    if got and want:
                        c[0] += 1
                    elif got and not want:
                        c[1] += 1
                    elif want and not got:
                        c[2] += 1
                if take in NO_PINCH_NO_FIST and (st.pinch or st.fist):
                    forbidden[who] += 1
    counts['forbidden'] = forbidden
    return counts


def evaluate(data_dir=DEFAULT_LEAPJS_DATA, verbose=True, runs=None):
    """runs: {take: run_take's result or None (no such take)}, filled and reused (a
    caller that looks at the takes itself passes one, and the takes run once)."""
    counts = {who: {g: [0, 0, 0, 0] for g in GESTURES} for who in ('recognizer', 'original')}
    forbidden = {'recognizer': 0, 'original': 0}
    missing = []
    runs = {} if runs is None else runs

    def take_run(take):
        if take not in runs:
            path = find_take(data_dir, take)
            runs[take] = None if path is None else run_take(path)
        if runs[take] is None and take not in missing:
            missing.append(take)
        return runs[take]
    for take in LEAPJS_LABELS:
        run = take_run(take)
        if run is None:
            continue
        sc = score_take(take, run[0])
        for who in counts:
            for g in GESTURES:
                for i in range(4):
                    counts[who][g][i] += sc[who][g][i]
            forbidden[who] += sc['forbidden'][who]
    results = {who: {g: _score(*counts[who][g]) for g in GESTURES} for who in counts}
    for who in results:
        results[who]['no_pinch_no_fist_violations'] = forbidden[who]
    # Circles: the recognizer's events against the SDK's circle gestures. The original
    # system had no circle detection of its own (it relied on the SDK's), so it has none.
    agg, agg_all, per_take = [0, 0, 0, 0], [0, 0, 0, 0], {}
    for take in EVERY_TAKE:
        run = take_run(take)
        if run is None:
            continue
        per_take[take] = circle_agreement(*run)
        for i, v in enumerate(per_take[take]):
            agg_all[i] += v
            if take in CIRCLE_TAKES:
                agg[i] += v
    results['recognizer']['circle'] = {
        'precision': _ratio(agg[2], agg[3]), 'recall': _ratio(agg[0], agg[1]), 'n': agg[1]}
    results['circle_events'] = {'events': agg[3], 'agreeing_events': agg[2],
                                'sdk_circles_in_recording': agg[1], 'matched': agg[0]}
    results['original']['circle'] = {'precision': None, 'recall': None, 'n': agg[1]}
    results['circle_all_takes'] = {
        'precision': _ratio(agg_all[2], agg_all[3]), 'recall': _ratio(agg_all[0], agg_all[1]),
        'events': agg_all[3], 'agreeing_events': agg_all[2],
        'sdk_circles_in_recording': agg_all[1], 'matched': agg_all[0],
        'per_take': {take: dict(zip(('matched', 'sdk_circles_in_recording', 'agreeing_events',
                                     'events'), v)) for take, v in per_take.items()}}
    results['missing_takes'] = missing
    if verbose:
        print_table(results)
    return results


def _fig(x):
    return '    -' if x is None else '%5.3f' % x


def print_table(results):
    print('%-10s %-24s %-24s' % ('gesture', 'recognizer P / R (n)', 'original P / R (n)'))
    for g in GESTURES + ('circle',):
        r, o = results['recognizer'][g], results['original'][g]
        print('%-10s %s / %s (%4d)      %s / %s (%4d)'
              % (g, _fig(r['precision']), _fig(r['recall']), r['n'], _fig(o['precision']),
                 _fig(o['recall']), o['n']))
    print('pinch or fist frames on gun / HandSplay / three-claps: recognizer %d, original %d'
          % (results['recognizer']['no_pinch_no_fist_violations'],
             results['original']['no_pinch_no_fist_violations']))
    c = results.get('circle_events')
    if c:
        print('circle events on Waiting-110fps / flapping: %d, %d of them on an SDK circle '
              '(same hand, sense, finger, place); SDK circles drawn inside the recordings: %d, %d found'
              % (c['events'], c['agreeing_events'], c['sdk_circles_in_recording'], c['matched']))
    c = results.get('circle_all_takes')
    if c:
        print('circle events on all %d takes (none draws a circle: the target is 0): %d, %d '
              'on an SDK circle (precision %s); SDK circles drawn inside them: %d, %d found '
              '(recall %s)'
              % (len(c['per_take']), c['events'], c['agreeing_events'], _fig(c['precision']).strip(),
                 c['sdk_circles_in_recording'], c['matched'], _fig(c['recall']).strip()))
        print('  per take (events / agreeing; SDK circles / found): ' + ', '.join(
            '%s %d/%d; %d/%d' % (take, v['events'], v['agreeing_events'],
                                 v['sdk_circles_in_recording'], v['matched'])
            for take, v in sorted(c['per_take'].items()) if v['events'] or v['sdk_circles_in_recording']))
    if results['missing_takes']:
        print('missing takes: %s' % ', '.join(results['missing_takes']))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--data', default=data_dir(),
                    help='folder of the LeapJS recordings (default %(default)s)')
    ap.add_argument('--out', default='eval_results.json')
    ap.add_argument('--no-people', action='store_true',
                    help='skip the leave-one-person-out evaluation (minutes)')
    ap.add_argument('--no-photos', action='store_true',
                    help='skip the labelled photos under camera / person changes')
    ap.add_argument('--hands-data', default=HANDS_DATA,
                    help='folder of the labelled hand photos (default %(default)s)')
    ap.add_argument('--shared-data', default=None,
                    help='the shared data folder the people and strokes parts read (default %s)'
                    % SHARED_DATA)
    args = ap.parse_args(argv)
    if not os.path.isdir(args.data):
        print('evaluate: no recordings folder at %s' % args.data, file=sys.stderr)
        return 2
    shared = args.shared_data or SHARED_DATA
    if not args.no_people:
        missing = [sub for sub in ('leap_people', 'keypoints', 'leapjs', 'strokes')
                   if not os.path.isdir(os.path.join(shared, sub))]
        if missing:
            print('evaluate: no %s folder in %s (--shared-data)' % (' or '.join(missing), shared),
                  file=sys.stderr)
            return 2
    # Every input is checked before the minutes of fitting that would otherwise be lost.
    missing = [take for take in dict.fromkeys(list(LEAPJS_LABELS) + list(EVERY_TAKE))
               if find_take(args.data, take) is None]
    if missing:             # a partial table would read as a result
        print('evaluate: takes missing from %s: %s' % (args.data, ', '.join(missing)), file=sys.stderr)
        return 2
    if not args.no_photos:
        from tools.evaluation.photo_views import photo_names, unreadable_photos
        if not os.path.isdir(args.hands_data) or not photo_names(args.hands_data):
            print('evaluate: no hand photos at %s (--hands-data)' % args.hands_data, file=sys.stderr)
            return 2
        damaged = unreadable_photos(args.hands_data, photo_names(args.hands_data))
        if damaged:
            print('evaluate: cannot read these photos in %s: %s' % (args.hands_data, ', '.join(damaged)),
                  file=sys.stderr)
            return 2
    # From here a run that stops leaves no earlier run's figures behind to read as its own.
    if os.path.exists(args.out):
        os.remove(args.out)
    results = {}
    if not args.no_people:
        from tools.evaluation import people as evaluate_people
        results['people'] = evaluate_people.run(shared)
        evaluate_people.print_tables(results['people'])
    results.update(evaluate(args.data))
    if results['missing_takes']:             # gone since the check above
        print('evaluate: takes missing from %s: %s' % (args.data, ', '.join(results['missing_takes'])),
              file=sys.stderr)
        return 2
    if not args.no_people:
        from tools.evaluation import strokes as evaluate_strokes
        where = {} if args.shared_data is None else {
            'strokes_dir': os.path.join(shared, 'strokes'),
            'leap_people_dir': os.path.join(shared, 'leap_people')}
        results['strokes'] = evaluate_strokes.run(leapjs_dir=args.data, loso=True, **where)
        evaluate_strokes.print_table(results['strokes'])
    from tools.evaluation import invariance as evaluate_invariance
    results['invariance'] = evaluate_invariance.run()
    evaluate_invariance.print_table(results['invariance'])
    if not args.no_photos:
        from tools.evaluation import photo_views as evaluate_photo_views
        results['photo_views'] = evaluate_photo_views.run(args.hands_data)
        evaluate_photo_views.print_table(results['photo_views'])
    write_json(args.out, results)
    return 0


if __name__ == '__main__':
    sys.exit(main())
