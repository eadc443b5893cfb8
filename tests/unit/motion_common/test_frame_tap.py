"""motion_common.frame_tap: only the messages around each multiple of the period go out,
and the recorder's blend at each multiple gets the same two messages it would from the
whole stream."""

import numpy as np
import pytest

from motion_apps.stamped_history import StampedHistory
from motion_common.frame_tap import FrameTap


def _tap(period=0.1, connected=True):
    sent = []
    return FrameTap(sent.append, lambda: connected, period), sent


def test_forwards_the_two_messages_around_each_multiple():
    tap, sent = _tap()
    for stamp in (0.071, 0.081, 0.091, 0.101, 0.111, 0.121):
        tap.add(stamp, stamp)
    assert sent == [0.091, 0.101]


def test_nothing_without_a_listener_or_a_period():
    tap, sent = _tap(connected=False)
    for stamp in np.arange(0.0, 1.0, 0.01):
        tap.add(float(stamp), stamp)
    assert sent == []
    tap, sent = _tap(period=None)
    for stamp in np.arange(0.0, 1.0, 0.01):
        tap.add(float(stamp), stamp)
    assert sent == []


def test_a_message_after_one_multiple_and_before_the_next_is_sent_once():
    # 30 ms between messages at a 20 ms period: each message is after one multiple and
    # before the next one.
    tap, sent = _tap(period=0.02)
    for stamp in (0.005, 0.035, 0.065, 0.095):
        tap.add(stamp, stamp)
    assert sent == [0.005, 0.035, 0.065, 0.095]


def test_the_blend_at_each_instant_is_the_whole_streams():
    rng = np.random.default_rng(3)
    stamps = np.cumsum(rng.uniform(0.006, 0.014, 400)) + 1000.0
    tap, sent = _tap(period=1 / 15)
    whole = StampedHistory(maxlen=2000)
    tapped = StampedHistory(maxlen=2000)
    for stamp in stamps:
        whole.add(stamp, stamp)
        tap.add(stamp, stamp)
    for stamp in sent:
        tapped.add(stamp, stamp)
    assert len(sent) < 0.35 * len(stamps)  # 2 of the ~6.7 messages a frame
    first = int(np.ceil(stamps[0] * 15)) + 1
    for k in range(first, int(stamps[-1] * 15)):
        assert tapped.around(k / 15) == whole.around(k / 15)


def test_without_pairs_only_the_first_message_after_each_multiple():
    sent = []
    tap = FrameTap(sent.append, lambda: True, 0.1, pairs=False)
    for stamp in (0.071, 0.081, 0.091, 0.101, 0.111, 0.191, 0.201, 0.211):
        tap.add(stamp, stamp)
    assert sent == [0.101, 0.201]


def test_one_message_a_frame_holds_the_whole_streams_value_at_each_instant():
    # The server and the core blend their own samples at each instant (motion_common.
    # frame_blend.sample_at): one message a frame, equal to the recorder's blend of the
    # whole stream at that instant, and stamped with it.
    from motion_common.frame_blend import blend, rate_between, sample_at

    rng = np.random.default_rng(5)
    stamps = np.cumsum(rng.uniform(0.006, 0.014, 400)) + 1000.0

    def sample(t):
        q = np.array([0.0, np.sin(t), 0.0, np.cos(t)])
        return np.array([np.sin(3 * t), np.cos(2 * t)]), np.concatenate([[t, 2 * t, -t], q])

    sent = []
    tap = FrameTap(sent.append, lambda: True, 1 / 15, at_instant=lambda *args: (args[-1], sample_at(*args)))
    whole = StampedHistory(maxlen=2000)
    for stamp in stamps:
        whole.add(stamp, sample(stamp))
        tap.add(stamp, sample(stamp))
    first = int(np.ceil(stamps[0] * 15))
    assert len(sent) == int(stamps[-1] * 15) - first + 1  # one a frame
    for k, (instant, (joints, velocity, pose)) in enumerate(sent, start=first):
        assert instant == k * (1 / 15)
        (t0, (j0, p0)), (t1, (j1, p1)), u = whole.around(instant)
        np.testing.assert_allclose(joints, blend(j0, j1, u), rtol=0, atol=1e-12)
        np.testing.assert_allclose(pose, blend(p0, p1, u, quaternion=slice(3, 7)), rtol=0, atol=1e-12)
        np.testing.assert_allclose(velocity, rate_between(j0, j1, t0, t1), rtol=0, atol=1e-9)


def test_after_a_gap_each_instant_gets_its_value_between_the_two_samples():
    # A producer held up (or a stalled simulation) for more than a period: every instant in
    # the gap is sent, each blended between the samples around it, not only the last one
    # (the recorder would otherwise repeat the previous frame's value there).
    sent = []
    tap = FrameTap(
        sent.append, lambda: True, 0.1, at_instant=lambda t0, a, t1, b, k: (k, a + (b - a) * (k - t0) / (t1 - t0))
    )
    for stamp in (0.095, 0.105, 0.345):
        tap.add(stamp, stamp * 10.0)
    assert [k for k, _ in sent] == pytest.approx([0.1, 0.2, 0.3])
    assert [v for _, v in sent] == pytest.approx([1.0, 2.0, 3.0])
