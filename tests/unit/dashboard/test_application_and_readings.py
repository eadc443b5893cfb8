"""Which panels the page shows per application, how the input device is named, and the
readings of camera frames and kitting events."""

import base64

import pytest

from dashboard.application import APPLICATIONS, PANELS, detect_application, panels_for
from dashboard.readings import campaign_line, device_label, image_data_url, kitting_event_line


def test_every_application_has_its_panels_and_the_common_ones():
    for name in APPLICATIONS:
        assert {"scene", "path", "joints", "series", "events"} <= panels_for(name)
    assert "camera" in PANELS["kitting"] and "camera" not in PANELS["teleop"]
    assert "kitting" not in PANELS["teach"] and "programs" in PANELS["teach"]
    with pytest.raises(ValueError, match="teleop, teach, kitting"):
        panels_for("painting")


@pytest.mark.parametrize(
    "topics, expected",
    [
        (["/joint_states", "/motion_commander/status"], "teleop"),
        (["/joint_states", "/teach/feedback"], "teach"),
        (["/kitting/object_poses", "/teach/feedback"], "kitting"),
        (["kitting/events"], "kitting"),
        ([], "teleop"),
    ],
)
def test_the_application_is_told_from_the_published_topics(topics, expected):
    assert detect_application(topics) == expected


@pytest.mark.parametrize(
    "launch, active, application, expected",
    [
        ("replay", "default", "teleop", "replay"),
        ("leap", "leap", "teleop", "leap"),
        ("leap", "spacemouse", "teleop", "leap (input spacemouse)"),
        ("", "webcam", "teleop", "webcam"),
        ("", "default", "teleop", "one input (the launch did not name the device)"),
        ("", None, "teleop", "-"),
        ("0", None, "kitting", "camera /dev/video0"),
    ],
)
def test_the_device_is_named_as_the_launch_knows_it_never_just_default(launch, active, application, expected):
    label = device_label(launch, active, application)
    assert label == expected
    assert label != "default"


def test_image_data_url_for_jpeg_and_png_only():
    url = image_data_url(b"\xff\xd8abc", "jpeg")
    assert url.startswith("data:image/jpeg;base64,")
    assert base64.b64decode(url.split(",", 1)[1]) == b"\xff\xd8abc"
    assert image_data_url(b"x", "bgr8; png compressed bgr8").startswith("data:image/png")
    assert image_data_url(b"x", "tiff") is None
    assert image_data_url(b"", "jpeg") is None


def test_campaign_and_kitting_event_lines():
    progress = {
        "done": 2,
        "trials": 6,
        "per_class": {"nut": {"picked": 1, "placed": 1}, "bolt": {"picked": 1, "placed": 0}},
    }
    assert campaign_line("campaign_progress", progress) == "trial 2/6 done: 2 picked, 1 placed so far"
    assert campaign_line("campaign_result", {"successes": 5, "trials": 6}) == "campaign done: 5/6 placed"
    assert campaign_line("campaign_result", {"error": "boom"}) == "campaign error: boom"
    # The kits scored so far (ARIAC's kitting score) follow the placed count.
    kits = {"kits": 2, "kit_score": 30, "kit_score_max": 36}
    assert campaign_line("campaign_result", {"successes": 12, "trials": 12, **kits}) == (
        "campaign done: 12/12 placed, kit score 30/36 (83 %) over 2 kit(s)"
    )
    assert campaign_line("campaign_progress", {**progress, "kits": 0, "kit_score": 0, "kit_score_max": 0}) == (
        "trial 2/6 done: 2 picked, 1 placed so far"
    )
    assert campaign_line("campaign_progress", []) == "campaign_progress: unreadable"
    assert kitting_event_line("picked", "nut_yellow", 3) == "picked nut_yellow #3"
    assert kitting_event_line("missed", "", 4, "too late") == "missed part #4: too late"
