"""The package's shape, checked from its source: ROS only at the edge, no import cycles,
one name per class. Static (ast), so it needs nothing built or running."""
import ast
import os
import re

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGE = os.path.join(ROOT, 'src', 'leap_teleop')
# What only leap_teleop.ros may import: rospy and the message / service packages.
ROS_ONLY = ('rospy', 'rosgraph', 'rosbag', 'rostest', 'roslib', 'genpy', 'dynamic_reconfigure',
            'diagnostic_updater', 'tf', 'tf2_ros', 'leap_teleop.msg', 'leap_teleop.srv')


def modules(top, prefix):
    """{dotted name: path} of every Python module under `top`."""
    out = {}
    for folder, dirs, files in os.walk(top):
        dirs[:] = [d for d in dirs if d != '__pycache__']
        for name in files:
            if name.endswith('.py'):
                rel = os.path.relpath(os.path.join(folder, name), top)[:-3].split(os.sep)
                if rel[-1] == '__init__':
                    rel = rel[:-1]
                out['.'.join([prefix] + rel)] = os.path.join(folder, name)
    return out


MODULES = {**modules(PACKAGE, 'leap_teleop'), **modules(os.path.join(ROOT, 'tools'), 'tools')}


def imports(path, name):
    """Every module `path` imports (absolute names; function-local imports included)."""
    tree = ast.parse(open(path).read(), path)
    package = name if path.endswith('__init__.py') else name.rpartition('.')[0]
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ''
            if node.level:
                parts = package.split('.')
                base = '.'.join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            out.add(base)
            # `from package import module` imports the module
            out.update(base + '.' + a.name for a in node.names if base + '.' + a.name in MODULES)
    return out


GRAPH = {name: {i for i in imports(path, name) if i in MODULES and i != name}
         for name, path in MODULES.items()}


def is_msg_package(name):
    top = name.split('.')[0]
    return top.endswith('_msgs') or top.endswith('_srvs')


def test_only_the_ros_folder_imports_rospy_or_messages():
    offenders = sorted(
        (name, i) for name, path in MODULES.items()
        if name.startswith('leap_teleop') and not name.startswith('leap_teleop.ros')
        for i in imports(path, name)
        if is_msg_package(i) or any(i == r or i.startswith(r + '.') for r in ROS_ONLY))
    assert not offenders, offenders


def test_the_installed_package_never_imports_the_tooling():
    offenders = sorted((name, i) for name in MODULES if name.startswith('leap_teleop')
                       for i in GRAPH[name] if i.startswith('tools'))
    assert not offenders, offenders


def cycles(graph):
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on_stack, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                out.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def without_parent_packages(graph):
    """A module importing its own package's __init__ is how Python loads it, not a cycle;
    what counts is the modules' own imports of each other."""
    return {v: {w for w in ws if not v.startswith(w + '.')} for v, ws in graph.items()}


def test_no_import_cycles():
    assert cycles(without_parent_packages(GRAPH)) == []


def test_the_cycle_finder_finds_one():
    assert cycles({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}) == [['a', 'b', 'c']]


def classes():
    """[(class name, file)] of every class in the package, the tooling and the tests."""
    out = []
    for top in ('src', 'tools', 'test'):
        for folder, dirs, files in os.walk(os.path.join(ROOT, top)):
            dirs[:] = [d for d in dirs if d != '__pycache__']
            for f in files:
                if f.endswith('.py'):
                    path = os.path.join(folder, f)
                    for node in ast.walk(ast.parse(open(path).read(), path)):
                        if isinstance(node, ast.ClassDef):
                            out.append((node.name, os.path.relpath(path, ROOT)))
    return out


# Fakes of a vendor SDK carry the SDK's own class names (Leap.Listener, leap.Listener).
VENDOR_NAMES = {'Listener': {'test/test_sources_recording.py'}}


def test_no_two_classes_share_a_name():
    seen = {}
    for name, path in classes():
        if path not in VENDOR_NAMES.get(name, ()):
            seen.setdefault(name, []).append(path)
    assert {n: p for n, p in seen.items() if len(p) > 1} == {}


def test_no_class_shares_a_message_or_service_name():
    messages = {os.path.splitext(f)[0] for d in ('msg', 'srv')
                for f in os.listdir(os.path.join(ROOT, d))}
    assert sorted((n, p) for n, p in classes() if n in messages) == []


@pytest.mark.parametrize('script', sorted(os.listdir(os.path.join(ROOT, 'scripts'))))
def test_scripts_are_few_line_wrappers(script):
    text = open(os.path.join(ROOT, 'scripts', script)).read()
    code = [line for line in text.splitlines() if line.strip() and not line.startswith('#')]
    assert len(code) <= 8, (script, code)
    assert 'main' in text


NODES = os.path.join(PACKAGE, 'ros', 'nodes')


@pytest.mark.parametrize('node', sorted(f for f in os.listdir(NODES) if f.endswith('.py')))
def test_nodes_are_about_a_hundred_lines(node):
    # A node is wiring: parameters, the library object, topics, spin. Logic grows elsewhere.
    with open(os.path.join(NODES, node)) as f:
        assert len(f.readlines()) <= 110, node


def test_every_module_the_architecture_page_names_exists():
    text = open(os.path.join(ROOT, 'docs', 'architecture.md')).read()
    named = set(re.findall(r'(?<![\w.])((?:hands|control|ur10|drone|ros)(?:\.\w+)+|params|vectors)'
                           r'(?![\w(])', text))
    named |= set(re.findall(r'(?<![\w.])(tools(?:\.\w+)+)', text))
    assert len(named) > 20
    missing = []
    for name in sorted(named):
        name = name.rstrip('.*').rstrip('.')
        full = name if name.startswith('tools') else 'leap_teleop.' + name
        if full not in MODULES:
            missing.append(name)
    assert not missing, missing


def test_the_architecture_page_names_every_module():
    # The reverse of the test above: a newcomer finds each module's job on one page. A
    # module may be named in full or, after its folder has been named, as `.name`.
    text = open(os.path.join(ROOT, 'docs', 'architecture.md')).read()
    unnamed = []
    for full in sorted(MODULES):
        if not full.startswith('leap_teleop.') or full.count('.') < 1:
            continue
        name = full[len('leap_teleop.'):]
        folder, _, last = name.rpartition('.')
        if name in ('ros', 'hands', 'control', 'ur10', 'drone', 'ros.nodes', 'hands.sources',
                    'hands.gestures'):
            continue
        if re.search(r'(?<![\w.])%s(?!\w)' % re.escape(name), text):
            continue
        if folder and folder in text and re.search(r'`\.%s`' % re.escape(last), text):
            continue
        unnamed.append(name)
    assert not unnamed, unnamed
