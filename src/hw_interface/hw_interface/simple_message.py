"""The ROS-Industrial simple_message wire format: frames and the standard message set, as
pure functions and dataclasses (no sockets).

Layouts are those of REP-I0004 (assigned message identifiers) and of the simple_message
message-structure REP (REP-I0006): every frame is an int32 ``length`` prefix (the byte count
of header and body, the prefix excluded), a header of three int32 (``msg_type``,
``comm_type``, ``reply_code``) and a type-specific body of int32 and float32 fields (the
usual 4-byte ``shared_real``). Joint arrays always have 10 slots; unused slots are zero.

Byte order: ``"little"`` is what the generic, non-swapping clients exchange with most
controllers (Stäubli VAL3, ABB, Motoman); ``"big"`` is the byte-swapped variant some
controllers need (Fanuc's server is normally run with the swapping client).

Decoding is strict: a truncated frame, a length prefix out of range (the usual sign of a
wrong byte order), an unknown message type, a body of the wrong length, an invalid
communication type or reply code, and a non-finite joint value each raise
``SimpleMessageError`` naming what was wrong.
"""

import math
import struct
from dataclasses import dataclass, field

__all__ = [
    "PING",
    "JOINT_POSITION",
    "JOINT_TRAJ_PT",
    "STATUS",
    "JOINT_TRAJ_PT_FULL",
    "JOINT_FEEDBACK",
    "TOPIC",
    "SERVICE_REQUEST",
    "SERVICE_REPLY",
    "REPLY_INVALID",
    "SUCCESS",
    "FAILURE",
    "START_TRAJECTORY_DOWNLOAD",
    "START_TRAJECTORY_STREAMING",
    "END_TRAJECTORY",
    "STOP_TRAJECTORY",
    "UNKNOWN",
    "OFF",
    "ON",
    "MAX_JOINTS",
    "PREFIX_SIZE",
    "HEADER_SIZE",
    "MAX_FRAME_LENGTH",
    "SimpleMessageError",
    "Header",
    "Ping",
    "JointPosition",
    "JointTrajPt",
    "RobotStatus",
    "JointTrajPtFull",
    "JointFeedback",
    "Frame",
    "encode",
    "encode_frame",
    "decode_frame",
    "decode_message",
    "FrameReader",
    "is_vendor_specific",
    "joint_array",
]

# Message types (REP-I0004, the standard set).
PING = 1
JOINT_POSITION = 10
JOINT_TRAJ_PT = 11
STATUS = 13
JOINT_TRAJ_PT_FULL = 14
JOINT_FEEDBACK = 15

# Communication types.
TOPIC = 1
SERVICE_REQUEST = 2
SERVICE_REPLY = 3

# Reply codes (INVALID also means "unused": every TOPIC and SERVICE_REQUEST carries it).
REPLY_INVALID = 0
SUCCESS = 1
FAILURE = 2

# Special sequence numbers of JOINT_TRAJ_PT / JOINT_TRAJ_PT_FULL.
START_TRAJECTORY_DOWNLOAD = -1
START_TRAJECTORY_STREAMING = -2
END_TRAJECTORY = -3
STOP_TRAJECTORY = -4

# Tri-states of STATUS.
UNKNOWN = -1
OFF = 0
ON = 1

MAX_JOINTS = 10
PREFIX_SIZE = 4
HEADER_SIZE = 12
#: Largest length prefix accepted: the longest standard message (JOINT_TRAJ_PT_FULL, 148)
#: with room to spare. A wrongly ordered prefix is in the millions.
MAX_FRAME_LENGTH = 1024

_ORDER = {"little": "<", "big": ">"}


class SimpleMessageError(ValueError):
    """Bytes that are not a valid simple_message frame; the message says what is wrong."""


def _order(byte_order: str) -> str:
    try:
        return _ORDER[byte_order]
    except KeyError:
        raise SimpleMessageError(f"byte_order must be 'little' or 'big', not {byte_order!r}") from None


def joint_array(values) -> tuple:
    """The 10 slots of a joint array: ``values`` then zeros; more than 10 is an error."""
    values = [float(v) for v in values]
    if len(values) > MAX_JOINTS:
        raise SimpleMessageError(f"{len(values)} joint values: a simple_message array holds {MAX_JOINTS}")
    return tuple(values + [0.0] * (MAX_JOINTS - len(values)))


def _zero_joints() -> tuple:
    """The default of a joint array field: 10 zero slots."""
    return (0.0,) * MAX_JOINTS


def _trajectory_arrays(message) -> tuple:
    """The 30 slots of a message's positions, velocities and accelerations, in wire order
    (the tail of JOINT_TRAJ_PT_FULL and of JOINT_FEEDBACK)."""
    return (*joint_array(message.positions), *joint_array(message.velocities), *joint_array(message.accelerations))


def _split_trajectory_arrays(values) -> tuple:
    """(positions, velocities, accelerations) from their 30 decoded slots."""
    return tuple(tuple(values[start : start + MAX_JOINTS]) for start in range(0, 3 * MAX_JOINTS, MAX_JOINTS))


def _finite(name, values):
    for i, value in enumerate(values):
        if not math.isfinite(value):
            raise SimpleMessageError(f"{name}[{i}] is {value}: joint values must be finite")


@dataclass(frozen=True)
class Header:
    """The three header fields."""

    msg_type: int
    comm_type: int
    reply_code: int = REPLY_INVALID


@dataclass(frozen=True)
class Ping:
    """PING (1): the body is 10 int32 to be ignored (sent as zeros); a reply may omit it."""

    MSG_TYPE = PING
    FORMAT = "10i"

    def fields(self):
        return (0,) * 10

    @classmethod
    def from_fields(cls, values):
        return cls()


@dataclass(frozen=True)
class JointPosition:
    """JOINT_POSITION (10): ``sequence`` (int32; 0 when reporting state), ``joints`` (10 x float32)."""

    sequence: int = 0
    joints: tuple = field(default_factory=_zero_joints)

    MSG_TYPE = JOINT_POSITION
    FORMAT = "i10f"

    def fields(self):
        return (self.sequence, *joint_array(self.joints))

    @classmethod
    def from_fields(cls, values):
        _finite("joint_data", values[1:11])
        return cls(values[0], tuple(values[1:11]))


@dataclass(frozen=True)
class JointTrajPt:
    """JOINT_TRAJ_PT (11): ``sequence`` (a point index or a special sequence number),
    ``joints`` (10 x float32, rad), ``velocity`` (fraction (0, 1] of the joint speed
    limits), ``duration`` (s, of the segment to this point)."""

    sequence: int
    joints: tuple = field(default_factory=_zero_joints)
    velocity: float = 0.0
    duration: float = 0.0

    MSG_TYPE = JOINT_TRAJ_PT
    FORMAT = "i10f2f"

    def fields(self):
        return (self.sequence, *joint_array(self.joints), float(self.velocity), float(self.duration))

    @classmethod
    def from_fields(cls, values):
        _finite("joint_data", values[1:13])
        return cls(values[0], tuple(values[1:11]), values[11], values[12])


@dataclass(frozen=True)
class RobotStatus:
    """STATUS (13): seven int32, tri-states (-1 unknown, 0 off, 1 on) but for
    ``error_code`` and ``mode`` (-1 unknown, 1 manual, 2 auto)."""

    drives_powered: int = UNKNOWN
    e_stopped: int = UNKNOWN
    error_code: int = 0
    in_error: int = UNKNOWN
    in_motion: int = UNKNOWN
    mode: int = UNKNOWN
    motion_possible: int = UNKNOWN

    MSG_TYPE = STATUS
    FORMAT = "7i"

    def fields(self):
        return (
            self.drives_powered,
            self.e_stopped,
            self.error_code,
            self.in_error,
            self.in_motion,
            self.mode,
            self.motion_possible,
        )

    @classmethod
    def from_fields(cls, values):
        status = cls(*values)
        for name in ("drives_powered", "e_stopped", "in_error", "in_motion", "motion_possible"):
            if getattr(status, name) not in (UNKNOWN, OFF, ON):
                raise SimpleMessageError(f"STATUS {name} is {getattr(status, name)}, not a tri-state (-1, 0, 1)")
        return status


@dataclass(frozen=True)
class JointTrajPtFull:
    """JOINT_TRAJ_PT_FULL (14): ``robot_id``, ``sequence``, ``valid_fields`` (bits: 1 time,
    2 position, 4 velocity, 8 acceleration), ``time`` (s), positions, velocities and
    accelerations (10 x float32 each)."""

    robot_id: int = 0
    sequence: int = 0
    valid_fields: int = 0
    time: float = 0.0
    positions: tuple = field(default_factory=_zero_joints)
    velocities: tuple = field(default_factory=_zero_joints)
    accelerations: tuple = field(default_factory=_zero_joints)

    MSG_TYPE = JOINT_TRAJ_PT_FULL
    FORMAT = "3if30f"

    def fields(self):
        return (self.robot_id, self.sequence, self.valid_fields, float(self.time), *_trajectory_arrays(self))

    @classmethod
    def from_fields(cls, values):
        _finite("time/positions/velocities/accelerations", values[3:])
        return cls(*values[:4], *_split_trajectory_arrays(values[4:]))


@dataclass(frozen=True)
class JointFeedback:
    """JOINT_FEEDBACK (15): ``robot_id``, ``valid_fields``, ``time`` (s), positions,
    velocities, accelerations (10 x float32 each)."""

    robot_id: int = 0
    valid_fields: int = 0
    time: float = 0.0
    positions: tuple = field(default_factory=_zero_joints)
    velocities: tuple = field(default_factory=_zero_joints)
    accelerations: tuple = field(default_factory=_zero_joints)

    MSG_TYPE = JOINT_FEEDBACK
    FORMAT = "2if30f"

    def fields(self):
        return (self.robot_id, self.valid_fields, float(self.time), *_trajectory_arrays(self))

    @classmethod
    def from_fields(cls, values):
        _finite("time/positions/velocities/accelerations", values[2:])
        return cls(*values[:3], *_split_trajectory_arrays(values[3:]))


_TYPES = {cls.MSG_TYPE: cls for cls in (Ping, JointPosition, JointTrajPt, RobotStatus, JointTrajPtFull, JointFeedback)}
#: Replies to these requests may carry 10 x int32/float32 of dummy data, or nothing.
_REPLY_BODY_SIZES = {PING: (0, 40), JOINT_TRAJ_PT: (0, 40, 52), JOINT_TRAJ_PT_FULL: (0, 40, 136)}


def is_vendor_specific(msg_type: int) -> bool:
    """True for identifiers REP-I0004 leaves to vendors or users (1000-1099, 2000-2099,
    65001-65535): a receiver ignores topics of those it does not know."""
    return 1000 <= msg_type <= 1099 or 2000 <= msg_type <= 2099 or 65001 <= msg_type <= 65535


@dataclass(frozen=True)
class Frame:
    """One received frame: its header and its raw body (without prefix and header)."""

    header: Header
    body: bytes


def encode_frame(header: Header, body: bytes, byte_order: str = "little") -> bytes:
    """Prefix + header + ``body``."""
    order = _order(byte_order)
    return (
        struct.pack(f"{order}4i", HEADER_SIZE + len(body), header.msg_type, header.comm_type, header.reply_code) + body
    )


def encode(message, comm_type: int = TOPIC, reply_code: int = REPLY_INVALID, byte_order: str = "little") -> bytes:
    """The whole frame of ``message`` (one of this module's message dataclasses)."""
    if comm_type not in (TOPIC, SERVICE_REQUEST, SERVICE_REPLY):
        raise SimpleMessageError(f"comm_type {comm_type} is not TOPIC (1), SERVICE_REQUEST (2) or SERVICE_REPLY (3)")
    values = message.fields()
    if any(isinstance(v, float) and not math.isfinite(v) for v in values):
        raise SimpleMessageError(f"refusing to encode a non-finite value in {type(message).__name__}")
    body = struct.pack(_order(byte_order) + message.FORMAT, *values)
    return encode_frame(Header(message.MSG_TYPE, comm_type, reply_code), body, byte_order)


def decode_frame(data: bytes, byte_order: str = "little") -> Frame:
    """Split one complete frame (prefix included) into header and body; checks the prefix
    against the bytes given, the communication type and the reply code."""
    order = _order(byte_order)
    if len(data) < PREFIX_SIZE + HEADER_SIZE:
        raise SimpleMessageError(
            f"truncated frame: {len(data)} bytes, a prefix and header need {PREFIX_SIZE + HEADER_SIZE}"
        )
    (length,) = struct.unpack_from(f"{order}i", data)
    _check_length(length)
    if len(data) != PREFIX_SIZE + length:
        kind = "truncated frame" if len(data) < PREFIX_SIZE + length else "frame longer than its prefix"
        raise SimpleMessageError(f"{kind}: length prefix {length} but {len(data) - PREFIX_SIZE} bytes follow it")
    msg_type, comm_type, reply_code = struct.unpack_from(f"{order}3i", data, PREFIX_SIZE)
    if comm_type not in (TOPIC, SERVICE_REQUEST, SERVICE_REPLY):
        raise SimpleMessageError(f"comm_type {comm_type} of message type {msg_type} is invalid (1, 2 or 3)")
    if reply_code not in (REPLY_INVALID, SUCCESS, FAILURE):
        raise SimpleMessageError(f"reply_code {reply_code} of message type {msg_type} is invalid (0, 1 or 2)")
    if comm_type != SERVICE_REPLY and reply_code != REPLY_INVALID:
        raise SimpleMessageError(f"a {'topic' if comm_type == TOPIC else 'request'} carries reply_code {reply_code}")
    return Frame(Header(msg_type, comm_type, reply_code), bytes(data[PREFIX_SIZE + HEADER_SIZE :]))


def decode_message(frame: Frame, byte_order: str = "little"):
    """The message dataclass of ``frame``; None for a reply without body. Raises
    SimpleMessageError for an unknown type, a wrong body length or non-finite joints."""
    msg_type = frame.header.msg_type
    cls = _TYPES.get(msg_type)
    if cls is None:
        raise SimpleMessageError(f"unknown message type {msg_type} ({len(frame.body)}-byte body)")
    expected = struct.calcsize("<" + cls.FORMAT)
    if frame.header.comm_type == SERVICE_REPLY and msg_type in _REPLY_BODY_SIZES:
        allowed = _REPLY_BODY_SIZES[msg_type]
        if len(frame.body) not in allowed:
            raise SimpleMessageError(
                f"reply to message type {msg_type} has a {len(frame.body)}-byte body; expected one of {allowed}"
            )
        if len(frame.body) != expected:
            return None  # an acknowledgement without (or with dummy) data
    elif len(frame.body) != expected:
        raise SimpleMessageError(
            f"message type {msg_type} ({cls.__name__}) has a {len(frame.body)}-byte body, expected {expected}"
        )
    return cls.from_fields(struct.unpack(_order(byte_order) + cls.FORMAT, frame.body))


def _check_length(length):
    if not HEADER_SIZE <= length <= MAX_FRAME_LENGTH:
        raise SimpleMessageError(
            f"length prefix {length} is outside {HEADER_SIZE}..{MAX_FRAME_LENGTH} "
            "(a corrupt stream or the wrong byte order: check byte_order)"
        )


class FrameReader:
    """Cuts a TCP byte stream into frames: ``feed(bytes)`` returns the complete frames so
    far. Holds at most one partial frame (bounded by MAX_FRAME_LENGTH); a bad length prefix
    raises SimpleMessageError (the stream cannot be resynchronised: close it)."""

    def __init__(self, byte_order: str = "little"):
        self.byte_order = byte_order
        self._order = _order(byte_order)
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list:
        self._buffer += data
        frames = []
        while len(self._buffer) >= PREFIX_SIZE:
            (length,) = struct.unpack_from(f"{self._order}i", self._buffer)
            _check_length(length)
            if len(self._buffer) < PREFIX_SIZE + length:
                break
            frames.append(decode_frame(bytes(self._buffer[: PREFIX_SIZE + length]), self.byte_order))
            del self._buffer[: PREFIX_SIZE + length]
        return frames

    @property
    def pending(self) -> int:
        """Bytes of an incomplete frame waiting for the rest (a truncated frame at a close)."""
        return len(self._buffer)
