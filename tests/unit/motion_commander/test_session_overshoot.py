"""The session report's overshoot at reversals and tracking against the raw hand, on
synthetic paths whose answers are known by construction."""

import numpy as np
import pytest

from motion_commander.session_report import SessionData, overshoot, raw_hand_targets, summarize


def rows(t, x, y=None, z=None):
    zeros = np.zeros_like(t)
    return np.column_stack([t, x, zeros if y is None else y, zeros if z is None else z])


def test_a_lagging_tool_that_never_goes_past_has_no_overshoot():
    t = np.linspace(0, 4, 401)
    target = 0.05 * np.sin(2 * np.pi * 0.5 * t)
    lagged = 0.05 * np.sin(2 * np.pi * 0.5 * (t - 0.08))  # 80 ms behind, same peaks
    assert overshoot(rows(t, target), rows(t, lagged)) == pytest.approx(0.0, abs=1e-4)


def test_overshoot_is_how_far_the_tool_goes_past_the_peak_on_any_axis():
    t = np.linspace(0, 4, 401)
    target = 0.05 * np.sin(2 * np.pi * 0.5 * t)  # peaks +-50 mm at t = 0.5, 1.5, 2.5, 3.5
    tool = 0.05 * np.sin(2 * np.pi * 0.5 * (t - 0.05))
    # On z the target dips to -20 mm at t = 2.5; the tool follows 0.1 s late and goes
    # 9 mm further down at its own bottom.
    target_z = -0.02 * np.exp(-(((t - 2.5) / 0.2) ** 2))
    tool_z = -0.02 * np.exp(-(((t - 2.6) / 0.2) ** 2)) - 0.009 * np.exp(-(((t - 2.6) / 0.03) ** 2))
    result = overshoot(rows(t, target, z=target_z), rows(t, tool, z=tool_z))
    assert result == pytest.approx(0.009, abs=3e-4)


def test_small_wiggles_below_the_prominence_are_not_extrema():
    t = np.linspace(0, 2, 401)
    target = 0.002 * np.sin(2 * np.pi * 3 * t)  # 2 mm wiggles: < 5 mm prominence
    tool = target * 3  # goes 4 mm past them
    assert overshoot(rows(t, target), rows(t, tool)) == 0.0
    assert overshoot(rows(t, target), rows(t, tool), prominence=0.001) == pytest.approx(0.004, abs=2e-4)


def test_only_the_window_up_to_the_next_extremum_counts():
    t = np.linspace(0, 3, 301)
    target = np.interp(t, [0, 1, 2, 3], [0.0, 0.02, -0.02, 0.05])  # max 20 mm, min -20 mm, then rises on
    tool = np.interp(t, [0, 1.1, 2.1, 3], [0.0, 0.02, -0.02, 0.05])  # 0.1 s late, never beyond
    assert overshoot(rows(t, target), rows(t, tool)) == pytest.approx(0.0, abs=1e-9)


def test_raw_hand_targets_recover_the_affine_mapping():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 2, 221)
    raw = np.column_stack([0.1 * np.sin(3 * t), 0.05 * np.cos(2 * t), 0.02 * t]) + rng.normal(0, 0.002, (221, 3))
    kernel = np.ones(10) / 10
    filtered = np.column_stack([np.convolve(raw[:, a], kernel, mode="same") for a in range(3)])
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    offset = np.array([0.4, -0.1, 0.5])
    mapped = offset + 0.5 * filtered @ rotation.T
    targets = np.column_stack([t, mapped])[10:]
    result = raw_hand_targets(targets, np.column_stack([t, filtered]), np.column_stack([t, raw]))
    expected = offset + 0.5 * raw @ rotation.T
    inside = t >= t[10]
    np.testing.assert_allclose(result[:, 0], t[inside])
    np.testing.assert_allclose(result[:, 1:], expected[inside], atol=1e-9)


def test_summary_reports_overshoot_and_raw_tracking():
    t = np.linspace(0, 2, 201)
    hand = rows(t, 0.1 * np.sin(np.pi * t))
    raw = hand.copy()
    raw[:, 1] += 0.004 * np.sin(40 * t)  # tremor the filter removed
    data = SessionData(
        targets=[tuple(r) for r in hand],
        tools=[tuple(r) for r in hand],
        hands=[tuple(r) for r in hand],
        raw_hands=[tuple(r) for r in raw],
    )
    summary = summarize(data)
    assert summary["overshoot_mm"] == 0.0
    assert summary["tracking_error_rms_mm"] == pytest.approx(0.0, abs=1e-6)
    assert summary["raw_tracking_error_rms_mm"] == pytest.approx(4.0 / np.sqrt(2), rel=0.05)
    assert summarize(SessionData())["raw_tracking_error_rms_mm"] is None
