"""scripts/record_demo at a reduced length: one gesture-taught pick-and-place session
recorded as a LeRobot episode with the scene camera, read back by LeRobot's loader and
replayed on a fresh simulated arm; the summary, the picture and the dataset are checked.
Its own master on a free port. About 100 s (one teach session, LeRobot's loader, a replay).
"""

import json
import os
import signal
import socket
import subprocess

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TIMEOUT = 600  # s, on a loaded 2-core machine


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_record_demo_one_episode(tmp_path):
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{free_port()}", ROS_HOME=str(tmp_path / "ros"))
    command = [os.path.join(ROOT, "scripts", "record_demo"), "--episodes", "1", "--output", str(tmp_path)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=ROOT)
    try:
        out, _ = process.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        process.send_signal(signal.SIGINT)
        out, _ = process.communicate(timeout=60)
        pytest.fail(f"record_demo did not end within {TIMEOUT} s:\n{out}")
    assert process.returncode == 0, out
    runs = os.listdir(tmp_path / "runs")
    run = tmp_path / "runs" / next(name for name in runs if name.startswith("record_demo-"))
    with open(run / "record_demo.json", encoding="utf-8") as stream:
        summary = json.load(stream)
    assert summary["episodes"] == 1 and summary["fps"] == 10
    assert summary["frames"] >= 50, summary  # the teaching takes well over 5 s
    assert summary["cameras"] == ["observation.images.scene"]
    assert summary["dropped_frames"] == 0
    assert summary["replay"]["compared"] == summary["frames"] - 1, summary["replay"]
    assert summary["replay"]["refused"] == 0
    # Joint velocities are recorded (the drivers' joint_states carry none: they come from the
    # measured positions) and agree with the recorded positions' own rate. The velocities are
    # the rate over one 10 ms state interval, the rate over two 0.1 s frames: their gain was
    # 0.91-1.32 on this machine (1.32 with a core kept busy); missing velocities give 0, a
    # sign error -1, degrees 57.
    assert summary["velocity"]["moving_frames"] > 10, summary["velocity"]
    assert 0.6 < summary["velocity"]["gain"] < 1.5, summary["velocity"]
    # The goal is 2 mm at every frame (docs/benchmarks.md). The replay sends the recorded
    # joint path once as a timed path the simulated arm samples by its own clock
    # (FOLLOW_PATH), so neither a client nor a server held up can bend it: with one core
    # kept busy max 0.09-0.20 mm, p95 0.02-0.04 mm over the demo's episodes, and 0.15 /
    # 0.10 / 0.04 mm in three runs of this test (streamed, as before, a client or server
    # held up for 10-90 ms put single frames at 3-4 mm, and the bound was 5 mm). The worst
    # is bounded at the goal, the p95 at half of it.
    # A recorder held up on a loaded machine no longer skips a frame (which put the next
    # one a period off its instant), and none may be skipped here.
    replay = summary["replay"]
    assert replay["curve"] == "state", replay
    assert replay["transport"] == "path", replay  # the driver followed the whole path by its clock
    assert replay["tool_error_mm_p95"] < 1.0, replay
    assert replay["tool_error_mm_max"] < 2.0, replay
    with open(run / "record_demo.png", "rb") as stream:
        assert stream.read(8) == b"\x89PNG\r\n\x1a\n"
    assert "=== recorded dataset ===" in out and "episodes                 : 1" in out
    records = json.loads((run / "dataset" / "meta" / "teleop_episodes.json").read_text())
    assert len(records) == 1 and records[0]["camera_new_frames"] > 0
    assert records[0]["ticks_skipped"] == 0, records[0]
