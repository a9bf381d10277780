"""Circles drawn in the air by real people (the drone's flip): the strokes evaluation meets
the issue's goals with the shipped rules, loop-free strokes never fire, a drawn circle
fires once, and no shared take fires one. Needs ../shared/data (fails without it)."""
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
    """The LOSO command, run once (about 1-2 minutes): (exit code, its stdout, the JSON it
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
    # The goals as the issue measures them: the rules refitted on 6 people, scored on
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
