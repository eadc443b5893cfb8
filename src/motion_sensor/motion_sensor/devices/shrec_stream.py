"""A SHREC'17-layout gesture file (.npz) played as a live hand device.

The file's sequences (real hand skeletons, 30 Hz, the camera's y-down frame) are turned
into the canonical REP 103 skeleton (``motion_sensor.skeleton_joints``) on load, then
played one after another with an idle gap after each (``gestures.skeleton_stream``: the
hand rests ``idle_s`` with 1 mm tremor, then moves to the next start in 0.5 s). Each frame
goes out as a ``HandSample`` (palm = the palm joint, orientation from the palm joints,
index tip) carrying the whole skeleton, stamped when it is published. ``labels`` picks
the gestures played (empty: all), ``limit`` the number of sequences; the order is the
file's, or shuffled with ``seed``. Finite unless ``loop``.
"""

import numpy as np

from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import HandDevice
from motion_sensor.errors import EndOfStream, MotionSensorError
from motion_sensor.gestures.skeleton_dataset import CLASSES_14, load_skeleton_dataset
from motion_sensor.gestures.skeleton_stream import build_stream
from motion_sensor.hand_sample import HandSample
from motion_sensor.skeleton_joints import JOINT_NAMES, palm_quaternion
from motion_sensor.skeleton_sample import SkeletonSample

__all__ = ["ShrecStreamDevice"]

_INDEX_TIP = JOINT_NAMES.index("index_tip")


class ShrecStreamDevice(HandDevice):
    """SHREC'17 skeleton sequences (.npz) played as a live hand with idle gaps."""

    name = "shrec_stream"
    publishes_skeletons = True
    default_frame_id = "camera"
    finite = True
    stamp_on_publish = True
    wrapper_defaults = {"min_subscribers": 1}  # never play to nobody
    params = ParamSchema(
        [
            Param("sequences_file", "", doc="SHREC'17-layout .npz (joints, offsets, label14, label28, subject)"),
            Param("labels", [], item_kind=str, doc="gestures to play (14-class names; empty: all)"),
            Param("limit", 0, low=0, doc="at most this many sequences (0: all)"),
            Param("idle_s", 1.5, unit="s", low=0.0, high=60.0, doc="rest after each gesture"),
            Param("seed", 0, doc="shuffles the order (-1: the file's order)"),
            Param("loop", False, doc="start again at the end (the node then never finishes)"),
            Param("hand_type", "right", choices=("left", "right"), doc="the side reported"),
        ]
    )

    def __init__(self, config, **kw):
        super().__init__(config, **kw)
        path = self.config["sequences_file"]
        if not path:
            raise MotionSensorError("parameter 'sequences_file' must name a SHREC'17-layout .npz")
        data = load_skeleton_dataset(path)
        wanted = self.config["labels"]
        unknown = sorted(set(wanted) - set(CLASSES_14))
        if unknown:
            raise MotionSensorError(f"parameter 'labels': unknown gestures {unknown} (known: {', '.join(CLASSES_14)})")
        chosen = [i for i, label in enumerate(data.label14) if not wanted or CLASSES_14[label] in wanted]
        if self.config["limit"]:
            chosen = chosen[: self.config["limit"]]
        if not chosen:
            raise MotionSensorError(f"{path}: no sequence of the gestures {wanted}")
        rng = np.random.default_rng(max(self.config["seed"], 0))
        order = None if self.config["seed"] >= 0 else range(len(chosen))
        idle = self.config["idle_s"]
        self.stamps, self.joints, self.truth = build_stream(
            [data.sequences[i] for i in chosen],
            [CLASSES_14[data.label14[i]] for i in chosen],
            rng,
            hold_s=(idle, idle),
            order=order,
        )
        self._index = 0
        self._start = None

    def describe(self) -> str:
        return f"SHREC'17 stream of {self.config['sequences_file']} ({len(self.truth)} gestures)"

    def open(self) -> None:
        self._index = 0
        self._start = self.clock()

    def read(self, now):
        if self._index >= len(self.stamps):
            if not self.config["loop"]:
                raise EndOfStream()
            self.counters["loops"] += 1
            self.open()
        delay = self._start + self.stamps[self._index] - self.clock()
        if delay > 0:
            self.sleep(delay)
        joints = self.joints[self._index]
        self._index += 1
        self.counters["frames"] += 1
        stamp = self.clock()
        hand = self.config["hand_type"]
        return HandSample(
            stamp=stamp,
            position=joints[1].copy(),
            orientation=palm_quaternion(joints),
            hands_num=1,
            hand_types=(hand,),
            frame_id=self.frame_id,
            hand_id=1,
            device=self.name,
            confidence=1.0,
            index_tip=joints[_INDEX_TIP].copy(),
            skeletons=(SkeletonSample(stamp, joints, hand, 1, 1.0, self.frame_id, self.name),),
        )

    def close(self) -> None:
        pass
