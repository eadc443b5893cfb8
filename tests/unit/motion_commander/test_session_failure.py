"""A finished session that did not do its job is named as failed, with the reason."""

from motion_commander.session_report import session_failure


def summary(frames_in=367, sent=348, refused=0):
    return {"frames_in": frames_in, "commands_sent": sent, "commands_refused": refused}


def test_a_good_session_passes():
    assert session_failure(summary(), 0.1) == ""
    assert session_failure(summary(sent=100, refused=10), 0.1) == ""


def test_no_hand_no_command_or_many_refused_fail_with_the_reason():
    assert "no hand frame" in session_failure(summary(frames_in=0, sent=0), 0.1)
    assert "clutch never engaged" in session_failure(summary(sent=0), 0.1)
    reason = session_failure(summary(sent=122, refused=106), 0.1)
    assert "106 of 122 commands were refused (87%" in reason and "robot_config:=" in reason
