"""The sequencer: turns irregular, noisy device frames into a clean pose stream.

Stages, in order, each counting what it drops (``counters``, by reason):
1. validation: finite values, unit quaternion, hands_num consistent with hand_type, stamp;
2. device binding: with several devices publishing, only the active one drives
   (forced by name, else the highest priority device heard within ``device_timeout_s``);
3. timing: duplicate, out-of-order, future, too old (``max_age_s``) or older than the
   robot's last accepted command (the latest frame wins: no queue builds up);
4. hand identity: a different hand (id or type) re-seeds the filter; two hands are never
   blended; a hand that (re)enters has its first ``entry_trim_frames`` frames trimmed;
5. jump rejection: a change larger than ``jump_distance_m`` / ``jump_angle_rad`` within
   ``jump_window_s`` is ignored, unless ``jump_accept_after`` frames in a row agree on the
   new place (then it is a real move and is accepted without an output jump);
6. exit trim: the last ``exit_trim_frames`` frames before a hand leaves are held back and
   discarded when it leaves (a delay of that many frames; 0 turns it off);
7. filtering (mean, kalman or one_euro), then a continuity offset so that device switches
   and accepted jumps never make the output jump.
"""

import math
from collections import Counter, deque
from dataclasses import dataclass, field

import numpy as np

from motion_common.errors import ParameterError
from motion_common.float_list import float_list
from motion_common.params import Param, ParamSchema
from motion_common.rotations import is_unit_quaternion, multiply_quaternions, quaternion_norm
from motion_sensor.errors import MotionSensorError
from motion_sensor.hand_sample import HandSample
from motion_sensor.sequencing.filters import FILTER_PARAMS, FILTERS, make_filter

# Drops that are the sequencer doing its job, not bad input: counted, never warned about.
EXPECTED_DROPS = frozenset({"entry_trim", "exit_trim", "no_hand", "inactive_device"})


INPUT_PARAMS = ParamSchema(
    [
        Param("topic", "~input", doc="motion_sensor/hand topic of the device"),
        Param("device", "default", doc="device name (binding, active_device)"),
        Param("priority", 0, doc="higher drives when several devices are alive"),
    ]
)

# The sequencer node's parameters (config/sequencer.yaml and what launch files set).
SEQUENCER_PARAMS = ParamSchema(
    [
        Param("filter", "one_euro", choices=tuple(sorted(FILTERS)), doc="pose filter"),
        Param("filter_params", {}, schema=FILTER_PARAMS, doc="per filter name, that filter's parameters"),
        Param(
            "queue_size",
            None,
            kind=int,
            unit="frames",
            low=1,
            high=10000,
            nullable=True,
            doc="mean filter window; overrides filter_params.mean.queue_size when set",
        ),
        Param("max_age_s", 0.25, unit="s", low=0, low_open=True, doc="older frames are stale and dropped"),
        Param("max_future_s", 0.05, unit="s", low=0, doc="frames stamped further ahead are dropped"),
        Param("entry_trim_frames", 10, unit="frames", low=0, doc="ignored when a hand (re)enters"),
        Param("exit_trim_frames", 0, unit="frames", low=0, doc="held back and discarded when a hand leaves"),
        Param("hand_lost_s", 0.2, unit="s", low=0, low_open=True, doc="a gap this long means the hand left"),
        Param(
            "jump_distance_m", 0.05, unit="m", low=0, low_open=True, doc="a larger move within jump_window_s is a jump"
        ),
        Param(
            "jump_angle_rad", 0.8, unit="rad", low=0, low_open=True, doc="a larger turn within jump_window_s is a jump"
        ),
        Param("jump_window_s", 0.05, unit="s", low=0, low_open=True, doc="time window of the jump test"),
        Param("jump_accept_after", 5, unit="frames", low=1, doc="frames agreeing on a new place accept it"),
        Param("device_timeout_s", 0.3, unit="s", low=0, low_open=True, doc="a silent device loses the binding"),
        Param("active_device", "", doc="force a device by name; empty = highest priority alive"),
        Param("hand_frame", "hand", doc="tf child frame of the filtered hand"),
        Param(
            "inputs",
            None,
            kind=list,
            item_kind=dict,
            nullable=True,
            doc="[{topic, device, priority}] per device; unset = one input ~input named default",
        ),
    ]
)


@dataclass
class SequencerConfig:
    """The stages' parameters; defaults, units and ranges are ``SEQUENCER_PARAMS`` (the
    node's declaration), and a value out of range raises MotionSensorError."""

    filter_name: str = SEQUENCER_PARAMS.field("filter")
    filter_params: dict = None
    max_age_s: float = SEQUENCER_PARAMS.field("max_age_s")
    max_future_s: float = SEQUENCER_PARAMS.field("max_future_s")
    entry_trim_frames: int = SEQUENCER_PARAMS.field("entry_trim_frames")
    exit_trim_frames: int = SEQUENCER_PARAMS.field("exit_trim_frames")
    hand_lost_s: float = SEQUENCER_PARAMS.field("hand_lost_s")
    jump_distance_m: float = SEQUENCER_PARAMS.field("jump_distance_m")
    jump_angle_rad: float = SEQUENCER_PARAMS.field("jump_angle_rad")
    jump_window_s: float = SEQUENCER_PARAMS.field("jump_window_s")
    jump_accept_after: int = SEQUENCER_PARAMS.field("jump_accept_after")
    device_timeout_s: float = SEQUENCER_PARAMS.field("device_timeout_s")
    device_priorities: dict[str, int] = field(default_factory=dict)
    active_device: str = SEQUENCER_PARAMS.field("active_device")

    def __post_init__(self):
        try:
            # filter_params here is one filter's mapping, checked by that filter's constructor.
            SEQUENCER_PARAMS.check_fields(self, "SequencerConfig", names={"filter_name": "filter", "filter_params": ""})
        except ParameterError as exc:
            raise MotionSensorError(str(exc)) from None
        if self.filter_params is None:
            self.filter_params = filter_params_for(SEQUENCER_PARAMS.defaults(), self.filter_name)


def filter_params_for(params: dict, name: str) -> dict:
    """The parameters of filter ``name`` from validated SEQUENCER_PARAMS values (its
    ``filter_params`` entry; ``queue_size`` overrides the mean filter's window)."""
    filter_params = dict((params["filter_params"] or {}).get(name) or {})
    if name == "mean" and params["queue_size"] is not None:
        filter_params["queue_size"] = params["queue_size"]
    return filter_params


def sequencer_setup(params: dict, source: str):
    """(SequencerConfig, inputs) of validated SEQUENCER_PARAMS values; raises ParameterError
    (inputs entries) or MotionSensorError (values the stages refuse)."""
    inputs = params["inputs"]
    if inputs is None:
        inputs = [INPUT_PARAMS.defaults()]
    else:
        inputs = [INPUT_PARAMS.validate(entry, f"{source}: 'inputs'[{i}]") for i, entry in enumerate(inputs)]
    name = params["filter"]
    filter_params = filter_params_for(params, name)
    keys = (
        "max_age_s",
        "max_future_s",
        "entry_trim_frames",
        "exit_trim_frames",
        "hand_lost_s",
        "jump_distance_m",
        "jump_angle_rad",
        "jump_window_s",
        "jump_accept_after",
        "device_timeout_s",
        "active_device",
    )
    config = SequencerConfig(
        filter_name=name,
        filter_params=filter_params,
        device_priorities={entry["device"]: entry["priority"] for entry in inputs},
        **{key: params[key] for key in keys},
    )
    return config, inputs


@dataclass
class SequencedPose:
    """A filtered pose ready for /motion_states, with the stamp of its sensor frame."""

    stamp: float
    position: np.ndarray
    orientation: np.ndarray
    frame_id: str
    hand_type: str
    hands_num: int
    device: str = ""


def _floats(values, length: int):
    """``values`` as a list of ``length`` floats, or None when it is not that."""
    if getattr(values, "shape", (length,)) != (length,):  # an array of another shape (e.g. 3x1)
        return None
    try:
        values = float_list(values)
    except (TypeError, ValueError):  # not a flat sequence of numbers (e.g. nested)
        return None
    return values if len(values) == length else None


def validate_sample(sample: HandSample) -> str | None:
    """Return why ``sample`` is unusable, or None when it is fine."""
    # Every frame passes here on the latency-critical path: plain floats and math, since
    # numpy's per-call overhead on 3- and 4-vectors costs more than the checks themselves.
    position = _floats(sample.position, 3)
    orientation = _floats(sample.orientation, 4)
    if position is None or orientation is None:
        return "malformed"
    if not all(map(math.isfinite, position + orientation)) or not math.isfinite(sample.stamp):
        return "non_finite"
    if not is_unit_quaternion(orientation):
        return "non_unit_quaternion"
    if sample.hands_num != len(sample.hand_types):
        return "hands_num_mismatch"
    if sample.stamp <= 0:
        return "bad_stamp"
    for value in (sample.confidence, sample.grab_strength, sample.pinch_strength):
        # 0-1, or the documented unknown value -1.
        if not (math.isfinite(value) and (value == -1.0 or 0.0 <= value <= 1.0)):
            return "bad_hand_field"
    if sample.index_tip is not None:
        tip = _floats(sample.index_tip, 3)
        if tip is None or not all(map(math.isfinite, tip)):
            return "bad_hand_field"
    return None


class DeviceBinder:
    """Chooses the device that drives: forced by name, else the highest priority heard
    within the timeout (unknown devices have priority 0; ties go to the earliest heard)."""

    def __init__(self, priorities: dict[str, int], timeout: float, forced: str = ""):
        self.priorities = dict(priorities)
        self.timeout = timeout
        self.forced = forced
        self.last_heard: dict[str, float] = {}
        self.active: str | None = None

    def hear(self, device: str, now: float) -> bool:
        """Record a frame from ``device``; return whether it is the active device."""
        self.last_heard[device] = now
        if self.forced:
            self.active = self.forced
            return device == self.forced
        if len(self.last_heard) == 1:  # the usual single device: it drives (no search per frame)
            self.active = device
            return True
        alive = [d for d, t in self.last_heard.items() if now - t <= self.timeout]
        self.active = max(alive, key=lambda d: self.priorities.get(d, 0)) if alive else device
        return device == self.active


class Sequencer:
    """Validates, binds, de-stales, de-jumps, trims and filters hand samples.

    Not thread-safe: one caller (the node holds a lock).
    """

    def __init__(self, config: SequencerConfig = None):
        self.config = config or SequencerConfig()
        self.filter = make_filter(self.config.filter_name, **self.config.filter_params)
        self.binder = DeviceBinder(
            self.config.device_priorities, self.config.device_timeout_s, self.config.active_device
        )
        self.counters = Counter()
        self.unexpected_drops = 0  # drops for bad or late input, worth a warning
        self._last_stamp: dict[str, float] = {}
        self._last_command_stamp = None
        self._hand_key = None
        self._last_seen = None
        self._since_entry = 0
        self._last_accepted = None  # (stamp, position, orientation) of the last accepted raw frame
        self._jump_candidates = []
        self._delay = deque()
        # Continuity offsets (see _emit), plain floats: they are applied on every frame.
        self._offset_position = [0.0, 0.0, 0.0]
        self._offset_rotation = (0.0, 0.0, 0.0, 1.0)
        self._continuity_pending = False
        self._last_output: SequencedPose | None = None
        self._active_device = None

    # -- inputs from the rest of the system ---------------------------------------------------
    def note_command(self, stamp: float) -> None:
        """The robot accepted a command made from the frame stamped ``stamp``; frames
        older than that are outdated and will be dropped."""
        if self._last_command_stamp is None or stamp > self._last_command_stamp:
            self._last_command_stamp = stamp

    def reset(self) -> None:
        """Forget the filter history and hand state (e.g. on an operator request)."""
        self.filter.reset()
        self._hand_key = None
        self._delay.clear()
        self._last_accepted = None
        self._jump_candidates = []

    def set_filter(self, name: str, params: dict | None = None) -> None:
        """Switch the pose filter live (e.g. from the dashboard) without an output jump.

        The new filter starts empty; the continuity offset (as for a device switch) keeps
        the output where the old filter left it, so the tool does not move. Raises
        MotionSensorError for an unknown filter or bad parameters (the old one stays).
        """
        self.filter = make_filter(name, **(params or {}))
        self.config.filter_name, self.config.filter_params = name, dict(params or {})
        self._continuity_pending = self._last_output is not None
        self.counters["filter_switches"] += 1

    @property
    def active_device(self) -> str | None:
        """The device currently driving the output."""
        return self.binder.active

    @property
    def dropped(self) -> int:
        """Total frames dropped for any reason."""
        return sum(v for k, v in self.counters.items() if k.startswith("dropped_"))

    # -- the pipeline ------------------------------------------------------------------------
    def process(self, sample: HandSample, now: float) -> SequencedPose | None:
        """Take one sample at wall time ``now`` (s); return the pose to publish, or None.

        None means the frame was dropped or is held back; ``counters`` say why.
        """
        self.counters["frames_in"] += 1
        device = sample.device or "default"
        if not self.binder.hear(device, now):
            return self._drop("inactive_device")
        if self._active_device is not None and device != self._active_device:
            self.counters["device_switches"] += 1
            self._restart_hand(continuity=True)
        self._active_device = device
        if sample.hands_num == 0 and not sample.hand_types:
            # The hand left the sensing area: what is still held back was its exit.
            self._hand_left()
            return self._drop("no_hand")
        reason = validate_sample(sample) or self._timing_problem(device, sample.stamp, now)
        if reason is not None:
            return self._drop(reason)
        self._last_stamp[device] = sample.stamp
        if self._last_seen is not None and sample.stamp - self._last_seen > self.config.hand_lost_s:
            self._hand_left()
        self._last_seen = sample.stamp
        key = (sample.hand_id, sample.primary_type)
        if key != self._hand_key:
            if self._hand_key is not None:
                self.counters["filter_reseeds"] += 1
            self._hand_key = key
            self._restart_hand(continuity=False)
        self._since_entry += 1
        if self._since_entry <= self.config.entry_trim_frames:
            self._last_accepted = (sample.stamp, float_list(sample.position), float_list(sample.orientation))
            return self._drop("entry_trim")
        if self._is_jump(sample):
            return self._drop("jump")
        self._delay.append(sample)
        if len(self._delay) <= self.config.exit_trim_frames:
            self.counters["held_for_exit_trim"] += 1
            return None
        return self._emit(self._delay.popleft())

    def _drop(self, reason: str) -> None:
        self.counters["dropped_" + reason] += 1
        if reason not in EXPECTED_DROPS:
            self.unexpected_drops += 1
        return None

    def _timing_problem(self, device: str, stamp: float, now: float) -> str | None:
        last = self._last_stamp.get(device)
        if last is not None and stamp == last:
            return "duplicate"
        if last is not None and stamp < last:
            return "out_of_order"
        if stamp > now + self.config.max_future_s:
            return "future_stamp"
        if now - stamp > self.config.max_age_s:
            return "stale"
        if self._last_command_stamp is not None and stamp < self._last_command_stamp:
            return "older_than_command"
        return None

    def _restart_hand(self, continuity: bool) -> None:
        """A new hand or device: fresh filter, entry trim again, no blending."""
        self.filter.reset()
        self._delay.clear()
        self._since_entry = 0
        self._last_accepted = None
        self._jump_candidates = []
        self._continuity_pending = continuity and self._last_output is not None

    def _hand_left(self) -> None:
        if self._delay:
            self.counters["dropped_exit_trim"] += len(self._delay)
            self._delay.clear()
        self._hand_key = None

    def _is_jump(self, sample: HandSample) -> bool:
        # Plain floats: this runs on every frame's latency (see validate_sample).
        position = float_list(sample.position)
        orientation = float_list(sample.orientation)
        if self._last_accepted is None:
            self._last_accepted = (sample.stamp, position, orientation)
            return False
        stamp, last_position, last_orientation = self._last_accepted
        distance = _distance(position, last_position)
        dot = sum(a * b for a, b in zip(orientation, last_orientation))
        angle = 2.0 * math.acos(min(abs(dot), 1.0))
        quick = sample.stamp - stamp <= self.config.jump_window_s
        if quick and (distance > self.config.jump_distance_m or angle > self.config.jump_angle_rad):
            # A real move shows up as frames that agree with each other at the new place.
            if self._jump_candidates and _distance(position, self._jump_candidates[-1]) > self.config.jump_distance_m:
                self._jump_candidates = []
            self._jump_candidates.append(position)
            if len(self._jump_candidates) < self.config.jump_accept_after:
                return True
            self.counters["jumps_accepted"] += 1
            self.filter.reset()
            self._continuity_pending = self._last_output is not None
        self._jump_candidates = []
        self._last_accepted = (sample.stamp, position, orientation)
        return False

    def _emit(self, sample: HandSample) -> SequencedPose:
        position, orientation = self.filter.update(sample.stamp, sample.position, sample.orientation)
        position, orientation = position.tolist(), orientation.tolist()
        if self._continuity_pending:
            # Keep the output where it was: later motion is relative to here.
            last = self._last_output
            self._offset_position = [a - b for a, b in zip(last.position.tolist(), position)]
            qx, qy, qz, qw = orientation
            self._offset_rotation = multiply_quaternions(last.orientation.tolist(), (-qx, -qy, -qz, qw))
            self._continuity_pending = False
        # Plain floats for the offsets (every frame), one array each at the end.
        position = np.array([p + o for p, o in zip(position, self._offset_position)])
        x, y, z, w = multiply_quaternions(self._offset_rotation, orientation)
        norm = quaternion_norm((x, y, z, w))
        orientation = np.array([x / norm, y / norm, z / norm, w / norm])
        out = SequencedPose(
            sample.stamp, position, orientation, sample.frame_id, sample.primary_type, sample.hands_num, sample.device
        )
        self._last_output = out
        self.counters["frames_out"] += 1
        return out


def _distance(a, b) -> float:
    """Euclidean distance of two 3-sequences of floats."""
    return math.sqrt((a[0] - b[0]) ** 2 + (a[1] - b[1]) ** 2 + (a[2] - b[2]) ** 2)
