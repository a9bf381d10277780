"""The arm bench's real hand motion: the palm paths it replays and its figures on them."""
import numpy as np
import pytest

from tools import hand_paths
from tools.bench import bench_arm_motion as bench
from tools.closed_loop import sim_params

# runs the simulated cell: not in make check
pytestmark = pytest.mark.integration


def test_real_paths_are_moving_hands_of_both_people_and_the_leapjs_takes(leapjs_data):
    paths = hand_paths.moving_paths()
    names = [name for name, _, _ in paths]
    for prefix in ('guinevere/01/', 'guinevere/02/', 'leapjs/'):
        assert any(n.startswith(prefix) for n in names), prefix
    assert 'leapjs/wave' in names and 'guinevere/01/swipe_left#palm-1' in names
    for name, t, palm in paths:
        assert t[0] == 0.0 and np.all(np.diff(t) > 0), name
        assert palm.shape == (len(t), 3)
        assert np.max(np.ptp(palm, axis=0)) > 60.0, name          # the hand travels
    _, t, palm = hand_paths.leapjs_path(hand_paths.LEAPJS_STILL)
    assert t[-1] > 2.0 and np.max(np.ptp(palm, axis=0)) < 10.0      # and one holds still


def test_real_take_lag_rms_and_jitter_at_rest(leapjs_data):
    swipe = [p for p in hand_paths.guinevere_paths() if p[0] == 'guinevere/01/open_hand_left-1']
    r = {}
    bench.tracking_real(r, sim_params(), paths=swipe)
    # The palm filter alone lags a little; the arm, bound to pi rad/s^2, far more.
    assert 0.0 <= r['arm.target_lag_ms_real'] < 30.0
    assert r['arm.target_lag_ms_real'] < r['arm.tracking_lag_ms_real'] < 300.0
    assert 0.0 < r['arm.tracking_rms_m_real'] < 0.5
    assert r['arm.tracking_takes_real'] == 1.0
    bench.jitter_real(r, sim_params())
    # Filtered, the arm shakes less than the raw palm would make it.
    assert 0.0 < r['arm.jitter_at_rest_mm_real'] < r['arm.jitter_at_rest_unfiltered_mm_real']
