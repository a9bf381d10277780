"""Circles drawn in the air by real people (the drone's flip): the strokes evaluation meets
the recognition goals with the shipped rules, loop-free strokes never fire, a drawn circle
fires once, and no shared take fires one. Needs ../shared/data (fails without it)."""
import math
import os

import pytest

from leap_teleop.hands.gestures import GestureRecognizer
from tools.evaluation import strokes as es

# fits models or fuzzes for minutes: not in make check
pytestmark = pytest.mark.slow

ZIG_ZAG_LIKE = ('zig-zag', 'check', 'caret', 'v')


def _need(path):
    if not os.path.exists(path):
        pytest.fail('shared data missing: %s' % path)
    return path


@pytest.fixture(scope='module')
def strokes():
    return es.load_strokes(_need(es.STROKES_DATA))


@pytest.fixture(scope='module')
def hands():
    _need(os.path.join(es.LEAP_PEOPLE_DATA, 'gti_dev.jsonl.gz'))
    return es.template_hands(es.LEAP_PEOPLE_DATA)


@pytest.fixture(scope='module')
def loso_command(leapjs_data, tmp_path_factory):
    """The LOSO command, run once (about half a minute): (exit code, its stdout, the JSON it
    wrote, the results dict its run() returned). Its run() computes the shipped rules'
    figures before the refit, so the tests of those read them here instead of running
    the evaluation a second time."""
    import contextlib
    import io
    import json
    _need(es.STROKES_DATA)
    _need(es.LEAP_PEOPLE_DATA)
    out = tmp_path_factory.mktemp('strokes') / 'strokes.json'
    returned, real_run = [], es.run
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(io.StringIO()) as text:
        mp.setattr(es, 'run', lambda *a, **kw: returned.append(real_run(*a, **kw)) or returned[-1])
        rc = es.main(['--loso', '--leapjs', leapjs_data, '--json', str(out)])
    written = json.loads(out.read_text()) if out.exists() else None
    return rc, text.getvalue(), written, (returned or [None])[0]


@pytest.fixture(scope='module')
def results(loso_command):
    rc, _, _, returned = loso_command
    assert rc == 0 and returned is not None
    return returned


def test_strokes_evaluation_meets_the_goals(results):
    total = results['total']
    assert len(results['people']) == 7
    for hand, c in total['per_hand'].items():
        # >= 6 of 7 people's circles, with either hand
        assert c['circles'] == 7 and c['circles_recognized'] >= 6, (hand, c)
        # <= 2 % of loop-free strokes fire one
        assert c['loop_free'] >= 70 and c['loop_free_fired'] <= 0.02 * c['loop_free'], (hand, c)
    assert total['circles_fired_twice'] == 0
    # every person, the worst included: their circle, no loop-free stroke
    for person, c in results['per_person'].items():
        assert c['circles_recognized'] == c['circles'] == 2, person
        assert c['loop_free_fired'] == 0, person


def test_no_circle_event_on_the_guinevere_and_leapjs_takes(results):
    assert results['takes'] == {'guinevere': 92, 'leapjs': 13}
    assert results['take_events'] == {} and results['takes_with_circles'] == 0


def test_results_are_json_and_print(results, capsys):
    import json
    json.dumps(results)
    es.print_table(results)
    out = capsys.readouterr().out
    assert 'worst person' in out and 'zig-zag' in out


@pytest.mark.parametrize('symbol', ZIG_ZAG_LIKE)
@pytest.mark.parametrize('hand_kind', sorted(es.HANDS))
def test_zig_zag_check_caret_and_v_never_fire(strokes, hands, symbol, hand_kind):
    drawn = 0
    for k, person in enumerate(sorted(strokes)):
        if symbol not in strokes[person]:
            continue
        t, xyz = strokes[person][symbol]
        for hand in hands[hand_kind][:6]:      # every person's stroke, 6 real hands
            assert es.draw(hand, t, xyz) == [], (person, hand_kind)
            drawn += 1
    assert drawn >= 6 * 6


@pytest.mark.parametrize('hand_kind', sorted(es.HANDS))
def test_a_drawn_circle_fires_exactly_once_at_its_size(strokes, hands, hand_kind):
    for person in sorted(strokes):
        t, xyz = strokes[person]['circle']
        for hand in hands[hand_kind][:4]:
            events = es.draw(hand, t, xyz)
            assert len(events) == 1, (person, hand_kind, events)
            e = events[0][1]
            # a pointing hand's palm follows its finger: either may close the circle first
            assert e.source in (('index', 'palm') if hand_kind == 'pointing' else ('palm',))
            # the people's circles are 120-260 mm across
            assert 50.0 <= e.value * 1e3 <= 140.0, (person, e)


@pytest.mark.parametrize('symbol,fires', [('circle', 1), ('zig-zag', 0), ('check', 0)])
def test_a_pointing_hand_read_as_not_pointing_now_and_then_keeps_its_circle(
        strokes, hands, symbol, fires):
    # The pose rules may read a moving pointing hand's middle finger as out on a frame:
    # every 10th frame here. The circle still fires once (the palm keeps the path), and
    # loop-free strokes still do not.
    for k, person in enumerate(sorted(strokes)):
        if symbol not in strokes[person]:
            continue
        t, xyz = strokes[person][symbol]
        calls = []
        es.draw(hands['pointing'][k], t, xyz, es._recording_recognizer(calls))
        assert all(c[3][1] and not c[3][2] for c in calls)
        flicker = [c[:3] + ((c[3][:2] + (True,) + c[3][3:]) if i % 10 == 5 else c[3],)
                   for i, c in enumerate(calls)]
        assert len(es.replay(flicker, es.DRAWN)) == fires, person


def test_a_circle_drawn_twice_fires_twice_and_a_lost_hand_forgets(strokes, hands):
    t, xyz = strokes['chiara']['circle']
    hand = hands['pointing'][0]
    rec = GestureRecognizer()
    first = es.draw(hand, t, xyz, rec)
    second = es.draw(hand, t + t[-1] + 0.5, xyz, rec)
    assert len(first) == 1 and len(second) == 1
    # half a circle, the hand lost, the other half: no circle
    rec = GestureRecognizer()
    n = len(t) // 2
    assert es.draw(hand, t[:n], xyz[:n], rec) == []
    rec.reset()
    assert es.draw(hand, t[n:], xyz[n:], rec) == []


def test_missing_data_is_a_clear_error(tmp_path):
    with pytest.raises(es.DataError, match='strokes'):
        es.load_strokes(str(tmp_path / 'nowhere'))
    with pytest.raises(es.DataError, match='gti_dev'):
        es.template_hands(str(tmp_path))
    bad = tmp_path / 'someone'
    bad.mkdir()
    (bad / 'circle.csv').write_text('1 2 3\n4 5 6\n')
    with pytest.raises(es.DataError, match='4 finite numbers'):
        es.load_strokes(str(tmp_path))
    assert es.main(['--strokes', str(tmp_path / 'nowhere')]) == 2


def test_loso_command_meets_the_goals(loso_command):
    # The goals as they are measured: the rules refitted on 6 people, scored on
    # the 7th, for each person.
    rc, text, written, _ = loso_command
    assert rc == 0
    assert 'leave-one-person-out' in text
    lo = written['loso']
    assert sorted(lo['folds']) == sorted(es.load_strokes())
    for hand, c in lo['pooled']['per_hand'].items():
        assert c['circles'] == 7 and c['circles_recognized'] >= 6, (hand, c)
        assert c['loop_free_fired'] <= 0.02 * c['loop_free'], (hand, c)
    for person, fold in lo['folds'].items():
        assert fold['held_out']['take_events'] == 0, person
    # the shipped rules are the ones fitted on all 7 people
    assert lo['all_people_rules'] == es._rules_dict(es.DRAWN)


def _moved(calls, dt, d):
    """The recorded calls `dt` s later, the hand `d` mm along x."""
    import dataclasses
    out = []
    for c in calls:
        hand, t, g, extended = c
        g = dataclasses.replace(g, palm=[g.palm[0] + d, g.palm[1], g.palm[2]],
                                tips_world=[[p[0] + d, p[1], p[2]] for p in g.tips_world])
        out.append((hand, t + dt, g, extended))
    return out


def test_the_refit_replays_rules_as_the_circle_detector(strokes, hands):
    # The LOSO refit replays each candidate rules through RecordedCircles, not through a
    # CircleDetector: the same events (times, senses, radii, centres, sources) on strokes
    # that fire from the palm and from the index tip, several times, with the hand lost
    # in between, a jump across the view and time going back.
    import dataclasses
    import math
    people = sorted(strokes)
    recorded = {}
    for kind, person, symbol in (('pointing', 'elenaf', 'spiral'), ('pointing', 'andrea', 'circle'),
                                 ('open', 'andrea', 'spiral'), ('pointing', 'chiara', 'zig-zag')):
        t, xyz = strokes[person][symbol]
        calls = recorded[kind, person, symbol] = []
        hand = hands[kind][people.index(person) % len(hands[kind])]
        es.draw(hand, t, xyz, es._recording_recognizer(calls))
    circle = recorded['pointing', 'andrea', 'circle']
    spiral = recorded['pointing', 'elenaf', 'spiral']
    span = circle[-1][1] + 0.5
    recordings = list(recorded.values()) + [
        circle + _moved(circle, span, 500.0) + [None] + _moved(spiral, 2 * span, 0.0),
        spiral + _moved(spiral, 0.0, 0.0)]          # time going back
    drawn = es.DRAWN
    rules = [drawn, es.CircleRules(),
             dataclasses.replace(drawn, tip_v_max=800.0, min_across=0.3),
             dataclasses.replace(drawn, r_max=100.0, max_s=1.6, min_roundness=0.5),
             dataclasses.replace(drawn, arc=1.5 * math.pi, r_max=math.inf, min_across=0.9)]
    fits = es.CachedFits()
    sources = set()
    for calls in recordings:
        recording = es.RecordedCircles(calls, fits)
        for r in rules:
            want = es.replay(calls, r)
            assert recording.events(r) == want, r
            assert recording.events(r, most=2) == want[:2], r      # what the refit reads
            sources.update(e.source for _, e in want)
    assert sources == {'palm', 'index'}


def _drawn(seconds, palm, tip, normal=lambda t: (0.0, 1.0, 0.0)):
    """Recorded calls of a pointing hand at 120 Hz whose palm and index tip are at palm(t)
    and tip(t) (mm), its palm normal normal(t), its finger along -z."""
    from types import SimpleNamespace

    import numpy as np
    hand = SimpleNamespace(fingers=[None, SimpleNamespace(direction=np.array([0.0, 0.0, -1.0]))])
    calls = []
    for k in range(int(seconds * 120)):
        t = k / 120.0
        g = SimpleNamespace(palm=list(palm(t)), tips_world=[None, list(tip(t))],
                            basis=(None, normal(t), (0.0, 0.0, -1.0)))
        calls.append((hand, t, g, (False, True, False, False, False)))
    return calls


def _loop(radius, period, centre=(0.0, 200.0, 0.0), jitter=0.0, moved_at=math.inf, by=0.0):
    """A point going round (x-y plane), `jitter` mm back and forth along x every other
    frame, moved `by` mm along x from time `moved_at` on."""
    def at(t):
        a = 2.0 * math.pi * t / period
        x = centre[0] + radius * math.cos(a) + (jitter if round(t * 120) % 2 else -jitter)
        return x + (by if t >= moved_at else 0.0), centre[1] + radius * math.sin(a), centre[2]
    return at


def test_the_refit_replays_the_detectors_rarer_paths():
    # As above, on made-up hands that reach what the people's strokes do not: circles
    # closing within the refractory time, a jittery tip that reads as a swipe, a palm
    # that turned before the circle, a hand jumping across the view.
    import dataclasses

    def still(t):
        return 0.0, 150.0, 0.0

    def turning(t):
        a = math.radians(60.0 * min(t, 1.0))
        return math.sin(a), math.cos(a), 0.0

    drawn = es.DRAWN
    cases = [   # (calls, the rules they are replayed with)
        (_drawn(1.2, _loop(30.0, 0.2, (0.0, 150.0, 0.0)), _loop(30.0, 0.2)), [drawn, es.CircleRules()]),
        (_drawn(2.0, still, _loop(50.0, 1.0, jitter=3.0)),
         [drawn, dataclasses.replace(drawn, tip_v_max=800.0)]),
        (_drawn(3.5, still, _loop(50.0, 1.0), normal=turning), [drawn, dataclasses.replace(drawn, max_s=1.0)]),
        (_drawn(2.5, _loop(40.0, 0.5, (0.0, 150.0, 0.0), moved_at=1.3, by=3000.0),
                _loop(40.0, 0.5, moved_at=1.3, by=3000.0)),
         [drawn, dataclasses.replace(drawn, r_max=50.0, max_s=1.0)])]
    fits = es.CachedFits()
    for calls, rules in cases:
        recording = es.RecordedCircles(calls, fits)
        for r in rules:
            assert recording.events(r) == es.replay(calls, r), r
