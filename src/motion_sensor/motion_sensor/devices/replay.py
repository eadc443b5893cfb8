"""Recorded hand streams: replay schedules, recording loading (Leap v6, rosbag, CSV), and
ReplayDevice, a recording as a HandDevice (nodes/hand_replay). Each of them gives the
hand's skeletons where the recording has them."""

import dataclasses
from collections.abc import Iterable, Iterator

from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import HAND_TYPE_PARAM, HandDevice, empty_sample, hand_preference
from motion_sensor.devices.hand_bag import read_bag
from motion_sensor.devices.hand_csv import CSV_COLUMNS, read_csv
from motion_sensor.errors import EndOfStream, MotionSensorError

__all__ = ["CSV_COLUMNS", "ReplayDevice", "load_samples", "read_csv", "replay_schedule"]


def replay_schedule(
    times: Iterable[float], rate: float = 1.0, start_offset: float = 0.0
) -> Iterator[tuple[int, float]]:
    """Yield (index, due seconds after start) for recorded ``times`` (s, any origin).

    ``rate`` > 1 plays faster; ``rate`` <= 0 means as fast as possible (every frame due at 0).
    Frames recorded before ``start_offset`` seconds into the recording are skipped.
    """
    times = list(times)
    if not times:
        return
    origin = times[0] + start_offset
    for index, t in enumerate(times):
        if t < origin:
            continue
        yield index, 0.0 if rate <= 0 else (t - origin) / rate


def load_samples(path: str, primary: str = "right", frame_id: str = "leap", strict: bool = False):
    """([(recorded time s, HandSample)], rejected lines) of a Leap v6 recording (.jsonl,
    .jsonl.gz), a rosbag of a session's hand streams (.bag, ``hand_bag``) or a CSV (.csv,
    ``hand_csv``), each sample with the skeletons the recording holds. Frames without a hand
    are kept (hands_num 0); with ``strict`` a Leap or CSV frame without the ``primary`` hand
    type counts as one without a hand. Raises MotionSensorError for a file that cannot be used."""
    if path.endswith(".bag"):
        return read_bag(path, frame_id)
    if path.endswith(".csv"):
        rows, rejected = read_csv(path, primary, strict, frame_id)
        return [(sample.stamp, sample) for sample in rows], rejected
    from motion_sensor.devices.leap_v6 import frame_to_sample, read_recording

    try:
        recording = read_recording(path)
    except OSError as exc:
        raise MotionSensorError(f"cannot read recording {path}: {exc}") from None
    if not recording.frames:
        raise MotionSensorError(f"recording {path} holds no usable frame ({len(recording.rejected)} rejected)")
    samples = []
    for frame in recording.frames:
        sample = frame_to_sample(frame, stamp=frame.timestamp, preference=primary, frame_id=frame_id, strict=strict)
        samples.append((frame.timestamp, empty_sample(frame.timestamp, frame_id, "leap") if sample is None else sample))
    return samples, recording.rejected


class ReplayDevice(HandDevice):
    """A recorded hand stream as a HandDevice: samples at recorded timing (``rate``), stamped
    with the time they are published, as a live driver stamps frames on reception; looped,
    or finite (EndOfStream at the end: the node reports ~finished and exits)."""

    name = "replay"
    publishes_skeletons = True  # whole-hand skeletons on motion_sensor/raw_hand_skeleton
    default_frame_id = "leap"
    finite = True
    stamp_on_publish = True
    wrapper_defaults = {"min_subscribers": 1}  # never play to nobody
    params = ParamSchema(
        [
            Param(
                "recording",
                "",
                doc="Leap v6 .jsonl(.gz), rosbag of record_hands (.bag) or CSV (.csv); skeletons replayed too",
            ),
            Param("rate", 1.0, low=0, doc="speed factor: 1 the recorded timing, 0 as fast as possible"),
            Param("loop", False, doc="start again at the end (the node then never finishes)"),
            Param(
                "repeat",
                1,
                low=1,
                high=1000,
                doc="passes over the recording when not looping, each after a pause with no hand (as an operator "
                "who lowers the hand and starts again); the node finishes after the last",
            ),
            Param(
                "repeat_pause",
                0.5,
                unit="s",
                low=0,
                high=60,
                doc="pause between passes; at least the sequencer's hand_lost_s, so each pass is a new entry",
            ),
            Param("start_offset", 0.0, unit="s", low=0, doc="seconds into the recording to start from"),
            Param(
                "primary_hand", "right", choices=("right", "left", "first"), doc="hand that steers when two are seen"
            ),
            HAND_TYPE_PARAM,
        ]
    )

    def __init__(self, config, **kw):
        super().__init__(config, **kw)
        if not self.config["recording"]:
            raise MotionSensorError("parameter 'recording' must name the file to replay")
        # Loaded now, so a missing or unusable file stops the node before it waits for anyone.
        preference, strict = hand_preference(self.config)
        self.samples, self._rejected = load_samples(self.config["recording"], preference, self.frame_id, strict)
        self.counters["rejected"] += len(self._rejected)
        self._schedule = None
        self._start = None
        self._passes_left = self.config["repeat"]

    def describe(self) -> str:
        return f"replay of {self.config['recording']}"

    def open(self) -> None:
        self._passes_left = self.config["repeat"]
        if self._rejected is not None:
            for problem in self._rejected[:5]:
                self.warn(f"{self.config['recording']}: {problem}")
            self._rejected = None
            self.info(
                f"playing {len(self.samples)} frames ({self.samples[-1][0] - self.samples[0][0]:.2f} s) "
                f"at rate {self.config['rate']:.2f}"
            )
        self._restart()

    def _restart(self) -> None:
        self._schedule = replay_schedule([t for t, _ in self.samples], self.config["rate"], self.config["start_offset"])
        self._start = self.clock()

    def read(self, now):
        step = next(self._schedule, None)
        if step is None and self.config["loop"]:
            self.counters["loops"] += 1
            self._restart()
            step = next(self._schedule, None)
        elif step is None and self._passes_left > 1:
            self._passes_left -= 1
            self.counters["passes"] += 1
            self.sleep(self.config["repeat_pause"])
            self._restart()
            step = next(self._schedule, None)
        if step is None:
            raise EndOfStream()
        index, due = step
        delay = self._start + due - self.clock()
        if delay > 0:
            self.sleep(delay)
        self.counters["frames"] += 1
        sample, now = self.samples[index][1], self.clock()
        skeletons = tuple(dataclasses.replace(skeleton, stamp=now) for skeleton in sample.skeletons)
        return dataclasses.replace(sample, stamp=now, skeletons=skeletons)

    def close(self) -> None:
        pass
