"""LeapJS Playback files: read, unpack, convert to / from leap_teleop Frames, write.

A recording is ``{"metadata": {...}, "frames": [...]}`` stored as plain JSON (.json),
gzip-compressed JSON (.json.gz) or ``LZString.compressToBase64(json)`` (.json.lz).
formatVersion 0.1 / 1 keeps each frame as the Leap WebSocket frame dict; formatVersion 2
packs frames as positional arrays whose key list is ``frames[0]``.

Leap timestamps are microseconds; Frame.timestamp is seconds. A camera source's hand also
keeps its 21 picture landmarks, ``"imageLandmarks": [[x, y], ...]`` (pixels of the processed
image, MediaPipe order), a field of this project's that LeapJS ignores.
"""
import base64
import gc
import gzip
import io
import itertools
import json
import logging
import math
import os

import numpy as np

try:                       # 4x faster parsing when installed (tools/requirements.txt)
    import orjson as _fastjson
except ImportError:        # pragma: no cover - the stdlib parser is the fallback
    _fastjson = None
try:                       # faster still for whole recordings (load_frames); optional
    import simdjson as _simdjson
except ImportError:        # pragma: no cover
    _simdjson = None

from leap_teleop.hands.frame import FINGER_NAMES, Finger, Frame, TrackedHand
from leap_teleop.hands.skeleton import MAX_JOINT, bounded_point, bounded_size, bounded_time
from leap_teleop.hands.sources.source import SourceError

log = logging.getLogger(__name__)


class FrameError(ValueError):
    """One frame dict cannot be turned into a Frame (the rest of the file may be fine)."""


# -- LZString ---------------------------------------------------------------------------
# Bit-reversal table: LZString reads each 6-bit base64 digit MSB first but assembles
# numbers LSB first; reversing the bits of each decoded byte turns the stream into a
# plain little-endian bit stream that can be read in whole chunks (~8x faster than the
# per-bit `lzstring` package).
_REVERSE = bytes(int('{:08b}'.format(i)[::-1], 2) for i in range(256))
_B64_ALPHABET = set('ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/=')
# A compressed recording may expand to at most this many times its size, and always to
# MIN_EXPANDED: real takes expand about 3 times, while a few crafted kilobytes of
# LZString (whose entries grow by a character each use) or gzip expand to gigabytes.
MAX_EXPANSION = 200
MIN_EXPANDED = 256 << 20


def expansion_limit(compressed_size):
    """Characters (bytes) a compressed recording of `compressed_size` may expand to."""
    return max(MIN_EXPANDED, MAX_EXPANSION * compressed_size)


def lz_decompress_base64(text, max_chars=None):
    """LZString.decompressFromBase64; ValueError when the text is not such a stream or
    expands beyond `max_chars` (default expansion_limit of the text's length)."""
    text = ''.join(text.split())
    if not text:
        raise ValueError('empty LZString text')
    if not set(text) <= _B64_ALPHABET:
        raise ValueError('not LZString base64 (characters outside the base64 alphabet)')
    limit = expansion_limit(len(text)) if max_chars is None else max_chars
    text = text.rstrip('=')
    text += 'A' * (-len(text) % 4)                     # 'A' = six zero bits, as '=' is
    stream = base64.b64decode(text).translate(_REVERSE) + bytes(8)
    n_bits_total = len(text) * 6
    buf, have, pos = 0, 0, 0                             # bit buffer, its size, byte pos
    used = 0

    def read(n):
        nonlocal buf, have, pos, used
        while have < n:
            buf |= int.from_bytes(stream[pos:pos + 6], 'little') << have
            have += 48
            pos += 6
        value = buf & ((1 << n) - 1)
        buf >>= n
        have -= n
        used += n
        return value

    first = read(2)
    if first == 2:
        return ''
    c = chr(read(8 if first == 0 else 16))
    dictionary = ['', '', '', c]
    w = c
    out = [c]
    size = 1
    enlarge_in, num_bits = 4, 3
    append = out.append
    add = dictionary.append
    while True:
        if used > n_bits_total:
            raise ValueError('truncated LZString stream')
        # Inline read(num_bits) for the hot path.
        if have < num_bits:
            buf |= int.from_bytes(stream[pos:pos + 6], 'little') << have
            have += 48
            pos += 6
        code = buf & ((1 << num_bits) - 1)
        buf >>= num_bits
        have -= num_bits
        used += num_bits
        if code < 2:
            add(chr(read(8 if code == 0 else 16)))
            code = len(dictionary) - 1
            enlarge_in -= 1
            if enlarge_in == 0:
                enlarge_in = 1 << num_bits
                num_bits += 1
        elif code == 2:
            return ''.join(out)
        if code < len(dictionary):
            entry = dictionary[code]
        elif code == len(dictionary):
            entry = w + w[0]
        else:
            raise ValueError('corrupt LZString stream (code %d beyond dictionary)' % code)
        append(entry)
        size += len(entry)
        if size > limit:
            raise ValueError('LZString data expands beyond %d characters' % limit)
        add(w + entry[0])
        enlarge_in -= 1
        w = entry
        if enlarge_in == 0:
            enlarge_in = 1 << num_bits
            num_bits += 1


def lz_compress_base64(text):
    """LZString.compressToBase64 (via the `lzstring` package; writing is not hot)."""
    try:
        import lzstring
    except ImportError:
        raise SourceError('writing .json.lz needs the PyPI package lzstring (pip install lzstring)')
    return lzstring.LZString().compressToBase64(text)


# -- files ------------------------------------------------------------------------------
def read_text(path):
    """The JSON text (str or UTF-8 bytes) of a recording, whatever its compression."""
    path = str(path)
    try:
        with open(path, 'rb') as f:
            raw = f.read()
    except OSError as e:
        raise SourceError('cannot read recording %s: %s' % (path, e.strerror or e))
    limit = expansion_limit(len(raw))       # of the file as stored, whatever it holds
    if raw[:2] == b'\x1f\x8b':
        raw = _gunzip(raw, limit, path)
    head = raw[:64].lstrip()
    if head[:1] in (b'{', b'['):
        return raw                      # JSON; both parsers take UTF-8 bytes
    try:
        text = raw.decode('ascii')
    except UnicodeDecodeError:
        raise SourceError('recording %s is neither JSON, gzip nor LZString base64 text' % path)
    if not text.strip():
        raise SourceError('recording %s is empty' % path)
    try:
        out = lz_decompress_base64(text, max_chars=limit)
    except ValueError as e:
        raise SourceError('recording %s: not JSON and not valid LZString base64: %s'
                          % (path, e))
    if not out:
        raise SourceError('recording %s: LZString data decodes to nothing' % path)
    return out


def _gunzip(raw, limit, path):
    """The gzip data `raw` decompressed, read in chunks (a read of the whole limit at once
    would allocate it); SourceError when corrupt or beyond `limit` bytes."""
    chunks, size = [], 0
    try:
        with gzip.GzipFile(fileobj=io.BytesIO(raw)) as g:
            while size <= limit:
                chunk = g.read(1 << 22)
                if not chunk:
                    return b''.join(chunks)
                chunks.append(chunk)
                size += len(chunk)
    except (OSError, EOFError, ValueError) as e:
        raise SourceError('recording %s: corrupt gzip data (%s)' % (path, e))
    raise SourceError('recording %s: gzip data expands beyond %d bytes (at most %d times its '
                      'size, or %d MiB)' % (path, limit, MAX_EXPANSION, MIN_EXPANDED >> 20))


def parse_json(text):
    """json.loads, through orjson when it is installed. The cyclic garbage collector is
    paused meanwhile: a recording is hundreds of thousands of fresh containers, none in a
    cycle, and collections triggered while building them cost ~30% of the parse."""
    paused = gc.isenabled()
    if paused:
        gc.disable()
    try:
        if _fastjson is not None:
            try:
                return _fastjson.loads(text)
            except _fastjson.JSONDecodeError as e:
                raise ValueError(str(e))
        # NaN / Infinity refused, as orjson does: a file reads the same with either
        return json.loads(text, parse_constant=_no_constant)
    except RecursionError:              # the stdlib parser on arrays nested thousands deep
        raise ValueError('nested too deeply') from None
    finally:
        if paused:
            gc.enable()


def _no_constant(name):
    raise ValueError('%s is not a JSON value' % name)


def unpack_frames(frames, path='<recording>'):
    """Frame dicts from a `frames` list, unpacking formatVersion 2 when frames[0] is
    the key list. Malformed packed entries become None (counted by the caller)."""
    if not frames or not isinstance(frames[0], list):
        return list(frames)
    keys = frames[0]
    return [_unpack(keys, f) if isinstance(f, list) else None for f in frames[1:]]


def _unpack(keys, values):
    out = {}
    for key, value in zip(keys, values):
        if isinstance(key, str):
            out[key] = value
        elif isinstance(key, dict) and len(key) == 1:
            (name, sub), = key.items()
            if isinstance(sub, list) and len(sub) == 1 and isinstance(sub[0], list):
                # a list of items, each packed with sub[0]
                out[name] = [_unpack(sub[0], v) for v in value if isinstance(v, list)] \
                    if isinstance(value, list) else []
            elif isinstance(sub, list):
                out[name] = _unpack(sub, value) if isinstance(value, list) else {}
    return out


def load(path):
    """(metadata dict, list of frame dicts or None) from a LeapJS recording file.

    SourceError when the file as a whole is unusable; a None entry marks a frame that
    is not a dict (the caller skips and counts those)."""
    return _load_text(read_text(path), path)


def _load_text(text, path):
    try:
        data = parse_json(text)
    except ValueError as e:
        raise SourceError('recording %s is not valid JSON (%s); truncated or not a LeapJS '
                          'recording?' % (path, e))
    if isinstance(data, list):          # a bare list of frames
        data = {'metadata': {}, 'frames': data}
    elif (isinstance(data, dict) and not isinstance(data.get('frames'), list)
          and isinstance(data.get('data'), list)):
        # QuantumLeap's form of its Leap datasets: {"frames": N, "data": [frame, ...]}
        data = {'metadata': {}, 'frames': data['data']}
    if not isinstance(data, dict) or not isinstance(data.get('frames'), list):
        raise SourceError('recording %s has no "frames" list; a LeapJS Playback file is '
                          '{"metadata": {...}, "frames": [...]} (or {"data": [...]})' % path)
    metadata = data.get('metadata') if isinstance(data.get('metadata'), dict) else {}
    frames = [f if isinstance(f, dict) else None for f in unpack_frames(data['frames'], path)]
    if not frames:
        raise SourceError('recording %s holds no frames' % path)
    return metadata, frames


def load_frames(path):
    """(metadata, frames, errors) from a LeapJS recording file, decoded once: frames are
    Frames stamped with their recorded time (s), in file order; errors lists (index,
    reason) of the frames that could not be decoded (skipped).

    SourceError when the file as a whole is unusable. Speed: with pysimdjson installed,
    the document is parsed without building Python objects and each frame becomes a
    dict only while it is converted (~20% faster than materialising the whole tree).
    The cyclic garbage collector is paused meanwhile: it would walk the hundreds of
    thousands of fresh containers again and again for nothing (none is in a cycle)."""
    text = read_text(path)
    paused = gc.isenabled()
    if paused:
        gc.disable()
    try:
        out = _load_frames_simdjson(text) if _simdjson is not None else None
        if out is None:
            metadata, dicts = _load_text(text, path)
            out = _convert(metadata, dicts)
            del dicts
    finally:
        if paused:
            gc.enable()
    return out


def _convert(metadata, dicts):
    frames, errors = [], []
    for k, d in enumerate(dicts):
        if d is None:
            errors.append((k, 'frame is not a JSON object'))
            continue
        try:
            frames.append(frame_from_dict(d))
        except (FrameError, TypeError, ValueError, OverflowError) as e:
            errors.append((k, str(e) or e.__class__.__name__))
    return metadata, frames, errors


def _load_frames_simdjson(text):
    """load_frames' result through pysimdjson, or None to let the reference path (and
    its error messages) handle the file: not parseable by simdjson, not a plain
    formatVersion 0.1 / 1 recording."""
    Array, Object = _simdjson.Array, _simdjson.Object
    try:
        doc = _simdjson.Parser().parse(text)
        if isinstance(doc, Array):
            metadata, frames = {}, doc
        elif isinstance(doc, Object):
            metadata, frames = doc.get('metadata'), doc.get('frames')
            metadata = metadata.as_dict() if isinstance(metadata, Object) else {}
        else:
            return None
        if not isinstance(frames, Array) or not len(frames) or isinstance(frames[0], Array):
            return None                  # not a frame list, or packed (format 2)
        dicts = (f.as_dict() if isinstance(f, Object) else None for f in frames)
        return _convert(metadata, dicts)
    except (ValueError, RuntimeError):  # simdjson's own errors: an integer beyond 64 bits
        return None


# -- frame dict <-> Frame ---------------------------------------------------------------
_NAN3 = (math.nan, math.nan, math.nan)


def _v3(value):
    """A 3-tuple of floats, or None when absent / malformed."""
    if isinstance(value, (list, tuple)) and len(value) == 3:
        try:
            return (float(value[0]), float(value[1]), float(value[2]))
        except (TypeError, ValueError, OverflowError):     # an integer beyond any float
            return None
    return None


def _num(value, default):
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):     # an integer beyond any float
        return default
    return x


def _is_id(value):
    """Whether a hand id or a finger's handId can be one (a list or an object cannot)."""
    return value is None or isinstance(value, (int, float, str))


def frame_from_dict(d, timestamp=None):
    """A Frame from one LeapJS frame dict; fields that are missing get defaults (SDK flags
    None, finger positions NaN). FrameError when it is not a frame at all."""
    if not isinstance(d, dict):
        raise FrameError('frame is not a JSON object')
    if timestamp is None:
        ts = _num(d.get('timestamp'), math.nan)
        timestamp = ts * 1e-6
    frame_id = d.get('id', 0)
    if not isinstance(frame_id, int) or isinstance(frame_id, bool):
        frame_id = int(_num(frame_id, 0.0)) if math.isfinite(_num(frame_id, math.nan)) else 0
    if not 0 <= frame_id < 2 ** 63:     # the SDK's ids count up from 0 in 64 signed bits
        frame_id = 0
    hands_raw = d.get('hands') or []
    pointables = d.get('pointables') or []
    if not isinstance(hands_raw, list) or not isinstance(pointables, list):
        raise FrameError('frame "hands" / "pointables" must be lists')
    by_hand = {}
    for p in pointables:
        if isinstance(p, dict) and not p.get('tool', False) and _is_id(p.get('handId')):
            by_hand.setdefault(p.get('handId'), []).append(p)
    hands = []
    for h in hands_raw:
        if not isinstance(h, dict):
            continue
        side = h.get('type')
        if side not in ('right', 'left'):
            _say_unknown_side(side)
            continue
        hand_id = h.get('id')
        hands.append(_hand_from_dict(h, side, by_hand.get(hand_id, ()) if _is_id(hand_id) else (),
                                     timestamp))
    gestures = [g for g in (d.get('gestures') or []) if isinstance(g, dict)] \
        if isinstance(d.get('gestures'), list) else []
    return Frame(id=frame_id, timestamp=timestamp, hands=hands, gestures=gestures)


def _say_unknown_side(side):
    """Warn once per value (a recording repeats it in every frame) that a hand is skipped."""
    key = repr(side)[:40]
    if key not in _SAID_SIDES and len(_SAID_SIDES) < 20:
        _SAID_SIDES.add(key)
        log.warning('LeapJS frame: a hand of type %s (not "right" or "left") is skipped', key)


_SAID_SIDES = set()
_LEN3, _LIST = {3}, {list}
_chain = itertools.chain.from_iterable
_FINGER_KEYS = ('tipPosition', 'direction', 'mcpPosition', 'pipPosition', 'dipPosition')


def _time_visible(value, timestamp):
    """A hand's timeVisible (s); None when absent, beyond skeleton.MAX_TIME_VISIBLE_S, or
    the frame's own timestamp (s, to 6 digits): LeapJS Playback 0.1 recorded that in every
    other frame, and a hand tracked since the service started is not a case worth keeping
    it for."""
    tv = bounded_time(value)
    if tv is not None and math.isfinite(timestamp) and abs(tv - timestamp) <= 1e-4 * abs(timestamp):
        return None
    return tv


def _hand_from_dict(h, side, pointables, timestamp=math.nan):
    by_type = [None] * 5
    for p in pointables:
        t = p.get('type')
        if t.__class__ is int and 0 <= t < 5 and by_type[t] is None:
            by_type[t] = p
    # Fast path: every vector present and well-formed -> one numpy call for the hand,
    # whose rows become the TrackedHand's and Fingers' vectors (views).
    have = []
    try:
        rows = [h['palmPosition'], h['palmVelocity'], h['palmNormal'], h['direction']]
        for i, p in enumerate(by_type):
            if p is not None:
                have.append(i)
                rows += (p['tipPosition'], p['direction'], p['mcpPosition'], p['pipPosition'],
                         p['dipPosition'])
        # JSON arrays of 3 each (a 3-char string would iterate as 3 numbers)
        if set(map(len, rows)) != _LEN3 or set(map(type, rows)) != _LIST:
            raise ValueError
        arr = np.fromiter(_chain(rows), float, 3 * len(rows)).reshape(-1, 3)
    except (KeyError, TypeError, ValueError, OverflowError):
        # Slow path: take what is there, NaN for what is not.
        rows = [_v3(h.get('palmPosition')) or _NAN3,
                _v3(h.get('palmVelocity')) or (0.0, 0.0, 0.0),
                _v3(h.get('palmNormal')) or _NAN3, _v3(h.get('direction')) or _NAN3]
        have = []
        for i, p in enumerate(by_type):
            if p is None or _v3(p.get('tipPosition')) is None:
                continue
            have.append(i)
            rows += [_v3(p.get(k)) or _NAN3 for k in _FINGER_KEYS]
        arr = np.array(rows, dtype=float)
    v = list(arr)                       # row views, cheaper than indexing one by one
    fingers = ()
    if have:
        fl = [None] * 5
        b = 4
        for i in have:
            ext = by_type[i].get('extended')
            fl[i] = Finger(v[b], v[b + 1], ext if ext.__class__ is bool else None,
                           v[b + 2], v[b + 3], v[b + 4], bounded_size(by_type[i].get('width')))
            b += 5
        _carpals(fl, have, [by_type[i].get('carpPosition') for i in have])
        if len(have) < 5:
            missing = np.full(3, math.nan)
            fl = [f if f is not None else Finger(tip=missing, direction=missing) for f in fl]
        fingers = tuple(fl)
    hid = h.get('id', 0)
    # The SDK's sphere fit and time tracked (protocol 6 frames; later ones drop the sphere).
    # Bounded as joints are: a corrupt 1e300 went on into the driver's Human's float32 and
    # ended the sender.
    return TrackedHand(side, v[0], v[1], v[2], v[3], _num(h.get('grabStrength'), math.nan),
                _num(h.get('pinchStrength'), math.nan), _num(h.get('confidence'), 1.0),
                fingers, hid if hid.__class__ is int else 0,
                palm_width=bounded_size(h.get('palmWidth')), sphere_radius=bounded_size(h.get('sphereRadius')),
                sphere_center=bounded_point(h.get('sphereCenter')),
                time_visible=_time_visible(h.get('timeVisible'), timestamp),
                image_landmarks=_image_landmarks(h.get('imageLandmarks')))


def _carpals(fingers, have, carps):
    """Set fingers[i].carpal (i in have) from its carpPosition (protocol 6 frames), bounded
    as a joint. Optional, so read apart from _hand_from_dict's rows (a take without it stays
    on that fast path); all five in one numpy call when well-formed (per finger it tripled
    the cost of a frame)."""
    if carps.count(None) == len(carps):
        return
    try:
        if set(map(len, carps)) != _LEN3 or set(map(type, carps)) != _LIST:
            raise ValueError
        arr = np.fromiter(_chain(carps), float, 3 * len(carps)).reshape(-1, 3)
        kept = np.all(np.abs(arr) <= MAX_JOINT, axis=1)       # NaN compares false
        for i, row, ok in zip(have, arr, kept.tolist()):
            if ok:
                fingers[i].carpal = row
    except (TypeError, ValueError, OverflowError):
        for i, carp in zip(have, carps):
            fingers[i].carpal = bounded_point(carp)


def _image_landmarks(value):
    """A camera hand's 21 picture landmarks ((21, 2) pixels) from a hand dict's
    imageLandmarks (written by frame_to_dict), or None when absent or not 21 pairs of
    finite numbers (a Leap take, a damaged file): the hand is then judged as a Leap's."""
    if value is None or value.__class__ is not list or len(value) != 21:
        return None
    for pair in value:
        if pair.__class__ is not list or len(pair) != 2 or not all(
                v.__class__ in (int, float) for v in pair):
            return None
    try:
        xy = np.array(value, dtype=float)
    except (TypeError, ValueError, OverflowError):      # an integer beyond any float
        return None
    return xy if np.all(np.isfinite(xy)) else None


def _list(v, nd=5):
    a = np.asarray(v, dtype=float).reshape(3)
    return [round(float(x), nd) if math.isfinite(x) else 0.0 for x in a]


def _whole(hand):
    """The palm's position and orientation are numbers: a hand to write."""
    return all(np.all(np.isfinite(np.asarray(v, dtype=float)))
               for v in (hand.palm_position, hand.palm_normal, hand.direction))


SIDE_IDS = {'right': 1, 'left': 2}      # ids written for hands that have none


def frame_to_dict(frame):
    """The LeapJS (formatVersion 1) dict of a Frame; what frame_from_dict reads back. A hand
    without a palm position or orientation (a recording's unreadable values) is left out:
    written as zeros it would read back as a hand at the device."""
    hands, pointables = [], []
    # A hand without an id (0) gets one no other hand of the frame has, its fingers are
    # found by it (k + 1 could be the other hand's, which then read back with these
    # fingers): its side's own (right 1, left 2) when free, so it keeps it from frame to
    # frame (a reader takes a new id for a new hand), else the next free one.
    taken = {hand.id for hand in frame.hands if hand.id}
    for hand in frame.hands:
        if not _whole(hand):
            continue
        hid = hand.id
        if not hid:
            hid = SIDE_IDS.get(hand.side, 1)
            while hid in taken:
                hid += 1
            taken.add(hid)
        h = {
            'id': hid, 'type': hand.side,
            'palmPosition': _list(hand.palm_position), 'palmVelocity': _list(hand.palm_velocity),
            'palmNormal': _list(hand.palm_normal), 'direction': _list(hand.direction),
            'stabilizedPalmPosition': _list(hand.palm_position),
            'grabStrength': _clean(hand.grab_strength), 'pinchStrength': _clean(hand.pinch_strength),
            'confidence': _clean(hand.confidence)}
        # What the source measured, read back as such; left out when it did not, or when
        # it is beyond what frame_from_dict reads.
        for key, value, bounded in (('palmWidth', hand.palm_width, bounded_size),
                                    ('sphereRadius', hand.sphere_radius, bounded_size),
                                    ('timeVisible', hand.time_visible, bounded_time)):
            if bounded(value) is not None:
                h[key] = _clean(value)
        if bounded_point(hand.sphere_center) is not None:
            h['sphereCenter'] = _list(hand.sphere_center)
        # A camera hand's picture landmarks: the keypoint model judges it by them, live and
        # replayed alike (without, a replay judged its 3-D joints with the Leap model).
        xy = _image_landmarks(_as_pairs(getattr(hand, 'image_landmarks', None)))
        if xy is not None:
            h['imageLandmarks'] = [[round(float(x), 3), round(float(y), 3)] for x, y in xy]
        hands.append(h)
        for i, f in enumerate(hand.fingers[:5]):
            if f is None or not np.all(np.isfinite(np.asarray(f.tip, dtype=float))):
                continue
            p = {'id': hid * 10 + i, 'handId': hid, 'type': i, 'tool': False,
                 'tipPosition': _list(f.tip), 'direction': _list(f.direction)}
            if f.extended is not None:
                p['extended'] = bool(f.extended)
            if bounded_size(f.width) is not None:
                p['width'] = _clean(f.width)
            for key, value in (('mcpPosition', f.mcp), ('pipPosition', f.pip),
                               ('dipPosition', f.dip)):
                if value is not None and np.all(np.isfinite(np.asarray(value, dtype=float))):
                    p[key] = _list(value)
            carpal = bounded_point(getattr(f, 'carpal', None))
            if carpal is not None:
                p['carpPosition'] = _list(carpal)
            pointables.append(p)
    ts = frame.timestamp
    return {'id': int(frame.id), 'timestamp': int(round(ts * 1e6)) if math.isfinite(ts) else 0,
            'hands': hands, 'pointables': pointables,
            'gestures': [g for g in frame.gestures if isinstance(g, dict)]}


def _as_pairs(xy):
    """(21, 2+) landmarks as a list of [x, y] lists, or None."""
    if xy is None:
        return None
    try:
        a = np.asarray(xy, dtype=float)
    except (TypeError, ValueError):
        return None
    return a[:, :2].tolist() if a.ndim == 2 and a.shape[1] >= 2 else None


def _clean(x):
    try:
        x = float(x)
    except (TypeError, ValueError):
        return 0.0
    return round(x, 6) if math.isfinite(x) else 0.0


def save(path, frame_dicts, metadata=None):
    """Write a LeapJS Playback (formatVersion 1) file; compression from the extension
    (.json.gz gzip, .json.lz LZString base64, else plain JSON)."""
    path = str(path)
    meta = {'formatVersion': 1, 'generatedBy': 'leap_teleop record_frames',
            'frames': len(frame_dicts), 'protocolVersion': 6}
    meta.update(metadata or {})
    text = json.dumps({'metadata': meta, 'frames': list(frame_dicts)}, separators=(',', ':'))
    tmp = path + '.part'
    if path.endswith('.gz'):
        data = gzip.compress(text.encode('utf-8'))
    elif path.endswith('.lz'):
        data = lz_compress_base64(text).encode('ascii')
    else:
        data = text.encode('utf-8')
    with open(tmp, 'wb') as f:
        f.write(data)
    os.replace(tmp, path)


__all__ = ['FINGER_NAMES', 'FrameError', 'frame_from_dict', 'frame_to_dict', 'load', 'load_frames',
           'lz_compress_base64', 'lz_decompress_base64', 'read_text', 'save', 'unpack_frames']
