"""Turn a gesture script, a LeapJS recording or camera footage into a bag of the sender's
topics.

The frames go through the real sender logic (LeapInterface, the gesture recognizer,
the same message conversion), as fast as possible, so the gestures in the bag are what
the recognizer saw. Message times are the frames' capture times, starting at --start
(default: now), so `rosbag play` reproduces the original timing.

usage: rosrun leap_teleop recording_to_bag RECORDING.json[.lz|.gz] OUT.bag
       python -m leap_teleop.ros.recording_to_bag --script config/gestures/X.yaml OUT.bag
       python -m leap_teleop.ros.recording_to_bag --video CLIP.mp4 OUT.bag   (also images / a glob)

Camera footage goes through the camera source as the sender's defaults run it: images
letterboxed to 640x480, a 60 deg field of view, a 95 mm palm, a camera that does not mirror.
"""
import argparse
import math
import os
import sys
import time

import genpy
import rosbag
import rospy

from leap_teleop.hands.frame import SIDES
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources import SourceError, capture, make_source
from leap_teleop.hands.sources.camera_params import DEFAULT_SIZE
from leap_teleop.output_file import output_problem
from leap_teleop.params import is_ros_name
from leap_teleop.ros import hand_conversions

KINDS = ('leapcobot', 'hand', 'gesture')
ROS_TIME_END = 2 ** 32      # ROS time counts seconds in 32 unsigned bits


class PastRosTimeError(ValueError):
    """A frame's time is past ROS time's end."""


def write_bag(source, out_path, sides=SIDES, topics=None, kinds=KINDS, start=None,
              compression='bz2'):
    """Run `source` through the sender logic into `out_path`; returns the number of frames
    that put at least one message into the bag (a frame without a valid capture time, or
    with none of `kinds` to write, puts none). topics: {side: {kind: topic}}, default the
    sender's, stored as global names as `rosbag record` stores them (so `rosbag play
    --topics /leapmotion/...` finds them). PastRosTimeError when a frame's time passes ROS
    time's end."""
    topics = topics or {side: hand_conversions.default_topics(side) for side in sides}
    topics = {side: {kind: '/' + t.lstrip('/') for kind, t in by_kind.items()}
              for side, by_kind in topics.items()}
    interface = LeapInterface(sides=list(sides))
    first_stamp = [None]
    offset = [0.0]
    wrote = [False]
    count = 0
    with rosbag.Bag(out_path, 'w', compression=compression) as bag:
        def on_hand(frame, state):
            for kind, msg in hand_conversions.hand_messages(state):
                if kind in kinds:
                    bag.write(topics[state.side][kind], msg, msg.header.stamp)
                    wrote[0] = True

        interface.add_hand_listener(on_hand)
        for frame in source.frames():
            if first_stamp[0] is None:
                first_stamp[0] = frame.timestamp
                offset[0] = (time.time() if start is None else start) - frame.timestamp
            frame.timestamp += offset[0]
            if frame.timestamp >= ROS_TIME_END:     # rosbag fails on it only when closing
                raise PastRosTimeError('a frame at %.0f s: past the end of ROS time (%d s)'
                                       % (frame.timestamp, ROS_TIME_END))
            wrote[0] = False
            interface.on_frame(frame)
            count += wrote[0]
    return count


def topic_collision(topics, kinds):
    """What is wrong when two outputs of `topics` ({side: {kind: topic}}) that get written
    (`kinds`) share a topic, else None. Two types on one topic replay as the first one
    only, and two streams of one type mix; the gesture topic is one stream for both hands."""
    used = {}
    for side, by_kind in topics.items():
        for kind, topic in by_kind.items():
            if kind not in kinds:
                continue
            topic = '/' + topic.lstrip('/')     # as write_bag stores it
            other = used.setdefault(topic, (side, kind))
            if other != (side, kind) and not (kind == other[1] == 'gesture'):
                return 'the %s %s and the %s %s are both on %s: one topic per output' % (
                    other[0], other[1], side, kind, topic)
    return None


def comma_list(allowed):
    """An argparse type: a comma-separated list of `allowed` names, in order, once each."""
    def parse(text):
        names = list(dict.fromkeys(n.strip() for n in text.split(',') if n.strip()))
        unknown = [n for n in names if n not in allowed]
        if unknown or not names:
            raise argparse.ArgumentTypeError('%r: one or more of %s, comma-separated'
                                             % (text, ', '.join(allowed)))
        return names
    return parse


def start_time(text):
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0.0 <= value < ROS_TIME_END):
        raise argparse.ArgumentTypeError('%r: seconds since 1970, 0 or more and before %d '
                                         '(the end of ROS time)' % (text, ROS_TIME_END))
    return value


def main(argv=None):
    ap = argparse.ArgumentParser(description=' '.join(__doc__.split('\n\n')[0].split()),
                                 epilog=__doc__.split('\n\n', 2)[-1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('recording', nargs='?', help='LeapJS recording (.json, .json.lz, .json.gz)')
    ap.add_argument('out', help='output bag (NAME.bag)')
    ap.add_argument('--script', help='a gesture script instead of a recording')
    ap.add_argument('--video', help='camera footage instead of a recording: a video, an image, '
                                    'a folder or a glob of images (the video source)')
    ap.add_argument('--sides', default=list(SIDES), type=comma_list(SIDES),
                    help='which hands to write, comma-separated (default: right,left)')
    ap.add_argument('--kinds', default=list(KINDS), type=comma_list(KINDS),
                    help='which messages to write, comma-separated (default: %s)' % ','.join(KINDS))
    ap.add_argument('--right-topic', default='/leapmotion/data_right',
                    help="the right hand's leapcobot topic (default %(default)s)")
    ap.add_argument('--left-topic', default='/leapmotion/data_left',
                    help="the left hand's leapcobot topic (default %(default)s)")
    ap.add_argument('--start', type=start_time, default=None,
                    help='time of the first frame, s (epoch; default: now)')
    args = ap.parse_args(rospy.myargv(sys.argv)[1:] if argv is None else argv)
    if sum(bool(x) for x in (args.script, args.recording, args.video)) != 1:
        ap.error('give one of: a recording, --script, --video')
    if not args.out.endswith('.bag'):
        ap.error('%r: name the bag file NAME.bag' % args.out)
    for option, topic in (('--right-topic', args.right_topic), ('--left-topic', args.left_topic)):
        if not is_ros_name(topic):
            ap.error('%s %r: not a legal ROS topic name' % (option, topic))
        if topic.startswith('~'):
            ap.error('%s %r: a bag has no node to be private to: give a global name' % (option, topic))
    topics = {side: hand_conversions.default_topics(side) for side in args.sides}
    if 'right' in topics:
        topics['right']['leapcobot'] = args.right_topic
    if 'left' in topics:
        topics['left']['leapcobot'] = args.left_topic
    problem = topic_collision(topics, args.kinds)
    if problem:
        ap.error(problem)
    inputs = [args.recording, args.script, args.video]
    if args.video:
        inputs += capture.resolve_stills(args.video)
    problem = output_problem(args.out, inputs)
    if problem:
        ap.error('%s: %s' % (args.out, problem))
    try:
        if args.video:     # letterboxed as the sender's defaults: the hands it would see
            source = make_source('video', path=args.video, realtime=False,
                                 width=DEFAULT_SIZE[0], height=DEFAULT_SIZE[1])
        elif args.script:
            source = make_source('scripted', script=args.script, realtime=False)
        else:
            source = make_source('recording', path=args.recording, realtime=False)
    except SourceError as e:
        print('recording_to_bag: %s' % e, file=sys.stderr)
        return 2
    try:
        n = write_bag(source, args.out, args.sides, topics, tuple(args.kinds), args.start)
    except (OSError, rosbag.ROSBagException) as e:
        print('recording_to_bag: cannot write %s: %s' % (args.out, e), file=sys.stderr)
        return 1
    except (PastRosTimeError, SourceError, genpy.SerializationError) as e:
        os.remove(args.out)     # the bag was open: what it holds is a part of the take
        print('recording_to_bag: %s: nothing written to %s' % (e, args.out), file=sys.stderr)
        return 1
    if not n:
        os.remove(args.out)     # an empty bag replays nothing: no file rather than a silent one
        print('recording_to_bag: no %s message for the %s hand: nothing written to %s' % (
            ' or '.join(args.kinds), ' or '.join(args.sides), args.out), file=sys.stderr)
        return 1
    print('wrote %s: %d frames' % (args.out, n))
    return 0


if __name__ == '__main__':
    sys.exit(main())
