"""Recording source, LeapJS reader / writer, recorder, and the Leap / LeapC backends
with fake SDK modules."""
import json
import math
import os
import sys
import threading
import time
import types

import numpy as np
import pytest

from leap_teleop.hands import record_frames
from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures.datasets import data_dir
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.sources import SourceError, leapjs, make_source
from leap_teleop.hands.tracker import HandTracker

DATA = data_dir()
need_data = pytest.mark.usefixtures('leapjs_data')     # fails without the shared recordings


def test_lz_decoder_matches_the_reference_package():
    import lzstring
    ref = lzstring.LZString()
    rng = np.random.default_rng(0)
    samples = ['', 'a', 'hello hello hello', json.dumps({'frames': [[1, 2.5, 'x']] * 50}),
               ''.join(chr(c) for c in rng.integers(32, 2000, 3000))]
    for text in samples[1:]:
        assert leapjs.lz_decompress_base64(ref.compressToBase64(text)) == text
    with pytest.raises(ValueError):
        leapjs.lz_decompress_base64('!!!not base64!!!')


def test_found_a_small_compressed_recording_cannot_expand_to_gigabytes(tmp_path, monkeypatch):
    # Before: 32 KB of LZString expanded to 370 MB (gzip: up to ~1000 times its size) with
    # no limit; now at most MAX_EXPANSION times the file, or MIN_EXPANDED.
    import gzip

    import lzstring
    text = '{"frames": [' + 'a' * 100000 + ']}'
    lz = lzstring.LZString().compressToBase64(text)
    assert len(text) > 100 * len(lz)                 # expands like a bomb
    with pytest.raises(ValueError, match='expands beyond 5000'):
        leapjs.lz_decompress_base64(lz, max_chars=5000)
    assert leapjs.lz_decompress_base64(lz, max_chars=len(text)) == text
    monkeypatch.setattr(leapjs, 'MIN_EXPANDED', 10000)
    monkeypatch.setattr(leapjs, 'MAX_EXPANSION', 20)
    (tmp_path / 'bomb.json.lz').write_text(lz)
    (tmp_path / 'bomb.json.gz').write_bytes(gzip.compress(text.encode()))
    for name in ('bomb.json.lz', 'bomb.json.gz'):
        with pytest.raises(SourceError, match='expands beyond'):
            leapjs.read_text(str(tmp_path / name))
    # LZString inside gzip: the limit is the file's as stored, not the gunzipped text's
    (tmp_path / 'bomb2.json.lz').write_bytes(gzip.compress(lz.encode()))
    with pytest.raises(SourceError, match='expands beyond'):
        leapjs.read_text(str(tmp_path / 'bomb2.json.lz'))
    # a real take's expansion (about 3 times) passes the same limits
    small = json.dumps({'frames': [[k, 0.5 * k] for k in range(300)]})
    (tmp_path / 'ok.json.gz').write_bytes(gzip.compress(small.encode()))
    assert leapjs.read_text(str(tmp_path / 'ok.json.gz')) == small.encode()


def test_a_small_gzip_recording_reads_without_allocating_the_whole_limit(tmp_path):
    import gzip
    import tracemalloc
    text = json.dumps({'frames': [[k, 0.5 * k] for k in range(300)]})
    (tmp_path / 'ok.json.gz').write_bytes(gzip.compress(text.encode()))
    tracemalloc.start()
    try:
        assert leapjs.read_text(str(tmp_path / 'ok.json.gz')) == text.encode()
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 32 << 20, peak        # MIN_EXPANDED is 256 MiB


@need_data
def test_every_shared_recording_reads_in_every_encoding():
    takes = sorted(f[:-len('.json.lz')] for f in os.listdir(DATA) if f.endswith('.json.lz'))
    assert len(takes) == 13
    for take in takes:
        lz = make_source('recording', path=os.path.join(DATA, take + '.json.lz'), realtime=False)
        gz = make_source('recording', path=os.path.join(DATA, 'decoded', take + '.json.gz'),
                         realtime=False, clock=lambda: 100.0)
        a, b = list(lz.frames()), list(gz.frames())
        assert len(a) == len(b) == int(lz.metadata['frames']) and len(a) > 50
        assert b[0].timestamp == 100.0 and all(y.timestamp > x.timestamp for x, y in zip(b, b[1:]))
        assert any(f.hands for f in b)
        h = next(h for f in b for h in f.hands)
        assert h.side in ('right', 'left') and len(h.fingers) == 5
        assert np.all(np.isfinite(h.palm_position)) and np.all(np.isfinite(h.fingers[1].pip))
        if take == 'finger-tap-54fps':       # packed format 2: no extended flag
            assert lz.metadata['formatVersion'] == 2 and h.fingers[1].extended is None
        else:
            assert isinstance(h.fingers[1].extended, bool)


@need_data
def test_sdk_gestures_pass_through():
    src = make_source('recording', path=os.path.join(DATA, 'flapping.json.lz'), realtime=False)
    types_ = {g['type'] for f in src.frames() for g in f.gestures}
    assert {'circle', 'swipe', 'keyTap'} <= types_


def _write(tmp_path, name, frames, meta=None):
    path = str(tmp_path / name)
    leapjs.save(path, frames, meta)
    return path


def _frames(n=30, dt_us=10000):
    return [leapjs.frame_to_dict(Frame(i, 5.0 + i * dt_us * 1e-6,
                                       [render_hand('right', 'open', (i, 200, 0))])) for i in range(n)]


def test_realtime_pacing_loop_and_clock_mapping(tmp_path):
    path = _write(tmp_path, 'r.json', _frames(30, 10000))    # 0.29 s
    t0 = time.monotonic()
    # a clock at real time: a stopped one stamps every frame with its time
    src = make_source('recording', path=path, realtime=True, loop=True,
                      clock=lambda: 1000.0 + (time.monotonic() - t0))
    got = []
    for f in src.frames():
        got.append(f)
        if len(got) == 60:
            break
    elapsed = time.monotonic() - t0
    assert 0.5 < elapsed < 2.0                                # two passes of 0.29 s + a period
    stamps = [f.timestamp for f in got]
    assert stamps[0] == pytest.approx(1000.0, abs=0.05) and all(b > a for a, b in zip(stamps, stamps[1:]))
    np.testing.assert_allclose(np.diff(stamps[28:33]), 0.01, atol=1e-5)
    assert got[29].hands and not got[30].hands             # a hand-less frame between passes
    assert got[31].hands[0].palm_position[0] == pytest.approx(0.0)


def test_realtime_play_follows_a_caller_clock_faster_than_real_time(tmp_path):
    # Under /use_sim_time with a simulator at 3x real time the stamps advanced at the
    # recorded pace, falling behind the graph's clock: the arm refused every frame as late.
    path = _write(tmp_path, 'r.json', _frames(40, 10000))    # 0.39 s
    t0 = time.monotonic()

    def sim_clock():
        return 1000.0 + 3.0 * (time.monotonic() - t0)
    stamps, lags = [], []
    for f in make_source('recording', path=path, realtime=True, clock=sim_clock).frames():
        lags.append(sim_clock() - f.timestamp)
        stamps.append(f.timestamp)
    assert len(stamps) == 40 and all(b > a for a, b in zip(stamps, stamps[1:]))
    assert 0.0 <= min(lags) and max(lags) < 0.1
    # played at the recorded pace all the same
    assert time.monotonic() - t0 > 0.35


def test_a_looped_take_or_a_break_loses_the_hand_and_starts_a_new_session(tmp_path):
    # The same hand ids in every pass: without a frame between them the tracker followed
    # one hand jumping 150 mm back in a frame, with its origin kept.
    script = tmp_path / 's.yaml'
    script.write_text('rate_hz: 60\nhands:\n  right:\n'
                      '    - {pose: thumbs_up, palm: [0, 200, 0], duration: 0.5}\n'
                      '    - {pose: rock, duration: 0.4}\n'
                      '    - {pose: open, palm: [150, 200, 0], duration: 1.0}\n'
                      '    - {pose: open, duration: 0.3}\n')
    frames = [leapjs.frame_to_dict(f) for f in make_source('scripted', script=str(script),
                                                             realtime=False).frames()]
    n = len(frames)
    for name, loop, recorded in (('loop.json', True, frames), ('joined.json', False, frames + frames)):
        src = make_source('recording', path=_write(tmp_path, name, recorded), loop=loop,
                          realtime=False, clock=lambda: 1000.0)
        tracker = HandTracker('right')
        states, stamps = [], []
        for f in src.frames():
            states.append(tracker.update(f.hand('right'), f.timestamp, f.id))
            stamps.append(f.timestamp)
            if len(states) == 2 * n + 1:
                break
        src.stop()
        assert len(states) == 2 * n + 1 and all(b > a for a, b in zip(stamps, stamps[1:]))
        end, seam, again = states[n - 1], states[n], states[n + 1]
        assert end.present and end.origin_set and end.palm_position[0] == pytest.approx(150, abs=1)
        assert not seam.present and not seam.origin_set and [e.gesture for e in seam.events] == ['hand_lost']
        assert again.present and not again.origin_set and again.palm_position[0] == pytest.approx(0, abs=1)
        assert [e.gesture for e in again.events][:1] == ['hand_found']
        assert seam.timestamp - end.timestamp == pytest.approx(again.timestamp - seam.timestamp)


def test_stop_from_another_thread(tmp_path):
    path = _write(tmp_path, 'r.json.gz', _frames(10, 100000))   # 1 s
    src = make_source('recording', path=path, loop=True)
    stopped_at = []

    def stop():
        src.stop()
        stopped_at.append(time.monotonic())
    # Judged from when stop() ran, not from when it was due: a loaded machine runs the
    # timer late, and the frames played meanwhile are no fault of the source.
    threading.Timer(0.3, stop).start()
    yielded = [time.monotonic() for _ in src.frames()]
    end = time.monotonic()
    assert stopped_at and len(yielded) >= 2
    assert sum(1 for t in yielded if t > stopped_at[0]) <= 1     # at most the frame under way
    assert end - stopped_at[0] < 0.7


@pytest.mark.parametrize('content,needle', [
    (b'', 'empty'), (b'not base64 at all!', 'LZString'), (b'{"metadata": {}, "frames": [', 'not valid JSON'),
    (b'{"metadata": {}}', 'no "frames"'), (b'{"frames": []}', 'no frames'),
    (b'\x1f\x8b\x08\x00garbage', 'gzip'), (b'{"frames": [{"id": 1}]}', 'timestamp'),
    (b'\xff\xfe\x00bin', 'neither')])
def test_malformed_files_raise_clear_errors(tmp_path, content, needle):
    path = tmp_path / 'bad.json'
    path.write_bytes(content)
    with pytest.raises(SourceError) as e:
        make_source('recording', path=str(path))
    assert needle in str(e.value) and 'bad.json' in str(e.value)


def test_missing_file(tmp_path):
    with pytest.raises(SourceError, match='cannot read'):
        make_source('recording', path=str(tmp_path / 'nope.json.lz'))


def test_truncated_gzip_and_lz(tmp_path):
    good = _write(tmp_path, 'g.json.gz', _frames(50))
    raw = open(good, 'rb').read()
    (tmp_path / 't.json.gz').write_bytes(raw[:len(raw) // 2])
    with pytest.raises(SourceError):
        make_source('recording', path=str(tmp_path / 't.json.gz'))
    lz = _write(tmp_path, 'g.json.lz', _frames(50))
    text = open(lz).read()
    (tmp_path / 't.json.lz').write_text(text[:len(text) // 2])
    with pytest.raises(SourceError):
        make_source('recording', path=str(tmp_path / 't.json.lz'))


def test_a_stamp_days_ahead_or_a_second_take_is_a_break_not_the_end(tmp_path):
    # Measured against the last stamp, one stamp 11.6 days ahead dropped every later frame
    # (and realtime play slept till then), and a second take appended to the file was lost.
    frames = _frames(20, 10000)
    frames[10]['timestamp'] += 10 ** 12
    path = _write(tmp_path, 'r.json', frames + _frames(20, 10000))
    src = make_source('recording', path=path, realtime=False, clock=lambda: 1000.0)
    got = list(src.frames())
    stamps = [f.timestamp for f in got]
    # 40 frames and a hand-less one at each break: on, back, back
    assert len(stamps) == 43 and src.breaks == 3 and src.bad_frames == 0
    assert sum(1 for f in got if not f.hands) == 3
    steps = np.diff(stamps)
    assert np.allclose(steps, 0.01) and src.duration == pytest.approx(0.42)
    # Played in real time, it takes its 0.43 s.
    src = make_source('recording', path=path, realtime=True)
    t0 = time.monotonic()
    assert len(list(src.frames())) == 43 and time.monotonic() - t0 < 2.0


@pytest.mark.parametrize('meta, rate_hz', [({'frameRate': '1.1e+2'}, 110.0), (None, 100.0),
                                           ({'frameRate': 'nan'}, 100.0), ({'frameRate': 1e9}, 100.0)])
@pytest.mark.parametrize('stamps', ['one', 'back'])
def test_a_take_whose_stamps_do_not_advance_is_spaced_by_its_frame_rate(tmp_path, caplog, meta,
                                                                         rate_hz, stamps):
    # All frames with one stamp were played at once, in 0 s with one stamp (frame-counting
    # gesture filters fired, the consumers got the whole take in an instant); going back,
    # every frame was a break with a hand-less frame between.
    frames = _frames(30, 10000)
    for k, f in enumerate(frames):
        f['timestamp'] = 0 if stamps == 'one' else 10 ** 6 - k * 10000
    path = _write(tmp_path, 'r.json', frames, meta)
    src = make_source('recording', path=path, realtime=False, clock=lambda: 1000.0)
    got = list(src.frames())
    assert len(got) == 30 and all(f.hands for f in got) and src.breaks == 0
    assert np.allclose(np.diff([f.timestamp for f in got]), 1 / rate_hz)
    assert src.rate_hz == pytest.approx(rate_hz) and src.duration == pytest.approx(29 / rate_hz)
    said = [r.getMessage() for r in caplog.records if 'do not advance' in r.getMessage()]
    assert len(said) == 1 and ('%g frames/s' % rate_hz) in said[0]
    if meta is None:
        # and in real time it takes its 0.29 s
        src = make_source('recording', path=path, realtime=True)
        t0 = time.monotonic()
        assert len(list(src.frames())) == 30 and 0.25 < time.monotonic() - t0 < 2.0


def test_bad_single_frames_are_skipped_and_counted(tmp_path):
    frames = _frames(10)
    frames[3] = 'garbage'
    frames[5] = {'id': 9, 'timestamp': 'x'}
    frames[7] = dict(frames[7], hands=[{'type': 'right', 'palmPosition': 'oops'}], pointables=5)
    path = tmp_path / 'm.json'
    path.write_text(json.dumps({'metadata': {}, 'frames': frames}))
    src = make_source('recording', path=str(path), realtime=False)
    got = list(src.frames())
    assert len(got) == 7 and src.bad_frames == 3


def test_a_recordings_sizes_and_time_visible_beyond_any_hand_are_unmeasured():
    # A corrupt sphereRadius (or sphereCenter, width, timeVisible) of 1e300 went on into the
    # driver's Human's float32 fields and ended the sender; one within bounds (2000 mm, as
    # a joint; 1e7 s) is kept.
    d = leapjs.frame_to_dict(Frame(id=1, timestamp=2.0, hands=[
        render_hand('right', 'open', [0.0, 200.0, 0.0], hand_id=3)]))
    h, pointables = d['hands'][0], d['pointables']
    h.update(sphereRadius=1e300, palmWidth=2001.0, sphereCenter=[0.0, 3000.0, 0.0],
             timeVisible=1e300)
    pointables[0]['width'], pointables[1]['width'] = 1e300, 2000.0
    hand = leapjs.frame_from_dict(d).hands[0]
    assert (hand.sphere_radius, hand.palm_width, hand.sphere_center, hand.time_visible) == (None,) * 4
    assert (hand.fingers[0].width, hand.fingers[1].width) == (None, 2000.0)
    h.update(sphereRadius=2000.0, sphereCenter=[-2000.0, 2000.0, 0.0], timeVisible=1e7)
    hand = leapjs.frame_from_dict(d).hands[0]
    assert (hand.sphere_radius, hand.time_visible) == (2000.0, 1e7)
    assert hand.sphere_center.tolist() == [-2000.0, 2000.0, 0.0]
    # Written as read: another source's value beyond the bounds is left out of a file.
    hand.sphere_radius, hand.time_visible, hand.fingers[1].width = 1e300, 2e7, 1e39
    hand.sphere_center = np.array([0.0, 0.0, 1e300])
    back = leapjs.frame_to_dict(Frame(id=1, timestamp=2.0, hands=[hand]))
    assert not {'sphereRadius', 'sphereCenter', 'timeVisible'} & set(back['hands'][0])
    assert 'width' not in back['pointables'][1]


def test_recorder_round_trip_from_the_scripted_source(tmp_path):
    script = tmp_path / 's.yaml'
    script.write_text('rate_hz: 100\nhands:\n  right:\n    - {pose: fist, palm: [10, 220, 5], duration: 0.3}\n'
                      '    - {pose: open, duration: 0.3}\n  left:\n    - {pose: pinch, value: 0.4, duration: 0.6}\n')
    for ext in ('json', 'json.gz', 'json.lz'):
        out = str(tmp_path / ('rec.' + ext))
        assert record_frames.main([out, '--source', 'scripted', '--script', str(script),
                                   '--realtime', '0']) == 0
        src = make_source('recording', path=out, realtime=False)
        frames = list(src.frames())
        assert len(frames) == 60 and src.metadata['source'] == 'scripted'
        orig = list(make_source('scripted', script=str(script), realtime=False).frames())
        for a, b in zip(orig, frames):
            for ha in a.hands:
                hb = b.hand(ha.side)
                assert np.allclose(ha.palm_position, hb.palm_position, atol=1e-4)
                assert np.allclose(ha.fingers[2].tip, hb.fingers[2].tip, atol=1e-4)
                assert hb.fingers[2].extended == ha.fingers[2].extended
                assert hb.pinch_strength == pytest.approx(ha.pinch_strength)


def test_recorder_reports_a_missing_sdk(tmp_path, capsys):
    assert record_frames.main([str(tmp_path / 'x.json'), '--source', 'leapc']) == 2
    assert 'leap' in capsys.readouterr().err


@pytest.mark.parametrize('args, message', [
    (['--frames', '-5', '{tmp}/f.json'], '--frames -5: 0 (no limit) or more'),
    (['--duration', 'nan', '{tmp}/f.json'], '--duration nan: 0 (no limit) or more seconds'),
    (['--duration', '-1', '{tmp}/f.json'], '--duration -1: 0 (no limit) or more seconds'),
    (['{tmp}/f.txt'], 'output {tmp}/f.txt: name it .json, .json.gz or .json.lz'),
    (['{tmp}/no_dir/f.json'], 'output {tmp}/no_dir/f.json: no folder {tmp}/no_dir'),
])
def test_recorder_refuses_bad_arguments_before_recording(tmp_path, capsys, args, message):
    script = os.path.join(os.path.dirname(__file__), '..', 'config', 'gestures', 'wave_hello.yaml')
    assert record_frames.main(['--source', 'scripted', '--script', script, '--realtime', '0']
                              + [a.format(tmp=tmp_path) for a in args]) == 2
    assert capsys.readouterr().err == 'record_frames: %s\n' % message.format(tmp=tmp_path)
    assert os.listdir(tmp_path) == []


def test_recorder_help_gives_the_whole_first_paragraph(capsys):
    with pytest.raises(SystemExit) as stop:
        record_frames.main(['--help'])
    assert stop.value.code == 0
    assert '(replayable with the recording source, LeapJS Playback and classify_frames).' in ' '.join(
        capsys.readouterr().out.split())


# -- hardware backends with fake SDK modules -----------------------------------------------
class V:
    def __init__(self, x, y, z):
        self.x, self.y, self.z = x, y, z


CARPAL_OFFSET = np.array([0.0, -20.0, 60.0])     # mm: the fake devices' carpal joint from the knuckle


def _fake_leap_v2(device_us=None):
    """device_us(i): frame i's device timestamp (us); by default 120 Hz ones, though the
    fake device runs at 200 frames a second."""
    Leap = types.ModuleType('Leap')

    class Bone:
        TYPE_METACARPAL, TYPE_PROXIMAL, TYPE_INTERMEDIATE, TYPE_DISTAL = 0, 1, 2, 3

        def __init__(self, prev):
            self.prev_joint = prev

    class FakeFinger:
        def __init__(self, t, hand):
            self.type = t
            p = hand.fingers[t]
            self._p = p
            self.tip_position = V(*p.tip)
            self.direction = V(*p.direction)
            self.is_extended = bool(p.extended)

        def bone(self, kind):
            p = self._p
            return Bone(V(*{0: p.mcp + CARPAL_OFFSET, 1: p.mcp, 2: p.pip, 3: p.dip}[kind]))

    class FakeHand:
        def __init__(self, h):
            self.is_right = h.side == 'right'
            self.is_left = not self.is_right
            self.id = 7
            for a, b in (('palm_position', 'palm_position'), ('palm_velocity', 'palm_velocity'),
                         ('palm_normal', 'palm_normal'), ('direction', 'direction')):
                setattr(self, a, V(*getattr(h, b)))
            self.grab_strength, self.pinch_strength, self.confidence = h.grab_strength, h.pinch_strength, 0.9
            self.fingers = [FakeFinger(t, h) for t in range(5)]

    class FakeFrame:
        def __init__(self, i):
            self.id = i
            self.timestamp = device_us(i) if device_us else 1_000_000 + i * 8333
            self.hands = [FakeHand(render_hand('right', 'fist', (0, 200, 0))),
                          FakeHand(render_hand('left', 'open', (-50, 200, 0)))]

    class Listener:
        pass

    class Controller:
        def __init__(self):
            self.listeners = []
            self.i = 0
            self._stop = threading.Event()
            threading.Thread(target=self._run, daemon=True).start()

        def _run(self):
            while not self._stop.is_set():
                time.sleep(0.005)
                self.i += 1
                for listener in list(self.listeners):
                    listener.on_frame(self)

        def frame(self):
            return FakeFrame(self.i)

        def add_listener(self, listener):
            self.listeners.append(listener)

        def remove_listener(self, listener):
            self.listeners.remove(listener)
            self._stop.set()

    Leap.Bone, Leap.Listener, Leap.Controller = Bone, Listener, Controller
    return Leap


def _fake_leapc(device_us=None):
    leap = types.ModuleType('leap')

    class HandType:
        Left, Right = 0, 1

    class TrackingMode:
        Desktop = 0

    def bone(a, b):
        return types.SimpleNamespace(prev_joint=V(*a), next_joint=V(*b))

    def hand(h):
        digits = []
        for f in h.fingers:
            digits.append(types.SimpleNamespace(
                is_extended=bool(f.extended), metacarpal=bone(f.mcp + CARPAL_OFFSET, f.mcp),
                proximal=bone(f.mcp, f.pip),
                intermediate=bone(f.pip, f.dip), distal=bone(f.dip, f.tip)))
        palm = types.SimpleNamespace(position=V(*h.palm_position), velocity=V(*h.palm_velocity),
                                     normal=V(*h.palm_normal), direction=V(*h.direction))
        return types.SimpleNamespace(type=HandType.Left if h.side == 'left' else HandType.Right,
                                     id=3, palm=palm, digits=digits, grab_strength=h.grab_strength,
                                     pinch_strength=h.pinch_strength, confidence=1.0)

    class Listener:
        pass

    class Connection:
        def __init__(self):
            self.listeners = []
            self.mode = None

        def add_listener(self, listener):
            self.listeners.append(listener)

        def set_tracking_mode(self, mode):
            self.mode = mode

        def open(self):
            conn = self

            class Ctx:
                def __enter__(self):
                    conn._stop = threading.Event()

                    def run():
                        i = 0
                        while not conn._stop.is_set():
                            time.sleep(0.005)
                            i += 1
                            ev = types.SimpleNamespace(
                                tracking_frame_id=i,
                                timestamp=device_us(i) if device_us else 2_000_000 + i * 8333,
                                hands=[hand(render_hand('right', 'thumbs_up', (0, 210, 0)))])
                            for listener in conn.listeners:
                                listener.on_tracking_event(ev)
                    threading.Thread(target=run, daemon=True).start()
                    return conn

                def __exit__(self, *exc):
                    conn._stop.set()
                    return False
            return Ctx()

    leap.HandType, leap.TrackingMode, leap.Listener, leap.Connection = HandType, TrackingMode, Listener, Connection
    return leap


def _take(source, n):
    out = []
    for f in source.frames():
        out.append(f)
        if len(out) >= n:
            source.stop()
    return out


def test_leap_v2_backend_with_a_fake_sdk(monkeypatch):
    monkeypatch.setitem(sys.modules, 'Leap', _fake_leap_v2())
    from leap_teleop.hands.leap_interface import LeapInterface
    ticks = iter(range(10 ** 6))            # a clock that moves on: no stamp is after its arrival
    src = make_source('leap', clock=lambda: 50.0 + 0.001 * next(ticks))
    frames = _take(src, 10)
    assert len(frames) == 10
    f = frames[-1]
    assert {h.side for h in f.hands} == {'right', 'left'}
    assert f.timestamp > 50.0 - 1e-9 and frames[1].timestamp - frames[0].timestamp > 0
    li = LeapInterface()
    for fr in frames:
        li.on_frame(fr)
    assert li.get_right_hand_fist() and li.get_left_hand_open()


@pytest.mark.parametrize('name, module, fake', [('leap', 'Leap', _fake_leap_v2),
                                                ('leapc', 'leap', _fake_leapc)])
def test_a_device_keeps_delivering_under_a_sim_clock_faster_than_real_time(monkeypatch, name,
                                                                           module, fake):
    # The sender stamps on rospy.get_time; under /use_sim_time with a simulator at 2x real
    # time, device frames mapped onto that clock fell behind it and, after 0.25 s, every one
    # was dropped as old: the sender published nothing.
    monkeypatch.setitem(sys.modules, module, fake(lambda i: int(time.monotonic() * 1e6)))
    t0 = time.monotonic()

    def sim_clock():
        return 1000.0 + 2.0 * (time.monotonic() - t0)
    src = make_source(name, clock=sim_clock)
    late, lags, stamps = 0, [], []
    timer = threading.Timer(1.5, src.stop)    # stops it even when nothing comes
    timer.start()
    for f in src.frames():
        lags.append(sim_clock() - f.timestamp)
        stamps.append(f.timestamp)
        late += time.monotonic() - t0 > 1.0
    timer.cancel()
    assert late > 20                          # still delivering after a second
    assert max(lags) < 0.25 and min(lags) >= 0.0     # stamped on the sim clock, not ahead
    assert all(b > a for a, b in zip(stamps, stamps[1:]))


def test_a_device_queue_ages_on_the_monotonic_clock_and_stamps_on_the_callers():
    from types import SimpleNamespace

    from leap_teleop.hands.sources.device_queue import PushQueue
    mono, sim = [50.0], [1000.0]
    pq = PushQueue(lambda: sim[0], monotonic=lambda: mono[0])
    got = []
    for i in range(1200):                     # 10 s of a 120 Hz device, the sim at 3x
        mono[0] += 1 / 120
        sim[0] += 3 / 120
        pq.put(SimpleNamespace(id=i, timestamp=pq.stamp(mono[0] * 1e6 - 2000)))
        if i % 2:                             # the consumer takes two at a time
            got += [pq.get(0.0), pq.get(0.0)]
    assert [f.id for f in got] == list(range(1200)) and pq.dropped == 0
    # each stamped at its arrival on the sim clock: its age is 0, or a frame's 25 ms of
    # sim time when taken late
    lags = [sim[0] - f.timestamp for f in got[-2:]]
    assert lags == pytest.approx([3 / 120, 0.0])
    # and a frame older than max_age by the monotonic clock is dropped, whatever the sim's
    pq.put(SimpleNamespace(id=-1, timestamp=pq.stamp(mono[0] * 1e6)))
    mono[0] += 0.3
    assert pq.get(0.0) is None and pq.dropped == 1


def test_leapc_backend_with_a_fake_sdk(monkeypatch):
    monkeypatch.setitem(sys.modules, 'leap', _fake_leapc())
    from leap_teleop.hands.gestures import GestureRecognizer
    frames = _take(make_source('leapc'), 8)
    assert len(frames) == 8 and frames[0].hands[0].side == 'right'
    rec = GestureRecognizer()
    states = [rec.update(f.hands[0], f.timestamp) for f in frames]
    assert states[-1].thumb_up


@pytest.mark.parametrize('name,module', [('leap', 'Leap'), ('leapc', 'leap')])
def test_missing_sdk_names_what_to_install(monkeypatch, name, module):
    monkeypatch.setitem(sys.modules, module, None)      # import fails
    with pytest.raises(SourceError) as e:
        make_source(name)
    assert 'install' in str(e.value) and ('import %s' % module) in str(e.value)


def _same_frames(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert (x.id, x.gestures, len(x.hands)) == (y.id, y.gestures, len(y.hands))
        assert x.timestamp == y.timestamp or (x.timestamp != x.timestamp and y.timestamp != y.timestamp)
        for h, k in zip(x.hands, y.hands):
            assert (h.side, h.id) == (k.side, k.id)
            for name in ('palm_position', 'palm_normal', 'direction', 'palm_velocity'):
                assert np.array_equal(getattr(h, name), getattr(k, name), equal_nan=True)
            for f, g in zip(h.fingers, k.fingers):
                assert f.extended == g.extended
                for name in ('tip', 'direction', 'mcp', 'pip', 'dip', 'carpal'):
                    u, v = getattr(f, name), getattr(g, name)
                    assert (u is None and v is None) or np.array_equal(u, v, equal_nan=True)


@pytest.mark.parametrize('fast', [True, False])
def test_load_frames_matches_frame_by_frame_decoding(tmp_path, monkeypatch, fast, leapjs_data):
    """load_frames (pysimdjson when installed, else the orjson/json tree) decodes exactly
    what load + frame_from_dict does, bad frames included."""
    if not fast:
        monkeypatch.setattr(leapjs, '_simdjson', None)
    else:                 # pinned in tools/requirements.txt: its absence is a broken setup
        assert leapjs._simdjson is not None, 'pysimdjson not installed'
    frames = _frames(12)
    frames[2] = 'garbage'
    frames[4] = {'id': 9, 'timestamp': 'x'}
    frames[6] = dict(frames[6], hands=[{'type': 'right', 'palmPosition': 'oops'}], pointables=5)
    frames[8] = dict(frames[8], pointables=[dict(p, tipPosition=[1, 2]) for p in frames[8]['pointables']])
    frames[9] = dict(frames[9], hands=[dict(h, palmNormal='abc') for h in frames[9]['hands']])
    frames[10] = dict(frames[10], pointables=[dict(p, carpPosition=[k, 150.0, 60.0])
                                              for k, p in enumerate(frames[10]['pointables'])])
    frames[11] = dict(frames[11], pointables=[dict(p, carpPosition=bad) for p, bad in zip(
        frames[11]['pointables'], ([1, 2, 3], 3e3, [1, 'x', 3], None, [0, 1e300, 0]))])
    paths = [_write(tmp_path, 'm.json', frames), _write(tmp_path, 'm.json.lz', frames),
             os.path.join(leapjs_data, 'decoded', 'flapping.json.gz'),
             os.path.join(leapjs_data, 'finger-tap-54fps.json.lz')]
    for path in paths:
        meta, got, errors = leapjs.load_frames(path)
        meta2, dicts = leapjs.load(path)
        want, idx = [], []
        for k, d in enumerate(dicts):
            try:
                want.append(leapjs.frame_from_dict(d))
            except leapjs.FrameError:
                idx.append(k)
        assert meta == meta2 and [k for k, _ in errors] == idx
        _same_frames(got, want)
    assert len(leapjs.load_frames(paths[0])[2]) == 2       # 'garbage' and pointables=5


@pytest.mark.parametrize('fastjson', [True, False])
def test_every_parser_refuses_deep_nesting_and_nan_with_a_clear_error(tmp_path, monkeypatch, fastjson):
    # Without orjson, nesting thousands deep escaped as a RecursionError, and NaN / Infinity
    # (what json.dumps writes) loaded where orjson refused the file.
    monkeypatch.setattr(leapjs, '_simdjson', None)
    if not fastjson:
        monkeypatch.setattr(leapjs, '_fastjson', None)
    frames = _frames(3)
    for name, text in (('deep.json', '[' * 100000 + ']' * 100000),
                       ('nan.json', json.dumps({'frames': [dict(frames[0], timestamp=math.nan)] + frames[1:]})),
                       ('inf.json', json.dumps({'frames': frames}).replace('200.0', '-Infinity', 1))):
        (tmp_path / name).write_text(text)
        with pytest.raises(SourceError, match='%s is not valid JSON' % name):
            make_source('recording', path=str(tmp_path / name))


def test_without_orjson_an_integer_beyond_any_float_is_a_bad_value_not_a_crash(tmp_path, monkeypatch):
    # float() of it raised OverflowError, which escaped the reader as a traceback.
    monkeypatch.setattr(leapjs, '_simdjson', None)
    monkeypatch.setattr(leapjs, '_fastjson', None)
    frames = _frames(3)
    frames[1]['hands'][0]['palmPosition'] = [10 ** 400, 200, 0]
    frames[2]['pointables'] = 5             # and the frame it makes unusable is counted
    frames[2]['hands'][0]['palmVelocity'] = [10 ** 400, 0, 0]
    path = tmp_path / 'huge.json'
    path.write_text(json.dumps({'frames': frames}))
    src = make_source('recording', path=str(path), realtime=False)
    got = list(src.frames())
    assert len(got) == 2 and src.bad_frames == 1
    assert got[0].hands[0].palm_position[1] == pytest.approx(200)
    assert not np.any(np.isfinite(got[1].hands[0].palm_position))     # no palm: no hand


def test_a_hand_of_an_unknown_type_is_skipped_with_one_warning_per_type(caplog):
    from leap_teleop.hands.sources import leapjs
    hand = render_hand('right', 'fist', (0, 200, 0))
    d = leapjs.frame_to_dict(Frame(1, 1.0, [hand]))
    d['hands'][0]['type'] = 'Right (typed by hand)'
    for _ in range(3):
        assert leapjs.frame_from_dict(d).hands == []
    said = [r.getMessage() for r in caplog.records if 'is skipped' in r.getMessage()]
    assert said == ["LeapJS frame: a hand of type 'Right (typed by hand)' (not \"right\" or "
                    "\"left\") is skipped"]
    d['hands'][0]['type'] = 'right'
    assert [h.side for h in leapjs.frame_from_dict(d).hands] == ['right']


@pytest.mark.parametrize('frame_id', [-1, 2 ** 64 + 5, 10 ** 30, 1e30, -2.5])
def test_a_frame_id_outside_the_sdks_is_no_id(frame_id, tmp_path, capsys):
    # A recording's id beyond 64 bits (or negative) reached the uint64 leap_frame_id:
    # recording_to_bag died on a SerializationError, leaving half a bag behind.
    from leap_teleop.ros import recording_to_bag
    assert leapjs.frame_from_dict({'id': frame_id, 'timestamp': 1000, 'hands': []}).id == 0
    assert leapjs.frame_from_dict({'id': 2 ** 63 - 1, 'timestamp': 1000, 'hands': []}).id == 2 ** 63 - 1
    take = tmp_path / 'take.json'
    hand = leapjs.frame_to_dict(Frame(1, 1.0, [render_hand('right', 'open', (0, 200, 0))]))
    frames = [dict(hand, id=(frame_id if k >= 5 else k + 1), timestamp=1000000 + k * 10000)
              for k in range(10)]
    take.write_text(json.dumps({'metadata': {'formatVersion': 1}, 'frames': frames}))
    bag = tmp_path / 'take.bag'
    assert recording_to_bag.main([str(take), str(bag)]) == 0, capsys.readouterr().err
    assert 'wrote %s: 10 frames' % bag in capsys.readouterr().out


def test_a_hand_without_a_palm_position_is_not_written_as_one_at_the_device():
    # A recording's unreadable palm (strings) reads as NaN; written back it became
    # [0, 0, 0]: record_frames and record_gestures kept it as a real hand at the device.
    from leap_teleop.hands.gestures.record import pose_record
    good = render_hand('right', 'open', (0, 200, 0))
    d = leapjs.frame_to_dict(Frame(1, 1.0, [good]))
    bad = leapjs.frame_from_dict(dict(d, hands=[dict(d['hands'][0], palmPosition=['a', 'b', 'c'])]))
    assert not np.all(np.isfinite(bad.hands[0].palm_position))
    out = leapjs.frame_to_dict(Frame(2, 1.0, [bad.hands[0], good]))
    assert len(out['hands']) == 1 and out['hands'][0]['palmPosition'] == pytest.approx([0, 200, 0], abs=1e-3)
    assert {p['handId'] for p in out['pointables']} == {out['hands'][0]['id']}
    assert pose_record(bad, bad.hands[0], 'p', 'open') is None
    assert pose_record(bad, good, 'p', 'open')['frame']['hands']


def test_a_source_that_fails_mid_take_leaves_the_frames_before_it(tmp_path, capsys):
    # Before: a camera failing after minutes of a take left no file at all.
    from leap_teleop.hands.sources.source import HandSource

    class Failing(HandSource):
        def frames(self):
            for i in range(5):
                yield Frame(i + 1, 1.0 + i / 100.0, [render_hand('right', 'open', (0, 200, 0))])
            raise SourceError('camera source: reading failed: gone')

        def stop(self):
            pass
    out = tmp_path / 'take.json'
    with pytest.raises(SourceError, match=r'gone \(the 5 frames before it are in .*take.json\)'):
        record_frames.record(Failing(), str(out))
    assert len(list(make_source('recording', path=str(out), realtime=False).frames())) == 5

    class FailingAtOnce(Failing):
        def frames(self):
            raise SourceError('camera source: reading failed: gone')
            yield
    with pytest.raises(SourceError, match='gone$'):       # nothing taken: nothing written
        record_frames.record(FailingAtOnce(), str(tmp_path / 'none.json'))
    assert not (tmp_path / 'none.json').exists()


def test_a_hand_without_an_id_keeps_its_own_fingers_through_a_recording():
    # Id 0 was written as its list position + 1: here the right hand's id, whose fingers
    # the left hand then read back.
    left = render_hand('left', 'fist', (-30.0, 170.0, 0.0), hand_id=0)
    right = render_hand('right', 'open', (40.0, 160.0, 0.0), hand_id=1)
    back = leapjs.frame_from_dict(leapjs.frame_to_dict(Frame(1, 2.0, [left, right])))
    for before, after in zip((left, right), sorted(back.hands, key=lambda h: h.side)):
        assert after.side == before.side
        np.testing.assert_allclose([f.tip for f in after.fingers],
                                   [f.tip for f in before.fingers], atol=1e-6)
    assert len({h.id for h in back.hands}) == 2
    # Each keeps its id from frame to frame, whoever else is in view: the left hand alone,
    # then listed after the right, was 1 then 2 (a new hand to a reader).
    ids = [{h.side: h.id for h in leapjs.frame_from_dict(leapjs.frame_to_dict(Frame(i, 2.0 + i, hands))).hands}
           for i, hands in enumerate([[left], [right, left], [left, right], [right]])]
    assert ids == [{'left': 2}, {'right': 1, 'left': 2}, {'left': 2, 'right': 1}, {'right': 1}]


def _camera_hands():
    """Camera hands (with their picture landmarks) of a few shared photos."""
    from leap_teleop.hands.gestures.datasets import HANDS_DATA
    from leap_teleop.hands.sources.landmarks import CameraModel, HandLandmarks, hand_from_landmarks
    with open(os.path.join(HANDS_DATA, 'hands.json')) as f:
        images = json.load(f)['images']
    hands = []
    for name in ('fist__htj__22.jpg', 'ok__htj__21.jpg', 'thumbs_up__mps__hand_thumb_up.jpg'):
        entry = images[name]
        cam = CameraModel.from_hfov(entry['width'], entry['height'])
        hands.append(hand_from_landmarks(HandLandmarks.from_dict(entry['hands'][0]), cam, False))
    return hands


@pytest.mark.parametrize('fast', [True, False])
def test_a_camera_hand_replays_with_its_picture_landmarks(tmp_path, monkeypatch, fast):
    # Before: the landmarks were not written, and a replayed camera take was judged by the
    # Leap pose model on its 3-D joints: pinches and fists the take never had.
    from leap_teleop.hands.gestures import GestureRecognizer
    if not fast:
        monkeypatch.setattr(leapjs, '_simdjson', None)
    hands = _camera_hands()
    path = _write(tmp_path, 'cam.json.gz', [leapjs.frame_to_dict(Frame(k + 1, 5.0 + k, [hand]))
                                            for k, hand in enumerate(hands)])
    replayed = [f.hands[0] for f in make_source('recording', path=path, realtime=False).frames()]
    assert len(replayed) == len(hands)
    for hand, again in zip(hands, replayed):
        np.testing.assert_allclose(again.image_landmarks, hand.image_landmarks, atol=1e-3)
        live = GestureRecognizer(stateless=True).update(hand, 0.0)
        replay = GestureRecognizer(stateless=True).update(again, 0.0)
        assert (replay.label, replay.fist, replay.pinch, replay.thumb_up) == \
            (live.label, live.fist, live.pinch, live.thumb_up)


def test_a_recording_says_which_model_judges_its_hands(tmp_path):
    # The sender checked the bindings of every recording against the Leap model, though a
    # camera take's hands are judged by the keypoint model.
    camera = _write(tmp_path, 'cam.json', [leapjs.frame_to_dict(Frame(k + 1, 5.0 + k, [hand]))
                                           for k, hand in enumerate(_camera_hands())])
    leap = _write(tmp_path, 'leap.json', [leapjs.frame_to_dict(
        Frame(k + 1, 5.0 + k, [render_hand('right', 'open', (0, 200, 0))])) for k in range(3)])
    assert make_source('recording', path=camera, realtime=False).hand_family == 'keypoints'
    assert make_source('recording', path=leap, realtime=False).hand_family == 'leap'


@pytest.mark.parametrize('value', [None, [], [[1.0, 2.0]] * 20, [[1.0, 2.0]] * 20 + [[1.0, 'x']],
                                   [[1.0, 2.0]] * 20 + [[1.0, 1e999]], [[1.0, 2.0, 3.0]] * 21,
                                   [[1.0, True]] * 21, {'x': 1}, 'landmarks'])
def test_a_hand_without_usable_picture_landmarks_reads_as_a_leap_hand(value):
    # a LeapJS take has none; a damaged one is no camera hand's
    d = leapjs.frame_to_dict(Frame(1, 5.0, [render_hand('right', 'open', (0, 200, 0))]))
    assert 'imageLandmarks' not in d['hands'][0]
    if value is not None:
        d['hands'][0]['imageLandmarks'] = value
    hand = leapjs.frame_from_dict(d).hands[0]
    assert hand.image_landmarks is None and np.isfinite(hand.palm_position).all()


def test_record_frames_letterboxes_camera_footage_as_the_sender_does(tmp_path, detector_sizes, capsys):
    # Before: record_frames and record_gestures (source_from_args) gave the detector the
    # images as they came, while the sender letterboxes them to 640x480: other hands.
    import cv2

    image = str(tmp_path / 'wide.png')
    cv2.imwrite(image, np.zeros((720, 1280, 3), np.uint8))
    assert record_frames.main([str(tmp_path / 'take.json'), '--source', 'video', '--video', image,
                               '--realtime', '0']) == 0
    assert detector_sizes == [(480, 640, 3)]


def _with_carpals(hand):
    for f in hand.fingers:
        f.carpal = f.mcp + CARPAL_OFFSET
    return hand


def test_the_carpal_joint_is_read_bounded_and_written_back():
    # LeapJS protocol 6 frames carry each finger's carpal joint (carpPosition): it was
    # dropped on reading and never written.
    hand = _with_carpals(render_hand('right', 'open', (0, 200, 0), hand_id=3))
    d = leapjs.frame_to_dict(Frame(1, 2.0, [hand]))
    for f, p in zip(hand.fingers, d['pointables']):
        assert p['carpPosition'] == pytest.approx(f.carpal.tolist(), abs=1e-5)
    back = leapjs.frame_from_dict(d).hands[0]
    for f, g in zip(hand.fingers, back.fingers):
        np.testing.assert_allclose(g.carpal, f.carpal, atol=1e-5)
    # Sources that do not measure it (scripted, camera, older takes): neither written nor read.
    plain = leapjs.frame_to_dict(Frame(1, 2.0, [render_hand('right', 'open', (0, 200, 0), hand_id=3)]))
    assert not any('carpPosition' in p for p in plain['pointables'])
    assert all(f.carpal is None for f in leapjs.frame_from_dict(plain).hands[0].fingers)
    # A value that is no joint is dropped for that finger only, as the bounds of the others.
    for bad in (1e300, [0.0, 2001.0, 0.0], [0.0, -1e300, 0.0], [1, 2], 'abc', [1, 'x', 3],
                {'x': 1}, [2 ** 70, 0, 0], [10 ** 400, 0, 0], [[1, 2, 3]]):
        p = d['pointables'][2]
        p['carpPosition'] = bad
        fingers = leapjs.frame_from_dict(d).hands[0].fingers
        assert fingers[2].carpal is None, bad
        assert fingers[3].carpal is not None and np.allclose(fingers[2].mcp, hand.fingers[2].mcp, atol=1e-5)
    p['carpPosition'] = [-2000, 2000, 0]                    # at the bound: kept
    assert leapjs.frame_from_dict(d).hands[0].fingers[2].carpal.tolist() == [-2000.0, 2000.0, 0.0]
    # Written as read: another source's value beyond the bound is left out of a file.
    hand.fingers[1].carpal = np.array([0.0, 0.0, 1e300])
    hand.fingers[2].carpal = np.array([math.nan, 0.0, 0.0])
    back = leapjs.frame_to_dict(Frame(1, 2.0, [hand]))['pointables']
    assert ['carpPosition' in p for p in back] == [True, False, False, True, True]


def test_the_shared_protocol_6_take_has_every_carpal_joint(leapjs_data):
    _, frames, _ = leapjs.load_frames(os.path.join(leapjs_data, 'finger-tap-54fps.json.lz'))
    fingers = [f for frame in frames for h in frame.hands for f in h.fingers]
    assert len(fingers) == 445 and all(f.carpal is not None for f in fingers)
    lengths = [np.linalg.norm(f.mcp - f.carpal) for f in fingers]
    # the thumb's metacarpal has length 0 on a Leap; the others are a palm's length
    assert max(lengths[0::5]) < 1.0 and 40.0 < min(lengths[4::5]) and max(lengths) < 90.0


@pytest.mark.parametrize('name, module, fake', [('leap', 'Leap', _fake_leap_v2),
                                                ('leapc', 'leap', _fake_leapc)])
def test_a_take_recorded_from_a_leap_keeps_its_carpal_joints(tmp_path, monkeypatch, name, module, fake):
    # The Leap SDKs measure each metacarpal's base (bone(TYPE_METACARPAL).prev_joint,
    # digit.metacarpal.prev_joint): the sources dropped it.
    monkeypatch.setitem(sys.modules, module, fake())
    for frame in _take(make_source(name), 3):
        for f in (f for h in frame.hands for f in h.fingers):
            np.testing.assert_allclose(f.carpal - f.mcp, CARPAL_OFFSET)
    out = str(tmp_path / 'take.json.gz')
    assert record_frames.record(make_source(name), out, max_frames=3) == 3
    _, frames, errors = leapjs.load_frames(out)
    assert len(frames) == 3 and not errors
    for frame in frames:
        for f in (f for h in frame.hands for f in h.fingers):
            np.testing.assert_allclose(f.carpal - f.mcp, CARPAL_OFFSET, atol=1e-4)
