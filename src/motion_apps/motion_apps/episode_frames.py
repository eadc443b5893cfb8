"""What one frame of a recorded episode holds, and the fixed-rate sampling that makes frames
from the latest value of each stream (plain Python: the recorder node feeds it).

LeRobot features (float32 unless said):

- ``observation.state``: measured joint positions (rad), URDF joint order, then the gripper
  (1 closed, 0 open; LeRobot's arms put it there too);
- ``observation.velocity``: measured joint velocities (rad/s);
- ``observation.tool_pose``: measured tool pose, x y z (m) qx qy qz qw, base frame;
- ``observation.hand``: the operator's primary hand: palm x y z (m) qx qy qz qw (device
  frame), grab and pinch strength (0..1, -1 unknown), visible (1/0);
- ``observation.hand_skeleton``: the primary hand's 22 canonical joints
  (``motion_sensor.skeleton_joints.JOINT_NAMES``), x y z each (m, device frame), then
  visible (1/0; 0 and the last skeleton seen while the device gives none);
- ``observation.images.<camera>``: the camera image (video, uint8 RGB);
- ``action``: the joint targets the core commanded (rad), then the gripper command (the
  server's gripper state after each accepted SET_GRIPPER); before the first command, the
  measured joints (holding still);
- ``tool_target``: the core's tool target pose, x y z qx qy qz qw; before the first,
  the measured tool pose. The action in tool space, kept outside LeRobot's ``action*``
  names on purpose: LeRobot's policies take every feature whose name starts with
  ``action`` as an output, and most predict one (``action``);
- ``command_velocity``: the rate of the core's joint commands at the frame's instant
  (rad/s, between the two commands around it); before the first command, the measured
  velocities. The action's own velocity (outside ``action*`` for the same reason): the
  commands run at the hand's ~110 Hz, and what they did between two frames shows in it
  (a replay's curve between the frames takes it as its tangents).

A frame is made at each tick of the recorder's clock from the latest value given for every
stream, so all frames are ``1 / fps`` apart (LeRobot's timestamps are ``index / fps``); the
recorder node gives the joints, the tool, the command and the target as they were at the
frame's instant (``stamped_history``), the rest as their newest message. A
camera image that is not new since the previous frame is counted as repeated, and a frame
before the camera's first image (black) as missing (``camera`` counts in the episode's
record), so a camera slower than ``fps``, or late, shows as a loss.
"""

from dataclasses import dataclass, field

import numpy as np

from motion_sensor.skeleton_joints import JOINT_NAMES

__all__ = [
    "EpisodeFrames",
    "FrameCounts",
    "HAND_NAMES",
    "POSE_NAMES",
    "SKELETON_NAMES",
    "camera_key",
    "rgb_from_image",
]

POSE_NAMES = ["x", "y", "z", "qx", "qy", "qz", "qw"]
SKELETON_NAMES = [f"{joint}_{axis}" for joint in JOINT_NAMES for axis in "xyz"] + ["visible"]
HAND_NAMES = ["palm_x", "palm_y", "palm_z", "palm_qx", "palm_qy", "palm_qz", "palm_qw", "grab", "pinch", "visible"]


def camera_key(name: str) -> str:
    return f"observation.images.{name}"


def rgb_from_image(encoding: str, height: int, width: int, step: int, data: bytes) -> np.ndarray:
    """HxWx3 uint8 RGB from a sensor_msgs/Image's fields (rgb8, bgr8, mono8); ValueError
    naming what does not add up otherwise."""
    channels = {"rgb8": 3, "bgr8": 3, "mono8": 1}.get(encoding)
    if channels is None:
        raise ValueError(f"image encoding {encoding!r} (rgb8, bgr8 or mono8 expected)")
    if step < width * channels or len(data) < step * height:
        raise ValueError(f"image {width}x{height} {encoding}: step {step}, {len(data)} bytes do not add up")
    rows = np.frombuffer(data, dtype=np.uint8, count=step * height).reshape(height, step)
    pixels = rows[:, : width * channels].reshape(height, width, channels)
    if encoding == "bgr8":
        return np.ascontiguousarray(pixels[:, :, ::-1])
    if encoding == "mono8":
        return np.repeat(pixels, 3, axis=2)
    return pixels.copy()


@dataclass
class FrameCounts:
    """Per-episode counts the recorder reports in the episode's record."""

    frames: int = 0
    camera_new: int = 0
    camera_repeated: int = 0
    camera_missing: int = 0
    skipped_not_ready: int = 0
    extra: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {
            "frames_sampled": self.frames,
            "camera_new_frames": self.camera_new,
            "camera_repeated_frames": self.camera_repeated,
            "camera_missing_frames": self.camera_missing,
            "ticks_without_state": self.skipped_not_ready,
            **self.extra,
        }


class EpisodeFrames:
    """The newest value of each stream, and frames made from them."""

    def __init__(self, camera: str = "", image_size: tuple = (0, 0)):
        self.camera = camera  # empty: no camera stream
        self.image_size = tuple(image_size)  # (width, height); (0, 0): as received
        self.joint_names = None
        self.joints = self.velocities = None
        self.tool = None
        self.gripper = 0.0
        self.hand = np.array([0, 0, 0, 0, 0, 0, 1, -1, -1, 0], dtype=np.float32)
        self.skeleton = np.zeros(len(SKELETON_NAMES), dtype=np.float32)
        self._skeleton_index = None  # (names, their rows, their places in JOINT_NAMES)
        self.command = None
        self.command_velocity = None
        self.target = None
        self.image = None
        self._image_serial = 0
        self._sampled_serial = 0
        self.counts = FrameCounts()

    # -- inputs -------------------------------------------------------------------------
    def on_joints(self, names, positions, velocities) -> None:
        if self.joint_names is None:
            self.joint_names = list(names)
        if list(names) != self.joint_names:
            return  # another arm's message on the same topic: not this episode's
        self.joints = np.asarray(positions, dtype=np.float32)
        v = np.asarray(velocities, dtype=np.float32)
        self.velocities = v if v.shape == self.joints.shape else np.zeros_like(self.joints)

    def on_tool(self, position, quaternion) -> None:
        self.tool = np.asarray(list(position) + list(quaternion), dtype=np.float32)

    def on_gripper(self, closed: bool) -> None:
        self.gripper = 1.0 if closed else 0.0

    def on_hand(self, visible: bool, position=(0, 0, 0), quaternion=(0, 0, 0, 1), grab=-1.0, pinch=-1.0) -> None:
        if visible:
            values = list(position) + list(quaternion) + [grab, pinch, 1.0]
        else:
            values = list(self.hand[:9]) + [0.0]  # the last pose seen, marked not visible
        self.hand = np.asarray(values, dtype=np.float32)

    def on_skeleton(self, names, points) -> None:
        """The primary hand's skeleton: joint names and (x, y, z) points; joints the device
        does not give stay 0. An empty skeleton marks the hand not visible."""
        if not len(points):
            self.skeleton[-1] = 0.0
            return
        if self._skeleton_index is None or self._skeleton_index[0] != names:
            index = {name: i for i, name in enumerate(JOINT_NAMES)}
            given = [(k, index[name]) for k, name in enumerate(names) if name in index]
            # the same names come with every skeleton of a device: their places, once
            self._skeleton_index = (list(names), [k for k, _ in given], [i for _, i in given])
        _, rows, places = self._skeleton_index
        values = np.zeros((len(JOINT_NAMES) + 1, 3), dtype=np.float32)
        values[places] = np.asarray(points, dtype=np.float64).reshape(-1, 3)[rows]
        values = values.reshape(-1)[: len(SKELETON_NAMES)].copy()
        values[-1] = 1.0
        self.skeleton = values

    def on_command(self, names, positions, velocities=()) -> None:
        """The core's joint command and, when given, its rate (rad/s)."""
        if self.joint_names is not None and list(names) and list(names) != self.joint_names:
            return
        self.command = np.asarray(positions, dtype=np.float32)
        v = np.asarray(velocities, dtype=np.float32)
        self.command_velocity = v if v.shape == self.command.shape else np.zeros_like(self.command)

    def on_target(self, position, quaternion) -> None:
        self.target = np.asarray(list(position) + list(quaternion), dtype=np.float32)

    def on_image(self, rgb: np.ndarray) -> None:
        """A new camera image, HxWx3 uint8 RGB (resized to ``image_size`` when set)."""
        if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
            raise ValueError(f"camera image must be HxWx3 uint8, got {rgb.shape} {rgb.dtype}")
        width, height = self.image_size
        if width and height and (rgb.shape[1], rgb.shape[0]) != (width, height):
            import cv2  # noqa: PLC0415 - only with a camera

            rgb = cv2.resize(rgb, (width, height), interpolation=cv2.INTER_AREA)
        self.image = rgb
        self._image_serial += 1

    # -- outputs ------------------------------------------------------------------------
    def missing(self) -> list:
        """The streams a frame still needs (a camera with a set image size is not waited
        for: its frames are black, and counted, until the first image)."""
        need = [("joint_states", self.joints), ("tool pose", self.tool)]
        if self.camera and not all(self.image_size):
            need.append((f"camera {self.camera}", self.image))
        return [name for name, value in need if value is None]

    def features(self) -> dict:
        """LeRobot's feature declarations (needs the joints, and the camera's first image)."""
        if self.missing():
            raise ValueError(f"cannot declare the dataset's features before {', '.join(self.missing())} arrive")
        joints = list(self.joint_names)
        with_gripper = joints + ["gripper"]
        out = {
            "observation.state": {"dtype": "float32", "shape": [len(with_gripper)], "names": with_gripper},
            "observation.velocity": {"dtype": "float32", "shape": [len(joints)], "names": joints},
            "observation.tool_pose": {"dtype": "float32", "shape": [7], "names": POSE_NAMES},
            "observation.hand": {"dtype": "float32", "shape": [len(HAND_NAMES)], "names": HAND_NAMES},
            "observation.hand_skeleton": {
                "dtype": "float32",
                "shape": [len(SKELETON_NAMES)],
                "names": SKELETON_NAMES,
            },
            "action": {"dtype": "float32", "shape": [len(with_gripper)], "names": with_gripper},
            "tool_target": {"dtype": "float32", "shape": [7], "names": POSE_NAMES},
            "command_velocity": {"dtype": "float32", "shape": [len(joints)], "names": joints},
        }
        if self.camera:
            h, w = self.image.shape[:2] if self.image is not None else self.image_size[::-1]
            out[camera_key(self.camera)] = {
                "dtype": "video",
                "shape": [h, w, 3],
                "names": ["height", "width", "channels"],
            }
        return out

    def reset_counts(self) -> None:
        self.counts = FrameCounts()
        self._sampled_serial = self._image_serial - 1  # the image already there is the episode's first

    def sample(self) -> dict | None:
        """The frame of this tick, or None (counted) while a required stream is missing."""
        if self.missing():
            self.counts.skipped_not_ready += 1
            return None
        gripper = np.array([self.gripper], dtype=np.float32)
        commanded = self.command is not None
        joints_target = self.command if commanded else self.joints
        frame = {
            "observation.state": np.concatenate([self.joints, gripper]),
            "observation.velocity": self.velocities.copy(),
            "observation.tool_pose": self.tool.copy(),
            "observation.hand": self.hand.copy(),
            "observation.hand_skeleton": self.skeleton.copy(),
            "action": np.concatenate([joints_target, gripper]),
            "tool_target": (self.target if self.target is not None else self.tool).copy(),
            "command_velocity": (self.command_velocity if commanded else self.velocities).copy(),
        }
        if self.camera:
            if self.image is None:
                width, height = self.image_size
                frame[camera_key(self.camera)] = np.zeros((height, width, 3), np.uint8)
                self.counts.camera_missing += 1
            else:
                frame[camera_key(self.camera)] = self.image
                if self._image_serial != self._sampled_serial:
                    self.counts.camera_new += 1
                else:
                    self.counts.camera_repeated += 1
            self._sampled_serial = self._image_serial
        self.counts.frames += 1
        return frame
