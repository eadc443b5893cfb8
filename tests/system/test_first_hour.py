"""What a new user meets, run as they run it: scripts/teleop_sim.

- a mistyped argument is refused in seconds, before ROS starts, with "did you mean";
- a normal run prints no WARN/ERROR line and no Python warning, only progress and the
  summary, into its own output folder with a 'latest' link;
- the worked examples (examples/kinematic_driver.py, examples/circle_device.py) drive a
  whole session by arguments;
- a SpaceMouse report log ends its session as the recordings do;
- a node that dies at start-up ends the session with its cause in the last lines, writes
  no summary and leaves 'latest' alone.

Each session starts its own master on a free port (ROS_MASTER_URI), so nothing here meets
another session. About 90 s.
"""

import json
import os
import re
import signal
import socket
import subprocess
import time

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
TELEOP = os.path.join(ROOT, "scripts", "teleop_sim")
TIMEOUT = 240  # s, for one session on a loaded 2-core machine
NOISE = re.compile(r"\[ ?WARN\]|\[ ?ERROR\]|\[FATAL\]|Warning|warning:|Traceback|cannot create a symlink|argv\[0\]")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def session(tmp_path, argv, env=None, merged=False):
    """Run a session command with its own master; (exit code, stdout, stderr, seconds)."""
    environment = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{free_port()}", ROS_HOME=str(tmp_path / "ros"))
    environment.update(env or {})
    start = time.monotonic()
    process = subprocess.Popen(
        argv,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT if merged else subprocess.PIPE,
        text=True,
        env=environment,
        cwd=ROOT,
    )
    try:
        out, err = process.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        # Ctrl-C, as a user would: roslaunch then stops every node (a kill would orphan them).
        process.send_signal(signal.SIGINT)
        out, err = process.communicate(timeout=60)
        pytest.fail(f"the session did not end by itself within {TIMEOUT} s:\n{out}\n{err}")
    return process.returncode, out, err or "", time.monotonic() - start


def teleop(tmp_path, *args, env=None):
    """scripts/teleop_sim with ``args``, its runs under tmp_path/out."""
    return session(tmp_path, [TELEOP, f"output_dir:={tmp_path / 'out'}", *args], env)


def latest_summary(tmp_path):
    with open(tmp_path / "out" / "latest" / "session_summary.json", encoding="utf-8") as stream:
        return json.load(stream)


def test_a_mistyped_argument_is_refused_before_ros_starts(tmp_path):
    code, out, err, seconds = teleop(tmp_path, "speed_ration:=0.5")
    assert code == 2, out + err
    assert "unknown argument 'speed_ration' (did you mean 'speed_ratio'?)" in err
    assert err.strip().splitlines()[-1].startswith("nothing started")
    assert not (tmp_path / "out").exists() and seconds < 60


def test_a_normal_run_is_quiet_and_keeps_its_results(tmp_path):
    code, out, err, _ = teleop(tmp_path)
    assert code == 0, out + err
    console = out + err
    noisy = [line for line in console.splitlines() if NOISE.search(line)]
    assert not noisy, "\n".join(noisy)
    assert "ROS master: http://localhost:" in out and "=== teleop session summary ===" in out
    summary = latest_summary(tmp_path)
    assert summary["commands_sent"] > 100 and summary["commands_refused"] == 0 and summary["failure"] == ""
    run = os.path.realpath(tmp_path / "out" / "latest")
    assert os.path.basename(run).startswith("teleop_sim-") and os.path.exists(os.path.join(run, "session_paths.png"))
    assert out.strip().splitlines()[-1].startswith(f"results: {run}")


def test_the_worked_examples_drive_a_session(tmp_path):
    code, out, err, _ = teleop(
        tmp_path,
        "driver:=kinematic_driver:KinematicDriver",
        "device:=circle_device:CircleDevice",
        env={"PYTHONPATH": os.path.join(ROOT, "examples") + os.pathsep + os.environ.get("PYTHONPATH", "")},
    )
    assert code == 0, out + err
    summary = latest_summary(tmp_path)
    assert summary["commands_sent"] > 100 and summary["commands_refused"] == 0
    assert summary["tracking_error_rms_mm"] < 20.0  # an ideal arm follows its targets


def test_a_spacemouse_log_ends_its_session(tmp_path):
    log = os.path.join(ROOT, "tests", "data", "spacemouse_push_forward.hidlog")
    code, out, err, seconds = teleop(tmp_path, "device:=spacemouse", f"spacemouse_log:={log}")
    assert code == 0, out + err
    assert latest_summary(tmp_path)["commands_sent"] > 50  # the button clutch was chosen by itself


def test_a_node_that_dies_ends_the_session_with_its_cause_last(tmp_path):
    (tmp_path / "broken_driver.py").write_text(
        "from hw_interface.errors import HwInterfaceError\n"
        "class Broken:\n"
        "    def __init__(self, **params):\n"
        "        raise HwInterfaceError('controller unreachable at 10.0.0.9')\n"
    )
    code, out, err, _ = teleop(
        tmp_path,
        "driver:=broken_driver:Broken",
        env={"PYTHONPATH": str(tmp_path) + os.pathsep + os.environ.get("PYTHONPATH", "")},
    )
    assert code != 0
    tail = "\n".join(err.strip().splitlines()[-4:])
    assert "session FAILED: node motion_controller_server" in tail and "controller unreachable at 10.0.0.9" in tail
    assert not (tmp_path / "out" / "latest").exists()
    assert not list((tmp_path / "out" / "runs").glob("*/session_summary.json"))


def test_a_hand_started_roslaunch_ends_cleanly(tmp_path):
    argv = ["roslaunch", "motion_bringup", "teleop_sim.launch", f"output_dir:={tmp_path / 'out'}"]
    code, out, _, _ = session(tmp_path, argv, merged=True)
    assert code == 0, out
    assert "REQUIRED process" not in out and "has died" not in out, out
    assert "=== teleop session summary ===" in out
    assert (tmp_path / "out" / "session_summary.json").exists()
