"""Session figures and plot, and the replay schedule."""

import json
import os

import numpy as np
import pytest

from motion_commander.session_report import (
    SessionData,
    final_error,
    format_summary,
    plot_session,
    summarize,
    tracking_errors,
    write_summary_json,
)
from motion_sensor.devices.replay import replay_schedule


def line(t, offset=0.0):
    return np.column_stack([t, 0.1 * t + offset, np.zeros_like(t), np.full_like(t, 0.5)])


def test_tracking_error_interpolates_the_target_in_time():
    t = np.linspace(0, 1, 101)
    targets = line(t)
    tools = line(t[::3] + 0.001, offset=0.002)[:-1]  # sampled at other times, 2 mm off in x
    errors = tracking_errors(targets, tools)
    np.testing.assert_allclose(errors, 0.002, atol=1e-9)


def test_samples_outside_the_commanded_span_do_not_count():
    targets = line(np.array([1.0, 2.0]))
    tools = line(np.array([0.0, 1.5, 3.0]))
    assert len(tracking_errors(targets, tools)) == 1


def test_summary_figures(tmp_path):
    t = np.linspace(0, 2, 201)
    data = SessionData(
        frames_in=210,
        frames_out=205,
        frames_dropped=5,
        targets=[tuple(r) for r in line(t)],
        tools=[tuple(r) for r in line(t, offset=0.003)],
        latencies=list(np.linspace(0.001, 0.003, 201)),
    )
    summary = summarize(data)
    assert summary["tracking_error_rms_mm"] == pytest.approx(3.0)
    assert summary["final_error_mm"] == pytest.approx(3.0)
    assert summary["latency_p50_ms"] == pytest.approx(2.0, abs=0.006)  # 10 us bins
    assert summary["hand_path_length_mm"] == pytest.approx(200.0)
    text = format_summary(summary, "/x/plot.png")
    assert "frames dropped           : 5" in text and "/x/plot.png" in text
    png = plot_session(data, str(tmp_path / "p.png"))
    assert open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n" and os.path.getsize(png) > 10_000
    write_summary_json(summary, str(tmp_path / "s.json"))
    assert json.load(open(tmp_path / "s.json"))["frames_in"] == 210


def test_empty_session_reports_without_crashing(tmp_path):
    summary = summarize(SessionData())
    assert summary["tracking_error_rms_mm"] is None and "n/a" in format_summary(summary)
    assert np.isnan(final_error(np.zeros((0, 4)), np.zeros((0, 4))))
    plot_session(SessionData(), str(tmp_path / "empty.png"))


def test_replay_schedule_rate_offset_and_fast_mode():
    times = [10.0, 10.1, 10.3, 10.6]
    assert list(replay_schedule(times)) == [
        (0, 0.0),
        (1, pytest.approx(0.1)),
        (2, pytest.approx(0.3)),
        (3, pytest.approx(0.6)),
    ]
    assert [due for _, due in replay_schedule(times, rate=2.0)] == pytest.approx([0, 0.05, 0.15, 0.3])
    assert [i for i, _ in replay_schedule(times, start_offset=0.2)] == [2, 3]
    assert {due for _, due in replay_schedule(times, rate=0)} == {0.0}
    assert list(replay_schedule([])) == []


def test_csv_replay_reads_rows_and_reports_bad_ones(tmp_path):
    from motion_sensor.devices.replay import read_csv
    from motion_sensor.errors import MotionSensorError

    path = tmp_path / "hand.csv"
    path.write_text(
        "stamp,x,y,z,qx,qy,qz,qw,hand_type\n"
        "1.00,0.1,0.0,0.2,0,0,0,1,right\n"
        "1.01,oops,0.0,0.2,0,0,0,1,right\n"
        "1.02,0.1,0.0,0.2,0,0,0,1,middle\n"
        "1.03,0.0,0.0,0.0,0,0,0,1,\n"
    )
    samples, rejected = read_csv(str(path))
    assert [s.hands_num for s in samples] == [1, 0] and samples[0].device == "csv"
    assert len(rejected) == 2 and rejected[0].startswith("line 3")
    (tmp_path / "bad.csv").write_text("t,x\n1,2\n")
    with pytest.raises(MotionSensorError, match="lacks columns"):
        read_csv(str(tmp_path / "bad.csv"))


def test_a_day_long_session_keeps_bounded_memory_and_exact_running_figures():
    """Samples beyond the window are dropped; the counts, the path length and the latency
    percentiles still cover every command (percentiles to within the 10 us bins)."""
    from motion_commander.latency_stats import LatencyStats

    rng = np.random.default_rng(7)
    data = SessionData(window=1000)
    latencies = rng.gamma(4.0, 0.0003, 20_000)
    for i, latency in enumerate(latencies):
        t = i * 0.01
        data.add_target((t, 0.001 * i, 0.0, 0.2))
        data.tools.append((t, 0.001 * i, 0.0, 0.2))
        data.latencies.append(latency)
        data.add_stage_latency(latency / 3, latency / 2, latency)
    assert len(data.targets) == len(data.tools) == 1000
    summary = summarize(data)
    assert summary["commands_sent"] == 20_000 and summary["latency_samples"] == 20_000
    assert summary["hand_path_length_mm"] == pytest.approx(19_999.0)
    for q, key in ((50, "latency_p50_ms"), (99, "latency_p99_ms")):
        assert summary[key] == pytest.approx(1000 * np.percentile(latencies, q), abs=0.006)
    assert summary["stage_latency_ms"]["driver"]["p99"] == pytest.approx(summary["latency_p99_ms"], abs=0.011)
    stats = LatencyStats([2.5, 0.001])  # past the 1 s span: counted, read as the maximum
    assert (
        stats.over_span == 1 and stats.percentile(100) == 2.5 and stats.percentile(0) == pytest.approx(0.001, abs=1e-5)
    )
