"""The replaying arm's lag behind its stream, measured from its stamped joint samples
(motion_apps.stream_lag), on simulated clocks."""

import numpy as np
import pytest

from motion_apps.stream_lag import StreamLag


def _path(t):
    """Two joints on a 1 Hz swing, up to ~1.3 rad/s."""
    return np.array([0.2 * np.sin(2 * np.pi * t), 0.1 * np.cos(2 * np.pi * t)])


def _feed(lag, delay, seconds=2.0, rate=100.0, phase=0.0037, start=0.0):
    """Targets of _path sent at ``rate`` Hz; the arm follows them ``delay`` s late (linear
    between the targets) and is sampled at ``rate`` Hz, ``phase`` s off the sends."""
    sends = start + np.arange(0.0, seconds, 1.0 / rate)
    for t in sends:
        lag.sent(t, _path(t))
    for t in start + np.arange(0.1, seconds - 0.1, 1.0 / rate) + phase:
        k = int(np.searchsorted(sends, t - delay)) - 1
        u = (t - delay - sends[k]) * rate
        lag.measured(t, (1 - u) * _path(sends[k]) + u * _path(sends[k + 1]))
    return lag


def test_the_lag_is_the_arms_delay_behind_the_stream():
    for delay in (0.0105, 0.0125):
        assert _feed(StreamLag(0.0), delay).lag_s() == pytest.approx(delay, abs=0.0002)
    # A servo's lookahead on top: the first-order estimate is 1.5 % short on this swing.
    assert _feed(StreamLag(0.0), 0.042).lag_s() == pytest.approx(0.042, rel=0.03)


def test_until_enough_motion_is_measured_the_start_is_kept():
    lag = StreamLag(0.011)
    assert lag.lag_s() == 0.011 and not lag.measuring
    for t in np.arange(0.0, 1.0, 0.01):  # a still arm: no speed to measure a lag by
        lag.sent(t, [0.0, 0.1])  # where _path starts again at 1 s
        lag.measured(t + 0.005, [0.0, 0.1])
    assert lag.lag_s() == 0.011 and not lag.measuring
    _feed(lag, 0.013, start=1.0)
    assert lag.measuring and lag.lag_s() == pytest.approx(0.013, abs=0.0005)


def test_samples_outside_the_stream_or_out_of_order_are_not_used():
    lag = StreamLag(0.02)
    for t in np.arange(0.0, 1.0, 0.01):  # the arm moving before any target was sent
        lag.measured(t, _path(t))
    lag.measured(0.5, _path(0.5))  # stamped before the sample before it
    lag.measured(0.6, [0.0, 0.0, 0.0])  # another arm's joints
    assert lag.lag_s() == 0.02 and not lag.measuring


def test_a_stall_of_the_stream_does_not_move_the_measured_lag():
    """A client or server held up for 60 ms: the arm falls behind its stream for a few
    samples, which a least squares over the window took in (18.9 ms against 12-13)."""
    lag = _feed(StreamLag(0.0), 0.0125)
    for t in np.arange(2.0, 2.2, 0.01):
        lag.sent(t, _path(t))
    for t in np.arange(2.0, 2.1, 0.01) + 0.0037:  # ten samples 60 ms behind the stream
        lag.measured(t, _path(t - 0.06))
    assert lag.lag_s() == pytest.approx(0.0125, abs=0.0003)


def test_a_sample_that_comes_before_the_next_target_is_used_once_it_is_sent():
    """The server's samples and the replay's sends are both 100 Hz: at some phases every
    sample comes just before the target after it is sent."""
    lag = StreamLag(0.0)
    for t in np.arange(0.0, 2.0, 0.01):
        lag.measured(t - 0.001, _path(t - 0.001 - 0.0125))  # stamped 1 ms before this send
        lag.sent(t, _path(t))
    assert lag.measuring and lag.lag_s() == pytest.approx(0.0125, abs=0.0003)


def test_a_sample_that_is_empty_or_no_number_is_refused_and_the_lag_stays_a_number():
    lag = StreamLag(0.0)
    sends = np.arange(0.0, 2.0, 0.01)
    for t in sends:
        lag.sent(t, _path(t))
    for t in np.arange(0.1, 1.9, 0.01) + 0.0037:
        joints = _path(t - 0.0125)
        if abs(t - 1.0037) < 1e-9:
            assert not lag.measured(t, [float("nan"), joints[1]])  # one joint read as NaN
            assert not lag.measured(t, [])  # a JointState with no positions
            assert not lag.measured(float("inf"), joints)
            continue
        assert lag.measured(t, joints)
    assert np.isfinite(lag.lag_s()) and lag.lag_s() == pytest.approx(0.0125, abs=0.0005)
