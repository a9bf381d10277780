"""Record frames from any hand source to a LeapJS Playback file (replayable with the
recording source, LeapJS Playback and classify_frames).

usage: rosrun leap_teleop record_frames OUT.json[.gz|.lz]
           [--source leap|leapc|scripted|recording|webcam|video] [--script YAML]
           [--recording PATH] [--video PATH] [--device N|/dev/videoN] [--mirror]
           [--duration S] [--frames N] [--realtime 0|1]

Compression follows the file name: .json.gz (gzip), .json.lz (LZString base64, the
LeapJS original) or plain .json. Stops at --duration seconds, --frames frames, the end
of a finite source, or Ctrl-C; the file is written on every way out.
"""
import argparse
import sys
import time

from leap_teleop.hands.sources import SourceError, leapjs, make_source


def build_source(args):
    if args.source == 'scripted':
        if not args.script:
            raise SourceError('--source scripted needs --script YAML')
        return make_source('scripted', script=args.script, realtime=args.realtime)
    if args.source == 'recording':
        if not args.recording:
            raise SourceError('--source recording needs --recording PATH')
        return make_source('recording', path=args.recording, realtime=args.realtime)
    if args.source == 'video':
        if not args.video:
            raise SourceError('--source video needs --video PATH (a video, an image, a folder '
                              'or a glob of images)')
        return make_source('video', path=args.video, realtime=args.realtime, mirror=args.mirror)
    if args.source == 'webcam':
        return make_source('webcam', device=args.device, mirror=args.mirror)
    return make_source(args.source)


def record(source, out, duration=None, max_frames=None, metadata=None):
    """Pull frames from `source` into `out`; returns the number of frames written."""
    frames = []
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
    finally:
        source.stop()
    meta = dict(metadata or {})
    if len(frames) > 1:
        span = (frames[-1]['timestamp'] - frames[0]['timestamp']) * 1e-6
        if span > 0:
            meta.setdefault('frameRate', '%.3g' % ((len(frames) - 1) / span))
    leapjs.save(out, frames, meta)
    return len(frames)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('out', help='output file: .json, .json.gz or .json.lz')
    ap.add_argument('--source', default='leap',
                    choices=['leap', 'leapc', 'scripted', 'recording', 'webcam', 'video'])
    ap.add_argument('--script', default='', help='gesture script for --source scripted')
    ap.add_argument('--recording', default='', help='input file for --source recording')
    ap.add_argument('--video', default='', help='--source video: a video, an image, a folder or '
                                                'a glob of images')
    ap.add_argument('--device', default='0', help='--source webcam: index or /dev/videoN')
    ap.add_argument('--mirror', action='store_true',
                    help='camera sources: flip the image (a selfie view)')
    ap.add_argument('--duration', type=float, default=0.0, help='seconds to record; 0 = no limit')
    ap.add_argument('--frames', type=int, default=0, help='frames to record; 0 = no limit')
    ap.add_argument('--realtime', type=int, default=1,
                    help='scripted / recording / video sources: 1 = at their timing, 0 = fast')
    ap.add_argument('--title', default='', help='metadata title')
    if argv is None:   # drop ROS remappings (__name:=...) that rosrun / roslaunch add
        argv = [a for a in sys.argv[1:] if ':=' not in a]
    args = ap.parse_args(argv)
    try:
        source = build_source(args)
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
    print('record_frames: wrote %d frames to %s' % (n, args.out))
    return 0


if __name__ == '__main__':
    sys.exit(main())
