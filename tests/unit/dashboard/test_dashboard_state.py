"""Dashboard state without ROS or a browser: the store, the plot's path buffer, latency
percentiles, readings of diagnostics and the status names and colours."""

import threading

import numpy as np
import pytest

from dashboard.path_buffer import PathBuffer
from dashboard.readings import LatencyWindow, driver_status, sequencer_counters, tool_reading
from dashboard.state import DashboardState
from dashboard.status_style import STATUS_COLOURS, is_engaged, status_view
from motion_commander.teleop_core import TeleopStatus


class FakeClock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_snapshot_copies_values_and_reports_ages():
    clock = FakeClock()
    state = DashboardState(clock=clock)
    state.set("hands", {"num": 1, "types": ["right"]})
    clock.now += 2.5
    state.update(status=2, speed_ratio=0.5)
    snap = state.snapshot()
    assert snap["values"]["status"] == 2 and snap["values"]["speed_ratio"] == 0.5
    assert snap["ages"]["hands"] == pytest.approx(2.5) and snap["ages"]["status"] == pytest.approx(0.0)
    snap["values"]["hands"]["types"].append("left")  # a snapshot is a copy
    assert state.get("hands")["types"] == ["right"]
    assert state.age("never") is None and snap["latency_ms"] is None


def test_concurrent_writers_and_readers_never_see_a_torn_state():
    state = DashboardState()
    errors = []

    def writer(offset):
        for i in range(2000):
            state.update(a=i + offset, b=i + offset)
            state.add_path_point("tool", float(i), (i, 0, 0))

    def reader():
        for _ in range(500):
            values = state.snapshot()["values"]
            if values.get("a") != values.get("b"):
                errors.append(values)

    threads = [threading.Thread(target=writer, args=(k * 10000,)) for k in range(3)] + [threading.Thread(target=reader)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []


def test_path_buffer_thins_bounds_and_converts_to_mm():
    paths = PathBuffer(max_points=5, min_interval_s=1.0)
    kept = [paths.add("tool", 0.25 * i, (0.001 * i, 0.002 * i, 0.3)) for i in range(100)]  # exact binary times
    assert sum(kept) == 25  # every 4th point: 4 Hz -> 1 Hz
    series = paths.series()
    assert len(series["tool"]) == 5 and series["hand"] == []  # only the newest 5 stay
    np.testing.assert_allclose(series["tool"][-1], [96.0, 192.0])
    paths.clear()
    assert paths.series()["tool"] == []
    with pytest.raises(ValueError):
        PathBuffer(max_points=1)


def test_latency_window_percentiles_over_the_last_commands():
    window = LatencyWindow(size=100)
    assert window.percentiles_ms() is None
    for value in [0.5] * 50 + list(np.linspace(0.001, 0.002, 100)) + [float("nan"), -1.0]:
        window.add(value)
    p50, p99, count = window.percentiles_ms()
    assert count == 100  # the 0.5 s ones fell out, bad values ignored
    assert p50 == pytest.approx(1.5, abs=0.01) and p99 == pytest.approx(1.99, abs=0.01)


def test_sequencer_counters_from_diagnostics():
    values = [
        ("frames_in", "367"),
        ("frames_out", "357"),
        ("dropped_entry_trim", "10"),
        ("dropped_jump", "2"),
        ("dropped_total", "12"),
        ("active_device", "default"),
        ("latency_p50_ms", "0.9"),
        ("dropped_stale", "not a number"),
    ]
    counters = sequencer_counters(values)
    assert counters["frames_in"] == 367 and counters["frames_out"] == 357 and counters["dropped_total"] == 12
    assert counters["drops"] == {"entry_trim": 10, "jump": 2}
    assert counters["active_device"] == "default" and counters["latency_p50_ms"] == 0.9


def test_driver_status_reading():
    values = [("connected", "True"), ("fault", ""), ("protective_stop", "False"), ("stop_latched", "True")]
    status = driver_status(values, "stop latched by dashboard", 1)
    assert status == {
        "connected": True,
        "fault": "",
        "protective_stop": False,
        "stop_latched": True,
        "message": "stop latched by dashboard",
        "level": 1,
    }
    assert driver_status([("fault", "overcurrent")], "", 2)["connected"] is None


def test_tool_reading_in_mm_and_degrees():
    half = np.sqrt(0.5)
    reading = tool_reading((0.4, -0.1, 0.25), (0.0, 0.0, half, half))  # 90 deg about z
    np.testing.assert_allclose(reading["xyz_mm"], [400.0, -100.0, 250.0])
    np.testing.assert_allclose(reading["rpy_deg"], [0.0, 0.0, 90.0], atol=1e-9)


def test_every_status_has_a_name_and_colour():
    assert set(STATUS_COLOURS) == set(TeleopStatus)
    assert status_view(11) == ("ESTOP", "red")
    assert status_view(2) == ("ENGAGED", "green")
    assert status_view(None) == ("NO STATUS", "grey")
    assert status_view(99) == ("UNKNOWN (99)", "grey")
    assert is_engaged(12) and is_engaged(3) and not is_engaged(1) and not is_engaged(11) and not is_engaged(None)


def test_status_changes_are_logged_and_charted_repeats_are_not_logged():
    clock = FakeClock()
    state = DashboardState(clock=clock, wall_clock=lambda: 0.0, series_interval_s=0.0)
    codes = [
        TeleopStatus.DISENGAGED,
        TeleopStatus.DISENGAGED,
        TeleopStatus.ENGAGED,
        TeleopStatus.JOINT_SPEED_LIMITED,  # still streaming: no new line
        TeleopStatus.ENGAGED,
        TeleopStatus.ESTOP,
    ]
    for code in codes:
        clock.now += 0.1
        state.set_status(int(code))
    snap = state.snapshot()
    assert snap["values"]["status"] == int(TeleopStatus.ESTOP)
    texts = [line.split(None, 2)[2] for line in snap["events"]]
    assert texts == ["ESTOP", "engaged (streaming)", "DISENGAGED"]  # newest first, one line per change
    assert [v for _, v in snap["series"]["status"]] == [float(c) for c in codes]  # the chart has every one


def test_watched_values_log_only_their_changes():
    state = DashboardState(wall_clock=lambda: 0.0)
    for latched in (False, False, True, True, False):
        state.set_watched("stop_latched", latched, "stop", "stop latched" if latched else "stop released")
    assert [line.split(None, 2)[2] for line in state.snapshot()["events"]] == [
        "stop released",
        "stop latched",
        "stop released",
    ]


def test_robot_pose_carries_joints_target_and_the_tool_path_in_metres():
    clock = FakeClock()
    state = DashboardState(clock=clock, path_interval_s=0.0)
    assert state.robot_pose()["joint_state"] is None
    state.set_joints(["a", "b"], [0.1, 0.2])
    state.add_target(1.0, (0.1, 0.2, 0.3))
    state.add_tool(1.0, (0.1, 0.2, 0.31))
    state.add_tool(1.1, (0.1, 0.2, 0.32))
    pose = state.robot_pose()
    assert pose["joint_state"] == (("a", "b"), (0.1, 0.2)) and pose["joint_version"] == 1
    assert pose["target"] == (0.1, 0.2, 0.3)
    assert pose["tool_path"] == [[0.1, 0.2, 0.31], [0.1, 0.2, 0.32]]
    tracking = state.snapshot()["series"]["tracking_mm"]
    assert tracking and tracking[0][1] == pytest.approx(10.0)


def test_the_camera_keeps_only_its_latest_frame():
    state = DashboardState()
    assert state.camera() is None
    state.set_camera("jpeg", b"one")
    state.set_camera("jpeg", b"two")
    assert state.camera() == (2, "jpeg", b"two")
    assert state.snapshot()["camera_frames"] == 2


def test_event_log_and_series_stay_bounded():
    clock = FakeClock()
    state = DashboardState(clock=clock, series_points=10, series_interval_s=0.0, events=10)
    for i in range(1000):
        clock.now += 0.01
        state.add_latency(0.001 * i)
        state.log("gesture", f"g{i}")
    snap = state.snapshot()
    assert len(snap["series"]["latency_ms"]) == 10 and len(snap["events"]) == 10
    assert snap["events"][0].endswith("g999")
