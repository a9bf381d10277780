"""A learned pose classifier stored as plain arrays: standardise, one hidden ReLU layer,
softmax. Fitted by hands/gestures/train.py (scikit-learn, training only); evaluated here with
numpy alone.

The model file is a .npz of arrays (loaded with allow_pickle=False): `classes` (names),
`family` ('leap' or 'keypoints'), `mean`, `scale`, `w0`, `b0`, `w1`, `b1`, and `card`
(a JSON string: what it was fitted on and how it scored on people it never saw).
"""
import json
import lzma
import math
import os
import re
import zipfile
import zlib

import numpy as np

from leap_teleop.hands.gestures.features import KEYPOINT_FEATURES, LEAP_FEATURES

MODEL_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'models')
DEFAULT_MODELS = {'leap': os.path.join(MODEL_DIR, 'leap_poses.npz'),
                  'keypoints': os.path.join(MODEL_DIR, 'keypoint_poses.npz')}
_exp = math.exp
_KEYS = ('classes', 'family', 'mean', 'scale', 'w0', 'b0', 'w1', 'b1')
FEATURES_OF = {'leap': LEAP_FEATURES, 'keypoints': KEYPOINT_FEATURES}
MAX_WEIGHT = 1e6
MAX_CLASS_NAME = 64        # a name in JSON keys, YAML bindings and the camera overlay
# The classes the recognizer reads its gestures from (thumb: up or down, judged apart).
BUILT_IN_CLASSES = ('fist', 'none', 'open', 'pinch', 'rock', 'thumb')
# Names no class may take: the recognizer's other gestures and events, and the keys beside
# the gestures in its output (fist, open, pinch, rock, thumb and none are the built-in
# classes: a user's samples may add to them).
CLASHING_NAMES = frozenset(('thumb_up', 'thumb_down', 'unfold', 'fold', 'circle', 'circle_cw',
                            'circle_ccw', 'hand_lost', 'hand_found', 'hover', 'type', 'events',
                            'pinch_value', 'extended', 'label', 'probability', 'id',
                            'timestamp', 'hands'))


def class_name_problem(name, new=False):
    """Why `name` cannot name a class of a pose model, or None; `new`: a label about to be
    recorded or trained (models made before that rule still load)."""
    if not re.fullmatch(r'[A-Za-z0-9_]+', name or ''):
        return 'letters, digits and _ only'
    if len(name) > MAX_CLASS_NAME:
        return 'at most %d characters' % MAX_CLASS_NAME
    if new:
        import yaml  # here: recognizing needs numpy only
        if yaml.safe_load(name) != name:
            return ('a bindings YAML reads it as a boolean, a null or a number unless '
                    'quoted: choose a word')
    if name in CLASHING_NAMES:
        return ('the name of a built-in gesture, event or output key; choose another (thumb, '
                'fist, open, pinch, rock or none add samples to the built-in classes)')
    return None


class ModelError(ValueError):
    """A model file that is missing, malformed or of the wrong family."""


def is_model_file(path):
    """Whether `path` holds a pose model's arrays, whether or not this code can use them (a
    model of older features is still a model: a refit may write over it)."""
    try:
        with zipfile.ZipFile(path) as z:
            names = {os.path.splitext(n)[0] for n in z.namelist()}
    except (OSError, zipfile.BadZipFile):
        return False
    return set(_KEYS) <= names


class PoseClassifier:
    """Feature vector -> probability per class."""

    def __init__(self, classes, family, mean, scale, w0, b0, w1, b1, card=None):
        self.classes = tuple(str(c) for c in classes)
        self.family = str(family)
        self.mean = np.asarray(mean, dtype=float)
        with np.errstate(divide='ignore', invalid='ignore'):   # a 0 scale is refused below
            self.inv_scale = 1.0 / np.asarray(scale, dtype=float)
        self.w0, self.b0 = np.asarray(w0, dtype=float), np.asarray(b0, dtype=float)
        self.w1, self.b1 = np.asarray(w1, dtype=float), np.asarray(b1, dtype=float)
        self.card = dict(card or {})
        self.path = ''                  # the file it was loaded from, if any
        if self.mean.ndim != 1 or self.w0.ndim != 2 or self.w1.ndim != 2 or not self.classes:
            raise ModelError('inconsistent model arrays')
        if len(set(self.classes)) != len(self.classes):
            raise ModelError('a class named twice')
        for c in self.classes:
            if class_name_problem(c):
                raise ModelError('class %r: %s' % (c, class_name_problem(c)))
        n = self.mean.shape[0]
        if (self.inv_scale.shape != (n,) or self.w0.shape[0] != n
                or self.b0.shape != (self.w0.shape[1],) or self.w1.shape[0] != self.w0.shape[1]
                or self.w1.shape[1] != len(self.classes) or self.b1.shape != (len(self.classes),)
                or not all(np.isfinite(a).all() for a in (self.mean, self.inv_scale, self.w0,
                                                          self.b0, self.w1, self.b1))):
            raise ModelError('inconsistent model arrays')
        self.index = {c: i for i, c in enumerate(self.classes)}
        # the standardisation folded into the first layer: one product per call
        with np.errstate(all='ignore'):     # an overflow here is refused just below
            self._w0 = self.w0 * self.inv_scale[:, None]
            self._b0 = self.b0 - (self.mean * self.inv_scale) @ self.w0
        # Fitted weights stay within tens; numbers near the float limit pass the finiteness
        # test above but overflow to NaN in the first product.
        if not max(float(np.abs(a).max()) for a in (self._w0, self._b0, self.w1, self.b1)) <= MAX_WEIGHT:
            raise ModelError('weights beyond %g: not a fitted model' % MAX_WEIGHT)
        # the ReLU's floor as an array: numpy would convert a Python float on every call
        self._zeros = np.zeros_like(self._b0)

    @property
    def n_features(self):
        return self.mean.shape[0]

    def proba(self, x):
        """Probabilities (n_classes,) for one feature vector, or (n, n_classes) for rows."""
        # ndarray.dot, not @: the same product at half the call overhead for one vector
        h = np.asarray(x, dtype=float).dot(self._w0)
        h += self._b0
        s = np.maximum(h, self._zeros).dot(self.w1)
        s += self.b1
        if s.ndim == 1:
            # one vector: the softmax of a handful of classes in plain floats costs a
            # fraction of numpy's per-call overhead
            s = s.tolist()
            top = max(s)
            e = [_exp(v - top) for v in s]
            total = sum(e)
            return np.array([v / total for v in e])
        s -= s.max(axis=-1, keepdims=True)
        np.exp(s, out=s)
        s /= s.sum(axis=-1, keepdims=True)
        return s

    def save(self, path):
        tmp = path + '.tmp.npz'
        np.savez(tmp, classes=np.array(self.classes), family=np.array(self.family),
                 mean=self.mean, scale=1.0 / self.inv_scale, w0=self.w0, b0=self.b0,
                 w1=self.w1, b1=self.b1, card=np.array(json.dumps(self.card, sort_keys=True)))
        os.replace(tmp, path)

    @classmethod
    def load(cls, path, family=None):
        try:
            _check_array_sizes(path)
            z = np.load(path, allow_pickle=False)
            if not isinstance(z, np.lib.npyio.NpzFile):
                raise ModelError('%s: not a pose model (one array, not a .npz of them)' % path)
            with z:
                missing = [k for k in _KEYS if k not in z.files]
                if missing:
                    raise ModelError('%s: not a pose model (missing %s)' % (path, ', '.join(missing)))
                card = json.loads(str(z['card'])) if 'card' in z.files else {}
                if not isinstance(card, dict):
                    raise ModelError('%s: its card is not a JSON object' % path)
                model = cls(np.atleast_1d(z['classes']).tolist(), str(z['family']), z['mean'],
                            z['scale'], z['w0'], z['b0'], z['w1'], z['b1'], card)
        # a card of deeply nested JSON raises RecursionError; arrays too big to hold,
        # MemoryError; a damaged zip, zlib.error or lzma.LZMAError (bad deflate or LZMA data),
        # NotImplementedError (a compression zipfile cannot read) or RuntimeError (a
        # password-protected member)
        except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile,
                RecursionError, MemoryError, NotImplementedError, RuntimeError, zlib.error,
                lzma.LZMAError) as e:
            if isinstance(e, ModelError):
                if str(e).startswith(str(path)):
                    raise
                raise ModelError('%s: %s' % (path, e)) from None
            raise ModelError('%s: cannot read a pose model (%s)' % (path, e or type(e).__name__)) from None
        if model.family not in FEATURES_OF:
            raise ModelError('%s: unknown model family %r (leap or keypoints)' % (path, model.family))
        if family is not None and model.family != family:
            raise ModelError('%s: a %s model, not a %s one' % (path, model.family, family))
        if model.n_features != FEATURES_OF[model.family]:
            raise ModelError('%s: a %s model takes %d features, not %d' % (
                path, model.family, FEATURES_OF[model.family], model.n_features))
        model.path = path
        return model


# .npy header readers by format version: 3.0 is 2.0 with the header in UTF-8 instead of
# latin-1 (the same for the ASCII numpy writes)
_HEADER_READERS = {(1, 0): np.lib.format.read_array_header_1_0,
                   (2, 0): np.lib.format.read_array_header_2_0,
                   (3, 0): np.lib.format.read_array_header_2_0}


def _check_array_sizes(path):
    """ModelError when an array of the .npz declares more data than its file holds: numpy
    allocates what the header says before it reads (a crafted header of 10**12 numbers
    asked for terabytes). Not a zip: np.load says what it is."""
    if not zipfile.is_zipfile(path):
        return
    with zipfile.ZipFile(path) as z:
        for info in z.infolist():
            if not info.filename.endswith('.npy'):
                continue
            with z.open(info) as f:
                version = np.lib.format.read_magic(f)
                read = _HEADER_READERS.get(version)
                if read is None:        # numpy may read a newer one: unchecked, it is refused
                    raise ModelError('%s: not a pose model (%s is .npy format %d.%d)'
                                     % (path, info.filename, *version))
                shape, _, dtype = read(f)
            declared = math.prod(shape) * dtype.itemsize
            if declared > info.file_size:
                raise ModelError('%s: not a pose model (%s declares %d bytes in %d)'
                                 % (path, info.filename, declared, info.file_size))


_cache = {}


def load_model(path=None, family='leap'):
    """The model at `path` (default: the shipped one of `family`), loaded once; a
    PoseClassifier passes through."""
    if isinstance(path, PoseClassifier):
        if path.family != family:
            raise ModelError('a %s model, not a %s one' % (path.family, family))
        return path
    path = os.path.abspath(path or DEFAULT_MODELS[family])
    key = (path, family)
    if key not in _cache:
        _cache[key] = PoseClassifier.load(path, family)
    return _cache[key]
