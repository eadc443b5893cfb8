"""The dashboard's episode panel: the recorder's messages checked and shown, and which of
its buttons can act."""

from dashboard.application import panels_for
from dashboard.controls import control_states
from dashboard.episodes import episode_rows, episode_status_text, parse_episode_message


def test_recorder_messages_are_checked():
    assert parse_episode_message('{"recording": true}', dict) == ({"recording": True}, "")
    value, reason = parse_episode_message("[1, 2", list)
    assert value is None and reason.startswith("not JSON")
    assert parse_episode_message("{}", list) == (None, "a JSON list was expected, got dict")


def test_status_line_and_rows_newest_first():
    assert episode_status_text(None).startswith("no episode recorder")
    status = {"recording": True, "episode_index": 3, "frames": 40, "success": True, "last_result": ""}
    assert episode_status_text(status) == "recording episode 3: 40 frames, marked success"
    assert episode_status_text({"recording": False, "last_result": "saved episode 2"}) == "idle - saved episode 2"
    rows = episode_rows(
        [
            {"episode_index": 0, "task": "pick", "frames": 90, "duration_s": 9.0, "success": True},
            {
                "episode_index": 1,
                "task": "pick",
                "frames": 50,
                "duration_s": 5.0,
                "success": False,
                "camera_loss_fraction": 0.125,
            },
            "garbage",
        ]
    )
    assert [r["episode"] for r in rows] == [1, 0]
    assert rows[0]["outcome"] == "failure" and rows[0]["camera loss"] == "12.5 %"
    assert rows[1]["outcome"] == "success" and rows[1]["camera loss"] == "-"


def test_episode_buttons_follow_the_recorder():
    states = control_states({})
    assert not states["episode_start"].enabled and "dataset:=" in states["episode_start"].reason
    idle = control_states({"episodes_status": {"recording": False}})
    assert idle["episode_start"].enabled and not idle["episode_stop"].enabled
    assert idle["episode_success"].enabled  # marks the last saved episode
    busy = control_states({"episodes_status": {"recording": True}})
    assert not busy["episode_start"].enabled and busy["episode_stop"].enabled and busy["episode_discard"].enabled


def test_every_application_shows_the_episode_panel():
    for application in ("teleop", "teach", "kitting"):
        assert "episodes" in panels_for(application)
