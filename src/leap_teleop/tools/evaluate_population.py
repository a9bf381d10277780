"""The recognizer on the synthetic population (leap_teleop.population).

Every person holds every pose of population.POSES once (30 frames at 60 Hz, one draw of
the pose, orientation and noise), each take through a fresh stream recognizer; the first
SETTLE_FRAMES of a take are not scored (the temporal filter needs on_frames to turn a
gesture on). Per gesture: recall over the frames of its pose, false-positive rate over
the frames of every other pose (the other gestures and the confusers). One exception: an
"O" (the fingers rounded onto the thumb tip) is not held against fist - to the rules a
closed O and the tracker's loose fists are the same hand - and its fist rate is reported
beside (o_read_as_fist). Worst 10 %: per gesture, the people sorted by their recall, the
pooled recall of the lowest tenth and the lowest person's.

Motions (population.motion_take): the fraction of takes with a circle event, per kind;
only 'circle' (the palm, hand-sized: >= 25 mm) and 'finger_circle' (a pointing index)
should fire.
"""
import numpy as np

from .. import population as pop
from ..gestures import GestureRecognizer

GESTURES = tuple(pop.GESTURE_POSES)
SETTLE_FRAMES = 6
NOT_HELD_AGAINST = {'O': {'fist'}}


def run(n_people=200, seed=1, frames=30):
    people = pop.make_people(n_people, seed=seed)
    rng = np.random.default_rng(seed + 1000)
    # per person, pose: frames scored and counts per gesture
    on = np.zeros((n_people, len(pop.POSES), len(GESTURES)))
    scored = np.zeros((n_people, len(pop.POSES)))
    for pi, person in enumerate(people):
        for qi, pose in enumerate(pop.POSES):
            rec = GestureRecognizer()
            for k, (hand, t) in enumerate(pop.take(person, pose, rng, frames=frames)):
                s = rec.update(hand, t)
                if k < SETTLE_FRAMES:
                    continue
                scored[pi, qi] += 1
                on[pi, qi] += [bool(getattr(s, g)) for g in GESTURES]
    out = {'people': n_people, 'seed': seed, 'frames_per_take': frames, 'gestures': {}}
    for gi, g in enumerate(GESTURES):
        qi = pop.POSES.index(pop.GESTURE_POSES[g])
        per_person = on[:, qi, gi] / scored[:, qi]
        neg = [j for j, pose in enumerate(pop.POSES)
               if j != qi and g not in NOT_HELD_AGAINST.get(pose, ())]
        fpr = on[:, neg, gi].sum() / scored[:, neg].sum()
        order = np.argsort(per_person, kind='stable')
        worst = order[:max(1, n_people // 10)]
        out['gestures'][g] = {
            'recall': round(float(on[:, qi, gi].sum() / scored[:, qi].sum()), 4),
            'fpr': round(float(fpr), 4),
            'worst10_recall': round(float(on[worst, qi, gi].sum() / scored[worst, qi].sum()), 4),
            'min_person_recall': round(float(per_person.min()), 4),
            'frames': int(scored[:, qi].sum())}
    # what each confuser was read as (any gesture, per frame)
    out['confusers'] = {pose: {g: round(float(on[:, j, gi].sum() / scored[:, j].sum()), 4)
                               for gi, g in enumerate(GESTURES)}
                        for j, pose in enumerate(pop.POSES) if pose in pop.CONFUSERS}
    out['o_read_as_fist'] = out['confusers']['O']['fist']
    # the worst tenth of people over every gesture at once: their pooled recall
    rec_all = np.array([on[:, pop.POSES.index(pop.GESTURE_POSES[g]), gi]
                        / scored[:, pop.POSES.index(pop.GESTURE_POSES[g])]
                        for gi, g in enumerate(GESTURES)]).mean(axis=0)
    worst = np.argsort(rec_all, kind='stable')[:max(1, n_people // 10)]
    out['worst10_people_mean_recall'] = round(float(rec_all[worst].mean()), 4)
    out['motions'] = motions(n_people // 2, seed)
    return out


def motions(n_people=100, seed=1):
    people = pop.make_people(n_people, seed=seed + 7)
    rng = np.random.default_rng(seed + 2000)
    fired = {k: 0 for k in pop.MOTIONS}
    flips = {k: 0 for k in pop.MOTIONS}     # a palm circle >= 25 mm: what flips the drone
    for person in people:
        for kind in pop.MOTIONS:
            rec = GestureRecognizer()
            events = [e for hand, t in pop.motion_take(person, kind, rng)
                      for e in rec.update(hand, t).events if e.gesture.startswith('circle')]
            fired[kind] += bool(events)
            flips[kind] += any(e.value >= 0.025 for e in events)
    return {'takes_per_kind': n_people,
            'circle_fired': {k: round(v / n_people, 4) for k, v in fired.items()},
            'flip_sized_circle': {k: round(v / n_people, 4) for k, v in flips.items()}}


def print_table(res):
    print('synthetic population: %d people x %d poses (seed %d)'
          % (res['people'], len(pop.POSES), res['seed']))
    print('%-10s %7s %7s %14s %11s' % ('gesture', 'recall', 'FPR', 'worst 10% rec', 'min person'))
    for g, r in res['gestures'].items():
        print('%-10s %7.3f %7.4f %14.3f %11.3f' % (g, r['recall'], r['fpr'], r['worst10_recall'],
                                                   r['min_person_recall']))
    print('worst 10%% of people (mean recall over the gestures): %.3f; an O read as fist: %.3f'
          % (res['worst10_people_mean_recall'], res['o_read_as_fist']))
    m = res['motions']
    print('takes with a circle event (%d per kind): %s' % (m['takes_per_kind'], ', '.join(
        '%s %.2f' % kv for kv in m['circle_fired'].items())))
