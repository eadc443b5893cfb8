"""The page's bounded time series (status, latency, tracking error) and its event log."""

import math

import pytest

from dashboard.event_log import EventLog
from dashboard.series import SeriesWindow, Telemetry, tracking_error_m


def test_a_window_is_bounded_thinned_and_relative_to_now():
    window = SeriesWindow(max_points=3, min_interval_s=0.1)
    assert window.add(0.0, 1.0)
    assert not window.add(0.05, 2.0)  # too soon
    assert window.add(0.05, 2.0, force=True)
    for i in range(10):
        window.add(1.0 + i, float(i))
    assert len(window) == 3
    assert window.relative(12.0) == [[-4.0, 7.0], [-3.0, 8.0], [-2.0, 9.0]]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_window_ignores_values_that_are_not_finite(bad):
    window = SeriesWindow()
    assert not window.add(0.0, bad) and len(window) == 0


def test_a_window_refuses_a_meaningless_size():
    with pytest.raises(ValueError):
        SeriesWindow(max_points=1)


def test_status_changes_are_always_kept_repeats_thinned():
    telemetry = Telemetry(max_points=100, min_interval_s=1.0)
    telemetry.add_status(0.0, 1)
    telemetry.add_status(0.1, 1)  # repeat, too soon
    telemetry.add_status(0.2, 2)  # change: kept although too soon
    assert telemetry.relative(1.0)["status"] == [[-1.0, 1.0], [-0.8, 2.0]]


def test_tracking_error_is_the_target_to_tool_distance_while_the_target_is_fresh():
    assert tracking_error_m((0, 0, 0), (0.003, 0.004, 0)) == pytest.approx(0.005)
    telemetry = Telemetry(min_interval_s=0.0, target_max_age_s=0.5)
    telemetry.add_tool(0.0, (0, 0, 0))  # no target yet
    telemetry.add_target(1.0, (0.0, 0.0, 0.5))
    telemetry.add_tool(1.2, (0.0, 0.01, 0.5))
    telemetry.add_tool(2.0, (0.0, 0.02, 0.5))  # target 1 s old: not tracking any more
    assert telemetry.relative(2.0)["tracking_mm"] == [[-0.8, pytest.approx(10.0)]]


def test_latency_is_charted_in_ms_and_negative_values_are_dropped():
    telemetry = Telemetry(min_interval_s=0.0)
    telemetry.add_latency(0.0, 0.004)
    telemetry.add_latency(0.1, -1.0)
    assert telemetry.relative(0.0)["latency_ms"] == [[0.0, pytest.approx(4.0)]]


class Clock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now


def test_event_log_is_newest_first_bounded_and_counts_repeats():
    clock = Clock()
    log = EventLog(max_events=3, repeat_s=2.0, clock=clock)
    log.add("gesture", "pinch (0.90)")
    clock.now += 1.0
    log.add("gesture", "pinch (0.90)")  # the same, soon after: counted
    assert len(log) == 1 and log.newest_first()[0].count == 2
    assert "(x2)" in log.newest_first()[0].line()
    clock.now += 5.0
    log.add("gesture", "pinch (0.90)")  # the same, later: a new line
    log.add("stop", "stop latched")
    log.add("status", "ESTOP")
    events = log.newest_first()
    assert [e.kind for e in events] == ["status", "stop", "gesture"]  # the oldest fell out
    assert log.newest_first(limit=1)[0].text == "ESTOP"


def test_event_log_changed_reports_only_changes():
    log = EventLog()
    assert log.changed("status", 2)
    assert not log.changed("status", 2)
    assert log.changed("status", 11)
    assert log.changed("other", None)  # the first value of a key is a change, even None


def test_event_log_version_moves_on_every_event():
    log = EventLog()
    before = log.version
    log.add("x", "y")
    assert log.version == before + 1
