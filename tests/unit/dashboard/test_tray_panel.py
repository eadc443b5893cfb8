"""The kitting panel's tray line: the kitting node's kitting/tray messages checked, and read."""

import json

import pytest

from dashboard.tray import parse_tray, tray_text

SLOTS = ["bolt_silver", "nut_yellow", "washer_yellow"]


def test_a_tray_message_is_read():
    tray, reason = parse_tray(json.dumps({"slots": SLOTS, "filled": ["nut_yellow"], "complete": False}))
    assert reason == "" and tray == {"slots": SLOTS, "filled": ["nut_yellow"], "complete": False}
    assert tray_text(tray) == "tray: 1/3 slots filled (nut_yellow)"
    tray, _ = parse_tray(json.dumps({"slots": SLOTS, "filled": SLOTS}))  # complete from the slots
    assert tray["complete"] and tray_text(tray).startswith("kit complete (3/3 slots)")
    assert "no kitting node" in tray_text(None)


@pytest.mark.parametrize(
    "text, words",
    [
        ("{", "not JSON"),
        ("[1]", "JSON dict"),
        (json.dumps({"slots": [], "filled": []}), "'slots'"),
        (json.dumps({"slots": SLOTS, "filled": ["gear"]}), "'filled'"),
        (json.dumps({"slots": SLOTS, "filled": "nut_yellow"}), "'filled'"),
        (json.dumps({"slots": SLOTS, "filled": [], "complete": "yes"}), "'complete'"),
        (json.dumps({"slots": SLOTS, "filled": SLOTS[:1], "complete": True}), "1 of 3 slots"),
    ],
)
def test_a_malformed_tray_message_is_refused_with_the_reason(text, words):
    tray, reason = parse_tray(text)
    assert tray is None and words in reason
