"""Why the leave-one-person-out evaluation missed a gesture: the model chose another
class, its class fell below MIN_P, or a guard said no (tools/evaluation/people.py)."""
from leap_teleop.hands.gestures import HELD_GESTURES
from tools.evaluation import people as ep


def decision(label, probability, **on):
    d = dict.fromkeys(HELD_GESTURES, False)
    d.update(on, label=label, probability=probability)
    return d


def test_each_cause_of_a_miss_is_told_apart():
    assert ep.why_missed(decision('none', 0.9), 'fist') == 'model: none'
    assert ep.why_missed(decision('open', 0.7, open=True), 'pinch') == 'model: open'
    assert ep.why_missed(decision('fist', 0.4), 'fist') == 'below MIN_P'
    # a thumb the model is sure of, but not measured up (or below THUMB_UP_MIN_P)
    assert ep.why_missed(decision('thumb', 0.9), 'thumb_up') == 'guard'
    assert ep.why_missed(decision('fist', 0.9, fist=True), 'thumb_up') == 'model: fist'
    assert ep.why_missed(decision('', 0.0), 'open') == 'no joints'


def test_the_tally_counts_causes_of_missed_positives_only():
    t = ep.Tally()
    t.add('a', 'fist_moved', 'fist', 'fist', 'never counted: a hit')
    t.add('a', 'fist_moved', 'fist', 'nothing', 'model: none')
    t.add('b', 'fist_moved', 'fist', 'thumb_up', 'model: thumb')
    t.add('b', 'fist_moved', 'fist', 'nothing', 'model: none')
    t.add('b', 'two', 'nothing', 'fist', 'a negative: no cause')
    t.add('b', 'ok', 'pinch', 'nothing')            # no cause given: not counted
    s = t.summary()['per_gesture']
    assert s['fist']['missed_because'] == {'model: none': 2, 'model: thumb': 1}
    assert s['pinch']['missed_because'] == {}
    assert s['fist']['recall_per_person'] == {'a': 0.5, 'b': 0.0}


def test_takes_that_did_not_arm_say_how_many_frames_read_thumbs_up():
    rows = [{'person': 'g1', 'take': 'thumbs_up-1', 'gesture': 'thumbs_up',
             'thumb_up_armed': False, 'thumb_down_held': False, 'thumb_up_frames': 2,
             'events': {}},
            {'person': 'g1', 'take': 'thumbs_up-2', 'gesture': 'thumbs_up',
             'thumb_up_armed': True, 'thumb_down_held': False, 'thumb_up_frames': 90,
             'events': {}},
            {'person': 'g2', 'take': 'thumbs_up-1', 'gesture': 'thumbs_up',
             'thumb_up_armed': False, 'thumb_down_held': False, 'thumb_up_frames': 0,
             'events': {}}]
    t = ep.take_summary(rows)
    assert t['thumbs_up_takes_armed'] == [1, 3]
    assert t['thumbs_up_takes_not_armed'] == {'g1/thumbs_up-1': 2, 'g2/thumbs_up-1': 0}


def test_an_unlabelled_frame_counts_against_thumbs_up_alone_read_as_it_or_not():
    # Before, only the unlabelled frames read as a thumbs-up were counted, as negatives
    # too: guinevere_02's knob turns made a thumbs-up FPR of 13 / (635 + 13), not 13 / 2889.
    t = ep.Tally()
    t.add('g', 'thumbs_up', 'thumb_up', 'thumb_up')
    for read in ['thumb_up'] + ['nothing'] * 8 + ['fist']:
        t.add_negative('g', 'thumb_up', 'turn_clockwise', read)
    s = t.summary()['per_gesture']
    assert s['thumb_up']['fpr_pooled'] == s['thumb_up']['fpr_worst'] == 0.1
    assert s['fist']['fpr_pooled'] == 0.0                       # the labelled frame alone
    assert t.summary()['confusion']['turn_clockwise'] == {'thumb_up': 1, 'nothing': 8, 'fist': 1}
