"""The session summary's hand_to_tool_ms: how far the measured tool trails the raw hand, on
paths whose delay is known by construction."""

import numpy as np
import pytest

from motion_commander.session_report import SessionData, format_summary, summarize


def session(delay_s, seed=3, amplitude=0.1):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 5.0, 1.0 / 110.0)
    hand = np.column_stack(
        [amplitude * np.sin(2.0 * t), 0.5 * amplitude * np.sin(3.1 * t + 1.0), 0.2 * amplitude * np.cos(t)]
    )
    hand += rng.normal(0.0, 0.0004, hand.shape)  # Leap-like jitter
    # The tool: the hand path at half scale, in a frame turned 90 degrees, offset, delayed,
    # sampled by the driver at 500 Hz.
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    tool_t = np.arange(0.5, 4.8, 0.002)
    delayed = np.column_stack([np.interp(tool_t - delay_s, t, hand[:, k]) for k in range(3)])
    tool = 0.5 * delayed @ rotation.T + [0.4, 0.1, 0.3]
    targets = np.column_stack([t, 0.5 * hand @ rotation.T + [0.4, 0.1, 0.3]])
    return SessionData(
        targets=[tuple(r) for r in targets],
        tools=[(ti, *p) for ti, p in zip(tool_t, tool)],
        raw_hands=[(ti, *p) for ti, p in zip(t, hand)],
        hands=[(ti, *p) for ti, p in zip(t, hand)],
    )


@pytest.mark.parametrize("delay_ms", [10, 34, 74])
def test_the_summary_tells_how_far_the_tool_trails_the_hand(delay_ms):
    summary = summarize(session(delay_ms / 1000.0))
    assert summary["hand_to_tool_ms"] == pytest.approx(delay_ms, abs=2.0)
    assert f"hand to tool (delay)     : {summary['hand_to_tool_ms']} ms" in format_summary(summary)


def test_a_still_hand_gives_no_delay_rather_than_a_guess():
    summary = summarize(session(0.03, amplitude=0.001))
    assert summary["hand_to_tool_ms"] is None
    assert "hand to tool (delay)     : n/a" in format_summary(summary)
