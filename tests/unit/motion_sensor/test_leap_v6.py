"""Leap v6 protocol parsing: units, axes, orientation, and rejection of bad messages."""

import gzip
import json
import os

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from motion_sensor.devices.leap_v6 import (
    LEAP_TO_REP103,
    frame_to_sample,
    palm_orientation,
    parse_message,
    read_recording,
    select_primary,
)
from motion_sensor.errors import MotionSensorError

from ..conftest import DATA


def hand(**overrides):
    base = {
        "id": 7,
        "type": "right",
        "confidence": 0.9,
        "palmPosition": [10.0, 200.0, -30.0],
        "palmNormal": [0.0, -1.0, 0.0],
        "direction": [0.0, 0.0, -1.0],
        "stabilizedPalmPosition": [11.0, 201.0, -29.0],
    }
    base.update(overrides)
    return base


def frame(hands, **overrides):
    base = {"id": 100, "timestamp": 5_000_000, "hands": hands}
    base.update(overrides)
    return json.dumps(base)


def test_axes_and_units_follow_rep103():
    # Leap: x right, y up, z toward the operator; REP 103: x forward, y left, z up.
    parsed = parse_message(frame([hand()]))
    np.testing.assert_allclose(parsed.hands[0].position, [0.030, -0.010, 0.200])
    assert parsed.timestamp == pytest.approx(5.0)
    assert np.linalg.det(LEAP_TO_REP103) == pytest.approx(1.0)


def test_flat_hand_pointing_away_is_identity():
    # Palm down (normal -y_leap), fingers away from the operator (-z_leap).
    quat = palm_orientation(np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, -1.0]))
    assert Rotation.from_quat(quat).magnitude() == pytest.approx(0.0, abs=1e-9)


def test_hand_turned_left_is_yaw_plus_90():
    # Fingers pointing to the operator's left (-x_leap), palm down: +90 deg about z (up).
    quat = palm_orientation(np.array([0.0, -1.0, 0.0]), np.array([-1.0, 0.0, 0.0]))
    np.testing.assert_allclose(Rotation.from_quat(quat).as_euler("xyz"), [0, 0, np.pi / 2], atol=1e-9)


def test_orientation_is_unit_even_for_non_orthogonal_vectors():
    quat = palm_orientation(np.array([0.1, -0.9, 0.2]), np.array([0.05, 0.1, -1.0]))
    assert np.linalg.norm(quat) == pytest.approx(1.0)


def test_version_handshake_is_not_a_frame():
    assert parse_message('{"version":6}') is None


@pytest.mark.parametrize(
    "text, fragment",
    [
        ('{"id": 1, "timestamp": 5, "hands": [', "malformed"),
        ("[1, 2]", "JSON object"),
        ('{"id": 1, "hands": []}', "timestamp"),
        ('{"id": 1, "timestamp": "soon", "hands": []}', "timestamp"),
        ('{"id": 1, "timestamp": 5, "hands": {}}', "hands"),
    ],
)
def test_malformed_frames_are_rejected_with_a_reason(text, fragment):
    with pytest.raises(MotionSensorError, match=fragment):
        parse_message(text)


@pytest.mark.parametrize(
    "override, fragment",
    [
        ({"palmPosition": [1.0, 2.0]}, "palmPosition"),
        ({"palmPosition": [1.0, "x", 3.0]}, "palmPosition"),
        ({"palmNormal": None}, "palmNormal"),
        ({"type": "middle"}, "type"),
        ({"id": "seven"}, "id"),
        ({"direction": [0.0, 0.0, 0.0]}, "direction"),
    ],
)
def test_bad_hand_fields_are_named(override, fragment):
    with pytest.raises(MotionSensorError, match=fragment):
        parse_message(frame([hand(**override)]))


def test_non_finite_values_are_rejected():
    # json accepts NaN literals; the parser must not.
    with pytest.raises(MotionSensorError, match="not finite"):
        parse_message(frame([hand()]).replace("200.0", "NaN"))


def test_oversized_message_is_rejected():
    with pytest.raises(MotionSensorError, match="exceeds"):
        parse_message("x" * 300_000)


def test_primary_hand_selection_and_sample():
    parsed = parse_message(frame([hand(id=1, type="left"), hand(id=2, type="right")]))
    assert select_primary(parsed, "right").hand_id == 2
    assert select_primary(parsed, "left").hand_id == 1
    assert select_primary(parsed, "first").hand_id == 1
    sample = frame_to_sample(parsed, stamp=3.0, preference="right")
    assert sample.hands_num == 2 and sample.hand_types == ("right", "left") and sample.hand_id == 2
    with pytest.raises(MotionSensorError):
        select_primary(parsed, "both")


def test_real_recording_reads_completely():
    recording = read_recording(os.path.join(DATA, "test-paddle-rightwards.jsonl.gz"))
    assert len(recording.frames) == 367 and recording.rejected == []
    assert recording.duration == pytest.approx(3.71, abs=0.01)
    positions = np.array([f.hands[0].position for f in recording.frames])
    # A palm held over the device: 5-40 cm above it, within +-25 cm sideways.
    assert np.all((positions[:, 2] > 0.05) & (positions[:, 2] < 0.4))
    assert np.all(np.abs(positions[:, :2]) < 0.25)


def test_bad_lines_in_a_recording_are_skipped_and_reported(tmp_path):
    source = os.path.join(DATA, "wave.jsonl.gz")
    with gzip.open(source, "rt") as fh:
        lines = fh.read().splitlines()
    lines.insert(5, lines[5][:100])  # a truncated frame
    lines.insert(9, "not json at all")
    path = tmp_path / "damaged.jsonl"
    path.write_text("\n".join(lines) + "\n")
    recording = read_recording(str(path))
    assert len(recording.frames) == len(lines) - 3  # minus the version line and two bad ones
    assert len(recording.rejected) == 2 and recording.rejected[0].startswith("line 6")


def test_unreadable_recording_says_what_to_do(tmp_path):
    path = tmp_path / "empty.jsonl"
    path.write_text('{"version":6}\n')
    with pytest.raises(MotionSensorError, match="no tracking frame"):
        read_recording(str(path))
    with pytest.raises(MotionSensorError, match="cannot read"):
        read_recording(str(tmp_path / "missing.jsonl.gz"))


def test_gesture_fields_come_from_the_protocol():
    """grabStrength / pinchStrength of the hand and the index tip of its pointables."""
    recording = read_recording(os.path.join(DATA, "grab.jsonl.gz"))
    samples = [frame_to_sample(f, f.timestamp) for f in recording.frames]
    samples = [s for s in samples if s is not None]
    grabs = np.array([s.grab_strength for s in samples])
    assert np.all((grabs >= 0) & (grabs <= 1))
    assert grabs.max() > 0.9 and grabs.min() < 0.2, "the grab recording closes and opens the hand"
    assert all(0 <= s.pinch_strength <= 1 and 0 <= s.confidence <= 1 for s in samples)
    tips = [s for s in samples if s.index_tip is not None]
    assert len(tips) > 0.9 * len(samples)
    reach = [np.linalg.norm(s.index_tip - s.position) for s in tips]
    assert 0.03 < np.median(reach) < 0.15, "the index tip lies a finger's length from the palm"


def test_missing_gesture_fields_read_as_unknown_and_bad_ones_are_named():
    sample = frame_to_sample(parse_message(frame([hand()])), 1.0)
    assert sample.grab_strength == -1.0 and sample.pinch_strength == -1.0 and sample.index_tip is None
    tip = {"type": 1, "handId": 7, "tipPosition": [10.0, 250.0, -100.0]}
    sample = frame_to_sample(parse_message(frame([hand(grabStrength=1.0, pinchStrength=0.25)], pointables=[tip])), 1.0)
    assert sample.grab_strength == 1.0 and sample.pinch_strength == 0.25
    np.testing.assert_allclose(sample.index_tip, LEAP_TO_REP103 @ np.array([10.0, 250.0, -100.0]) / 1000)
    with pytest.raises(MotionSensorError, match="grabStrength"):
        parse_message(frame([hand(grabStrength=1.7)]))
