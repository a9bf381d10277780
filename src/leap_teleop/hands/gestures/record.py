"""Record samples of one gesture from any hand source, in the shared data's formats, for
train_gestures --add FILE --label NAME.

usage: rosrun leap_teleop record_gestures --source SOURCE --label NAME [--seconds N]
           [--out FILE] [--person NAME] [--side right|left|any]
           [--script YAML] [--recording PATH] [--video PATH] [--device N|/dev/videoN]
           [--mirror] [--realtime 0|1]

SOURCE: leap, leapc, scripted, recording (Leap-family hands: 3-D joints; a recording of
camera hands, as record_frames keeps them, is camera-family) or webcam,
video (camera hands: image landmarks). Hold the gesture, moving and turning the hand a
little, for N seconds (of the source's time: a scripted or recording source with
--realtime 0 takes no longer than it needs).

Leap-family hands are written as JSON Lines pose records, one per hand per frame:
{"person", "label", "frame": the LeapJS frame dict with that hand} (FILE .jsonl, or
.jsonl.gz for gzip; default NAME.jsonl). Camera hands are written as keypoint CSV with
the shared header (person,label,source_label,x0,y0,...,x20,y20; default NAME.csv), the
21 landmarks relative to the wrist and divided by the largest absolute coordinate, as
the community's keypoint.csv. Frames without a (matching) hand are counted as missing.
With --side any (the default) a take must show one hand: if any frame shows two, or the
take shows a left and a right hand, nothing is written (the other hand, resting in view,
and the frames where the gesture's hand was lost would be written under NAME): give
--side right|left to record the hand showing the gesture. With a side given, a frame
showing two hands of that side is skipped and counted.
"""
import argparse
import collections
import csv
import gzip
import json
import math
import os
import secrets
import sys

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures.classifier import class_name_problem
from leap_teleop.hands.gestures.features import normalize_keypoints
from leap_teleop.hands.gestures.training_set import shared_label_problem
from leap_teleop.hands.sources import SourceError, add_source_arguments, leapjs, source_from_args
from leap_teleop.hands.sources.camera_params import source_family
from leap_teleop.output_file import output_problem

MAX_SESSIONS = 99      # NAME.csv, NAME_2.csv, ... NAME_99.csv
KEYPOINT_HEADER = ['person', 'label', 'source_label'] + [
    '%s%d' % (axis, i) for i in range(21) for axis in 'xy']


# what a recording session gave: its rows, frames seen, frames without a usable hand, the
# source time it covered, why it ended ('time', 'source ended', 'interrupted' or the
# source's SourceError) and the frames skipped for showing a left and a right hand
Take = collections.namedtuple('Take', 'rows seen missing seconds ended two_hands sides')


class RecordError(ValueError):
    """Arguments or a source that cannot record."""


def check_label(label):
    problem = class_name_problem(label, new=True) or shared_label_problem(label)
    if problem:
        raise RecordError('--label %r: %s' % (label, problem))
    return label


def output_path(out, label, family):
    """The file to write: `out` checked against the family, or NAME.jsonl / NAME.csv."""
    if not out:
        return label + ('.csv' if family == 'keypoints' else '.jsonl')
    low = out.lower()
    if family == 'keypoints' and not low.endswith('.csv'):
        raise RecordError('--out %s: camera hands are written as keypoint CSV: name it '
                          '.csv' % out)
    if family == 'leap' and not low.endswith(('.jsonl', '.jsonl.gz')):
        raise RecordError('--out %s: Leap hands are written as JSON Lines: name it .jsonl '
                          'or .jsonl.gz' % out)
    return out


def keypoint_row(hand, person, label):
    """The CSV row of a camera hand, or None when it has no usable image landmarks."""
    xy = getattr(hand, 'image_landmarks', None)
    p = normalize_keypoints(xy) if xy is not None else None
    if p is None:
        return None
    return [person, label, label] + ['%.4f' % v for v in p.ravel()]


def pose_record(frame, hand, person, label):
    """The JSON Lines record of one hand of a frame; None for a hand without a palm
    position or orientation (nothing to learn from)."""
    one = leapjs.frame_to_dict(Frame(id=frame.id, timestamp=frame.timestamp, hands=[hand]))
    return {'person': person, 'label': label, 'frame': one} if one['hands'] else None


def collect(source, family, label, person, seconds, side='any'):
    """The Take of `seconds` of source time (or less, if the source ends or fails first:
    the rows before a failure are kept, its SourceError is the Take's `ended`). With
    side 'any', a frame showing two hands is skipped, as is one showing two hands of the
    side given: one of them is not the gesture (`two_hands` counts them; `sides`: the sides
    of the hands written)."""
    rows, seen, missing, two_hands, sides = [], 0, 0, 0, set()
    t0 = t_last = None
    period = 0.0                # between the last two frames: what the last one stands for
    ended = 'source ended'
    try:
        for frame in source.frames():
            t = frame.timestamp
            if t0 is None and math.isfinite(t):
                t0 = t
            if t0 is not None and math.isfinite(t):
                if t - t0 >= seconds:
                    ended = 'time'
                    break
                period = t - t_last if t_last is not None else 0.0
                t_last = t
            seen += 1
            hands = [h for h in frame.hands if side == 'any' or h.side == side]
            if len(hands) > 1:
                two_hands += 1
                continue
            got = 0
            for hand in hands:
                if family == 'keypoints':
                    row = keypoint_row(hand, person, label)
                else:
                    row = pose_record(frame, hand, person, label)
                if row is not None:
                    rows.append(row)
                    sides.add(hand.side)
                    got += 1
            missing += got == 0
    except KeyboardInterrupt:
        ended = 'interrupted'
    except SourceError as e:        # a webcam unplugged near the end: the take so far stays
        ended = e
    finally:
        source.stop()
    covered = seconds if ended == 'time' else (t_last - t0 + period if t0 is not None else 0.0)
    if ended == 'source ended' and covered >= seconds - 1e-6:
        ended, covered = 'time', seconds    # its last frame ended the time asked: a whole take
    return Take(rows, seen, missing, covered, ended, two_hands, sides)


def session_names(path):
    """`path`, then the names of further sessions beside it: NAME_2.csv, NAME_3.csv, ..."""
    low = path.lower()
    ending = '.jsonl.gz' if low.endswith('.jsonl.gz') else os.path.splitext(path)[1]
    stem = path[:len(path) - len(ending)]
    yield path
    for k in range(2, MAX_SESSIONS + 1):
        yield '%s_%d%s' % (stem, k, ending)


def free_session_name(path):
    """The first of session_names(path) that names no file, or None."""
    return next((p for p in session_names(path) if not os.path.lexists(p)), None)


def write(path, family, rows):
    """Write `rows` whole under `path`, or under the next free session name if a file
    came to be at `path` meanwhile (a take is never written over); the name used. Goes
    through a temporary file beside it, removed if writing fails."""
    tmp = os.path.join(os.path.dirname(os.path.abspath(path)),
                       '.record_gestures-%d-%s.part' % (os.getpid(), secrets.token_hex(4)))
    # made as any new file is (the umask applies), never over another
    os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        if family == 'keypoints':
            with open(tmp, 'w', newline='', encoding='utf-8') as f:
                w = csv.writer(f)
                w.writerow(KEYPOINT_HEADER)
                w.writerows(rows)
        else:
            opener = gzip.open if path.lower().endswith('.gz') else open
            with opener(tmp, 'wt', encoding='utf-8') as f:
                for r in rows:
                    f.write(json.dumps(r, separators=(',', ':')) + '\n')
        for name in session_names(path):
            if _move_unless_taken(tmp, name):
                return name
        raise OSError('%s and its next %d session names are all taken' % (path, MAX_SESSIONS - 1))
    finally:
        if os.path.lexists(tmp):
            os.remove(tmp)


def _move_unless_taken(tmp, name):
    """Move `tmp` to `name` unless a file is there; whether it moved."""
    try:
        os.link(tmp, name)      # fails where a file is, unlike a rename
    except FileExistsError:
        return False
    except OSError:             # a file system without hard links: check, then rename
        if os.path.lexists(name):
            return False
        os.replace(tmp, name)
        return True
    os.remove(tmp)
    return True


def main(argv=None):
    ap = argparse.ArgumentParser(description=' '.join(__doc__.split('\n\n')[0].split()))
    add_source_arguments(ap)
    ap.add_argument('--label', required=True, metavar='NAME', help='the gesture\'s name (the class to train)')
    ap.add_argument('--seconds', type=float, default=10.0, metavar='N',
                    help='how long to record, in the source\'s time (default %(default)s)')
    ap.add_argument('--out', default='', help='output file (default NAME.jsonl or NAME.csv)')
    ap.add_argument('--person', default='user', help='who is recorded (default %(default)s)')
    ap.add_argument('--side', default='any', choices=('any', 'right', 'left'),
                    help='which hands to keep (default: any, for a take that shows one hand '
                    'only: nothing is written if two show)')
    if argv is None:   # drop ROS remappings (__name:=...) that rosrun / roslaunch add
        argv = [a for a in sys.argv[1:] if ':=' not in a]
    args = ap.parse_args(argv)
    source = None
    try:
        if args.source == 'recording':      # a camera take keeps its hands' picture landmarks
            source = source_from_args(args)
        family = (source and source.hand_family) or source_family(args.source)
        check_label(args.label)
        if not (math.isfinite(args.seconds) and 0.0 < args.seconds <= 3600.0):
            raise RecordError('--seconds %g: more than 0, at most 3600' % args.seconds)
        if not args.person.strip() or ',' in args.person or '\n' in args.person:
            raise RecordError('--person %r: a name without commas' % args.person)
        out = output_path(args.out, args.label, family)
        # before the source starts: a take is not lost at the end
        problem = output_problem(out, [args.script, args.recording, args.video])
        if problem:
            raise RecordError('--out %s: %s' % (out, problem))
        if os.path.lexists(out):    # an earlier session: it stays, the next goes beside it
            free = free_session_name(out)
            raise RecordError('--out %s: holds an earlier take; record to another file%s or '
                              'remove it' % (out, ' (e.g. --out %s)' % free if free else ''))
        source = source or source_from_args(args)
    except (RecordError, SourceError) as e:
        print('record_gestures: %s' % e, file=sys.stderr)
        return 2
    print('record_gestures: recording %r for %g s from the %s source; hold the gesture, '
          'moving and turning the hand a little' % (args.label, args.seconds, args.source),
          file=sys.stderr)
    try:
        take = collect(source, family, args.label, args.person.strip(), args.seconds,
                       args.side)
    except (OSError, SourceError) as e:
        print('record_gestures: the %s source failed: %s' % (args.source, e), file=sys.stderr)
        return 1
    rows, seen, missing = take.rows, take.seen, take.missing
    failed = isinstance(take.ended, SourceError)
    if failed:
        print('record_gestures: the %s source failed after %.1f of the %g s asked: %s' % (
            args.source, take.seconds, args.seconds, take.ended), file=sys.stderr)
    elif take.ended != 'time':    # a short take is kept, but not passed off as a whole one
        print('record_gestures: %s after %.1f of the %g s asked' % (
            'the source ended' if take.ended == 'source ended' else 'interrupted',
            take.seconds, args.seconds), file=sys.stderr)
    # The other hand would be written under the label: with --side any a take showing two
    # hands is not written (the frames where the gesture's hand was lost would be the other
    # one's); with a side, a frame showing two of its hands is skipped.
    if args.side == 'any' and (take.two_hands or len(take.sides) > 1):
        detail = ('%d of the %d frames showed two hands' % (take.two_hands, seen) if take.two_hands
                  else 'a left hand in some frames, a right one in others')
        print('record_gestures: the take showed more than one hand (%s): nothing written; give '
              '--side right|left to record the hand showing the gesture' % detail, file=sys.stderr)
        return 1
    two = ('record_gestures: %d of the %d frames showed two %s hands and were skipped'
           % (take.two_hands, seen, args.side))
    if not rows:
        # said above when the source failed before any frame
        if not (failed and seen == 0):
            print('record_gestures: no hand in %d frames: nothing written%s' % (
                seen - take.two_hands, ' (a camera hand needs its image landmarks)'
                if family == 'keypoints' else ''), file=sys.stderr)
        if take.two_hands:
            print(two, file=sys.stderr)
        return 1
    try:
        written = write(out, family, rows)
    except OSError as e:
        print('record_gestures: cannot write %s: %s' % (out, e), file=sys.stderr)
        return 1
    if written != out:
        print('record_gestures: %s appeared while recording: the take went to %s'
              % (out, written), file=sys.stderr)
        out = written
    print('record_gestures: wrote %d %s of %r to %s (%d frames, hands missing in %d)'
          % (len(rows), 'keypoint rows' if family == 'keypoints' else 'hand poses',
             args.label, out, seen, missing))
    if take.two_hands:
        print(two, file=sys.stderr)
    return 1 if failed else 0       # written, but a script should know the source failed


if __name__ == '__main__':
    sys.exit(main())
