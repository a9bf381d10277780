"""Hand sources by name: make_source('scripted', script=...), or from a command line's
options (add_source_arguments, source_from_args)."""
import importlib

from leap_teleop.hands.sources.source import HandSource, SourceError

# name -> (module, class); modules load lazily so optional SDKs stay optional.
SOURCES = {
    'scripted': ('leap_teleop.hands.sources.scripted', 'ScriptedSource'),
    'recording': ('leap_teleop.hands.sources.recording', 'RecordingSource'),
    'leap': ('leap_teleop.hands.sources.leap_sdk', 'LeapSdkSource'),
    'leapc': ('leap_teleop.hands.sources.leapc', 'LeapCSource'),
    'webcam': ('leap_teleop.hands.sources.camera', 'WebcamSource'),
    'video': ('leap_teleop.hands.sources.camera', 'VideoSource'),
}


def make_source(name, **kwargs):
    """Build the source called `name`; SourceError with the fix when it cannot."""
    if name not in SOURCES:
        raise SourceError('unknown hand source %r; choose one of: %s'
                          % (name, ', '.join(sorted(SOURCES))))
    module_name, class_name = SOURCES[name]
    try:
        module = importlib.import_module(module_name)
    except ImportError as e:
        raise SourceError('hand source %r is not available: %s' % (name, e))
    return getattr(module, class_name)(**kwargs)


def add_source_arguments(parser, default=None):
    """The command-line options that choose and configure a hand source (read by
    source_from_args); --source is required unless given a default."""
    parser.add_argument('--source', choices=sorted(SOURCES), default=default,
                        required=default is None)
    parser.add_argument('--script', default='', help='gesture script for --source scripted')
    parser.add_argument('--recording', default='', help='input file for --source recording')
    parser.add_argument('--video', default='', help='--source video: a video, an image, a '
                                                    'folder or a glob of images')
    parser.add_argument('--device', default='0', help='--source webcam: index or /dev/videoN')
    parser.add_argument('--mirror', action='store_true',
                        help='camera sources: flip the image (a selfie view)')
    parser.add_argument('--realtime', type=int, default=1, choices=(0, 1),
                        help='scripted / recording / video sources: 1 = at their timing, '
                             '0 = fast')


def source_from_args(args):
    """The source that add_source_arguments' options describe; SourceError naming the
    missing option otherwise."""
    if args.source == 'scripted':
        if not args.script:
            raise SourceError('--source scripted needs --script YAML')
        return make_source('scripted', script=args.script, realtime=args.realtime)
    if args.source == 'recording':
        if not args.recording:
            raise SourceError('--source recording needs --recording PATH')
        return make_source('recording', path=args.recording, realtime=args.realtime)
    if args.source in ('video', 'webcam'):
        # images letterboxed to the sender's default size: the hands it would see
        from leap_teleop.hands.sources.camera_params import DEFAULT_SIZE
        width, height = DEFAULT_SIZE
        if args.source == 'webcam':
            return make_source('webcam', device=args.device, mirror=args.mirror, width=width,
                               height=height)
        if not args.video:
            raise SourceError('--source video needs --video PATH (a video, an image, a folder '
                              'or a glob of images)')
        return make_source('video', path=args.video, realtime=args.realtime, mirror=args.mirror,
                           width=width, height=height)
    return make_source(args.source)


__all__ = ['HandSource', 'SourceError', 'SOURCES', 'add_source_arguments', 'make_source',
           'source_from_args']
