"""The recognizer on the labelled hand photos seen as another camera or person would give
them.

usage: python -m tools.evaluation.photo_views [--data DIR] [--out FILE]
                                                      [--photos NAME,NAME,...]

The keypoint pose model is fitted on these photos too (with mirror images, turns and
landmark noise among its copies), so the figures are in-sample: a check that the camera
pipeline keeps what the model knows under these changes, not a result on other people
(those are tools.evaluation.people's, leave one person out). Every labelled photo
(shared/data/hands, label = the file name before "__") goes through the same pipeline
classify_frames runs on images (the video source's image preparation and MediaPipe
detector, the landmark conversion, the stateless classifier) under changes a different
camera, pose of the hand or person would bring: a mirror image (MediaPipe's handedness
flips), in-plane rotations (thumbs-up / down only to +-30 deg: a thumb turned further is
on its way to sideways, and no thumbs-up), downscaling to sign-digit sizes, off-centre
crops and padding, brightness and contrast, blur, noise, JPEG re-encoding. Each view is
judged twice: with MediaPipe's handedness label as given and with it swapped (the label is
unreliable on some photos; a held gesture must not depend on it).

A case is right when MediaPipe finds a hand and every hand found shows the photo's
gesture (pointing and the other negatives: no held gesture); a false thumbs-up is any
hand reading thumbs-up on a photo that is not one. Views are fixed (the noise has a fixed
seed): the figures are deterministic on one machine.
"""
import argparse
import math
import os
import sys

import numpy as np

from leap_teleop.hands.classify_frames import FrameClassifier
from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures import HELD_GESTURES, datasets
from tools.evaluation.results_file import write_json

# Photo label (file name before "__") -> the held gesture it must give (None: none).
EXPECTED = {'open_palm': 'open', 'flat_hand': 'open', 'fist': 'fist',
            'thumbs_up': 'thumb_up', 'thumbs_down': 'thumb_down', 'ok': 'pinch',
            'pinch_o': 'pinch', 'pointing': None, 'neg_half_curl': None, 'neg_pinky': None}
THUMB_LABELS = ('thumbs_up', 'thumbs_down')
# In-plane rotations (deg, both ways): thumbs-up / down, the rest.
THUMB_ROTATIONS = (15, 30)
OTHER_ROTATIONS = (15, 30, 45)
MIRROR_ROTATION = 20
# Downscaled widths (px; the sign-digit photos are 100 px) - only for wider photos.
SMALL_WIDTHS = (100, 130, 160)
NOISE_SEED = 7
NOISE_SD = 8.0                      # grey levels
JPEG_QUALITY = 25
BLUR_SIGMA = 1.5                    # px at 640 px wide, scaled with the photo
PAD_FACTOR = 1.6                    # padded canvas size over the photo's
CROP_KEEP = 0.6                     # off-centre crop: at least this share of each side
LEAN_ROTATION = 20                  # deg, lean_views


def photo_names(data_dir):
    """The labelled photos (not the clips, not the no-hand pictures)."""
    return sorted(n for n in os.listdir(data_dir)
                  if n.split('__')[0] in EXPECTED and not n.startswith('clip_')
                  and n.lower().endswith(('.jpg', '.jpeg', '.png')))


def unreadable_photos(data_dir, names):
    """The photos among names that OpenCV cannot decode (damaged or not an image)."""
    import cv2
    return [n for n in names if cv2.imread(os.path.join(data_dir, n), cv2.IMREAD_COLOR) is None]


def label_of(name):
    return name.split('__')[0]


def _rotate(cv2, bgr, deg):
    """bgr turned by deg (counter-clockwise on screen) on a canvas grown to keep it all."""
    h, w = bgr.shape[:2]
    m = cv2.getRotationMatrix2D((w / 2.0, h / 2.0), deg, 1.0)
    c, s = abs(m[0, 0]), abs(m[0, 1])
    nw, nh = int(math.ceil(h * s + w * c)), int(math.ceil(h * c + w * s))
    m[0, 2] += nw / 2.0 - w / 2.0
    m[1, 2] += nh / 2.0 - h / 2.0
    return cv2.warpAffine(bgr, m, (nw, nh), flags=cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0))


def _scale_to_width(cv2, bgr, width):
    h, w = bgr.shape[:2]
    return cv2.resize(bgr, (width, max(1, round(h * width / w))), interpolation=cv2.INTER_AREA)


def _pad(bgr):
    """The photo in the bottom-right corner of a grey canvas PAD_FACTOR times its size."""
    h, w = bgr.shape[:2]
    canvas = np.full((int(h * PAD_FACTOR), int(w * PAD_FACTOR), 3), 114, dtype=np.uint8)
    canvas[-h:, -w:] = bgr
    return canvas


def _crop(bgr, box):
    """A window of the photo with the hand's box at its top-left corner."""
    h, w = bgr.shape[:2]
    x0, y0, x1, y1 = box
    bw, bh = x1 - x0, y1 - y0
    cw = int(min(w, max(CROP_KEEP * w, 1.25 * bw)))
    ch = int(min(h, max(CROP_KEEP * h, 1.25 * bh)))
    left = int(min(max(0, x0 - 0.05 * bw), w - cw))
    top = int(min(max(0, y0 - 0.05 * bh), h - ch))
    return np.ascontiguousarray(bgr[top:top + ch, left:left + cw])


def views(cv2, bgr, label, box):
    """[(view name, BGR image)] for one photo; box: its hand's pixel box, or None."""
    h, w = bgr.shape[:2]
    out = [('original', bgr), ('mirror', cv2.flip(bgr, 1))]
    rots = THUMB_ROTATIONS if label in THUMB_LABELS else OTHER_ROTATIONS
    for a in rots:
        out += [('rot%+d' % a, _rotate(cv2, bgr, a)), ('rot%+d' % -a, _rotate(cv2, bgr, -a))]
    flipped = cv2.flip(bgr, 1)
    out += [('mirror_rot%+d' % MIRROR_ROTATION, _rotate(cv2, flipped, MIRROR_ROTATION)),
            ('mirror_rot%+d' % -MIRROR_ROTATION, _rotate(cv2, flipped, -MIRROR_ROTATION))]
    out += [('width%d' % sw, _scale_to_width(cv2, bgr, sw)) for sw in SMALL_WIDTHS
            if w > 1.2 * sw]
    out.append(('pad_offcentre', _pad(bgr)))
    if box is not None:
        crop = _crop(bgr, box)
        if crop.shape != bgr.shape:
            out.append(('crop_offcentre', crop))
    out += [('bright', cv2.convertScaleAbs(bgr, alpha=1.3, beta=40)),
            ('dark', cv2.convertScaleAbs(bgr, alpha=0.55, beta=-10)),
            ('low_contrast', cv2.convertScaleAbs(bgr, alpha=0.5, beta=64))]
    sigma = BLUR_SIGMA * max(w, h) / 640.0
    out.append(('blur', cv2.GaussianBlur(bgr, (0, 0), max(0.6, sigma))))
    noise = np.random.default_rng(NOISE_SEED).normal(0.0, NOISE_SD, bgr.shape)
    out.append(('noise', np.clip(bgr + noise, 0, 255).astype(np.uint8)))
    ok, enc = cv2.imencode('.jpg', bgr, [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if ok:
        out.append(('jpeg%d' % JPEG_QUALITY, cv2.imdecode(enc, cv2.IMREAD_COLOR)))
    return out


def lean_views(cv2, bgr, label, box):
    """The few views a quick check affords: mirrored, turned LEAN_ROTATION either way."""
    return [('mirror', cv2.flip(bgr, 1)),
            ('rot%+d' % LEAN_ROTATION, _rotate(cv2, bgr, LEAN_ROTATION)),
            ('rot%+d' % -LEAN_ROTATION, _rotate(cv2, bgr, -LEAN_ROTATION))]


# lean_views ignore the hand's box: run() skips the detection that finds it (the detector
# judges stills one by one, so the other detections do not change)
lean_views.uses_box = False


def swapped(landmarks):
    """The detections with MediaPipe's handedness label swapped."""
    from leap_teleop.hands.sources.landmarks import HandLandmarks
    return [HandLandmarks(lm.image, lm.world, 'Left' if lm.label == 'Right' else 'Right',
                          lm.score) for lm in landmarks]


def judge(hands, want):
    """(right, false thumbs-up) for the classified hands of one case."""
    false_up = want != 'thumb_up' and any(h['thumb_up'] for h in hands)
    if not hands:
        return False, false_up
    for h in hands:
        got = {g for g in HELD_GESTURES if h[g]}
        if want is None:
            if got:
                return False, false_up
        elif want not in got or (want != 'thumb_up' and 'thumb_up' in got):
            return False, false_up
    return True, false_up


class PhotoPipeline:
    """classify_frames' image path on in-memory images: the video source's preparation
    (letterboxed to the sender's default size) and detector, its hands_of conversion, the
    stateless FrameClassifier."""

    def __init__(self, any_image_path):
        from leap_teleop.hands.sources import make_source
        from leap_teleop.hands.sources.camera_params import DEFAULT_SIZE
        self.source = make_source('video', path=any_image_path, realtime=False,
                                  clock=lambda: 0.0, width=DEFAULT_SIZE[0], height=DEFAULT_SIZE[1])
        self.cv2 = self.source.cv2

    def detect(self, bgr):
        """(landmarks, CameraModel) of one image."""
        _, rgb, cam = self.source.prepare(bgr)
        return self.source.detector.detect(rgb), cam

    def hand_box(self, bgr):
        """(x0, y0, x1, y1) around the hands found in bgr, in its own pixels (the detector
        saw it letterboxed); None when none is found."""
        found, _ = self.detect(bgr)
        if not found:
            return None
        h, w = bgr.shape[:2]
        scale, pad_x, pad_y, out_w, out_h = (1.0, 0, 0, w, h)
        if self.source.size is not None and (w, h) != self.source.size:
            scale, pad_x, pad_y, out_w, out_h = self.source.letterbox(bgr)[1]
        xy = np.concatenate([lm.image[:, :2] for lm in found]) * (out_w, out_h)
        xy = (xy - (pad_x, pad_y)) / scale
        return (*xy.min(axis=0), *xy.max(axis=0))

    def classify(self, landmarks, cam):
        """The classify_frames output hands for these detections."""
        self.source.forget_hands()         # unrelated pictures: no velocity between them
        frame = Frame(id=1, timestamp=0.0, hands=self.source.hands_of(landmarks, cam, 0.0))
        return FrameClassifier(stateless=True).classify_frame(frame, 1, 0)['hands']

    def close(self):
        self.source.detector.close()


def run(data_dir=datasets.HANDS_DATA, names=None, make_views=views, log=None):
    """Per label: cases, right, fraction, false thumbs-up, no hand found, failures
    [(photo, view, 'label as given' | 'label swapped', gestures read)]. make_views(cv2,
    bgr, label, hand box) -> [(view name, BGR image)]: views (default) or lean_views."""
    names = photo_names(data_dir) if names is None else list(names)
    if not names:
        raise FileNotFoundError('no labelled hand photos in %s' % data_dir)
    pipe = PhotoPipeline(os.path.join(data_dir, names[0]))
    cv2 = pipe.cv2
    per_label = {}
    try:
        for name in names:
            label = label_of(name)
            want = EXPECTED[label]
            bgr = cv2.imread(os.path.join(data_dir, name), cv2.IMREAD_COLOR)
            if bgr is None:
                raise FileNotFoundError('cannot read %s' % os.path.join(data_dir, name))
            box = pipe.hand_box(bgr) if getattr(make_views, 'uses_box', True) else None
            r = per_label.setdefault(label, {'cases': 0, 'right': 0, 'false_thumb_up': 0,
                                             'no_hand': 0, 'failures': []})
            for view, img in make_views(cv2, bgr, label, box):
                lms, cam = pipe.detect(img)
                for how, marks in (('label as given', lms), ('label swapped', swapped(lms))):
                    hands = pipe.classify(marks, cam)
                    right, false_up = judge(hands, want)
                    r['cases'] += 1
                    r['right'] += right
                    r['false_thumb_up'] += false_up
                    r['no_hand'] += not hands
                    if not right or false_up:
                        got = [sorted(g for g in HELD_GESTURES if h[g]) for h in hands]
                        r['failures'].append([name, view, how, got])
                        if log:
                            log('%s %s (%s): %s' % (name, view, how, got or 'no hand'))
    finally:
        pipe.close()
    for r in per_label.values():
        r['fraction'] = round(r['right'] / r['cases'], 4) if r['cases'] else 0.0
    total = {k: sum(r[k] for r in per_label.values())
             for k in ('cases', 'right', 'false_thumb_up', 'no_hand')}
    total['fraction'] = round(total['right'] / total['cases'], 4) if total['cases'] else 0.0
    # the keypoint model is fitted on these photos: a check, not a result
    return {'photos': len(names), 'labels': per_label, 'total': total, 'in_sample': True}


def print_table(res, failures=True):
    print('labelled photos under camera / person changes (%d photos; every view with '
          "MediaPipe's handedness as given and swapped; in-sample: the model is fitted on "
          'them):' % res['photos'])
    print('%-14s %6s %6s %9s %14s %8s' % ('label', 'cases', 'right', 'fraction',
                                          'false thumb_up', 'no hand'))
    for label, r in sorted(res['labels'].items()):
        print('%-14s %6d %6d %9.3f %14d %8d' % (label, r['cases'], r['right'], r['fraction'],
                                                r['false_thumb_up'], r['no_hand']))
    t = res['total']
    print('%-14s %6d %6d %9.3f %14d %8d' % ('all', t['cases'], t['right'], t['fraction'],
                                            t['false_thumb_up'], t['no_hand']))
    if failures:
        for label, r in sorted(res['labels'].items()):
            for name, view, how, got in r['failures']:
                print('  failing: %s %s (%s): %s' % (name, view, how,
                                                    ', '.join('+'.join(g) or '-' for g in got)
                                                    or 'no hand'))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument('--data', default=datasets.HANDS_DATA,
                    help='folder of the labelled hand photos (default %(default)s)')
    ap.add_argument('--out', default='', help='also write the figures as JSON here')
    ap.add_argument('--photos', default='',
                    help='comma-separated file names: only these photos (default: all)')
    args = ap.parse_args(argv)
    if not os.path.isdir(args.data):
        print('evaluate_photo_views: no photo folder at %s' % args.data, file=sys.stderr)
        return 2
    names = [n for n in args.photos.split(',') if n] or photo_names(args.data)
    unlabelled = [n for n in names if label_of(n) not in EXPECTED]
    missing = [n for n in names if n not in unlabelled and not os.path.isfile(os.path.join(args.data, n))]
    damaged = unreadable_photos(args.data, [n for n in names if n not in missing + unlabelled])
    if unlabelled or missing or damaged or not names:
        print('evaluate_photo_views: %s in %s' % (
            '; '.join(what + ': ' + ', '.join(ns) for what, ns in (
                ('not named LABEL__SOURCE__NAME with a LABEL of %s' % ', '.join(sorted(EXPECTED)),
                 unlabelled),
                ('no such photo', missing), ('cannot read', damaged)) if ns)
            or 'no labelled hand photos', args.data), file=sys.stderr)
        return 2
    res = run(args.data, names)
    print_table(res)
    if args.out:
        write_json(args.out, res, announce=False)
    return 0


if __name__ == '__main__':
    sys.exit(main())
