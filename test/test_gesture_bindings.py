"""Gesture -> action bindings: loading, validation, and their effect through HandTracker."""
import os

import pytest

from leap_teleop.hands.frame import Frame
from leap_teleop.hands.gestures import GestureRecognizer, GestureState, HandEvent
from leap_teleop.hands.gestures.bindings import (
    BOUND_FLIP_RADIUS_M,
    DEFAULTS,
    GRIPPER_CLOSED,
    BindingError,
    Bindings,
    load_bindings,
)
from leap_teleop.hands.leap_interface import LeapInterface
from leap_teleop.hands.rendered_hand import render_hand
from leap_teleop.hands.tracker import HandTracker

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_YAML = os.path.join(ROOT, 'config', 'gestures', 'bindings', 'default.yaml')


def write(tmp_path, text, name='b.yaml'):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_defaults_and_the_shipped_default_file_agree():
    assert load_bindings('').actions == DEFAULTS
    assert load_bindings(None).is_default()
    assert load_bindings(DEFAULT_YAML).actions == DEFAULTS


def test_a_file_changes_only_what_it_names(tmp_path):
    b = load_bindings(write(tmp_path, 'arm: {arm: [thumb_up, open]}\ndrone:\n  hover: rock\n'))
    assert b.actions['arm'] == dict(DEFAULTS['arm'], arm=('thumb_up', 'open'))
    assert b.actions['drone'] == dict(DEFAULTS['drone'], hover=('rock',))
    assert not b.is_default()
    assert load_bindings(write(tmp_path, '', 'empty.yaml')).is_default()


@pytest.mark.parametrize('text, message', [
    ('arm: {launch: fist}', "unknown arm action 'launch'"),
    ('drone: {arm: fist}', "unknown drone action 'arm'"),
    ('boat: {arm: fist}', "unknown section 'boat'"),
    ('arm: [fist]', 'arm: a mapping of actions'),
    ('- fist', 'a mapping of sections'),
    ('arm: {stop: 3}', 'arm.stop: a gesture name or a list of them, not 3'),
    ('arm: {stop: [fist, ""]}', 'arm.stop: a gesture name'),
    ('arm: {stop: circle}', "arm.stop: 'circle' is a moment"),
    ('arm: {stop: open, arm: open}', "'open' is bound to both arm.arm and arm.stop"),
    ('arm: {stop: [fist\n', 'line'),
    # blank reads as "keep the default" but unbound the fist's stop
    ('arm:\n  stop:\n', 'arm.stop: no gesture given (write [] to leave it unbound'),
    ('drone: {land: ~}', 'drone.land: no gesture given'),
])
def test_bad_files_get_one_clear_error(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(BindingError) as e:
        load_bindings(path)
    assert message in str(e.value) and path in str(e.value)
    assert '\n' not in str(e.value)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(BindingError, match='missing.yaml: cannot read'):
        load_bindings(str(tmp_path / 'missing.yaml'))


def test_unknown_gestures_are_named_against_what_the_model_reports(tmp_path):
    b = load_bindings(write(tmp_path, 'arm: {arm: peace}'))
    with pytest.raises(BindingError, match="arm.arm: unknown gesture 'peace' \\(known: "):
        b.check(())
    assert b.check(('peace',)) is b
    with pytest.raises(BindingError, match="unknown gesture 'peace'"):
        HandTracker('right', GestureRecognizer(), bindings=b)     # the shipped model
    with pytest.raises(BindingError, match="class 'fold' takes the name"):
        Bindings().check(('fold',))


def state(**kw):
    return GestureState(**kw)


def test_flags_follow_the_bound_gestures():
    actions = Bindings({'arm': {'arm': 'two', 'origin': ['rock', 'gun'],
                                'stop': 'thumb_down', 'gripper': ['pinch', 'open']}}
                       ).applier(('two', 'gun'))
    assert actions.flags(state(thumb_up=True, fist=True)) == (False, False, False, False, 0.0)
    assert actions.flags(state(user=('two',))) == (True, False, False, False, 0.0)
    assert actions.flags(state(user=('gun',), thumb_down=True)) == (False, True, True, False, 0.0)
    assert actions.flags(state(pinch=True, pinch_value=0.3)) == (False, False, False, True, 0.3)
    assert actions.flags(state(open=True)) == (False, False, False, True, GRIPPER_CLOSED)


def test_events_become_the_bound_drone_actions():
    actions = Bindings({'drone': {'takeoff': 'two', 'land': 'unfold', 'flip': ['circle', 'gun'],
                                  'hover': 'open'}}).applier(('two', 'gun'))
    circle = HandEvent('circle_ccw', True, 0.07, 'index', (1.0, 2.0, 3.0))
    out = actions.events([HandEvent('hand_found'), HandEvent('two'), HandEvent('fold'),
                          HandEvent('unfold'), circle, HandEvent('gun'),
                          HandEvent('open'), HandEvent('two', False)])
    assert [(e.gesture, e.active) for e in out] == [
        ('hand_found', True), ('two', True), ('unfold', True),     # takeoff on two's start
        # the raw fold is bound to nothing now: not sent; unfold is the landing
        ('fold', True), ('circle_ccw', True), ('gun', True), ('circle_cw', True),
        ('open', True), ('hover', True), ('two', False)]
    assert out[4].value == 0.07 and out[4].source == 'index' and out[4].center == (1.0, 2.0, 3.0)
    assert out[6].value == BOUND_FLIP_RADIUS_M
    default = Bindings().applier()
    events = [HandEvent('unfold'), HandEvent('circle_cw', True, 0.05)]
    assert default.events(events) is events                      # the defaults change nothing


def frames(*segments, t0=100.0, dt=0.01):
    """Frames of right hands: (pose, n frames) segments."""
    out, i = [], 0
    for pose, n in segments:
        for _ in range(n):
            hands = [render_hand('right', pose, [0, 200, 0])] if pose else []
            out.append(Frame(id=i, timestamp=t0 + i * dt, hands=hands))
            i += 1
    return out


def run(li, frames_):
    return [li.on_frame(f)['right'] for f in frames_]


def test_tracker_applies_bindings_to_flags_origin_and_events():
    b = Bindings({'arm': {'arm': 'open', 'origin': 'fist', 'stop': 'rock'},
                  'drone': {'takeoff': 'thumb_up', 'hover': 'rock'}})
    li = LeapInterface(sides=['right'], bindings=b)
    states = run(li, frames(('fist', 40), ('open', 40), ('rock', 20), ('thumbs_up', 20)))
    fist, opened, rock, thumb = states[39], states[79], states[99], states[119]
    assert fist.rock and fist.origin_set and not fist.fist          # fist sets the origin
    assert opened.thumb_up and opened.origin_set and not opened.rock    # open arms
    assert rock.fist and not rock.rock                               # rock stops
    assert not thumb.thumb_up                                        # thumbs-up arms no more
    names = [e.gesture for s in states for e in s.events]
    # fist -> open is a raw unfold: bound to nothing now, so no takeoff from it
    assert names.count('unfold') == 1
    assert [e.gesture for e in thumb.events] == [] and 'unfold' in [
        e.gesture for s in states[100:] for e in s.events]
    assert 'hover' in [e.gesture for s in states[80:100] for e in s.events]


def test_default_tracker_is_unchanged():
    li = LeapInterface(sides=['right'])
    states = run(li, frames(('fist', 40), ('open', 40)))
    assert states[39].fist and not states[39].rock and states[79].open
    assert [e.gesture for s in states for e in s.events if e.gesture in ('unfold', 'fold')] == [
        'unfold']


def test_no_model_class_can_take_a_name_the_bindings_reserve():
    # train_gestures accepted --label hover, whose model every recognizer then refused
    from leap_teleop.hands.gestures.bindings import RESERVED
    from leap_teleop.hands.gestures.classifier import class_name_problem
    built_in_classes = {'fist', 'open', 'pinch', 'rock', 'thumb', 'none'}
    for name in RESERVED - built_in_classes:
        assert class_name_problem(name), name
