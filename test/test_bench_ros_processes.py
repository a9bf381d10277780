"""make bench reports only what it measured: a fresh results file per run, failures and
the data behind each figure recorded, frames counted as received, slow replies kept."""
import json
import math
import os
import sys
import types

import numpy as np
import pytest

from tools.bench import __main__ as bench_main
from tools.bench.bench_arm import _p99_ms, median_ci
from tools.bench.bench_sender import max_rate_no_drop, received_hz


def fake(run, doc='fake benchmark'):
    return types.SimpleNamespace(run=run, __doc__=doc)


def test_a_failing_module_is_recorded_and_leaves_no_figures():
    def boom():
        raise RuntimeError('no data')
    modules = {'bench_ok': fake(lambda: {'ok.x': 1.5, '_sources': {'ok.x': '3 takes'}}),
               'bench_boom': fake(boom),
               'bench_nan': fake(lambda: {'nan.x': math.nan, 'nan.y': 2.0})}
    figures, sources, failed = bench_main.collect(list(modules), load=modules.get)
    assert figures == {'ok.x': 1.5}
    assert sources == {'ok.x': 'bench_ok: 3 takes'}
    assert failed['bench_boom'] == 'RuntimeError: no data'
    assert 'nan.x' in failed['bench_nan']


def test_a_figure_without_a_stated_source_names_its_module():
    modules = {'bench_a': fake(lambda: {'a.x': 3}, doc='Sender throughput.\nmore')}
    _, sources, _ = bench_main.collect(['bench_a'], load=modules.get)
    assert sources == {'a.x': 'bench_a: Sender throughput.'}


def test_each_module_runs_in_a_fresh_interpreter_of_its_own(tmp_path, monkeypatch):
    """What one benchmark leaves behind (imports, heap, threads) never reaches the next:
    each run() is in a new process that starts without the parent's modules."""
    pkg = tmp_path / 'fresh_bench_pkg'
    pkg.mkdir()
    (pkg / '__init__.py').write_text('')
    (pkg / 'bench_where.py').write_text(
        '"""Where it ran."""\nimport os, sys\n'
        'def run():\n'
        '    with open(%r, "a") as f:\n'
        '        f.write("%%d %%d\\n" %% (os.getpid(), "fresh_bench_marker" in sys.modules))\n'
        '    return {"where.x": 1.0}\n' % str(tmp_path / 'runs.txt'))
    (pkg / 'bench_boom.py').write_text('def run():\n    raise ValueError("child says no")\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(sys.modules, 'fresh_bench_marker', types.ModuleType('marker'))

    def load(name):
        return bench_main.fresh_process_module(name, package='fresh_bench_pkg')
    figures, sources, failed = bench_main.collect(['bench_where', 'bench_where', 'bench_boom'],
                                                  load=load)
    assert figures == {'where.x': 1.0}
    assert sources == {'where.x': 'bench_where: Where it ran.'}
    assert failed == {'bench_boom': 'ValueError: child says no'}
    runs = [line.split() for line in (tmp_path / 'runs.txt').read_text().splitlines()]
    pids = [int(pid) for pid, _ in runs]
    assert len(pids) == 2 and len(set(pids)) == 2 and os.getpid() not in pids
    assert [marker for _, marker in runs] == ['0', '0']     # nothing of the parent's


def test_each_run_writes_a_fresh_file(tmp_path, monkeypatch):
    out = tmp_path / 'bench_results.json'
    out.write_text(json.dumps({'stale.figure': 42.0}))
    monkeypatch.setattr(bench_main, 'discover', lambda: ['bench_quiet'])
    monkeypatch.setattr(bench_main, 'collect', lambda modules: ({'quiet.figure': 1.0}, {}, {}))
    assert bench_main.main(['--only', 'quiet', '--out', str(out)]) == 0
    results = json.loads(out.read_text())
    assert 'stale.figure' not in results and results['quiet.figure'] == 1.0
    assert results['_failed'] == {} and results['_run']['modules'] == ['bench_quiet']


@pytest.mark.parametrize('only', [['no_such_area'], ['gesture', 'gestures'], []])
def test_an_unknown_or_empty_only_is_refused_before_anything_runs(only, tmp_path, capsys):
    out = tmp_path / 'bench_results.json'
    out.write_text(json.dumps({'earlier.figure': 42.0}))
    with pytest.raises(SystemExit) as stop:
        bench_main.main(['--only', *only, '--out', str(out)])
    assert stop.value.code == 2
    assert json.loads(out.read_text()) == {'earlier.figure': 42.0}
    if only:
        assert 'no benchmark %s (areas: ' % only[-1] in capsys.readouterr().err


def test_only_takes_the_module_name_too(monkeypatch, tmp_path):
    ran = []
    monkeypatch.setattr(bench_main, 'collect', lambda modules: (ran.extend(modules), ({}, {}, {}))[1])
    assert bench_main.main(['--only', 'bench_gesture', 'drone', '--out', str(tmp_path / 'r.json')]) == 0
    assert ran == ['bench_drone', 'bench_gesture']


@pytest.mark.parametrize('argv, why', [
    (['--rtf', '0.2'], '--rtf must be between 0.25 and 10'), (['--rtf', 'nan'], '--rtf must be between'),
    (['--rtf', '0.3'], '--rtf 0.3 gives ~hand_timeout = 0.045'),
    (['--rtf', '8'], '--rtf 8 gives ~resubscribe_silent_after = 64'),
    (['--resubscribe-after', '40', '--rtf', '2'], '--rtf 2 gives ~resubscribe_after = 80')])
def test_a_soak_refuses_a_real_time_factor_its_timeouts_cannot_follow(argv, why, capsys, monkeypatch):
    # --rtf 0.2 scaled the arm's input_timeout to 0.04 s, under its 0.05 s floor: the arm
    # nodes refused it and the soak's graph never started (and 0.3 the pilot's, 8 the
    # consumers' resubscribe_silent_after).
    from tools import soak
    monkeypatch.setattr(soak, 'run', lambda *a, **k: pytest.fail('ran'))
    with pytest.raises(SystemExit) as e:
        soak.main(argv)
    assert e.value.code == 2 and why in capsys.readouterr().err


def test_every_real_time_factor_the_soak_takes_gives_timeouts_the_nodes_take():
    from tools import soak
    for rtf in (0.34, 0.5, 1.0, 2.0, 7.0):
        assert soak.timeouts_problem(rtf, 0.5) is None, rtf


@pytest.mark.parametrize('outcome', ['measured', 'raised'])
def test_each_soak_writes_a_fresh_file_of_its_own(tmp_path, monkeypatch, outcome):
    from tools import soak
    def run(minutes, rtf, rate_hz=None, log=print, **options):
        assert options == {'player_queue': 2000, 'hand_queue': 500, 'command_queue': 50,
                           'joint_states_queue': 100, 'burst_minutes': 0.0, 'burst_hogs': 2,
                           'resubscribe_after': 0.5}
        if outcome == 'raised':
            raise SystemExit('[soak] the graph died: ur10_sim')
        return ({'soak.dropped_msgs': 0, 'soak.rss_growth_pct': 1.5,
                 'soak.arm_latency_drift_ms': math.nan},
                {'soak.dropped_msgs': 'sent minus received', 'soak.rss_growth_pct': 'VmRSS',
                 'soak.arm_latency_drift_ms': 'medians'})
    monkeypatch.setattr(soak, 'run', run)
    out = tmp_path / 'soak_results.json'
    out.write_text(json.dumps({'soak.dropped_msgs': 7, 'soak.sim_minutes': 30.0}))
    assert soak.main(['--minutes', '0.5', '--out', str(out)]) == 1
    results = json.loads(out.read_text())
    assert 'soak.sim_minutes' not in results and results['_run']['minutes'] == 0.5
    if outcome == 'raised':
        assert 'soak.dropped_msgs' not in results
        assert results['_failed'] == {'soak': 'SystemExit: [soak] the graph died: ur10_sim'}
    else:
        assert results['soak.dropped_msgs'] == 0 and results['soak.rss_growth_pct'] == 1.5
        assert results['_sources'] == {'soak.dropped_msgs': 'sent minus received',
                                       'soak.rss_growth_pct': 'VmRSS'}
        assert list(results['_failed']) == ['soak.arm_latency_drift_ms']


@pytest.mark.parametrize('args', [['--hand-queue', '0'], ['--player-queue', '-1'],
                                  ['--command-queue', '0'], ['--joint-states-queue', '2001'],
                                  ['--burst-minutes', '61'], ['--burst-hogs', '17'],
                                  ['--resubscribe-after', '-0.1']])
def test_the_soak_refuses_options_out_of_range(args, capsys):
    from tools import soak
    with pytest.raises(SystemExit) as e:
        soak.main(args)
    assert e.value.code == 2 and args[0] in capsys.readouterr().err


def test_cycles_after_a_load_burst_are_those_that_began_after_it():
    from tools.soak import LoadBurst
    assert LoadBurst(0.0, 2, print).after(4) == [0, 1, 2, 3]     # no burst: every cycle
    burst = LoadBurst(1.0, 2, print)
    assert burst.after(4) == []                                   # not over yet: none
    burst.ended_in_cycle = 1
    assert burst.after(4) == [2, 3]


def test_the_median_interval_narrows_with_rounds_and_holds_the_median():
    rng = np.random.default_rng(7)
    few, many = rng.normal(1.0, 2.0, 10), rng.normal(1.0, 2.0, 40)
    lo10, hi10 = median_ci(few)
    lo40, hi40 = median_ci(many)
    assert lo10 <= np.median(few) <= hi10 and lo40 <= np.median(many) <= hi40
    assert hi40 - lo40 < hi10 - lo10
    assert hi40 - lo40 < 2.0               # what 40 rounds of this spread resolve
    assert median_ci(many) == (lo40, hi40)  # fixed seed: the same figures every run
    assert median_ci([1.5] * 12) == (1.5, 1.5)


def record(frame_ids, window=(0.0, 5.0)):
    return {'frame_id': list(frame_ids), 'window': list(window)}


def test_max_rate_counts_frames_received():
    full = {120: record(range(600)), 200: record(range(1000))}
    assert received_hz(full[200]) == pytest.approx(200.0)
    assert max_rate_no_drop(full) == 200
    # A gap (lost frames) or a sender that only managed 150 Hz (no gap) do not count.
    assert max_rate_no_drop({120: record(range(600)),
                             200: record(list(range(500)) + list(range(510, 1000)))}) == 120
    assert max_rate_no_drop({120: record(range(600)), 200: record(range(750))}) == 120
    assert max_rate_no_drop({120: record(range(100))}) == 0


def test_a_lost_reply_weighs_in_the_tail():
    times = np.full(98, 0.001)
    assert _p99_ms(times) == pytest.approx(1.0)
    assert _p99_ms(np.append(times, [0.8, 0.9])) > 700.0   # slow replies stay in the tail
    assert _p99_ms(times, lost=2) == math.inf


def test_the_arms_lost_replies_are_its_own_not_the_bare_echos(monkeypatch):
    import contextlib

    from tools.bench import bench_arm, ros_processes
    monkeypatch.setattr(ros_processes, 'ros_master', contextlib.contextmanager(lambda: (yield {})))
    monkeypatch.setattr(ros_processes, 'spawn_node', lambda env, args: None)
    monkeypatch.setattr(ros_processes, 'stop_spawned', lambda proc: None)
    rounds = {'arm': [[0.002] * 150] * 4, 'bare': [[0.001] * 147] * 4}
    monkeypatch.setattr(bench_arm, '_round_trips', lambda env, r, c: {
        'rounds': rounds, 'lost': {'arm': 0, 'bare': 3}, 'count': 150})
    figures = bench_arm._latency(rounds=4)
    assert figures['arm.latency_replies_lost'] == 0 and figures['arm.bare_echo_replies_lost'] == 3


def test_a_spawned_node_that_writes_much_to_stderr_does_not_block():
    # A pipe nobody drains fills after 64 KiB and blocks the writer at its next line.
    import subprocess
    import sys

    from tools.bench import ros_processes
    proc = ros_processes.spawn_node({}, [sys.executable, '-c',
                                         'import sys; sys.stderr.write("warning\\n" * 100000)'])
    try:
        assert proc.wait(30) == 0
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError('the node blocked writing its stderr')
    ros_processes.stop_spawned(proc)
    assert proc.stderr.read() == b'warning\n' * 100000       # kept, to read afterwards
