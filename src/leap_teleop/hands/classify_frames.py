"""Classify Leap frames offline: one JSON line of per-hand gestures per input frame.

usage: python -m leap_teleop.hands.classify_frames [INPUT] [--stateless] [--out FILE]
       python -m leap_teleop.hands.classify_frames --keypoints FILE.csv
       rosrun leap_teleop classify_frames [INPUT] [--stateless] [--model MODEL]
           [--keypoint-model MODEL]

--keypoints FILE.csv reads webcam hand keypoints: the community's keypoint.csv (a class
id then 42 numbers, x0 y0 .. x20 y20, no header; the id is ignored) or the shared
files' form with a header (person,label,source_label,x0,...,y20). Each row is one hand
judged on its own by the keypoint model (a left hand is a mirrored right one: no side;
its pinch strength measured from the landmarks, as the camera source does): one line
per row, {"id": ROW, "timestamp": null, "hands": [{"type": null, "fist": ...}]}.

INPUT may also be camera footage, told by its file extension: a video (.mp4, .avi, .mov,
.mkv, .webm, ...; one line per video frame, timestamps from the video's start) or
images (.jpg, .jpeg, .png, ...: a file, a folder or a quoted glob; one line per image,
in name order, id = its place from 1, each classified on its own as with --stateless; an
image that cannot be read, or a JPEG cut short, gives {"id": ID, "timestamp": null,
"hands": [], "error": "cannot read image PATH"}, the reason on stderr). Hands come from the camera source's
pipeline (MediaPipe Hands, then the landmark conversion) with its defaults: frames
letterboxed to 640x480, a 60 deg field of view, a 95 mm palm, a camera that does not
mirror.

INPUT is a LeapJS Playback recording (.json, .json.gz, .json.lz; formatVersion 0.1, 1 or
packed 2; also QuantumLeap's {"frames": N, "data": [...]}, the shared dynamic takes), or
JSON Lines, plain or gzipped: one LeapJS frame dict per line (fields as in a recording:
id, timestamp [us], hands[] with id, type, palmPosition, palmNormal, direction,
grabStrength, pinchStrength, confidence, and for a camera hand recorded by record_frames
imageLandmarks, its 21 [x, y] picture landmarks, which make it judged by the keypoint model
as live; pointables[] with handId, type 0..4, tipPosition, dipPosition, pipPosition,
mcpPosition, direction, extended), or one pose record per line as the shared static poses
and record_gestures write them ({"person": ..., "label": ..., "frame": FRAME}: FRAME is
classified; isolated poses, so give --stateless). Without INPUT (or with "-") JSON Lines are read from stdin.

Output, one line per input frame, in input order:

    {"id": 139235, "timestamp": 12439621196,
     "hands": [{"type": "right", "fist": false, "thumb_up": false, "pinch": true,
                "pinch_value": 0.62, "rock": false, "open": false,
                "thumb_down": false, "events": ["pinch", "circle_cw"]}]}

- id, timestamp: copied from the frame (timestamp in the frame's microseconds; null
  when absent). A frame without a timestamp is judged 10 ms after the one before, and so
  is a JSON Lines frame stamped as the one before. A recording whose timestamps mostly do
  not advance (all one stamp, or going back) is stamped k / its frame rate, as the
  sender's recording source plays it, with the same warning on stderr.
- hands: one entry per left / right hand in the frame, in frame order. fist, thumb_up,
  pinch, rock, open, thumb_down: the recognizer's held gestures; pinch_value: pinch strength - 0.2
  in 0..0.8 while pinching, else 0.
- events: what started on this frame: a held gesture's name when it turns on
  ("fist", "thumb_up", "pinch", "rock", "open", "thumb_down"), "unfold" (fist -> open), "fold"
  (open -> fist), "circle_cw" / "circle_ccw" (palm or fingertip circle).
- A line that is not a JSON object yields {"id": null, "timestamp": null, "hands": [],
  "error": "..."}; a frame with missing fields is classified from what is there (a hand
  without fingers shows every gesture false). Input that cannot be read on (a truncated
  gzip) ends the run after the frames it held, with one line on stderr and status 2.

--model MODEL (Leap frames) and --keypoint-model MODEL (camera hands, keypoint rows)
classify with a user's model (train_gestures --out MODEL) instead of the shipped one;
each class of it that is no built-in gesture is one more key of every hand, true while it
is held.

--stateless classifies every frame on its own (no temporal filter, no events): for
snapshot data whose frames are unrelated. Otherwise frames are a stream: a gesture
turns on after 3 consistent frames and off after 3, per hand side, following one hand by
its id as the sender does: of two hands typed alike, the one followed (else the more
confident) carries the side's gestures and the other is judged on its own, and a hand of
another id taking the side starts afresh (every gesture false on that frame).
"""
import argparse
import itertools
import json
import math
import sys
import zlib

from leap_teleop.hands.frame import Frame, TrackedHand
from leap_teleop.hands.gestures import GestureRecognizer, GestureState, ModelError
from leap_teleop.hands.gestures import datasets as gesture_data
from leap_teleop.hands.sources import SourceError, leapjs
from leap_teleop.hands.sources.recording import stalled_steps, stalled_warning
from leap_teleop.hands.tracker import hand_placement
from leap_teleop.output_file import output_problem


class FrameClassifier:
    """Frames -> output dicts, keeping one recognizer per hand side that follows one hand
    by its id, as the sender does (LeapInterface / HandTracker): of two hands of a side,
    the one followed, else the more confident (on a tie the first listed) carries the
    side's state, the other is judged on its own; when the one chosen cannot be placed the
    side is lost for that frame; another id taking the side starts it again, from the next
    frame. model / keypoint_model: pose model paths (None: the
    shipped ones); their own classes show as one more key each, true while held."""

    def __init__(self, stateless=False, model=None, keypoint_model=None):
        self.stateless = stateless
        self.models = {'model': model, 'keypoint_model': keypoint_model}
        self.user_gestures = self._recognizer(stateless).user_gestures
        self.recognizers = {}
        self.followed = {}              # side -> the id of the hand followed (0: none known)

    def _recognizer(self, stateless):
        return GestureRecognizer(stateless=stateless, **self.models)

    def classify(self, d):
        """A LeapJS frame dict -> output dict."""
        try:
            frame = leapjs.frame_from_dict(d)
        except leapjs.FrameError as e:
            return {'id': None, 'timestamp': None, 'hands': [], 'error': str(e)}
        ts = d.get('timestamp')
        ts = ts if isinstance(ts, (int, float)) and not isinstance(ts, bool) and \
            math.isfinite(ts) else None
        fid = d.get('id')
        fid = fid if isinstance(fid, (int, str)) and not isinstance(fid, bool) else None
        return self.classify_frame(frame, fid, ts)

    def classify_frame(self, frame, fid, ts):
        """A Frame -> output dict (id and timestamp as given)."""
        t = frame.timestamp if math.isfinite(frame.timestamp) else None
        t = t if t is not None else math.nan
        # The side's hand is chosen among all its hands, then placed, as in the sender
        # (LeapInterface, then HandTracker): chosen among the placeable ones only, a NaN
        # palm for a frame moved the side to the other hand for good, while the sender
        # reports the side lost and follows the same hand again.
        chosen = {}
        for hand in frame.hands:        # on a tie the first listed stays
            if hand.side not in chosen or self._rank(hand) > self._rank(chosen[hand.side]):
                chosen[hand.side] = hand
        # A hand that cannot be placed counts as gone: judged as nothing, and when it is the
        # side's, the side starts anew (no fist before it makes an unfold after it).
        placed = [hand for hand in frame.hands if hand_placement(hand) is not None]
        hands = []
        for hand in frame.hands:
            if not any(hand is h for h in placed):
                state = GestureState(judged=False)
            elif chosen[hand.side] is not hand:   # another hand of the side: judged on its own
                state = self._recognizer(True).update(hand, t)
            else:
                state = self._followed_state(hand, t)
            hands.append(hand_output(hand.side, state, self.user_gestures))
        for side, rec in self.recognizers.items():
            if side not in chosen or not any(chosen[side] is h for h in placed):
                rec.reset()
                self.followed.pop(side, None)
        return {'id': fid, 'timestamp': ts, 'hands': hands}

    def _rank(self, hand):
        followed = bool(self.followed.get(hand.side)) and hand.id == self.followed[hand.side]
        c = hand.confidence
        return followed, float(c) if isinstance(c, (int, float)) and c == c else 0.0

    def _followed_state(self, hand, t):
        rec = self.recognizers.get(hand.side)
        if rec is None:
            rec = self.recognizers[hand.side] = self._recognizer(self.stateless)
        followed = self.followed.get(hand.side)
        if not self.stateless and hand.id and followed and hand.id != followed:
            # Another hand took the side: nothing of the one before carries over, and
            # this one is judged from the next frame (the sender reports the side lost).
            rec.reset()
            self.followed[hand.side] = hand.id
            return GestureState(judged=False)
        if hand.id:                     # an id-less hand keeps the one followed
            self.followed[hand.side] = hand.id
        return rec.update(hand, t)


def hand_output(side, state, user_gestures=()):
    out = {'type': side, 'fist': bool(state.fist), 'thumb_up': bool(state.thumb_up),
           'pinch': bool(state.pinch), 'pinch_value': round(float(state.pinch_value), 4),
           'rock': bool(state.rock), 'open': bool(state.open),
           'thumb_down': bool(state.thumb_down),
           'events': [e.gesture for e in state.events if e.active]}
    for name in user_gestures:
        out[name] = name in state.user
    return out


def keypoint_lines(path, classifier):
    """Output dicts of a keypoint CSV, one per row, as the rows are read."""
    rec = classifier._recognizer(True)
    for i, (_, _, _, pts) in enumerate(gesture_data.iter_keypoints(path)):
        # a row holds no pinch strength: not known (0.0 read as "barely pinching")
        hand = TrackedHand(side='right', image_landmarks=pts, pinch_strength=math.nan)
        yield {'id': i, 'timestamp': None,
               'hands': [hand_output(None, rec.update(hand, 0.0), classifier.user_gestures)]}


class NotAFrame(ValueError):
    """A line of valid JSON that is no frame."""


class UnreadableImage:
    """An image of the input that the camera source could not read (`id`: its place)."""

    def __init__(self, fid, path):
        self.id, self.path = fid, path


def iter_json_lines(stream):
    for line in gesture_data.bounded_lines(stream):
        if line is None:
            yield NotAFrame('a line longer than %d characters' % gesture_data.MAX_LINE_CHARS)
            continue
        line = line.strip()
        if not line:
            continue
        try:
            d = leapjs.parse_json(line)
        except ValueError as e:
            yield e
            continue
        if isinstance(d, dict) and 'hands' not in d and isinstance(d.get('frame'), dict):
            d = d['frame']          # a pose record: person, label and the frame
        elif isinstance(d, dict) and 'hands' not in d and (
                isinstance(d.get('frames'), list) or isinstance(d.get('data'), list)):
            d = NotAFrame('a whole recording on one line: give its file as INPUT')
        yield d


HEAD_BYTES = 1 << 16     # far more than a frame or pose record's line


def _head(path, size=HEAD_BYTES):
    """The first `size` bytes of a file as text, decompressed when gzipped (a truncated
    stream still gives its start), or None when that cannot be read."""
    try:
        with open(path, 'rb') as f:
            raw = f.read(size)
        if raw[:2] == b'\x1f\x8b':
            raw = zlib.decompressobj(16 + zlib.MAX_WBITS).decompress(raw, size)
    except (OSError, zlib.error):
        return None
    return raw[:size].decode('utf-8', errors='replace')


def looks_like_recording(path):
    """A recording is one JSON document holding every frame (an object with "metadata"
    and "frames", or "data", often on one long line or spread over many; or a bare list);
    JSON Lines hold one frame or pose record per line."""
    if path.endswith('.lz'):
        return True
    head = _head(path)
    if head is None:
        return True                 # unreadable: the recording reader says why
    head = head.lstrip()
    first, ended, _ = head.partition('\n')
    if head.startswith('[') or (not ended and len(head.encode()) >= HEAD_BYTES - 4):
        return True
    first = first.strip()
    return first.startswith('{') and (first == '{' or '"frames"' in first
                                      or '"metadata"' in first)


def camera_input(path):
    """'video' or 'stills' when `path` names camera footage (by extension), else None."""
    from leap_teleop.hands.sources import capture
    if path in (None, '-'):
        return None
    if capture.is_video_path(path):
        return 'video'
    if capture.resolve_stills(path) or capture.is_image_path(path):
        return 'stills'
    return None


def camera_frames(path):
    """Frames of the hands the camera pipeline finds in a video or images, letterboxed to
    the sender's default size, stamped from the footage's start (kept as Frames: their
    hands carry the image landmarks)."""
    from leap_teleop.hands.sources import make_source
    from leap_teleop.hands.sources.camera_params import DEFAULT_SIZE
    source = make_source('video', path=path, realtime=False, clock=lambda: 0.0,
                         width=DEFAULT_SIZE[0], height=DEFAULT_SIZE[1])
    return source.frames()


def with_unreadable_images(frames, paths):
    """The frames of still images (ids: each image's place in `paths`, from 1) with an
    error line in place of each image the camera source could not read, so that the
    output keeps one line per image, in order."""
    expected = 1
    for frame in frames:
        while expected < frame.id <= len(paths):
            yield UnreadableImage(expected, paths[expected - 1])
            expected += 1
        expected = frame.id + 1
        yield frame
    for k in range(expected, len(paths) + 1):
        yield UnreadableImage(k, paths[k - 1])


def _stamp(d):
    """A frame dict's timestamp (us) when a finite number, else None."""
    ts = d.get('timestamp') if isinstance(d, dict) else None
    if not isinstance(ts, (int, float)) or isinstance(ts, bool):
        return None
    try:
        return float(ts) if math.isfinite(ts) else None
    except OverflowError:       # an integer beyond any float
        return None


def spaced_if_stalled(path, metadata, dicts):
    """A recording's frame dicts, restamped k / frame rate (as copies; a warning on stderr)
    when its stamps do not advance, as the sender's recording source plays it; else as
    they are."""
    stamped = [k for k, d in enumerate(dicts) if _stamp(d) is not None]
    stalled = stalled_steps([_stamp(dicts[k]) * 1e-6 for k in stamped])
    if not stalled:
        return dicts
    rate, warning = stalled_warning(path, stalled, metadata)
    print('classify_frames: %s' % warning, file=sys.stderr)
    dicts = list(dicts)
    for n, k in enumerate(stamped):
        dicts[k] = dict(dicts[k], timestamp=round(n * 1e6 / rate))
    return dicts


def frames_of(path):
    """The frames of INPUT. A recording is spaced as the sender's recording source spaces
    it; JSON Lines keep their stamps (a frame repeated with its stamp is no time passing,
    as for the sender: judged 10 ms on, it came after the next frame of a 115 Hz Leap)."""
    if camera_input(path):
        return camera_frames(path)
    if path not in (None, '-') and looks_like_recording(path):
        metadata, dicts = leapjs.load(path)
        return iter(spaced_if_stalled(path, metadata, dicts))
    if path in (None, '-'):
        return iter_json_lines(sys.stdin)
    return iter_json_lines(gesture_data.open_text(path, errors='replace'))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('input', nargs='?', default='-', help='recording or JSON Lines; - = stdin')
    ap.add_argument('--stateless', action='store_true', help='no temporal filtering / events')
    ap.add_argument('--out', default='-', help='output file; - = stdout')
    ap.add_argument('--keypoints', default=None, metavar='FILE.csv',
                    help='classify the rows of a webcam keypoint CSV instead of INPUT')
    ap.add_argument('--model', default=None, help='Leap-family pose model (.npz, from '
                                                  'train_gestures); default: the shipped one')
    ap.add_argument('--keypoint-model', default=None,
                    help='camera keypoint pose model (.npz); default: the shipped one')
    if argv is None:   # drop ROS remappings that rosrun / roslaunch add
        argv = [a for a in sys.argv[1:] if ':=' not in a]
    args = ap.parse_args(argv)
    if args.keypoints is not None and args.input != '-':
        ap.error('give INPUT or --keypoints, not both')
    for option, value in (('--keypoints', args.keypoints), ('--model', args.model),
                          ('--keypoint-model', args.keypoint_model)):
        if value is not None and not value.strip():
            ap.error('%s: name a file' % option)
    stills = None
    if not args.keypoints and camera_input(args.input) == 'stills':
        from leap_teleop.hands.sources import capture
        stills = capture.resolve_stills(args.input)
    try:
        # Still images are unrelated pictures: each is judged on its own.
        classifier = FrameClassifier(args.stateless or stills is not None, args.model,
                                args.keypoint_model)
        if args.keypoints:
            frames = keypoint_lines(args.keypoints, classifier)
            first = next(frames, None)      # a file that cannot be opened: before any output
            if first is None:
                raise gesture_data.DataError('%s: no keypoint row in it' % args.keypoints)
            frames = itertools.chain([first], frames)
        else:
            frames = frames_of(args.input)
    except (SourceError, OSError, ModelError, gesture_data.DataError) + gesture_data.UNREADABLE as e:
        print('classify_frames: %s: %s' % (args.keypoints or args.input, e)
              if isinstance(e, gesture_data.UNREADABLE) else 'classify_frames: %s' % e,
              file=sys.stderr)
        return 2
    if args.out != '-':
        problem = output_problem(args.out, [args.keypoints or args.input, args.model,
                                            args.keypoint_model] + (stills or []))
        if problem:
            print('classify_frames: --out %r: %s' % (args.out, problem), file=sys.stderr)
            return 2
    try:
        out = sys.stdout if args.out == '-' else open(args.out, 'w')
    except OSError as e:
        print('classify_frames: cannot write %s: %s' % (args.out, e), file=sys.stderr)
        return 2
    n, status = 0, 0
    if stills is not None:
        frames = with_unreadable_images(frames, stills)
    try:
        for d in frames:
            if args.keypoints:
                result = d
            elif isinstance(d, Frame):
                ts = round(d.timestamp * 1e6) if math.isfinite(d.timestamp) else None
                result = classifier.classify_frame(d, d.id, ts)
            elif isinstance(d, UnreadableImage):
                result = {'id': d.id, 'timestamp': None, 'hands': [],
                          'error': 'cannot read image %s' % d.path}
            elif isinstance(d, Exception) or not isinstance(d, dict):
                why = ('not a frame object' if not isinstance(d, Exception) else str(d)
                       if isinstance(d, NotAFrame) else 'not JSON: %s' % d)
                result = {'id': None, 'timestamp': None, 'hands': [], 'error': why}
            else:
                result = classifier.classify(d)
            try:
                out.write(json.dumps(result) + '\n')
            except BrokenPipeError:
                raise
            except OSError as e:
                raise _WriteError(e) from None
            n += 1
    except BrokenPipeError:
        return 0
    except _WriteError as e:
        print('classify_frames: cannot write %s: %s' % (args.out, e), file=sys.stderr)
        status = 1
    except gesture_data.DataError as e:     # a keypoint file cut or bad after its first rows
        print('classify_frames: %s' % e, file=sys.stderr)
        status = 2
    except (OSError,) + gesture_data.UNREADABLE as e:   # a cut or corrupt gzip, a read error
        print('classify_frames: %s: cannot read on after %d frames (%s)'
              % (args.keypoints or args.input, n, e),
              file=sys.stderr)
        status = 2
    finally:
        if out is not sys.stdout:
            try:
                out.close()
            except OSError as e:        # what was still buffered: the disk is full
                print('classify_frames: cannot write %s: %s' % (args.out, e), file=sys.stderr)
                status = status or 1
    if n == 0 and status == 0 and args.input != '-':    # an empty pipe is fine; a file, no
        print('classify_frames: %s: no frame in it' % args.input, file=sys.stderr)
        status = 2
    return status


class _WriteError(Exception):
    """Writing the output failed (not reading the input)."""


if __name__ == '__main__':
    sys.exit(main())
