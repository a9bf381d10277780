"""Typed, bounded node parameters: one declaration is checked at start-up and shown by --help.

A `Param` knows its default, doc, unit and what values are allowed; `check_params` turns the
raw values (from the parameter server) into checked ones or raises `ParamError` with one line
naming the parameter, the value and the allowed range. Pure Python: testable without a master.
"""
import copy
import dataclasses
import difflib
import functools
import math
import numbers
import re

# A legal ROS graph name (the ROS 1 naming rules), not ending in '/'.
_ROS_NAME = re.compile(r'[~/A-Za-z][A-Za-z0-9_/]*(?<!/)')


def is_ros_name(value):
    """Whether `value` can name a topic: ROS 1's naming rules, no '//', no trailing '/'."""
    return bool(_ROS_NAME.fullmatch(value)) and '//' not in value


class ParamError(ValueError):
    """A parameter value outside what its declaration allows."""


class Param:
    """One ~parameter. The kind follows the default (bool, int, float, str, list), or `kind`.

    Numbers (and list items) must be finite and within `gt` / `ge` / `lt` / `le`; `choices`
    lists the allowed values; `length` fixes a list's length (`min_length` bounds it);
    `item` is a list's item kind ('float', 'int', 'str') or a Param (a list of lists:
    each item is checked against it); `empty_ok=False` refuses ''; `ros_name` wants a
    legal ROS graph name (a topic: letters, digits, _, / and a leading ~, no //); `path`
    marks a file path (the node reads a relative one from where it was launched);
    `or_zero` also allows 0 (an "off") below the bounds. A single
    string given for a list of strings is a list of one (`_sides:=right` means ['right']).
    """

    KINDS = ('bool', 'int', 'float', 'str', 'list')

    def __init__(self, default, doc, unit='', kind=None, gt=None, ge=None, lt=None, le=None,
                 choices=None, length=None, min_length=None, item=None, empty_ok=True,
                 ros_name=False, path=False, or_zero=False):
        self.default = default
        self.doc = doc
        self.unit = unit
        self.kind = kind or _kind_of(default)
        if self.kind not in self.KINDS:
            raise TypeError('unknown parameter kind %r' % (self.kind,))
        self.gt, self.ge, self.lt, self.le = gt, ge, lt, le
        self.choices = tuple(choices) if choices is not None else None
        self.length = length
        self.min_length = min_length
        self.item = item or (_kind_of(default[0]) if self.kind == 'list' and default else 'str')
        if isinstance(self.item, Param):
            self.item.unit = self.item.unit or unit
        self.empty_ok = empty_ok
        self.ros_name = ros_name
        self.path = path
        self.or_zero = or_zero

    # -- checking -------------------------------------------------------------------------
    def check(self, name, value):
        """The checked (and normalised: int -> float where a float is wanted) value."""
        try:
            if self.kind == 'list':
                return self._check_list(value)
            return self._check_scalar(value, self.kind)
        except ParamError as e:
            raise ParamError('~%s = %r: %s; allowed: %s' % (name, value, e, self.allowed()))

    def _check_list(self, value):
        if isinstance(value, str) and self.item == 'str':
            value = [value] if value else []        # _name:='' (an empty launch arg): none
        if not isinstance(value, (list, tuple)):
            raise ParamError('not a list')
        if self.item == 'str' and self.ros_name and '' in value:
            raise ParamError('an empty name')       # rospy resolves it to '/'; no topic is
        if self.length is not None and len(value) != self.length:
            raise ParamError('%d items' % len(value))
        if self.min_length is not None and len(value) < self.min_length:
            raise ParamError('%d items' % len(value))
        if isinstance(self.item, Param):
            try:
                return [self.item.check('item', v) for v in value]
            except ParamError:
                raise ParamError('an item is not %s' % self.item.allowed())
        return [self._check_scalar(v, self.item) for v in value]

    def _check_scalar(self, value, kind):
        if kind == 'bool':
            if not isinstance(value, bool):
                raise ParamError('not true / false')
            return value
        if kind == 'str':
            if not isinstance(value, str):
                raise ParamError('not a string')
            if not value and not self.empty_ok:
                raise ParamError('empty')
            if value and self.ros_name and not is_ros_name(value):
                raise ParamError('not a legal ROS name')
        elif kind == 'int':
            if isinstance(value, bool) or not isinstance(value, numbers.Integral):
                raise ParamError('not an integer')
            value = int(value)
        else:  # float
            if isinstance(value, bool) or not isinstance(value, numbers.Real):
                raise ParamError('not a number')
            try:
                value = float(value)
            except OverflowError:       # an integer of hundreds of digits
                value = math.inf
            if not math.isfinite(value):
                raise ParamError('not finite')
        if self.choices is not None and value not in self.choices:
            raise ParamError('not one of the choices')
        if kind in ('int', 'float') and not (self.or_zero and value == 0):
            for bound, ok in ((self.gt, lambda b: value > b), (self.ge, lambda b: value >= b),
                              (self.lt, lambda b: value < b), (self.le, lambda b: value <= b)):
                if bound is not None and not ok(bound):
                    raise ParamError('out of range')
        return value

    # -- describing -----------------------------------------------------------------------
    def allowed(self):
        """What the check accepts, in words: 'a number > 0 (s)', 'one of: a, b', ..."""
        if self.kind == 'list':
            n = ('%d ' % self.length if self.length is not None
                 else '>= %d ' % self.min_length if self.min_length else '')
            if isinstance(self.item, Param):
                return 'a list of %sitems, each %s' % (n, self.item.allowed())
            if self.choices is not None:
                return 'a list of %sitems, each %s' % (n, self._scalar_text(self.item))
            return 'a list of %s%s' % (n, self._scalar_text(self.item, plural=True))
        return self._scalar_text(self.kind)

    def _scalar_text(self, kind, plural=False):
        if self.choices is not None:
            return 'one of: ' + ', '.join(str(c) if c != '' else "''" for c in self.choices)
        words = {'bool': 'true or false',
                 'str': ('ROS names' if plural else 'a ROS name') if self.ros_name else
                 'a path (a relative one from where it was launched)' if self.path else
                 'strings' if plural else 'a string',
                 'int': 'integers' if plural else 'an integer',
                 'float': 'finite numbers' if plural else 'a finite number'}[kind]
        if kind == 'str' and not self.empty_ok:
            words += ' (not empty)'
        elif kind == 'str' and self.ros_name and not plural:
            words += " or ''"           # '' is the node's default name (see its doc)
        bounds = [op + ' ' + _fmt(b) for op, b in (('>', self.gt), ('>=', self.ge),
                                                  ('<', self.lt), ('<=', self.le))
                  if b is not None]
        if bounds:
            words += ' ' + ' and '.join(bounds)
            if self.or_zero:
                words = '0 or ' + words
        if self.unit:
            words += ' (%s)' % self.unit
        return words


def check_params(table, raw):
    """{name: checked value} for every parameter of `table`, values from `raw` (a dict of the
    values found; missing ones take the default). Raises ParamError for the first bad one."""
    return {name: p.check(name, raw.get(name, p.default)) for name, p in table.items()}


def unknown_param_warnings(node, declared, found):
    """One warning per name in `found` (the private parameters set for `node`) that is not in
    `declared`, naming the declared ones closest to it: a misspelt or renamed parameter is
    otherwise silently ignored."""
    out = []
    for name in sorted(set(found) - set(declared)):
        close = ['~' + c for c in difflib.get_close_matches(name, sorted(declared), n=3)]
        hint = ''
        if close:
            hint = ' (did you mean %s?)' % (close[0] if len(close) == 1 else
                                            '%s or %s' % (', '.join(close[:-1]), close[-1]))
        out.append('~%s is not a parameter of %s%s; ignored' % (name, node, hint))
    return out


_FIELD_TYPES = {'bool': bool, 'int': int, 'float': float, 'str': str, 'list': list}


def declared_fields(table):
    """Class decorator: make the class a dataclass whose fields are `table`'s parameters, in
    its order, with its defaults (a list default is copied for each instance), so a
    configuration class never restates what the `Param` table declares."""
    def make(cls):
        annotations = {}
        for name, p in table.items():
            annotations[name] = _FIELD_TYPES[p.kind]
            if p.kind == 'list':
                default = dataclasses.field(
                    default_factory=functools.partial(copy.deepcopy, p.default))
            else:
                default = p.default
            setattr(cls, name, default)
        cls.__annotations__ = annotations
        return dataclasses.dataclass(cls)
    return make


def _kind_of(value):
    for kind, types in (('bool', bool), ('int', numbers.Integral), ('float', numbers.Real),
                        ('str', str), ('list', (list, tuple))):
        if isinstance(value, types):
            return kind
    raise TypeError('no parameter kind for %r' % (value,))


def _fmt(x):
    return ('%g' % x) if isinstance(x, float) else str(x)
