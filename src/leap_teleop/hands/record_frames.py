"""Record frames from any hand source to a LeapJS Playback file (replayable with the
recording source, LeapJS Playback and classify_frames).

usage: rosrun leap_teleop record_frames OUT.json[.gz|.lz]
           [--source leap|leapc|scripted|recording|webcam|video] [--script YAML]
           [--recording PATH] [--video PATH] [--device N|/dev/videoN] [--mirror]
           [--duration S] [--frames N] [--realtime 0|1]

Compression follows the file name: .json.gz (gzip), .json.lz (LZString base64, the
LeapJS original) or plain .json. Stops at --duration seconds, --frames frames, the end
of a finite source, Ctrl-C or a source that fails; the file holds every frame taken (no
frame taken: no file, status 1).
"""
import argparse
import math
import sys
import time

from leap_teleop.hands.sources import SourceError, add_source_arguments, leapjs, source_from_args
from leap_teleop.output_file import output_problem


def record(source, out, duration=None, max_frames=None, metadata=None):
    """Pull frames from `source` into `out`; returns the number of frames written. A source
    that fails mid-take still has the frames before it written, then its SourceError
    (saying so) raised. No frame: nothing is written (no reader takes an empty file)."""
    frames = []
    failed = None
    t0 = time.monotonic()
    try:
        for frame in source.frames():
            frames.append(leapjs.frame_to_dict(frame))
            if max_frames and len(frames) >= max_frames:
                break
            if duration and time.monotonic() - t0 >= duration:
                break
    except KeyboardInterrupt:
        pass
    except SourceError as e:
        failed = e
    finally:
        source.stop()
    if failed is not None:
        if not frames:
            raise failed
        _save(out, frames, metadata)
        raise SourceError('%s (the %d frames before it are in %s)' % (failed, len(frames), out))
    if frames:
        _save(out, frames, metadata)
    return len(frames)


def _save(out, frames, metadata):
    meta = dict(metadata or {})
    if len(frames) > 1:
        span = (frames[-1]['timestamp'] - frames[0]['timestamp']) * 1e-6
        if span > 0:
            meta.setdefault('frameRate', '%.3g' % ((len(frames) - 1) / span))
    leapjs.save(out, frames, meta)


# the endings leapjs.save picks its compression by
OUT_ENDINGS = ('.json', '.json.gz', '.json.lz')


def argument_problem(args):
    """What is wrong with the output file or the limits, in one line, or None."""
    if not args.out.endswith(OUT_ENDINGS):
        return 'output %s: name it .json, .json.gz or .json.lz' % args.out
    if args.out.endswith('.lz'):    # leapjs imports it only to save, after the take
        try:
            import lzstring  # noqa: F401
        except ImportError:
            return ('output %s: writing .json.lz needs the PyPI package lzstring (pip install '
                    'lzstring); or name it .json or .json.gz' % args.out)
    problem = output_problem(args.out, [args.recording, args.script, args.video])
    if problem:
        return 'output %s: %s' % (args.out, problem)
    if not (math.isfinite(args.duration) and args.duration >= 0.0):
        return '--duration %g: 0 (no limit) or more seconds' % args.duration
    if args.frames < 0:
        return '--frames %d: 0 (no limit) or more' % args.frames
    return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=' '.join(__doc__.split('\n\n')[0].split()))
    ap.add_argument('out', help='output file: .json, .json.gz or .json.lz')
    add_source_arguments(ap, default='leap')
    ap.add_argument('--duration', type=float, default=0.0, help='seconds to record; 0 = no limit')
    ap.add_argument('--frames', type=int, default=0, help='frames to record; 0 = no limit')
    ap.add_argument('--title', default='', help='metadata title')
    if argv is None:   # drop ROS remappings (__name:=...) that rosrun / roslaunch add
        argv = [a for a in sys.argv[1:] if ':=' not in a]
    args = ap.parse_args(argv)
    problem = argument_problem(args)
    if problem:     # before the source starts: a live take is not lost at the end
        print('record_frames: %s' % problem, file=sys.stderr)
        return 2
    try:
        source = source_from_args(args)
    except SourceError as e:
        print('record_frames: %s' % e, file=sys.stderr)
        return 2
    meta = {'title': args.title} if args.title else {}
    meta['source'] = args.source
    try:
        n = record(source, args.out, args.duration or None, args.frames or None, meta)
    except (OSError, SourceError) as e:
        print('record_frames: %s' % e, file=sys.stderr)
        return 1
    if not n:
        print('record_frames: no frame from the source: nothing written', file=sys.stderr)
        return 1
    print('record_frames: wrote %d frames to %s' % (n, args.out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
