"""MediaPipe Hands (legacy solution) on RGB images -> HandLandmarks per image.

The only module that imports mediapipe, and only when a detector is built, so nodes that
do not use the camera start as fast as before.

Speed. With max_num_hands=2 the legacy graph runs its palm detector on every frame in
which fewer than two hands are tracked: about twice the cost of tracking one hand. The
default strategy ('paired') instead gives each hand its own one-hand graph, which skips
the detector while its hand is tracked; the graph looking for a further hand sees the
image with the tracked hands blanked out (so both never lock onto one hand) and looks
only every `detect_every`-th frame. A new second hand is then found within
`detect_every` frames; while no hand is tracked at all, the first graph looks on every
frame.
Search thread. Looking for a hand runs the palm detector: on top of tracking when
looking for a further hand (every `detect_every`-th frame), alone but costlier than
tracking while no hand is tracked; in the caller's call either makes that frame late.
With `search_thread` (for live and paced sources) every search runs on a worker thread
instead (the graph releases the GIL while it runs, so it uses the other core), started
after the frame's tracking so it runs while the frame is published and the next one
awaited: detect() returns the tracked hands only, and a hand a search found is tracked
by its graph from the first detect() after the search has ended (never waited for; the
graph sits out until then). Without it (processing a file as fast as possible, tests)
the search runs in the call, so results never depend on timing.
A graph is only ever run by one thread at a time: a graph searching is not touched until
collected. A failed search is logged and counted (search_failures), never raised.
'single' is the plain legacy graph with max_num_hands (and static_image_mode for
unrelated images).

Re-detection. A tracking graph crops each frame where the hand was in the last one, turned
the way it read the hand then: a misreading (a thumbs-up toward the camera read as an
index finger pointing up, say) can persist for as long as the hand stays, all the more
when frames are dropped. With `redetect_every` > 0 a tracking graph is made to lose its
hand every that many frames (it is shown a blank image, whose result is dropped) so the
palm detector starts it afresh on the next real frame. On the shared thumbs-up clip,
processing every 3rd frame, that turns 1 of 44 thumbs-up frames read right into 30 (every
15 frames), but processing every frame 135 of 135 into 77: off by default.
"""
import concurrent.futures
import logging

import numpy as np

from leap_teleop.hands.sources.landmarks import HandLandmarks
from leap_teleop.hands.sources.source import SourceError

INSTALL_HINT = ('the camera sources need MediaPipe 0.10.21 and OpenCV: run tools/setup.sh, or '
                '`pip install --no-deps -r tools/requirements-camera.txt` in the venv')
MODEL_COMPLEXITY = {'lite': 0, 'full': 1}
# Blanked box around a tracked hand for the graph looking for another: landmark box
# grown by this fraction of its size on every side (landmarks lie inside the skin).
MASK_MARGIN = 0.15
log = logging.getLogger(__name__)


def import_mediapipe():
    """The mediapipe module, or SourceError naming what to install."""
    try:
        import mediapipe
        from mediapipe.python.solutions import hands  # noqa: F401 (ships the models)
    except ImportError as e:
        raise SourceError('%s (%s)' % (INSTALL_HINT, e))
    return mediapipe


def _landmarks(result):
    """HandLandmarks list from one legacy Hands result."""
    out = []
    if not result.multi_hand_landmarks:
        return out
    worlds = result.multi_hand_world_landmarks or [None] * len(result.multi_hand_landmarks)
    labels = result.multi_handedness or [None] * len(result.multi_hand_landmarks)
    for image_lms, world_lms, handedness in zip(result.multi_hand_landmarks, worlds, labels):
        if world_lms is None or handedness is None:
            continue
        image = np.array([(p.x, p.y, p.z) for p in image_lms.landmark], dtype=float)
        world = np.array([(p.x, p.y, p.z) for p in world_lms.landmark], dtype=float)
        c = handedness.classification[0]
        out.append(HandLandmarks(image, world, c.label, float(c.score)))
    return out


def _box(lm, width, height):
    """Integer pixel box (x0, y0, x1, y1) around a hand's image landmarks, grown."""
    x, y = lm.image[:, 0] * width, lm.image[:, 1] * height
    mx, my = MASK_MARGIN * (x.max() - x.min()), MASK_MARGIN * (y.max() - y.min())
    return (int(max(0, x.min() - mx)), int(max(0, y.min() - my)),
            int(min(width, x.max() + mx + 1)), int(min(height, y.max() + my + 1)))


class HandDetector:
    """detect(rgb) -> [HandLandmarks], for a stream of frames (or still images with
    static=True). rgb: (H, W, 3) uint8, RGB, C-contiguous."""

    def __init__(self, max_hands=2, model='full', strategy='paired', detect_every=8,
                 redetect_every=0, static=False, min_detection_confidence=0.5,
                 min_tracking_confidence=0.5, search_thread=False):
        if model not in MODEL_COMPLEXITY:
            raise SourceError('model must be one of %s, got %r' % (sorted(MODEL_COMPLEXITY), model))
        if strategy not in ('paired', 'single'):
            raise SourceError('strategy must be paired or single, got %r' % (strategy,))
        if not 1 <= int(max_hands) <= 2:
            raise SourceError('max_hands must be 1 or 2, got %r' % (max_hands,))
        mp = import_mediapipe()
        self.static = bool(static)
        self.max_hands = int(max_hands)
        self.detect_every = max(1, int(detect_every))
        self.redetect_every = int(redetect_every)      # 0: never
        # Still images are unrelated: no tracking, the plain graph.
        self.strategy = 'single' if static else strategy
        n_graphs, per_graph = ((self.max_hands, 1) if self.strategy == 'paired'
                               else (1, self.max_hands))
        self._graphs = [mp.solutions.hands.Hands(
            static_image_mode=bool(static), max_num_hands=per_graph,
            model_complexity=MODEL_COMPLEXITY[model],
            min_detection_confidence=min_detection_confidence,
            min_tracking_confidence=min_tracking_confidence) for _ in range(n_graphs)]
        self._tracked = [None] * n_graphs        # each graph's last hand (paired)
        self._idle = [0] * n_graphs              # frames since each graph last ran
        self._tracked_runs = [0] * n_graphs      # frames each graph has tracked since detecting
        self._blank = None
        self.graph_runs = 0                      # for benchmarks: graph invocations
        self._pool = (concurrent.futures.ThreadPoolExecutor(1, 'hand-search')
                      if search_thread and self.strategy == 'paired' else None)
        self._searching = {}                     # graph -> Future of its search
        self.search_failures = 0
        self._failed_in_row = 0

    def close(self):
        """Waits for a running search (its graph is closed after it), closes the graphs."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
        self._searching = {}
        for g in self._graphs:
            g.close()
        self._graphs = []

    def _process(self, k, image, tracking):
        """Graph k on image, made to re-detect first when it has tracked long enough."""
        graph = self._graphs[k]
        if tracking and self.redetect_every:
            self._tracked_runs[k] += 1
            if self._tracked_runs[k] >= self.redetect_every:
                if self._blank is None or self._blank.shape != image.shape:
                    self._blank = np.zeros_like(image)
                graph.process(self._blank)
                self.graph_runs += 1
                self._tracked_runs[k] = 0
        else:
            self._tracked_runs[k] = 0
        self.graph_runs += 1
        return _landmarks(graph.process(image))

    @staticmethod
    def _search(graph, image):
        """A graph looking for a hand (on the worker thread: touches no shared state)."""
        return _landmarks(graph.process(image))

    def _collect(self):
        """Adopt the searches that have ended."""
        for k, future in sorted(self._searching.items()):
            if not future.done():
                continue
            del self._searching[k]
            try:
                hands = future.result()
                self._failed_in_row = 0
            except Exception as e:      # logged and counted; the tracked hands go on
                hands = []
                self.search_failures += 1
                self._failed_in_row += 1
                if self._failed_in_row == 1:
                    log.warning('hand detector: looking for a hand failed (tracking '
                                'goes on; logged again after a success): %s', e)
            self._tracked[k] = hands[0] if hands else None

    def detect(self, rgb):
        if self.strategy == 'single':
            found = self._process(0, rgb, self._tracked[0] is not None and not self.static)
            self._tracked[0] = found[0] if found else None
            return found
        self._collect()
        height, width = rgb.shape[:2]
        found = {}
        # Tracking first, then the searches: one on the worker then runs while this frame
        # is published and the next one awaited, not beside this frame's tracking (which
        # it would slow down when the other core is busy).
        for k in sorted(range(len(self._graphs)), key=lambda j: self._tracked[j] is None):
            if k in self._searching:
                continue
            others = [lm for j, lm in enumerate(self._tracked) if j != k and lm is not None]
            # The first graph that has nothing to track looks every frame while no hand
            # is tracked at all; any other idle graph every detect_every frames.
            looking_first = self._tracked[k] is None and not others and k == 0
            if self._tracked[k] is None and not looking_first \
                    and self._idle[k] + 1 < self.detect_every:
                self._idle[k] += 1
                continue
            # One search at a time: a second one started beside it would see the image
            # without the first one's hand blanked, and both graphs could lock onto it.
            if self._tracked[k] is None and self._searching:
                continue
            self._idle[k] = 0
            image = rgb
            if others:
                image = rgb.copy()
                for lm in others:
                    x0, y0, x1, y1 = _box(lm, width, height)
                    image[y0:y1, x0:x1] = 0
            if self._pool is not None and self._tracked[k] is None:
                self.graph_runs += 1
                self._tracked_runs[k] = 0
                self._searching[k] = self._pool.submit(self._search, self._graphs[k], image)
                continue
            hands = self._process(k, image, self._tracked[k] is not None)
            self._tracked[k] = hands[0] if hands else None
            found[k] = hands[:1]
        return [lm for k in sorted(found) for lm in found[k]]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
