"""Every node's ~parameters as Markdown tables, generated from their declarations.

usage: python -m tools.param_table [--check FILE | --write FILE]

Prints one table per node (parameter, default, allowed values, meaning; "live" marks
what dynamic_reconfigure changes while the node runs); docs/nodes.md holds this output
between the `<!-- param-table -->` markers. With --check FILE, exits 1 when FILE's copy
differs from the declarations; with --write FILE, replaces FILE's copy with them.
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


def docs_copy(path):
    """The text between the markers in `path` (None when they are missing)."""
    with open(path) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        return None
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip('\n') + '\n'


def write_copy(path, table):
    """Replace the text between the markers in `path` with `table`; False when the markers
    are missing (the file is left as it was)."""
    with open(path) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        return False
    before, rest = text.split(BEGIN, 1)
    after = rest.split(END, 1)[1]
    with open(path, 'w') as f:
        f.write(before + BEGIN + '\n' + table + END + after)
    return True


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument('--check', metavar='FILE', help='compare FILE\'s table with the '
                      'declarations instead of printing')
    mode.add_argument('--write', metavar='FILE', help='replace FILE\'s table (between the '
                      'param-table markers) with the declarations\' one')
    args = ap.parse_args(argv)
    table = markdown()
    if args.check:
        copy = docs_copy(args.check)
        if copy is None:
            print('%s: no %s ... %s markers holding the parameter table'
                  % (args.check, BEGIN, END), file=sys.stderr)
            return 1
        if copy != table:
            print('%s: the parameter table differs from the declarations; regenerate it '
                  'with python -m tools.param_table --write %s'
                  % (args.check, args.check), file=sys.stderr)
            return 1
        return 0
    if args.write:
        if not write_copy(args.write, table):
            print('%s: no %s ... %s markers to write the table between'
                  % (args.write, BEGIN, END), file=sys.stderr)
            return 1
        return 0
    sys.stdout.write(table)
    return 0


if __name__ == '__main__':
    sys.exit(main())
