"""scripts/run_session's bookkeeping: a new folder per run, an atomic 'latest' link, the
failed node's last errors from its log, and the argument split (--monitor, --check)."""

import importlib.util
import os
from importlib.machinery import SourceFileLoader

from ..conftest import ROOT

_LOADER = SourceFileLoader("run_session", os.path.join(ROOT, "scripts", "run_session"))
run_session = importlib.util.module_from_spec(importlib.util.spec_from_loader("run_session", _LOADER))
_LOADER.exec_module(run_session)


def test_each_run_gets_its_own_folder(tmp_path):
    import datetime

    now = datetime.datetime(2026, 11, 25, 9, 30, 5)
    first = run_session.run_folder(str(tmp_path), "/x/teleop_sim.launch", now)
    second = run_session.run_folder(str(tmp_path), "/x/teleop_sim.launch", now)
    assert first.endswith("runs/teleop_sim-20261125-093005") and second == first + "-2"
    assert os.path.isdir(first) and os.path.isdir(second)


def test_latest_points_at_the_last_good_run(tmp_path):
    good = run_session.run_folder(str(tmp_path), "a.launch")
    run_session.point_latest(str(tmp_path), good)
    assert os.path.realpath(tmp_path / "latest") == os.path.realpath(good)
    assert os.readlink(tmp_path / "latest") == os.path.relpath(good, tmp_path)  # the folder can move
    newer = run_session.run_folder(str(tmp_path), "b.launch")
    run_session.point_latest(str(tmp_path), newer)
    assert os.path.realpath(tmp_path / "latest") == os.path.realpath(newer)
    assert sorted(os.listdir(tmp_path)) == ["latest", "runs"]


def test_the_failed_nodes_last_errors_are_found(tmp_path):
    (tmp_path / "sequencer-6.log").write_text(
        "[rosout][INFO] 2026 start\n[rosout][FATAL] 2026 sequencer: bad filter\n[rosout][INFO] bye\n"
    )
    (tmp_path / "rosout.log").write_text("x [ERROR] /motion_commander: unrelated\n")
    (tmp_path / "motion_commander-4.log").write_text("[ERROR] something else\n")
    assert run_session.last_error_lines(str(tmp_path), "sequencer-6") == ["[rosout][FATAL] 2026 sequencer: bad filter"]
    assert run_session.last_error_lines(str(tmp_path), "hand_replay-5") == []


def test_arguments_split_into_monitor_check_launch_and_args():
    assert run_session._parse(["f.launch", "a:=1"]) == ("session_monitor", False, "f.launch", ["a:=1"])
    assert run_session._parse(["--monitor", "teach_demo", "f.launch", "--check", "a:=1"]) == (
        "teach_demo",
        True,
        "f.launch",
        ["a:=1"],
    )
    assert run_session._parse(["--monitor"]) is None
