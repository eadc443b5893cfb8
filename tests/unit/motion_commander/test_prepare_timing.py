"""When the core prepares its between-frames work (motion_commander.prepare_timing)."""

import numpy as np
import pytest

from motion_commander.errors import MotionCommanderError
from motion_commander.prepare_timing import PrepareTiming


def test_prepares_lead_before_the_median_period_of_a_jittery_stream():
    rng = np.random.default_rng(7)
    timing = PrepareTiming(lead_s=0.0015)
    arrival = 100.0
    for _ in range(40):
        arrival += 0.0091 + rng.uniform(-0.0004, 0.0004)  # a 110 Hz device with jitter
        timing.on_frame(arrival)
    assert timing.period == pytest.approx(0.0091, abs=0.0003)
    assert timing.prepare_at() == pytest.approx(arrival + timing.period - 0.0015)


def test_one_late_frame_and_a_pause_do_not_move_the_prediction():
    timing = PrepareTiming(lead_s=0.001)
    arrival = 0.0
    for _ in range(20):
        arrival += 0.01
        timing.on_frame(arrival)
    arrival += 0.5  # the hand left: not a frame period
    timing.on_frame(arrival)
    arrival += 0.03  # one late frame
    timing.on_frame(arrival)
    assert timing.period == pytest.approx(0.01)
    assert timing.prepare_at() == pytest.approx(arrival + 0.009)


def test_learns_a_new_rate():
    timing = PrepareTiming(lead_s=0.001, window=9)
    arrival = 0.0
    for period in [0.009] * 20 + [0.02] * 9:  # the device switched to 50 Hz
        arrival += period
        timing.on_frame(arrival)
    assert timing.period == pytest.approx(0.02)


def test_prepares_at_once_until_the_rate_is_known_or_without_a_lead():
    timing = PrepareTiming(lead_s=0.0015)
    assert timing.prepare_at() is None
    for arrival in (0.0, 0.01, 0.02):
        timing.on_frame(arrival)
    assert timing.prepare_at() is None  # two intervals: not yet
    timing.on_frame(0.03)
    assert timing.prepare_at() == pytest.approx(0.0385)
    off = PrepareTiming(lead_s=0.0)
    for k in range(10):
        off.on_frame(0.01 * k)
    assert off.prepare_at() is None
    # A stream so fast that the lead would reach back to the frame just handled.
    fast = PrepareTiming(lead_s=0.002)
    for k in range(10):
        fast.on_frame(0.003 * k)
    assert fast.prepare_at() is None


def test_refuses_a_negative_lead():
    with pytest.raises(MotionCommanderError, match="lead"):
        PrepareTiming(lead_s=-0.001)
