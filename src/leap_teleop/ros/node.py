"""What every node shares: a parameter table that is both read and shown by --help, and
the library's log records on the node's console and /rosout."""
import logging
import sys
import textwrap
import time

import rospy

from leap_teleop.package_files import user_path
from leap_teleop.params import ParamError, check_params, unknown_param_warnings
from leap_teleop.repeat_limit import RepeatLimit
from leap_teleop.ros.diagnostics import DIAGNOSTIC_PARAMS
from leap_teleop.ros.signals import init_node

# Private parameters of a library every node uses (diagnostic_updater's period).
LIBRARY_PARAMS = DIAGNOSTIC_PARAMS


def handle_help(node_name, description, params, argv=None, live=()):
    """Print the node's private parameters (`live`: those dynamic_reconfigure changes while
    it runs) and exit when --help / -h is given."""
    argv = rospy.myargv(argv if argv is not None else sys.argv)
    if '-h' not in argv and '--help' not in argv:
        return
    print('usage: rosrun leap_teleop %s [_param:=value ...] [topic:=remapped ...]\n' % node_name)
    print(textwrap.fill(description, 88) + '\n')
    print('private parameters (~name, default, allowed values; live: changes while it runs, '
          'through dynamic_reconfigure):')
    for name, p in list(params.items()) + list(LIBRARY_PARAMS.items()):
        print('  ~%-22s %-28r %s%s\n  %-51s allowed: %s' % (name, p.default, p.doc,
                                                           ' (live)' if name in live else '', '',
                                                           p.allowed()))
    sys.exit(0)


def start_node(script, name, doc, params, make, argv=None, errors=(ValueError, TypeError),
               hint=''):
    """The start every node shares: --help, init_node, the ~params, then make(p). A bad
    parameter (make raising one of `errors`) ends the node with one fatal log line (plus
    `hint`) and exit status 1, not a traceback. Returns (p, what make returned)."""
    # the node module's RECONFIGURABLE, as the docs' tables read it
    live = getattr(sys.modules.get(getattr(make, '__module__', '')), 'RECONFIGURABLE', ())
    handle_help(script, doc, params, argv, live)
    try:
        init_node(name)
    except OverflowError as e:      # rospy sends _name:=value params over XML-RPC first
        sys.stderr.write('%s: bad parameter: %s (an integer beyond 32 bits given as '
                         '_name:=value)\n' % (name, e))
        raise SystemExit(1)
    forward_library_logs()
    label = rospy.get_name().lstrip('/') or name     # with its namespace: dual launches
    warn_unknown_params(label, params)
    try:
        p = read_params(params)
        read_params(LIBRARY_PARAMS)         # checked, then read where they are used
        return p, make(p)
    except (ParamError,) + tuple(errors) as e:
        rospy.logfatal('%s: bad parameter: %s%s', label, e, hint)
        raise SystemExit(1)


class _RospyHandler(logging.Handler):
    """Passes a log record on to rospy's function of its level; a warning or error at most
    once per `period` s per call site and message (some come once a frame), with a count
    of those left out."""

    def __init__(self, period=2.0):
        super().__init__()
        self._limit = RepeatLimit(period)    # per (logger, message template), monotonic time

    def emit(self, record):
        try:
            level = record.levelno
            n = 0
            if level >= logging.WARNING:
                n = self._limit.take((record.name, record.msg), time.monotonic())
                if n is None:
                    return
            text = self.format(record) + RepeatLimit.suffix(n)
            log = (rospy.logerr if level >= logging.ERROR else rospy.logwarn
                   if level >= logging.WARNING else rospy.loginfo if level >= logging.INFO
                   else rospy.logdebug)
            log(text)
        except Exception:   # noqa: BLE001 - logging must never end the caller
            self.handleError(record)


def forward_library_logs():
    """The library logs through Python's `leap_teleop` loggers (the sources' warnings about
    bad frames, for one); rospy sends those to the node's log file only. Passed on to rospy,
    they reach the console and /rosout like the node's own lines (once: not also to the
    file directly)."""
    logger = logging.getLogger('leap_teleop')
    if not any(isinstance(h, _RospyHandler) for h in logger.handlers):
        logger.addHandler(_RospyHandler())
    logger.setLevel(logging.INFO)
    logger.propagate = False


def read_params(params):
    """A dict of every ~param, defaults from the table, each checked against its declaration
    (ParamError names the first bad one)."""
    p = check_params(params, {name: rospy.get_param('~' + name, params[name].default)
                              for name in params})
    for name, declared in params.items():
        if declared.path:
            p[name] = user_path(p[name])
    return p


def warn_unknown_params(node, params):
    """Warn once for each private parameter set for this node that `params` does not declare
    (a misspelt or renamed one would otherwise be ignored without a word)."""
    prefix = rospy.get_name().rstrip('/') + '/'
    found = {name[len(prefix):].split('/')[0] for name in rospy.get_param_names()
             if name.startswith(prefix)}
    for text in unknown_param_warnings(node, list(params) + list(LIBRARY_PARAMS), found):
        rospy.logwarn(text)


class RateLimitedLog:
    """Warn at most once per period per key, with a count of what was suppressed."""

    def __init__(self, period=2.0):
        self._limit = RepeatLimit(period)

    def warn(self, key, fmt, *args):
        n = self._limit.take(key, rospy.get_time() if rospy.core.is_initialized() else 0.0)
        if n is not None:
            rospy.logwarn(fmt + RepeatLimit.suffix(n), *args)
