"""A finishing node stops only a roslaunch parent, with SIGINT (as Ctrl-C does)."""

import signal

from motion_common.session_end import end_parent_roslaunch


def run(cmdline, pid=4242):
    sent = []
    done = end_parent_roslaunch(lambda: pid, lambda _: cmdline, lambda p, s: sent.append((p, s)))
    return done, sent


def test_a_roslaunch_parent_gets_sigint():
    assert run(["/usr/bin/python3", "/usr/bin/roslaunch", "motion_bringup", "teleop_sim.launch"]) == (
        True,
        [(4242, signal.SIGINT)],
    )
    assert run(["roslaunch", "x.launch"])[0]


def test_other_parents_are_left_alone():
    for cmdline in (
        ["/usr/bin/python3", "/usr/bin/rostest", "motion_tests", "teleop_sim.test"],
        ["/work/.venv/bin/python", "/work/scripts/run_session", "teleop_sim.launch"],
        ["bash"],
        [],
    ):
        assert run(cmdline) == (False, [])
    assert run(["roslaunch"], pid=1) == (False, [])
