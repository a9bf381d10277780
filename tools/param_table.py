"""Every node's ~parameters as Markdown tables, generated from their declarations.

usage: python -m tools.param_table [--check README.md]

Prints one table per node (parameter, default, allowed values, meaning; "live" marks
what dynamic_reconfigure changes while the node runs); README.md's
Safety section holds this output between the `<!-- param-table -->` markers. With
--check FILE, exits 1 when FILE's copy differs from the declarations.
"""
import argparse
import importlib
import pkgutil
import sys

import leap_teleop.ros.nodes

BEGIN, END = '<!-- param-table begin -->', '<!-- param-table end -->'


def node_tables():
    """[(module name, script, PARAMS)] of every node module that declares parameters."""
    out = []
    for info in sorted(pkgutil.iter_modules(leap_teleop.ros.nodes.__path__), key=lambda i: i.name):
        module = importlib.import_module('leap_teleop.ros.nodes.' + info.name)
        params = getattr(module, 'PARAMS', None)
        if params:
            out.append((info.name, info.name + '.py', params))
    return out


def _cell(text):
    return str(text).replace('|', '\\|').replace('<', '&lt;').replace('\n', ' ')


def _default(value):
    if isinstance(value, str):
        return "`''`" if value == '' else '`%s`' % value
    if isinstance(value, bool):
        return '`%s`' % str(value).lower()
    if isinstance(value, float):
        return '`%s`' % (repr(value) if len(repr(value)) <= 8 else '%g' % value)
    return '`%s`' % (list(value) if isinstance(value, tuple) else value,)


def markdown():
    lines = []
    for module, script, params in node_tables():
        live = getattr(importlib.import_module('leap_teleop.ros.nodes.' + module), 'RECONFIGURABLE',
                       ())
        lines += ['', '`%s`:' % script, '',
                  '| parameter | default | allowed | meaning |', '|---|---|---|---|']
        for name, p in params.items():
            doc = p.doc + (' (live: dynamic_reconfigure)' if name in live else '')
            lines.append('| `~%s` | %s | %s | %s |' % (name, _cell(_default(p.default)),
                                                      _cell(p.allowed()), _cell(doc)))
    return '\n'.join(lines[1:]) + '\n'


def readme_copy(path):
    """The text between the markers in `path` (None when they are missing)."""
    with open(path) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        return None
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip('\n') + '\n'


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--check', metavar='FILE', help='compare FILE\'s table with the '
                    'declarations instead of printing')
    args = ap.parse_args(argv)
    table = markdown()
    if args.check:
        if readme_copy(args.check) != table:
            print('%s: the parameter table differs from the declarations; regenerate it '
                  'with python -m tools.param_table' % args.check, file=sys.stderr)
            return 1
        return 0
    sys.stdout.write(table)
    return 0


if __name__ == '__main__':
    sys.exit(main())
