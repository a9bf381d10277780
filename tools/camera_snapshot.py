"""Save the annotated camera view (what the sender publishes on ~annotated_image_topic) of
one frame of camera footage, after the recognizer has seen every frame up to it.

usage: python -m tools.camera_snapshot INPUT OUT.png [--frame N] [--mirror]

INPUT: a video, an image, a folder or a glob of images (the video source's input).
"""
import argparse
import sys

from leap_teleop.hands.camera_view import CameraView
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources import SourceError, make_source


def snapshot(path, frame_number=1, mirror=False, width=640, height=480):
    """The annotated BGR image of frame `frame_number` (1-based) of `path` as the sender
    shows it (letterboxed to width x height; the frame rate is the processing rate), or
    None."""
    got = {}
    view = CameraView(mirror, lambda frame, img: got.__setitem__(frame.id, img))
    source = make_source('video', path=path, realtime=False, mirror=mirror, width=width,
                         height=height, clock=lambda: 0.0, on_image=view.on_image)
    interface = LeapInterface(source)
    interface.add_listener(lambda frame, states: view.on_frame(frame, states)
                           if frame.id == frame_number else None)
    for frame in source.frames():
        interface.on_frame(frame)
        if frame.id >= frame_number:
            source.stop()
    return got.get(frame_number)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('input')
    ap.add_argument('out')
    ap.add_argument('--frame', type=int, default=1, help='1-based frame number')
    ap.add_argument('--mirror', action='store_true', help='flip the image (a selfie view)')
    args = ap.parse_args(argv)
    try:
        img = snapshot(args.input, args.frame, args.mirror)
    except SourceError as e:
        print('camera_snapshot: %s' % e, file=sys.stderr)
        return 2
    if img is None:
        print('camera_snapshot: %s has no frame %d' % (args.input, args.frame), file=sys.stderr)
        return 1
    import cv2
    cv2.imwrite(args.out, img)
    print('camera_snapshot: wrote %s' % args.out)
    return 0


if __name__ == '__main__':
    sys.exit(main())
