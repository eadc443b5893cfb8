"""A recorded frame's state, tool and command stand for the frame's instant, not for
whenever the newest message of each stream happened to be sampled (0-10 ms earlier, at a
phase of its own): the cause of the replay's worst frames (5-6 mm at the teach demo's
0.6 m/s tool speed)."""

import numpy as np
import pytest

from motion_apps.stamped_history import StampedHistory
from motion_common.frame_blend import blend, rate_between

FPS = 10.0
DELAY = 0.02  # the recorder's FRAME_DELAY_S


def _tool(t):
    """A fast tool path: up to ~0.6 m/s and 4 m/s^2, as the teach demo's carries."""
    return np.array([0.4 + 0.1 * np.sin(6.0 * t), 0.1 * np.cos(4.0 * t), 0.3 + 0.05 * np.sin(9.0 * t)])


def _frames(rate_hz, phase, pick):
    """Tool positions of 10 Hz frames from a ``rate_hz`` stream of stamped samples, each frame
    made at its tick from what has arrived (``pick``: history -> value); with the error
    against the true tool at the instant each frame stands for."""
    history = StampedHistory()
    stamps = phase + np.arange(0.0, 3.0, 1.0 / rate_hz)
    errors, j = [], 0
    for k in range(5, 29):
        tick = k / FPS
        while j < len(stamps) and stamps[j] + 0.002 <= tick:  # published 2 ms after its stamp
            history.add(stamps[j], _tool(stamps[j]))
            j += 1
        moment, value = pick(history, tick)
        errors.append(1000 * np.linalg.norm(value - _tool(moment)))
    return np.array(errors)


def _blended(history, tick):
    (_, a), (_, b), u = history.around(tick - DELAY)
    return tick - DELAY, blend(a, b, u)


def _newest(history, tick):
    return tick, history.newest()[1]


@pytest.mark.parametrize("rate_hz, phase", [(100.0, 0.0031), (110.0, 0.0077), (100.0, 0.0093), (125.0, 0.001)])
def test_a_frame_is_the_streams_value_at_its_instant(rate_hz, phase):
    errors = _frames(rate_hz, phase, _blended)
    assert errors.max() < 0.1  # mm: linear between samples 8-10 ms apart
    stale = _frames(rate_hz, phase, _newest)
    assert stale.max() > 1.0  # the newest message instead: mm off, by its phase


def test_blend_between_quaternions_takes_the_short_way_and_stays_unit():
    half = np.sqrt(0.5)
    a = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    b = np.array([1.0, 2.0, 3.0, 0.0, 0.0, -half, -half])  # +90 deg about z, written with w < 0
    mid = blend(a, b, 0.5, quaternion=slice(3, 7))
    np.testing.assert_allclose(mid[:3], [0.5, 1.0, 1.5])
    assert np.linalg.norm(mid[3:]) == pytest.approx(1.0)
    assert mid[6] > 0.9 and mid[5] > 0  # 45 deg the short way, not 135 the long way


def test_history_ends_and_order():
    history = StampedHistory(maxlen=3)
    assert history.around(1.0) is None
    for stamp in (1.0, 1.01, 1.02, 1.03):
        assert history.add(stamp, stamp)
    assert not history.add(1.025, "late")  # out of order: dropped
    assert len(history) == 3
    assert history.around(0.5) == ((1.01, 1.01), (1.01, 1.01), 0.0)  # before the oldest kept
    assert history.around(2.0) == ((1.03, 1.03), (1.03, 1.03), 0.0)  # an idle stream holds
    before, after, u = history.around(1.015)
    assert (before[0], after[0], u) == (1.01, 1.02, pytest.approx(0.5))


def test_the_rate_between_two_samples_is_the_velocity_of_a_stream_without_one():
    # The drivers' joint_states carry positions only: the recorded joint velocity is the
    # rate between the two samples around the frame's instant (it was left at zero).
    np.testing.assert_allclose(rate_between([0.0, 1.0], [0.02, 0.99], 10.00, 10.01), [2.0, -1.0])
    np.testing.assert_allclose(rate_between([0.5], [0.5], 3.0, 3.0), [0.0])  # one sample: at rest
