"""ArrivalStamps: sample times of a steady sender's states from their arrival times."""

import numpy as np
import pytest

from hw_interface.arrival_stamps import ArrivalStamps

PERIOD = 0.01


def stamps_of(arrivals, **kw):
    """One state a read, as a reader that is never behind gets them."""
    estimator = ArrivalStamps(**kw)
    return np.array([estimator.stamps(a)[0] for a in arrivals])


def steady(n, start=0.0, period=PERIOD):
    return start + period * np.arange(n)


def test_on_time_states_are_stamped_at_their_arrival():
    arrivals = steady(100)
    np.testing.assert_allclose(stamps_of(arrivals), arrivals)


def test_a_state_a_busy_reader_took_late_does_not_squeeze_the_next_one():
    # Sample times 0, 10, 20 ... ms; the state sampled at 410 ms is read at 418 ms (the
    # reader was busy), the one at 420 on time.
    sampled = steady(80)
    arrivals = sampled.copy()
    arrivals[41] = 0.418
    stamps = stamps_of(arrivals)
    # Stamped on receipt the state at 420 ms would be 2 ms after the one before: a speed
    # five times the true one. Now within the 1 % slack of the period.
    assert np.diff(arrivals).min() < 0.0025
    assert np.diff(stamps).min() >= 0.989 * PERIOD, np.diff(stamps).min()
    assert np.all(stamps <= arrivals + 1e-12)
    assert np.abs(stamps - sampled).max() <= 0.011 * PERIOD


def test_states_read_together_are_stamped_a_period_apart():
    estimator = ArrivalStamps()
    for a in steady(30):
        estimator.stamps(a)
    # The reader stalls 37 ms: the states sampled at 300, 310, 320 ms come in one read at
    # 327 ms, the next on time.
    burst = estimator.stamps(0.327, 3)
    after = estimator.stamps(0.33)
    stamps = np.array([0.29, *burst, *after])
    np.testing.assert_allclose(burst, [0.3001, 0.3102, 0.3203], atol=2e-4)
    assert np.diff(stamps).min() >= 0.96 * PERIOD and stamps[-1] == 0.33


def test_a_pause_of_the_sender_costs_at_most_the_stated_delay_and_is_caught_up():
    arrivals = np.concatenate([steady(50), steady(400, start=1.0)])  # 0.5 s of silence
    stamps = stamps_of(arrivals)
    lag = arrivals - stamps
    assert lag.max() <= 3 * PERIOD + 1e-9
    assert lag[-1] < 1e-9  # caught up at 1 % of a period a state
    assert np.all(np.diff(stamps) >= 0)


def test_a_slower_sender_is_followed():
    arrivals = np.concatenate([steady(100), 1.0 + steady(400, period=0.02)])
    lag = arrivals - stamps_of(arrivals)
    assert lag.max() <= 3 * 0.02 + 1e-9 and lag[-1] < 1e-9  # three of its own periods at most


def test_arrivals_out_of_order_and_jitter_keep_the_stamps_in_order_and_never_late():
    rng = np.random.default_rng(7)
    arrivals = steady(500) + rng.exponential(0.004, 500)
    stamps = stamps_of(arrivals)
    assert np.all(np.diff(stamps) >= 0)
    assert np.all(stamps <= np.maximum.accumulate(arrivals) + 1e-12)


def test_memory_is_bounded_and_settings_are_checked():
    estimator = ArrivalStamps(window=20)
    for a in steady(1000):
        estimator.stamps(a)
    assert len(estimator._spacings) == 20 and estimator.period == pytest.approx(PERIOD)
    assert estimator.stamps(11.0, 0) == []
    estimator.reset()
    assert estimator.period == 0.0 and estimator.stamps(5.0) == [5.0]
    for bad in ({"window": 2}, {"slack": 0.9}, {"max_delay_periods": 0}, {"min_spacings": 0}):
        with pytest.raises(ValueError, match="out of range"):
            ArrivalStamps(**bad)
