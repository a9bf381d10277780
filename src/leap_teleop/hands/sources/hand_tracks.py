"""Camera hands from image to image (HandTracks): each physical hand keeps its id, and its
side, though the detector reads every image afresh. Pure numpy: testable without a camera.
"""
import numpy as np

VELOCITY_SMOOTHING = 0.5            # weight of the newest finite difference
# A hand is the last image's hand only within this many hand sizes (the diagonal of its
# landmarks' box in the image) of where that one was predicted to be (last place + image
# velocity x dt); else it is a new hand (new id, new session), so a side's palm never
# jumps further with its session kept. On the shared clips a followed hand is at most 0.18
# sizes off its prediction; a hand setting off at 1.8 m/s 0.5 m away, 0.31.
MATCH_MAX_SIZES = 0.5
# A hand read as the other side keeps its followed hand's side (a misread) only within
# this many sizes of the prediction: a misread hand on the shared clips is within 0.05 of
# it; the other hand in view 6 cm from where one left, 0.34. Further, it is a new hand on
# the side it is read as.
HOLD_MAX_SIZES = 0.25
# ... and only when its shape in the image (landmarks about their centre, in hand sizes)
# is within this of the followed hand's: from one image to the next a hand's changes by
# 0.04 at most when misread, 0.12 when closing into a fist, on the shared clips; the
# mirror-image hand (the other one) in its place is 0.24 off.
HOLD_SHAPE_MAX = 0.15
# Cost, in hand sizes off the prediction, of matching a hand to a followed hand of the
# other side: two hands near each other (crossing, one passing in front of the other) go
# by their reading unless their places tell them apart by more.
SIDE_DISAGREE_COST = 0.25
# Images in a row whose reading disagrees with a followed hand's side before it changes
# side: a single hand's side read wrongly for 6 images in a row on the shared palm clip.
SIDE_SWITCH_FRAMES = 8
# More hands than this in one image are matched greedily (the exact search grows fast).
EXACT_MATCH_MAX_HANDS = 4
# A hand matched to none, read as the side of the one followed hand of that side matched to
# none, is still that hand within this many sizes of its last place, when no other followed
# hand was that near: a hand faster than its prediction (a track starts with no velocity, and
# one that stops is overshot), which got a new session every image from 1.35 m/s at 15
# images/s. Another hand near where one vanished is still new.
LONE_MATCH_MAX_SIZES = 1.5
LONE_SIZE_RATIO = 1.25      # ... and its size in the image within this ratio (its depth)
# Images a new hand's side must be read again before it is held against the reading, when
# it started where the other side's hand vanished (that hand, misread)
CONFIRM_IMAGES = 2


class _Track:
    __slots__ = ('id', 'side', 't', 'palm', 'velocity', 'centre', 'size', 'shape',
                 'image_velocity', 'against', 'published', 'unconfirmed')


def image_place(hand):
    """(centre, size) of a hand in the image: its landmarks' mean and box diagonal, in
    pixels; from the palm position (mm) when it has no image landmarks."""
    px = getattr(hand, 'image_landmarks', None)
    if px is not None:
        px = np.asarray(px, dtype=float)[:, :2]
        if px.size and np.all(np.isfinite(px)):
            size = float(np.linalg.norm(px.max(axis=0) - px.min(axis=0)))
            return px.mean(axis=0), max(size, 1.0)
    return np.asarray(hand.palm_position, dtype=float)[:2], 200.0


def image_shape(hand, centre, size):
    """The hand's landmarks about their centre, in hand sizes; None without landmarks."""
    px = getattr(hand, 'image_landmarks', None)
    if px is None:
        return None
    px = np.asarray(px, dtype=float)[:, :2]
    return (px - centre) / size if px.size and np.all(np.isfinite(px)) else None


def _same_shape(a, b):
    """Much the same shape in the image (or not known)."""
    return a is None or b is None or a.shape != b.shape or \
        float(np.mean(np.linalg.norm(a - b, axis=1))) <= HOLD_SHAPE_MAX


def _best_assignment(costs, n_hands, n_tracks):
    """{hand: track} of the most pairs, then the lowest total cost, among the allowed
    pairs costs[(track, hand)]."""
    if n_hands > EXACT_MATCH_MAX_HANDS:
        track_of, used = {}, set()
        for (i, j), _ in sorted(costs.items(), key=lambda kv: kv[1]):
            if i not in used and j not in track_of:
                used.add(i)
                track_of[j] = i
        return track_of
    best = []                            # [(rank, {hand: track})]

    def search(j, used, chosen, total):
        if j == n_hands:
            rank = (-len(chosen), total)
            if not best or rank < best[0][0]:
                best[:] = [(rank, dict(chosen))]
            return
        for i in range(n_tracks):
            if i not in used and (i, j) in costs:
                chosen[j] = i
                search(j + 1, used | {i}, chosen, total + costs[(i, j)])
                del chosen[j]
        search(j + 1, used, chosen, total)
    search(0, frozenset(), {}, 0.0)
    return best[0][1]


class HandTracks:
    """Camera hands from image to image: each physical hand keeps its id, and its side.

    The detector reads each image afresh, the side of each hand too, and a side can be
    misread for a few images (a right hand's shape read as a left one's). Ids given by side
    handed one hand's id to the other when both were misread. Here a hand is followed by
    where it is in the image: each image's hands are matched to the last image's at the
    lowest total cost, the distance from where each was predicted to be (last place + image
    velocity x dt, in hand sizes) plus SIDE_DISAGREE_COST for a hand read as the other side:
    crossing hands keep their own, and near each other the reading decides. A hand further
    than MATCH_MAX_SIZES from every prediction is new (new id, new session), so a side's
    palm never jumps with its session kept, unless it is the lone hand of its side near
    where that side's hand was, alike in size and shape (LONE_MATCH_MAX_SIZES): a hand
    faster than predicted. A followed hand keeps its id, and its side against the reading
    when it is the same hand misread (within HOLD_MAX_SIZES, much the same shape), until
    SIDE_SWITCH_FRAMES images in a row read the other side; it then changes side with a
    new id."""

    def __init__(self):
        self._tracks = []
        self._next_id = 1
        self._unrelated = False

    def forget(self):
        """The next image is unrelated to the last (a cut): new ids, no velocity."""
        self._tracks = []
        self._unrelated = False

    def forget_motion(self):
        """The next image is a separate photo: no velocity, and its hands are matched by
        side (their place says nothing), so each side's hand keeps its id."""
        for tr in self._tracks:
            tr.t, tr.palm, tr.velocity = None, None, np.zeros(3)
            tr.image_velocity = np.zeros(2)
        self._unrelated = True

    def _new_id(self):
        self._next_id += 1
        return self._next_id - 1

    def _pairs(self, hands, t):
        """[(track or None, hand, place)]: the last image's tracks matched to these hands."""
        places = [image_place(h) for h in hands]
        costs = {}
        for i, tr in enumerate(self._tracks):
            for j, hand in enumerate(hands):
                agree = hand.side == tr.side
                if self._unrelated:
                    if agree:                    # the most confident first
                        costs[(i, j)] = -float(hand.confidence or 0.0)
                    continue
                centre, size = places[j]
                predicted = tr.centre
                if tr.t is not None and t - tr.t > 0:
                    predicted = tr.centre + tr.image_velocity * (t - tr.t)
                d = float(np.linalg.norm(centre - predicted)) / max(size, tr.size)
                if agree and d <= MATCH_MAX_SIZES or not agree and d <= HOLD_MAX_SIZES \
                        and _same_shape(image_shape(hand, centre, size), tr.shape):
                    costs[(i, j)] = d + (0.0 if agree else SIDE_DISAGREE_COST)
        track_of = _best_assignment(costs, len(hands), len(self._tracks))
        if not self._unrelated:
            self._lone_matches(hands, places, track_of)
        return [(self._tracks[track_of[j]] if j in track_of else None, hand, places[j])
                for j, hand in enumerate(hands)]

    def _lone_matches(self, hands, places, track_of):
        """Add to track_of each hand matched to none that is the one unmatched followed hand
        of its side, within LONE_MATCH_MAX_SIZES of that hand's last place, with no other
        followed hand as near (LONE_MATCH_MAX_SIZES)."""
        free = [i for i in range(len(self._tracks)) if i not in track_of.values()]
        for j, hand in enumerate(hands):
            same = [i for i in free if self._tracks[i].side == hand.side]
            if j in track_of or len(same) != 1:
                continue
            centre, size = places[j]
            tr = self._tracks[same[0]]

            def within(c, s, t):
                return np.linalg.norm(c - t.centre) / min(s, t.size) <= LONE_MATCH_MAX_SIZES
            near = [i for i, t in enumerate(self._tracks) if within(centre, size, t)]
            # no other hand of this image near that place either (first in the detector's
            # order took a session while its hand was still in view), and the same size
            # (depth) and shape: the place in the image alone gave a hand 1.3 m away the
            # session of one at 0.5 m
            others = [k for k, (c, s) in enumerate(places) if k != j and within(c, s, tr)]
            if near == same and not others and max(size, tr.size) <= LONE_SIZE_RATIO * min(size, tr.size) \
                    and _same_shape(image_shape(hand, centre, size), tr.shape):
                track_of[j] = same[0]
                free.remove(same[0])

    def update(self, hands, t, as_side=None):
        """Hands of one image (their side as read in it), at time t -> the hands to
        publish: at most one per side, with ids, sides and palm velocities that follow
        the hands. as_side(hand, side) gives a hand read as the other side (its normal
        and thumb depend on it), or None when unusable; by default the side is changed
        on the hand itself."""
        pairs = self._pairs(hands, t)
        # Sides held by a hand published on them in the last image.
        taken = {tr.side for tr, hand, _ in pairs
                 if tr is not None and tr.published and (hand.side == tr.side
                                                         or tr.against + 1 < SIDE_SWITCH_FRAMES)}
        matched = {id(tr) for tr, _, _ in pairs if tr is not None}
        tracks, out = [], []
        for tr, hand, (centre, size) in pairs:
            if tr is None:
                tr = self._start(hand)
                # Where the other side's hand vanished this image: maybe that hand misread
                # off its course (a jerk, a quick roll); its side is held only once read
                # again (held at once, it kept the wrong side against 7 right readings).
                tr.unconfirmed = CONFIRM_IMAGES if any(
                    o.side != hand.side and id(o) not in matched
                    and np.linalg.norm(centre - o.centre) / min(size, o.size) <= LONE_MATCH_MAX_SIZES
                    for o in self._tracks) else 0
            elif hand.side == tr.side or self._unrelated:
                tr.against = 0
                tr.unconfirmed = max(0, tr.unconfirmed - 1)
            else:
                tr.against += 1
                # Read so for long enough; or a hand not published (another one holds
                # its side) read as a side no other hand holds: two hands in view are
                # mostly a left and a right one.
                if tr.against >= SIDE_SWITCH_FRAMES or tr.unconfirmed or (
                        not tr.published and hand.side not in taken):
                    tr = self._start(hand)
                else:
                    hand = as_side(hand, tr.side) if as_side else _with_side(hand, tr.side)
                    if hand is None:
                        continue                            # lost with its side
            velocity, image_velocity = tr.velocity, tr.image_velocity
            if tr.t is not None and t - tr.t > 0:
                velocity = ((1 - VELOCITY_SMOOTHING) * tr.velocity
                            + VELOCITY_SMOOTHING * (hand.palm_position - tr.palm) / (t - tr.t))
                image_velocity = ((1 - VELOCITY_SMOOTHING) * tr.image_velocity
                                  + VELOCITY_SMOOTHING * (centre - tr.centre) / (t - tr.t))
            hand.palm_velocity = velocity
            hand.id = tr.id
            tr.t, tr.palm, tr.velocity, tr.centre, tr.size = t, hand.palm_position, velocity, centre, size
            tr.image_velocity, tr.shape = image_velocity, image_shape(hand, centre, size)
            tracks.append(tr)
            out.append((tr, hand))
        self._tracks = tracks
        self._unrelated = False
        # One per side: the hand published on it in the last image, else the most confident.
        chosen = {}
        for tr, hand in out:
            rank = (tr.published, float(hand.confidence or 0.0))
            if hand.side not in chosen or rank > chosen[hand.side][0]:
                chosen[hand.side] = (rank, tr, hand)
        for tr in tracks:
            tr.published = any(c[1] is tr for c in chosen.values())
        return [chosen[s][2] for s in ('right', 'left') if s in chosen]

    def _start(self, hand):
        """A new track for a hand seen first now (or on a new side): new id, no velocity."""
        tr = _Track()
        tr.id, tr.side, tr.published, tr.against, tr.unconfirmed = self._new_id(), hand.side, False, 0, 0
        tr.t, tr.palm, tr.velocity, tr.image_velocity = None, None, np.zeros(3), np.zeros(2)
        return tr


def _with_side(hand, side):
    hand.side = side
    return hand
