"""dynamic_reconfigure for a node's runtime-changeable ~parameters, from their Param
declarations: the same names, docs and bounds, no .cfg file or generated code.

`rosrun dynamic_reconfigure dynparam set NODE name value` and rqt_reconfigure see them.
A value the declaration refuses (out of range, NaN, not a number) is refused with a
warning and the previous value kept: dynamic_reconfigure's own server would clamp it to
the nearest bound instead, and lets NaN through. A request is taken whole or not at all:
the other values sent with a refused one are kept as they were too.
"""
import math
from types import SimpleNamespace

import rospy
from dynamic_reconfigure.server import Server

from leap_teleop.params import ParamError
from leap_teleop.ros.node import RateLimitedLog

_TYPES = {'bool': ('bool', 'bool'), 'int': ('int', 'int'), 'float': ('double', 'double')}
_INT32 = (-2 ** 31, 2 ** 31 - 1)


def bounds(param):
    """(min, max) of a scalar Param as dynamic_reconfigure shows them: its bounds, strict
    or not (a strict one is refused at the bound itself), else the type's range."""
    if param.kind == 'bool':
        return False, True
    lo = param.ge if param.ge is not None else param.gt
    hi = param.le if param.le is not None else param.lt
    if param.kind == 'int':
        return (_INT32[0] if lo is None else int(lo)), (_INT32[1] if hi is None else int(hi))
    return (-math.inf if lo is None else float(lo)), (math.inf if hi is None else float(hi))


def config_type(table, names, values):
    """What dynamic_reconfigure's Server takes (a generated *Config module's contents) for
    `names` of the Param `table`, with `values` (the node's current ones) as defaults.
    Raises ValueError for a parameter that is not a bool, int or float."""
    params = []
    for name in names:
        p = table[name]
        if p.kind not in _TYPES:
            raise ValueError('~%s is a %s: dynamic_reconfigure takes bool, int and float here'
                             % (name, p.kind))
        kind, ctype = _TYPES[p.kind]
        lo, hi = bounds(p)
        params.append({'name': name, 'type': kind, 'default': values[name], 'level': 1,
                       'description': '%s; allowed: %s' % (p.doc, p.allowed()),
                       'min': lo, 'max': hi, 'edit_method': '', 'srcline': 0,
                       'srcfile': __file__, 'ctype': ctype, 'cconsttype': 'const ' + ctype})
    description = {'name': 'Default', 'type': '', 'state': True, 'cstate': 'true', 'id': 0,
                   'parent': 0, 'parameters': params, 'groups': [], 'srcline': 0,
                   'srcfile': __file__, 'class': 'DEFAULT', 'parentclass': '',
                   'parentname': 'Default', 'field': 'default', 'upper': 'DEFAULT',
                   'lower': 'groups'}
    return SimpleNamespace(
        config_description=description, all_level=1,
        min={q['name']: q['min'] for q in params}, max={q['name']: q['max'] for q in params},
        defaults={q['name']: q['default'] for q in params},
        level={q['name']: q['level'] for q in params}, type={q['name']: q['type'] for q in params})


class _RefusingServer(Server):
    def _clamp(self, config):
        """No clamping: Reconfigure's callback refuses what the declaration refuses."""


class Reconfigure:
    """A dynamic_reconfigure server on the node's private namespace for `names` of the
    Param `table`. apply(changes) gets each accepted change ({name: checked value}) and
    applies it to the running node; a ValueError from it refuses the whole change."""

    def __init__(self, node, table, names, values, apply):
        self.node, self.table, self.names, self.apply = node, table, tuple(names), apply
        self.values = {name: values[name] for name in self.names}
        self.refused = 0
        self.log = RateLimitedLog(1.0)
        self.server = _RefusingServer(config_type(table, self.names, self.values),
                                      self._on_request)

    def _on_request(self, config, _level):
        changes, refused = {}, []
        for name in self.names:
            value, old = config[name], self.values[name]
            if value == old and type(value) is type(old):
                continue
            try:
                changes[name] = self.table[name].check(name, value)
            except ParamError as e:
                self._refuse(name, e, config)
                refused.append(name)
        if refused:
            # All or nothing: values sent together (a tuning file loaded at once) belong
            # together, e.g. a steeper gain with the lower cap meant to go with it.
            for name in changes:
                self._refuse(name, '~%s = %r: sent with the refused ~%s (a request is taken '
                             'whole or not at all)' % (name, config[name], ', ~'.join(refused)),
                             config)
            config.update(self.values)
            return config
        changes = {k: v for k, v in changes.items() if v != self.values[k]}
        if changes:
            try:
                self.apply(dict(changes))
            except ValueError as e:
                for name in changes:
                    self._refuse(name, e, config)
                return config
            self.values.update(changes)
            rospy.loginfo('%s: reconfigured %s', self.node,
                          ', '.join('%s = %r' % kv for kv in sorted(changes.items())))
        config.update(self.values)
        return config

    def _refuse(self, name, error, config):
        self.refused += 1
        # Rate-limited per parameter and value: a client repeating one bad value.
        self.log.warn('refused %s %r' % (name, config[name]),
                      '%s: dynamic_reconfigure refused %s; keeping ~%s = %r',
                      self.node, error, name, self.values[name])
        config[name] = self.values[name]
