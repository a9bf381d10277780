"""The evaluation on the real recordings meets the issue's targets (fails without data)."""

import pytest

from leap_teleop.tools import evaluate


@pytest.fixture(scope='module')
def results(leapjs_data):
    return evaluate.evaluate(leapjs_data, verbose=False)


def test_all_takes_found(results):
    assert results['missing_takes'] == []


@pytest.mark.parametrize('gesture', evaluate.GESTURES)
def test_precision_and_recall_at_least_095_and_not_worse_than_original(results, gesture):
    r, o = results['recognizer'][gesture], results['original'][gesture]
    assert r['n'] > 500
    assert r['precision'] >= 0.95 and r['recall'] >= 0.95, r
    f1 = lambda s: 2 * s['precision'] * s['recall'] / (s['precision'] + s['recall'] or 1)  # noqa: E731
    assert f1(r) >= f1(o) - 1e-9, (r, o)


def test_no_pinch_and_no_fist_on_gun_and_open_hand_takes(results):
    assert results['recognizer']['no_pinch_no_fist_violations'] == 0


def test_circle_recall_against_the_sdk(results):
    # the SDK circles whose arc lies inside the recordings (evaluate's docstring)
    assert results['recognizer']['circle']['n'] == 5
    assert results['recognizer']['circle']['recall'] >= 0.9


@pytest.mark.xfail(strict=True, reason='known weak (precision 5/11 at recall 5/5): on flapping '
                   'every flap cycle makes the left thumb loop about the same centre; the SDK '
                   'called one of those loops a circle (its circle 86) and not the two later ones '
                   '(same radius, arc, roundness, speed, finger angle); it also left an earlier '
                   'thumb loop, 2 pinky loops of flapping and a 5.7 mm thumb loop in Waiting '
                   'unreported. Recall needs circle 86, so its siblings come with it')
def test_circle_events_agree_with_the_sdk_when_they_fire(results):
    assert results['recognizer']['circle']['precision'] >= 0.9


def test_circle_figures_over_every_take_include_the_two_circle_takes(results):
    every, two = results['circle_all_takes'], results['circle_events']
    per_take = every['per_take']
    assert sorted(per_take) == sorted(evaluate.EVERY_TAKE)
    # The two circle takes: the SDK circles inside them (4 in flapping, 1 in Waiting, read
    # off the data below) and the README's 5 of 11 events agreeing, 5 of 5 found.
    assert {t: per_take[t]['sdk_circles_in_recording'] for t in evaluate.CIRCLE_TAKES} == {
        'flapping': 4, 'Waiting-110fps': 1}
    assert two == {'events': 11, 'agreeing_events': 5, 'sdk_circles_in_recording': 5,
                   'matched': 5}
    # SDK circles drawn inside the other takes (their start events, read off the data)
    assert {t: v['sdk_circles_in_recording'] for t, v in per_take.items()
            if t not in evaluate.CIRCLE_TAKES and v['sdk_circles_in_recording']} == {
        'pinch': 1, 'rollAndPitchCropped': 5, 'test-paddle-rightwards': 1, 'three-claps': 2}
    assert every['sdk_circles_in_recording'] == 5 + 1 + 5 + 1 + 2
    # The figures the README states: 27 events, 6 on an SDK circle; 6 of the 14 found.
    assert (every['events'], every['agreeing_events'], every['matched']) == (27, 6, 6), every
    assert every['precision'] == pytest.approx(6 / 27, abs=1e-4)
    assert every['recall'] == pytest.approx(6 / 14, abs=1e-4)


def test_circle_ground_truth_counts_what_the_recordings_show(leapjs_data):
    rows, sdk = evaluate.run_take(evaluate.find_file(leapjs_data, 'flapping'))
    assert len(sdk) == 8 and sum(c.in_recording for c in sdk.values()) == 4
    rows, sdk = evaluate.run_take(evaluate.find_file(leapjs_data, 'Waiting-110fps'))
    assert len(sdk) == 2 and sum(c.in_recording for c in sdk.values()) == 1
    assert all(c.clockwise is not None for c in sdk.values())


def test_a_circle_event_agrees_only_with_the_sdk_circle_it_is():
    from leap_teleop.gestures import GestureEvent
    sdk = evaluate.SdkCircle('left', 1.0, 1.2, False)
    sdk.finger, sdk.places = 'thumb', [([20.0, 170.0, 25.0], 17.0)]
    rows = lambda e, t=1.1, side='left': [(0, side, type('S', (), {'events': [e]}), None, t)]  # noqa: E731
    here = GestureEvent('circle_ccw', True, 0.017, 'thumb', (22.0, 166.0, 27.0))
    assert evaluate.circle_agreement(rows(here), {1: sdk}) == (1, 1, 1, 1)
    for other in (GestureEvent('circle_ccw', True, 0.017, 'pinky', (22.0, 166.0, 27.0)),   # finger
                  GestureEvent('circle_ccw', True, 0.017, 'thumb', (22.0, 215.0, 27.0)),   # place
                  GestureEvent('circle_cw', True, 0.017, 'thumb', (22.0, 166.0, 27.0))):   # sense
        assert evaluate.circle_agreement(rows(other), {1: sdk}) == (0, 1, 0, 1)
    assert evaluate.circle_agreement(rows(here, t=1.5), {1: sdk}) == (0, 1, 0, 1)        # time
    assert evaluate.circle_agreement(rows(here, side='right'), {1: sdk}) == (0, 1, 0, 1)
    # a palm circle carries every fingertip round its own centre: placed by hand and time
    palm = GestureEvent('circle_ccw', True, 0.05, 'palm', (0.0, 200.0, 0.0))
    assert evaluate.circle_agreement(rows(palm), {1: sdk}) == (1, 1, 1, 1)


def test_main_writes_the_json(tmp_path):
    import json
    out = tmp_path / 'eval_results.json'
    assert evaluate.main(['--out', str(out)]) == 0
    data = json.loads(out.read_text())
    for who in ('recognizer', 'original'):
        for g in evaluate.GESTURES:
            assert set(data[who][g]) == {'precision', 'recall', 'n'}
