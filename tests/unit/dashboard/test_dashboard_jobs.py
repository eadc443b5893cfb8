"""The dashboard's child jobs (output kept, SIGINT end) and the programs folder (list, delete)."""

import os
import sys
import time

import pytest

from dashboard.jobs import Job, campaign_command, campaign_summary, run_program_command
from dashboard.programs import delete_program, list_programs, program_path
from motion_commander.program import Program, Waypoint, save_program


def test_job_keeps_output_and_exit_code():
    exits = []
    job = Job("t", [sys.executable, "-c", "print('one'); print('two'); raise SystemExit(3)"], on_exit=exits.append)
    assert job.wait(30) == 3
    assert job.lines() == ["one", "two"] and not job.running and exits == [job]


def test_job_stop_sends_sigint_so_the_child_can_report():
    code = (
        "import signal, sys, time\n"
        "def bye(*_):\n    print('interrupted, reporting', flush=True); sys.exit(7)\n"
        "signal.signal(signal.SIGINT, bye)\nprint('ready', flush=True)\n"
        "while True: time.sleep(0.05)\n"
    )
    job = Job("t", [sys.executable, "-c", code])
    deadline = time.monotonic() + 30
    while not job.lines() and time.monotonic() < deadline:  # wait for readiness, not a fixed sleep
        time.sleep(0.01)
    assert job.stop(timeout=30) == 7
    assert job.lines() == ["ready", "interrupted, reporting"]


def test_commands():
    assert run_program_command("/p/a.yaml", True, "/s.yaml") == [
        "rosrun",
        "motion_apps",
        "run_program",
        "/p/a.yaml",
        "--dry-run",
        "--scene",
        "/s.yaml",
    ]
    assert run_program_command("/p/a.yaml", False) == ["rosrun", "motion_apps", "run_program", "/p/a.yaml"]
    command = campaign_command(6, 2, True, "/out")
    assert command[:3] == ["rosrun", "kitting", "kitting_trials"]
    assert {"_trials:=6", "_seed:=2", "_perturb:=true", "_output_dir:=/out"} <= set(command)
    with pytest.raises(ValueError):
        campaign_command(0, 1, False, "/out")


def make_program(folder, name, robot="ur5e"):
    waypoints = [Waypoint(name="w0", position=[0.4, 0.0, 0.3], orientation=[1.0, 0.0, 0.0, 0.0], joints=[0.0] * 6)]
    return save_program(Program(robot=robot, waypoints=waypoints), os.path.join(folder, name + ".yaml"))


def test_list_programs_newest_first_with_unreadable_ones_flagged(tmp_path):
    make_program(str(tmp_path), "older")
    os.utime(tmp_path / "older.yaml", (1000, 1000))
    make_program(str(tmp_path), "newer")
    (tmp_path / "broken.yaml").write_text("robot: [\n")
    (tmp_path / "notes.txt").write_text("not a program")
    listing = list_programs(str(tmp_path))
    names = [p.name for p in listing]
    assert set(names) == {"older", "newer", "broken"} and names.index("newer") < names.index("older")
    by_name = {p.name: p for p in listing}
    assert by_name["newer"].waypoints == 1 and by_name["newer"].robot == "ur5e" and not by_name["newer"].error
    assert by_name["broken"].error
    assert list_programs(str(tmp_path / "missing")) == []


def test_delete_only_names_inside_the_folder(tmp_path):
    make_program(str(tmp_path), "pick")
    outside = tmp_path.parent / "outside.yaml"
    outside.write_text("keep me")
    for bad in ("../outside", "/etc/passwd", "", ".hidden", "a/b"):
        assert delete_program(str(tmp_path), bad) is not None
    assert outside.exists()
    assert "no such program" in delete_program(str(tmp_path), "ghost")
    assert delete_program(str(tmp_path), "pick") is None and not (tmp_path / "pick.yaml").exists()
    with pytest.raises(ValueError):
        program_path(str(tmp_path), "../x")


def test_a_campaign_reads_only_the_summary_it_wrote(tmp_path):
    path = tmp_path / "kitting_summary.json"
    path.write_text('{"successes": 6, "trials": 6}\n')
    os.utime(path, (1000.0, 1000.0))  # an earlier run's
    assert "before writing a summary of this run" in campaign_summary(str(path), 2000.0, 1)["error"]
    os.utime(path, (3000.0, 3000.0))
    assert campaign_summary(str(path), 2000.0, 0) == {"successes": 6, "trials": 6}
    assert "no summary" in campaign_summary(str(tmp_path / "none.json"), 2000.0, 2)["error"]
