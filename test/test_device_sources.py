"""The device sources (leapc, leap) and record_frames when the SDK or its service is not
there: stand-in `leap` / `Leap` packages on sys.path, no hardware."""
import logging
import sys
import textwrap

import pytest

from leap_teleop.hands import record_frames
from leap_teleop.hands.gestures import record as record_gestures
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.sources import HandSource, SourceError, make_source

# ultraleap/leapc-python-bindings' leap/__init__.py, reduced to its check for the service's
# leapc_cffi folder: a plain Exception, not an ImportError
LEAPC_NO_CFFI = '''
raise Exception("Error: Unable to find leapc_cffi dir within directory "
                "/usr/lib/ultraleap-hand-tracking-service")
'''
# the bindings when the service does not run: Connection.open() times out (10 s there)
LEAPC_NO_SERVICE = '''
import contextlib
class LeapError(Exception):
    pass
class LeapTimeoutError(LeapError):
    pass
class Listener:
    pass
class Connection:
    def __init__(self, **kw):
        self.listeners = []
    def add_listener(self, listener):
        self.listeners.append(listener)
    @contextlib.contextmanager
    def open(self, *, auto_poll=True, timeout=10):
        raise LeapTimeoutError("Did not received expected event in time")
        yield self
'''


def _stand_in(tmp_path, monkeypatch, name, body):
    """`import name` finds `body` (a package in tmp_path) from now on, in this test only."""
    pkg = tmp_path / 'stand_in' / name
    pkg.mkdir(parents=True)
    (pkg / '__init__.py').write_text(textwrap.dedent(body))
    monkeypatch.setitem(sys.modules, name, None)    # so that the undo removes what it imported
    monkeypatch.delitem(sys.modules, name)
    monkeypatch.syspath_prepend(str(tmp_path / 'stand_in'))


@pytest.mark.parametrize('name, module', [('leapc', 'leap'), ('leap', 'Leap')])
def test_an_sdk_whose_import_raises_a_plain_exception_names_what_to_install(tmp_path, monkeypatch,
                                                                            capsys, name, module):
    # Before: the bindings' own Exception (service not found) went through as a traceback.
    _stand_in(tmp_path, monkeypatch, module, LEAPC_NO_CFFI)
    with pytest.raises(SourceError, match='install.*Unable to find leapc_cffi dir'):
        make_source(name)
    out = tmp_path / 'take.json'
    assert record_frames.main([str(out), '--source', name]) == 2
    err = capsys.readouterr().err
    assert err.startswith('record_frames: the "%s" source needs' % name) and err.count('\n') == 1
    assert not out.exists()


def test_leapc_without_its_service_running_ends_in_one_line(tmp_path, monkeypatch, capsys, caplog):
    # Before: Connection.open()'s LeapTimeoutError ended record_frames and record_gestures
    # with a traceback, and the sender logged it as a bug.
    _stand_in(tmp_path, monkeypatch, 'leap', LEAPC_NO_SERVICE)
    line = ('leapc source: cannot connect to the Ultraleap hand-tracking service (is it installed '
            'and running?): LeapTimeoutError: Did not received expected event in time')
    with pytest.raises(SourceError) as e:
        list(make_source('leapc').frames())
    assert str(e.value) == line

    out = tmp_path / 'take.json'
    assert record_frames.main([str(out), '--source', 'leapc']) == 1
    assert capsys.readouterr().err == 'record_frames: %s\n' % line
    assert not out.exists()

    rows = tmp_path / 'wave.jsonl'
    assert record_gestures.main(['--source', 'leapc', '--label', 'wave', '--out', str(rows)]) == 1
    err = capsys.readouterr().err
    assert line in err and 'Traceback' not in err and not rows.exists()

    with caplog.at_level(logging.DEBUG):                 # the sender's loop
        li = LeapInterface(source=make_source('leapc')).start()
        assert li.finished.wait(5.0)
    assert isinstance(li.error, SourceError) and str(li.error) == line
    assert not [r for r in caplog.records if r.exc_info]


def test_leap_v2_whose_controller_fails_ends_in_one_line(tmp_path, monkeypatch):
    _stand_in(tmp_path, monkeypatch, 'Leap', '''
        class Listener:
            pass
        class Controller:
            def __init__(self):
                raise RuntimeError("cannot reach the Leap service")
    ''')
    with pytest.raises(SourceError, match=r'^leap source: cannot start the Leap Motion controller '
                                          r'.*: RuntimeError: cannot reach the Leap service$'):
        list(make_source('leap').frames())


class _Empty(HandSource):
    """A source that ends before its first frame (a folder of unreadable images, Ctrl-C
    before a device delivered)."""

    def frames(self):
        return iter(())


def test_a_take_without_frames_writes_nothing_and_says_so(tmp_path, monkeypatch, capsys):
    # Before: 'wrote 0 frames', status 0, and a file every reader refuses.
    out = tmp_path / 'take.json'
    assert record_frames.record(_Empty(), str(out)) == 0 and not out.exists()
    monkeypatch.setattr(record_frames, 'source_from_args', lambda args: _Empty())
    assert record_frames.main([str(out), '--source', 'video', '--video', str(tmp_path / 'imgs')]) == 1
    assert capsys.readouterr().err == 'record_frames: no frame from the source: nothing written\n'
    assert not out.exists()


def test_an_lz_take_without_lzstring_is_refused_before_recording(tmp_path, monkeypatch, capsys):
    # Before: found only when saving, after the whole take, which was then lost.
    monkeypatch.setitem(sys.modules, 'lzstring', None)          # not installed

    def no_source(args):
        raise AssertionError('the source was started')
    monkeypatch.setattr(record_frames, 'source_from_args', no_source)
    out = tmp_path / 'take.json.lz'
    assert record_frames.main([str(out), '--source', 'scripted', '--script', 'any.yaml']) == 2
    assert capsys.readouterr().err == (
        'record_frames: output %s: writing .json.lz needs the PyPI package lzstring (pip install '
        'lzstring); or name it .json or .json.gz\n' % out)
    assert not out.exists()
