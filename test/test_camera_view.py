"""The annotated camera view's text: the gestures the recognizer holds for each hand, not
the actions the bindings make of them. Without MediaPipe or a camera."""
import types

import numpy as np
import pytest

from leap_teleop.hands import camera_view
from leap_teleop.hands.gestures import GestureState
from leap_teleop.hands.gestures.bindings import Bindings
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.tracker import HandTracker


class Holds:
    """A recognizer that holds the given GestureState on every frame; its model has a
    user class 'two'."""
    user_gestures = ('two',)

    def __init__(self, state):
        self.state = state

    def update(self, hand, timestamp):
        return self.state

    def reset(self):
        pass


def _labels(monkeypatch, state):
    """The text drawn beside a right hand whose HandState is `state`."""
    drawn = []
    monkeypatch.setattr(camera_view, '_text', lambda img, text, *a, **k: drawn.append(text))
    lm = types.SimpleNamespace(image=np.column_stack((np.linspace(0.3, 0.6, 21),
                                                     np.linspace(0.3, 0.7, 21), np.zeros(21))),
                               score=0.9)
    camera_view.draw(np.zeros((120, 160, 3), np.uint8), [lm], False, {'right': state},
                     sides=['right'])
    return drawn


@pytest.mark.parametrize('held, shown', [
    (GestureState(user=('two',)), ['two']),              # a V sign, bound to arm
    (GestureState(thumb_up=True), ['thumb_up']),         # a thumbs-up, bound to nothing
    (GestureState(fist=True, user=('two',)), ['fist', 'two']),
])
def test_the_view_shows_the_held_gestures_not_the_bound_actions(monkeypatch, held, shown):
    # With arm: {arm: two} the overlay read the HandState's action flags as gestures: a V
    # sign showed "thumb_up", a thumbs-up showed nothing and a user's class never showed.
    tracker = HandTracker('right', Holds(held), bindings=Bindings({'arm': {'arm': 'two'}}))
    state = tracker.update(render_hand('right', 'two', (0, 200, 0), hand_id=1), 0.0, 1)
    assert state.thumb_up is ('two' in shown)        # the action, as the arm reads it
    assert camera_view.held_gestures(state) == shown
    assert _labels(monkeypatch, state) == ['right 0.90: ' + ' '.join(shown)]
    # a GestureState, as the recognizer gives it, reads the same
    assert camera_view.held_gestures(held) == shown


def test_a_lost_hand_shows_no_gesture():
    tracker = HandTracker('right', Holds(GestureState(fist=True)))
    assert camera_view.held_gestures(tracker.update(None, 0.0, 1)) == []
    assert camera_view.held_gestures(None) == []
