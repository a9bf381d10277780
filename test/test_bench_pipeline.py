"""The capture-to-command bench: ages counted once per input, from the first command that
acts on it, only for the measured source's inputs; and a short run of the real graph."""
import numpy as np
import pytest

from tools.bench import bench_pipeline
from tools.bench.bench_pipeline import first_command_ages, round_ages, summary_ms


def test_each_input_counts_once_from_its_first_command():
    # Hands at 1.000 and 1.010; the arm commands at 1.004 (first hand), 1.008 (periodic,
    # same hand), 1.013 (second hand) and 1.020 (periodic again).
    commands = [(1.004, 1.000), (1.008, 1.000), (1.013, 1.010), (1.020, 1.010)]
    assert first_command_ages(commands) == pytest.approx([0.004, 0.003])


def test_no_input_yet_and_older_inputs_are_no_samples():
    commands = [(0.5, 0.0), (1.004, 1.000), (1.006, 0.990), (1.015, 1.010)]
    assert first_command_ages(commands) == pytest.approx([0.004, 0.005])


def test_only_the_measured_sources_inputs_count():
    # 2.000 was injected (arming), not captured by the measured source; the others come
    # back from the arm through float seconds, a nanosecond off.
    measured = [1.000, 1.010, 1.020]
    commands = [(1.003, 1.000 + 1e-9), (2.001, 2.000), (2.010, 1.010), (2.023, 2.020)]
    # 1.010 after 2.000 is older than an input already acted on: no new command.
    assert first_command_ages(commands, measured) == pytest.approx([0.003])
    commands = [(1.003, 1.000 + 1e-9), (1.012, 1.010 - 1e-9), (1.015, 1.0125),
                (1.024, 1.020)]
    assert first_command_ages(commands, measured) == pytest.approx([0.003, 0.002, 0.004])


def test_summary_gives_the_percentiles_in_ms_and_refuses_no_samples():
    ages = np.linspace(0.001, 0.100, 100)
    p50, p99, n = summary_ms(ages)
    assert n == 100
    assert p50 == pytest.approx(50.5, abs=0.01)
    assert p99 == pytest.approx(99.01, abs=0.01)
    with pytest.raises(ValueError, match='no arm command'):
        summary_ms([])


def test_a_driver_record_gives_ages_of_its_hands_only():
    data = {'status': [[1.004, 1.000, 'tracking'], [1.007, 1.005, 'tracking'],
                       [1.012, 1.010, 'tracking']],
            'hands': [[1.000, 1.002, True], [1.010, 1.011, True]]}
    ages, transit = round_ages(data)
    assert ages == pytest.approx([0.004, 0.002])
    assert transit == pytest.approx([0.002, 0.001])


@pytest.mark.integration
def test_a_short_run_measures_both_sources_through_the_real_graph():
    got = bench_pipeline.measure(rounds=1, duration=4.0)
    assert set(got) == {'leap_recording', 'video'}
    for source, (ages, transit, rocks) in got.items():
        # ~114 recorded frames/s and 30 video frames/s for 4 s; the clip arms the arm
        # only after its fist, and the arm tracks only after a rock.
        assert len(ages) > (200 if source == 'leap_recording' else 20), source
        assert rocks >= 1
        assert min(ages) > 0.0
        # Capture stamps on this run's wall clock, not the file's: well under a second.
        assert 0.0 < np.median(transit) < 1.0
        assert np.median(ages) < 1.0
