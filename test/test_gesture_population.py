"""The recognizer on people it was not tuned on: named gesture variants, hand sizes,
orientations, missing fields (leap_teleop.population), the population's figures against
the goals, circles only from circles, and a thumbs-down never arming an arm."""
import dataclasses
import math

import numpy as np
import pytest

from leap_teleop import population as pop
from leap_teleop.gestures import GestureRecognizer
from leap_teleop.teleop.arm import ARMED, DISARMED, ArmTeleop, HandInput
from leap_teleop.tools import evaluate_population
from leap_teleop.ur10 import kinematics as kin

HELD = ('fist', 'thumb_up', 'thumb_down', 'pinch', 'rock', 'open')
BASE = pop.make_people(1, seed=0)[0]
# A tidy tracker: no noise, no dips, nothing missing (the variants are what is tested).
CLEAN = dict(palm_noise=0.0, tip_noise=0.0, missing='', mistrack_rate=0.0, dip_rate=0.0)


def person(**kw):
    values = dict(CLEAN)
    values.update(kw)
    return dataclasses.replace(BASE, **values)


def shown(p, pose, seed=0, frames=30):
    """The set of gestures on at the end of a take, over several takes (orientations)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(6):
        rec = GestureRecognizer()
        state = None
        for hand, t in pop.take(p, pose, rng, frames=frames):
            state = rec.update(hand, t)
        out.append({g for g in HELD if getattr(state, g)})
    return out


@pytest.mark.parametrize('side', ['right', 'left'])
@pytest.mark.parametrize('thumb', ['tucked', 'alongside', 'over'])
@pytest.mark.parametrize('looseness', [0.0, 1.0])
def test_fist_tight_or_loose_with_the_thumb_tucked_alongside_or_laid_over(side, thumb,
                                                                           looseness):
    assert shown(person(side=side, fist_thumb=thumb, looseness=looseness),
                 'fist') == [{'fist'}] * 6


@pytest.mark.parametrize('looseness', [0.0, 1.0])
def test_a_hooked_index_beside_a_fist_is_no_gesture(looseness):
    assert shown(person(looseness=looseness), 'hook') == [set()] * 6
    # Without knuckle positions only the bends tell: enough beside a tight fist (beside a
    # loose one the hook and a curled index overlap: a known limit, in the population).
    if looseness == 0.0:
        assert shown(person(looseness=looseness, missing='knuckles'), 'hook') == [set()] * 6


@pytest.mark.parametrize('thumb', ['folded', 'out'])
def test_horns_with_the_thumb_folded_or_out(thumb):
    assert shown(person(horns_thumb=thumb), 'horns') == [{'rock'}] * 6


def test_hang_loose_is_not_rock():
    assert shown(person(), 'hang_loose') == [set()] * 6


@pytest.mark.parametrize('style', ['flat', 'relaxed'])
def test_open_hand_flat_or_relaxed_and_with_one_mistracked_finger(style):
    assert shown(person(open_style=style), 'open') == [{'open'}] * 6
    assert shown(person(open_style=style, mistrack_rate=1.0), 'open', seed=1) == [{'open'}] * 6


@pytest.mark.parametrize('fingers', ['straight', 'relaxed', 'curled', 'O'])
def test_ok_sign_with_the_other_fingers_in_any_state_or_gathered_as_an_o(fingers):
    assert shown(person(ok_fingers=fingers), 'ok') == [{'pinch'}] * 6
    # fingers rounded with their tips apart (the 'O' confuser) or a C: no pinch
    assert all('pinch' not in s for s in shown(person(), 'O') + shown(person(), 'C'))



@pytest.mark.parametrize('side', ['right', 'left'])
def test_an_o_whose_index_curls_past_150_deg_is_a_pinch(side):
    """A round "O" may bend the index 150 deg and more (the pinch's index limit keeps a fist's
    index curled under a laid-over thumb out; the O's gathered fingertips are no fist)."""
    p = person(side=side, ok_fingers='O')
    seeds = [s for s in range(400)
             if pop.local_pose(p, 'ok', np.random.default_rng(s))[1][0].sum() >= 150.0][:6]
    assert len(seeds) == 6
    for s in seeds:
        rec = GestureRecognizer()
        states = [rec.update(hand, t) for hand, t in pop.take(p, 'ok', np.random.default_rng(s))]
        assert all(st.pinch and not st.fist for st in states[6:]), s


def test_thumbs_up_down_and_sideways():
    assert shown(person(), 'thumbs_up') == [{'thumb_up'}] * 6
    assert shown(person(), 'thumbs_down') == [{'thumb_down'}] * 6
    assert shown(person(), 'sideways_thumb') == [set()] * 6


@pytest.mark.parametrize('breadth', [72.0, 97.0])     # 5th / 95th percentile hand breadth
def test_small_and_large_hands(breadth):
    p = person(palm_width=0.62 * breadth)
    for pose in pop.POSES:
        want = {pop.EXPECTED[pose]} if pose in pop.EXPECTED else set()
        got = shown(p, pose, frames=20)
        if pose == 'O':
            got = [s - {'fist'} for s in got]       # not held against fist (population docs)
        assert got == [want] * 6, (breadth, pose)


@pytest.mark.parametrize('missing', ['knuckles', 'joints', 'strengths', 'timestamps'])
def test_missing_fields_degrade_not_fail(missing):
    p = person(missing=missing)
    for pose in ('fist', 'thumbs_up', 'thumbs_down', 'ok', 'horns', 'open', 'three', 'L'):
        want = {pop.EXPECTED[pose]} if pose in pop.EXPECTED else set()
        assert shown(p, pose, frames=20) == [want] * 6, (missing, pose)


def test_thumbs_down_never_thumbs_up_and_never_arms():
    rng = np.random.default_rng(5)
    frames = shown_down = 0
    for p in pop.make_people(20, seed=5):
        rec = GestureRecognizer()
        arm = ArmTeleop()
        arm.on_joints(kin.HOME_Q.copy())
        for hand, t in pop.take(p, 'thumbs_down', rng, frames=90):     # 1.5 s held
            t = 0.0 if math.isnan(t) else t
            s = rec.update(hand, t)
            assert not s.thumb_up
            arm.on_hand(HandInput(present=True, palm_mm=(0.0, 200.0, 0.0), fist=s.fist,
                                  thumb_up=s.thumb_up, stamp=100.0 + t), 100.0 + t)
            arm.step(100.0 + t)
            assert arm.status.state == DISARMED
            frames += 1
        shown_down += s.thumb_down
    # It was a thumbs-down the arm saw (not no hand at all): every person's is recognised.
    assert frames == 20 * 90 and shown_down == 20


def test_a_held_thumbs_up_arms():
    rng = np.random.default_rng(6)
    rec, arm = GestureRecognizer(), ArmTeleop()
    arm.on_joints(kin.HOME_Q.copy())
    for hand, t in pop.take(person(), 'thumbs_up', rng, frames=40):
        s = rec.update(hand, t)
        arm.on_hand(HandInput(present=True, palm_mm=(0.0, 200.0, 0.0), thumb_up=s.thumb_up,
                              stamp=100.0 + t), 100.0 + t)
        arm.step(100.0 + t)
    assert arm.status.state == ARMED


def test_population_is_seeded_and_spans_adult_hands():
    a, b = pop.make_people(300, seed=3), pop.make_people(300, seed=3)
    assert all(x.palm_width == y.palm_width and np.array_equal(x.lengths, y.lengths)
               and x.missing == y.missing for x, y in zip(a, b))
    widths = np.array([x.palm_width for x in a])
    assert widths.min() <= 0.62 * 74 and widths.max() >= 0.62 * 95
    for attr, values in (('fist_thumb', {'tucked', 'alongside', 'over'}),
                         ('ok_fingers', {'straight', 'relaxed', 'curled', 'O'}),
                         ('horns_thumb', {'folded', 'out'}),
                         ('missing', {'', 'knuckles', 'joints', 'strengths', 'timestamps'}),
                         ('side', {'right', 'left'})):
        assert {getattr(x, attr) for x in a} == values


@pytest.fixture(scope='module')
def figures():
    return evaluate_population.run(n_people=40, seed=11, frames=24)


@pytest.mark.parametrize('gesture', evaluate_population.GESTURES)
def test_population_meets_the_goals(figures, gesture):
    r = figures['gestures'][gesture]
    assert r['recall'] >= 0.95 and r['fpr'] <= 0.01 and r['worst10_recall'] >= 0.85, r


def test_only_circles_make_circles(figures):
    m = figures['motions']
    assert m['circle_fired']['circle'] >= 0.95
    assert m['flip_sized_circle']['circle'] >= 0.95
    assert m['circle_fired']['finger_circle'] >= 0.95      # pointing index, 40-120 mm
    for kind in ('swipe', 'tap', 'point_tap', 'knob', 'translate', 'arc'):
        assert m['flip_sized_circle'][kind] == 0.0, kind
        assert m['circle_fired'][kind] <= 0.01, (kind, m)
