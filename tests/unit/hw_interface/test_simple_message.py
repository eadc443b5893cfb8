"""The simple_message codec against golden byte strings written from the REP documents, not
from the codec: the three bytestream examples of the message-structure REP (REP-I0006,
Appendix A: JOINT_POSITION, JOINT_TRAJ_PT, STATUS; big-endian, as printed there), and
frames of the other messages laid out by hand from the field tables of REP-I0006 and the
identifiers of REP-I0004 (PING 1, JOINT_POSITION 10, JOINT_TRAJ_PT 11, STATUS 13,
JOINT_TRAJ_PT_FULL 14, JOINT_FEEDBACK 15; comm types TOPIC 1, SERVICE_REQUEST 2,
SERVICE_REPLY 3; reply codes INVALID 0, SUCCESS 1, FAILURE 2; special sequence numbers
-1..-4). Little-endian fixtures are the same words byte-swapped. Then every malformed input
the driver may meet raises a SimpleMessageError naming it."""

import math
import struct

import pytest

from hw_interface import simple_message as sm


def words(text: str) -> bytes:
    """Big-endian bytes of whitespace-separated 32-bit hex words (the REP's notation)."""
    return bytes.fromhex("".join(text.split()))


def little(big: bytes) -> bytes:
    """The same 32-bit words in little-endian order."""
    return b"".join(big[i : i + 4][::-1] for i in range(0, len(big), 4))


# REP-I0006, Appendix A, "Example: JOINT_POSITION": a six-axis robot near zero, server -> client.
REP_JOINT_POSITION = words(
    """00000038 0000000A 00000001 00000000
       00000000 B81AD9FA B6836312 B7C043F5 B8B81516 B865D055 B8B6365E
       00000000 00000000 00000000 00000000"""
)
# REP-I0006, Appendix A, "Example: JOINT_TRAJ_PT": the second point (sequence 1), client -> server.
REP_JOINT_TRAJ_PT = words(
    """00000040 0000000B 00000002 00000000
       00000001 A7600000 3EA7CDE8 BF5D9E57 C0490FDB 3F34815F C0490FDB
       00000000 00000000 00000000 00000000 3DCCCCCD 40A00000"""
)
# REP-I0006, Appendix A, "Example: STATUS": drives on, e-stop unknown, no error, still, AUTO, ready.
REP_STATUS = words(
    """00000028 0000000D 00000001 00000000
       00000001 FFFFFFFF 00000000 00000000 00000000 00000002 00000001"""
)
# By hand from REP-I0006 "PING": request = prefix, header, data int32[10] (zeros).
PING_REQUEST = words("00000034 00000001 00000002 00000000" + " 00000000" * 10)
# REP-I0006 "Alternative reply" of PING / JOINT_TRAJ_PT: prefix and header only.
PING_REPLY_SHORT = words("0000000C 00000001 00000003 00000001")
TRAJ_PT_REPLY_FAILURE = words("0000000C 0000000B 00000003 00000002")
# The full JOINT_TRAJ_PT reply: dummy_data float32[10].
TRAJ_PT_REPLY_DUMMY = words("00000034 0000000B 00000003 00000001" + " 00000000" * 10)
# STOP_TRAJECTORY: JOINT_TRAJ_PT with sequence -4 (FFFFFFFC), joints, velocity, duration zero.
STOP_REQUEST = words("00000040 0000000B 00000002 00000000 FFFFFFFC" + " 00000000" * 12)
# JOINT_TRAJ_PT_FULL (14), length 148 = 12 + 136: robot_id 0, sequence 2, valid_fields TIME|POSITION (3), time 1.5 s
# (3FC00000), positions [1.0 (3F800000), -0.5 (BF000000)], velocities and accelerations zero.
TRAJ_PT_FULL = words(
    "00000094 0000000E 00000002 00000000 00000000 00000002 00000003 3FC00000 3F800000 BF000000" + " 00000000" * 28
)
# JOINT_FEEDBACK (15), length 144 = 12 + 132: robot_id 1, valid_fields POSITION|VELOCITY (6), time 0.25 s (3E800000),
# positions [0.5 (3F000000), 2.0 (40000000)], velocities [0.125 (3E000000)], accelerations zero.
JOINT_FEEDBACK = words(
    "00000090 0000000F 00000001 00000000 00000001 00000006 3E800000 3F000000 40000000"
    + " 00000000" * 8
    + " 3E000000"
    + " 00000000" * 19
)

GOLDEN = [
    REP_JOINT_POSITION,
    REP_JOINT_TRAJ_PT,
    REP_STATUS,
    PING_REQUEST,
    PING_REPLY_SHORT,
    TRAJ_PT_REPLY_FAILURE,
    TRAJ_PT_REPLY_DUMMY,
    STOP_REQUEST,
    TRAJ_PT_FULL,
    JOINT_FEEDBACK,
]


def decode(data, byte_order="big"):
    return sm.decode_message(sm.decode_frame(data, byte_order), byte_order)


def test_the_protocol_numbers_are_the_reps():
    assert (sm.PING, sm.JOINT_POSITION, sm.JOINT_TRAJ_PT, sm.STATUS) == (1, 10, 11, 13)
    assert (sm.JOINT_TRAJ_PT_FULL, sm.JOINT_FEEDBACK) == (14, 15)
    assert (sm.TOPIC, sm.SERVICE_REQUEST, sm.SERVICE_REPLY) == (1, 2, 3)
    assert (sm.REPLY_INVALID, sm.SUCCESS, sm.FAILURE) == (0, 1, 2)
    assert (sm.START_TRAJECTORY_DOWNLOAD, sm.START_TRAJECTORY_STREAMING) == (-1, -2)
    assert (sm.END_TRAJECTORY, sm.STOP_TRAJECTORY) == (-3, -4)
    assert (sm.UNKNOWN, sm.OFF, sm.ON, sm.MAX_JOINTS) == (-1, 0, 1, 10)


def test_rep_joint_position_example_decodes_and_encodes_byte_for_byte():
    message = decode(REP_JOINT_POSITION)
    assert message.sequence == 0
    expected = [-0.000036919, -0.000003916, -0.000022920, -0.000087777, -0.000054792, -0.000086886]
    assert message.joints[:6] == pytest.approx(expected, rel=1e-4)
    assert message.joints[6:] == (0.0,) * 4
    assert sm.encode(message, sm.TOPIC, byte_order="big") == REP_JOINT_POSITION
    frame = sm.decode_frame(REP_JOINT_POSITION, "big")
    assert frame.header == sm.Header(sm.JOINT_POSITION, sm.TOPIC, sm.REPLY_INVALID)


def test_rep_joint_traj_pt_example_is_what_the_codec_sends():
    joints = [-3.1086245e-15, 0.327742815, -0.865697324, -3.141592741, 0.705099046, -3.141592741]
    point = sm.JointTrajPt(1, tuple(joints), 0.1, 5.0)
    assert sm.encode(point, sm.SERVICE_REQUEST, byte_order="big") == REP_JOINT_TRAJ_PT
    assert sm.encode(point, sm.SERVICE_REQUEST, byte_order="little") == little(REP_JOINT_TRAJ_PT)
    back = decode(REP_JOINT_TRAJ_PT)
    assert back.sequence == 1 and back.velocity == pytest.approx(0.1) and back.duration == 5.0
    assert back.joints[3] == pytest.approx(-math.pi, abs=1e-6)


def test_rep_status_example():
    status = decode(REP_STATUS)
    assert status == sm.RobotStatus(
        drives_powered=sm.ON, e_stopped=sm.UNKNOWN, error_code=0, in_error=sm.OFF, in_motion=sm.OFF, mode=2,
        motion_possible=sm.ON,
    )  # fmt: skip
    assert sm.encode(status, byte_order="big") == REP_STATUS
    assert decode(little(REP_STATUS), "little") == status


def test_ping_stop_and_reply_frames():
    assert sm.encode(sm.Ping(), sm.SERVICE_REQUEST, byte_order="big") == PING_REQUEST
    assert decode(PING_REPLY_SHORT) is None  # the alternative reply carries no body
    assert sm.decode_frame(PING_REPLY_SHORT, "big").header == sm.Header(sm.PING, sm.SERVICE_REPLY, sm.SUCCESS)
    assert sm.decode_frame(TRAJ_PT_REPLY_FAILURE, "big").header.reply_code == sm.FAILURE
    assert decode(TRAJ_PT_REPLY_DUMMY) is None
    assert sm.encode(sm.JointTrajPt(sm.STOP_TRAJECTORY), sm.SERVICE_REQUEST, byte_order="big") == STOP_REQUEST


def test_full_point_and_feedback_layouts():
    full = sm.JointTrajPtFull(0, 2, 0x03, 1.5, (1.0, -0.5))
    assert sm.encode(full, sm.SERVICE_REQUEST, byte_order="big") == TRAJ_PT_FULL
    assert decode(TRAJ_PT_FULL) == sm.JointTrajPtFull(0, 2, 3, 1.5, (1.0, -0.5) + (0.0,) * 8)
    feedback = decode(JOINT_FEEDBACK)
    assert (feedback.robot_id, feedback.valid_fields, feedback.time) == (1, 6, 0.25)
    assert feedback.positions[:2] == (0.5, 2.0) and feedback.velocities[0] == 0.125
    assert sm.encode(feedback, byte_order="little") == little(JOINT_FEEDBACK)


@pytest.mark.parametrize("fixture", GOLDEN)
def test_every_golden_frame_round_trips_in_both_byte_orders(fixture):
    for byte_order, data in (("big", fixture), ("little", little(fixture))):
        frame = sm.decode_frame(data, byte_order)
        assert len(data) == sm.PREFIX_SIZE + sm.HEADER_SIZE + len(frame.body)
        message = sm.decode_message(frame, byte_order)
        if message is not None:
            assert sm.encode(message, frame.header.comm_type, frame.header.reply_code, byte_order) == data


def test_the_frame_reader_cuts_a_stream_anywhere():
    stream = little(REP_JOINT_POSITION) + little(REP_STATUS) + little(PING_REPLY_SHORT)
    for cut in range(1, len(stream)):
        reader = sm.FrameReader("little")
        frames = reader.feed(stream[:cut]) + reader.feed(stream[cut:])
        assert [f.header.msg_type for f in frames] == [sm.JOINT_POSITION, sm.STATUS, sm.PING]
        assert reader.pending == 0


MALFORMED = {
    "truncated frame": (little(REP_STATUS)[:-3], "truncated"),
    "frame shorter than a header": (little(REP_STATUS)[:10], "truncated"),
    "longer than its prefix": (little(REP_STATUS) + b"\0\0\0\0", "longer than its prefix"),
    "wrong byte order": (REP_STATUS, "byte order"),
    "length prefix below a header": (struct.pack("<4i", 8, 13, 1, 0), "outside"),
    "negative length prefix": (struct.pack("<4i", -4, 13, 1, 0), "outside"),
    "unknown message type": (struct.pack("<4i", 12, 99, 1, 0), "unknown message type 99"),
    "JOINT_POSITION one joint short": (struct.pack("<4ii9f", 52, 10, 1, 0, 0, *[0.0] * 9), "expected 44"),
    "STATUS with an extra word": (struct.pack("<4i8i", 44, 13, 1, 0, *[0] * 8), "expected 28"),
    "NaN joint": (struct.pack("<4ii10f", 56, 10, 1, 0, 0, 0.1, math.nan, *[0.0] * 8), "finite"),
    "infinite joint": (struct.pack("<4ii10f", 56, 10, 1, 0, 0, math.inf, *[0.0] * 9), "finite"),
    "comm_type 0": (struct.pack("<4i7i", 40, 13, 0, 0, *[0] * 7), "comm_type 0"),
    "comm_type 7": (struct.pack("<4i7i", 40, 13, 7, 0, *[0] * 7), "comm_type 7"),
    "reply code 5": (struct.pack("<4i", 12, 11, 3, 5), "reply_code 5"),
    "topic with a reply code": (struct.pack("<4i7i", 40, 13, 1, 1, *[0] * 7), "reply_code"),
    "tri-state 3": (struct.pack("<4i7i", 40, 13, 1, 0, 3, 0, 0, 0, 0, 2, 1), "tri-state"),
    "reply of an odd size": (struct.pack("<4i3i", 24, 11, 3, 1, 0, 0, 0), "12-byte body"),
}


@pytest.mark.parametrize("name", sorted(MALFORMED))
def test_malformed_input_raises_a_clear_error(name):
    data, words_expected = MALFORMED[name]
    with pytest.raises(sm.SimpleMessageError, match=words_expected):
        decode(data, "little")


def test_the_reader_refuses_a_wrong_order_prefix_before_buffering_it():
    reader = sm.FrameReader("little")
    with pytest.raises(sm.SimpleMessageError, match="byte order"):
        reader.feed(REP_STATUS[:4])  # 0x28000000: 671 million bytes announced


def test_the_encoder_refuses_what_no_controller_may_receive():
    with pytest.raises(sm.SimpleMessageError, match="non-finite"):
        sm.encode(sm.JointTrajPt(0, (math.nan,) * 6, 0.5, 1.0), sm.SERVICE_REQUEST)
    with pytest.raises(sm.SimpleMessageError, match="11 joint values"):
        sm.encode(sm.JointTrajPt(0, (0.0,) * 11, 0.5, 1.0), sm.SERVICE_REQUEST)
    with pytest.raises(sm.SimpleMessageError, match="comm_type"):
        sm.encode(sm.Ping(), 0)
    with pytest.raises(sm.SimpleMessageError, match="byte_order"):
        sm.encode(sm.Ping(), sm.SERVICE_REQUEST, byte_order="middle")
    assert sm.is_vendor_specific(2001) and sm.is_vendor_specific(1000) and not sm.is_vendor_specific(16)
