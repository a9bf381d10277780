"""A benchmark module run in a newly spawned interpreter: what one benchmark leaves behind
(imports, heap, threads) must not slow the next one's figures."""
import ast
import concurrent.futures
import importlib
import importlib.util
import multiprocessing
import types


def _run_module(module):
    return dict(importlib.import_module(module).run())


def run_in_fresh_process(module):
    """The figures of `module`'s run(), measured in a newly spawned interpreter; its
    exception (with the child's traceback) when it raises."""
    ctx = multiprocessing.get_context('spawn')
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=ctx) as pool:
        return pool.submit(_run_module, module).result()


def fresh_process_module(name, package='tools.bench'):
    """Benchmark `name` as collect() runs it: run() in a fresh interpreter, the docstring
    read from its source (this process imports nothing of it)."""
    module = '%s.%s' % (package, name)
    with open(importlib.util.find_spec(module).origin) as f:
        doc = ast.get_docstring(ast.parse(f.read()))
    return types.SimpleNamespace(run=lambda: run_in_fresh_process(module), __doc__=doc)
