"""Turn a gesture script, a LeapJS recording or camera footage into a bag of the sender's
topics.

The frames go through the real sender logic (LeapInterface, the gesture recognizer,
the same message conversion), as fast as possible, so the gestures in the bag are what
the recognizer saw. Message times are the frames' capture times, starting at --start
(default: now), so `rosbag play` reproduces the original timing.

usage: rosrun leap_teleop recording_to_bag RECORDING.json[.lz|.gz] OUT.bag
       python -m leap_teleop.ros.recording_to_bag --script config/gestures/X.yaml OUT.bag
       python -m leap_teleop.ros.recording_to_bag --video CLIP.mp4 OUT.bag   (also images / a glob)
"""
import argparse
import sys
import time

import rosbag
import rospy

from leap_teleop.hands.frame import SIDES
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources import SourceError, make_source
from leap_teleop.ros import conversions


def write_bag(source, out_path, sides=SIDES, topics=None, kinds=('leapcobot', 'hand', 'gesture'),
              start=None, compression='bz2'):
    """Run `source` through the sender logic into `out_path`; returns the frame count.
    topics: {side: {kind: topic}}, default the sender's."""
    topics = topics or {side: conversions.default_topics(side) for side in sides}
    interface = LeapInterface(sides=list(sides))
    first_stamp = [None]
    offset = [0.0]
    count = 0
    with rosbag.Bag(out_path, 'w', compression=compression) as bag:
        def on_hand(frame, state):
            for kind, msg in conversions.hand_messages(state):
                if kind in kinds:
                    bag.write(topics[state.side][kind], msg, msg.header.stamp)

        interface.add_hand_listener(on_hand)
        for frame in source.frames():
            if first_stamp[0] is None:
                first_stamp[0] = frame.timestamp
                offset[0] = (time.time() if start is None else start) - frame.timestamp
            frame.timestamp += offset[0]
            interface.on_frame(frame)
            count += 1
    return count


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 epilog=__doc__.split('\n\n', 2)[-1],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('recording', nargs='?', help='LeapJS recording (.json, .json.lz, .json.gz)')
    ap.add_argument('out', help='output bag')
    ap.add_argument('--script', help='a gesture script instead of a recording')
    ap.add_argument('--video', help='camera footage instead of a recording: a video, an image, '
                                    'a folder or a glob of images (the video source)')
    ap.add_argument('--sides', default='right,left')
    ap.add_argument('--kinds', default='leapcobot,hand,gesture',
                    help='which of leapcobot, hand, gesture to write')
    ap.add_argument('--right-topic', default='leapmotion/data_right')
    ap.add_argument('--left-topic', default='leapmotion/data_left')
    ap.add_argument('--start', type=float, default=None, help='time of the first frame, s (epoch)')
    args = ap.parse_args(rospy.myargv(sys.argv)[1:] if argv is None else argv)
    if sum(bool(x) for x in (args.script, args.recording, args.video)) != 1:
        ap.error('give one of: a recording, --script, --video')
    try:
        if args.video:
            source = make_source('video', path=args.video, realtime=False)
        elif args.script:
            source = make_source('scripted', script=args.script, realtime=False)
        else:
            source = make_source('recording', path=args.recording, realtime=False)
    except SourceError as e:
        print('error: %s' % e, file=sys.stderr)
        return 2
    sides = [s for s in args.sides.split(',') if s]
    topics = {side: conversions.default_topics(side) for side in sides}
    if 'right' in topics:
        topics['right']['leapcobot'] = args.right_topic
    if 'left' in topics:
        topics['left']['leapcobot'] = args.left_topic
    n = write_bag(source, args.out, sides, topics, tuple(args.kinds.split(',')), args.start)
    print('wrote %s: %d frames' % (args.out, n))
    return 0


if __name__ == '__main__':
    sys.exit(main())
