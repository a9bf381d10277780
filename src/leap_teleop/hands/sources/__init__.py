"""Hand sources by name: make_source('scripted', script=...)."""
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


__all__ = ['HandSource', 'SourceError', 'SOURCES', 'make_source']
