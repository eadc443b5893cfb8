"""The hand-to-tool bench's lag estimate (bench/hand_to_tool.py) finds a known delay under a
scaled, rotated, offset and noisy copy of a hand path, and each stage's own delay."""

import os
import sys

import numpy as np
import pytest

from ..conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "bench"))
from hand_to_tool import stage_lags  # noqa: E402
from motion_commander.lag_estimate import best_lag  # noqa: E402


def hand_path(rng, seconds=4.0, rate=110.0):
    t = np.arange(0.0, seconds, 1.0 / rate)
    xyz = np.column_stack([0.1 * np.sin(2.1 * t), 0.05 * np.sin(3.3 * t + 1.0), 0.03 * np.cos(1.7 * t)])
    return np.column_stack([t, xyz + rng.normal(0.0, 0.0005, xyz.shape)])


def delayed(source, lag, rng, scale=1.5, rate=100.0):
    t = np.arange(source[0, 0] + 0.35, source[-1, 0], 1.0 / rate)
    x = np.column_stack([np.interp(t - lag, source[:, 0], source[:, k]) for k in (1, 2, 3)])
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    y = scale * x @ rotation.T + [0.4, -0.1, 0.3] + rng.normal(0.0, 0.0002, x.shape)
    return np.column_stack([t, y])


@pytest.mark.parametrize("lag", [0.0, 0.012, 0.064, 0.1])
def test_a_known_delay_is_found(lag):
    rng = np.random.default_rng(7)
    source = hand_path(rng)
    found, rms = best_lag(source, delayed(source, lag, rng))
    assert found == pytest.approx(lag, abs=0.0021) and rms < 0.001


def test_each_stage_and_the_whole_chain():
    rng = np.random.default_rng(11)
    raw = hand_path(rng)
    filtered = delayed(raw, 0.04, rng, scale=1.0)
    target = delayed(filtered, 0.01, rng)
    commanded = delayed(target, 0.0, rng, scale=1.0)
    tool = delayed(commanded, 0.05, rng, scale=1.0)
    lags = stage_lags({"raw": raw, "filtered": filtered, "target": target, "commanded": commanded, "tool": tool})
    assert lags["raw->filtered"] == pytest.approx(40, abs=2.1)
    assert lags["filtered->target"] == pytest.approx(10, abs=2.1)
    assert lags["commanded->tool"] == pytest.approx(50, abs=2.1)
    assert lags["raw->tool"] == pytest.approx(100, abs=4.1)


def test_a_still_hand_or_an_arm_that_does_not_follow_gives_no_lag():
    rng = np.random.default_rng(3)
    raw = hand_path(rng)
    still = raw.copy()
    still[:, 1:] = 0.001 * still[:, 1:]
    frozen = delayed(raw, 0.0, rng)
    frozen[:, 1:] = frozen[0, 1:] + rng.normal(0.0, 0.0002, frozen[:, 1:].shape)
    streams = {"raw": raw, "filtered": raw, "target": frozen, "commanded": frozen, "tool": frozen}
    lags = stage_lags(streams)
    assert lags["raw->filtered"] == 0.0
    quiet = stage_lags({**streams, "raw": still, "filtered": still})
    assert quiet["raw->filtered"] is None and quiet["raw->tool"] is None
