"""Teleop mapping and clutches: hand motion since the clutch engaged, scaled, becomes tool
motion.

At engage, the current hand pose and tool pose become the reference; afterwards the tool
target is the reference tool pose moved by the hand's displacement (scaled by the speed
ratio) and rotated by the hand's rotation since engage. Because the first target equals the
current tool pose, engaging never makes the robot jump.
"""

import numpy as np

from motion_common.float_list import float_list
from motion_common.kinematics import matrix_to_quat, quat_to_matrix

from .errors import MotionCommanderError


def _checked_ratio(speed_ratio) -> float:
    """``speed_ratio`` as a float; MotionCommanderError unless finite and > 0."""
    if not (np.isfinite(speed_ratio) and speed_ratio > 0):
        raise MotionCommanderError(f"speed_ratio must be a finite number > 0, got {speed_ratio!r}")
    return float(speed_ratio)


class TeleopMapper:
    """Relative, scaled mapping from hand space {O} to robot space {W}.

    ``hand_to_robot`` is the 3x3 rotation of the device frame in the robot base frame
    (identity when the device axes are aligned with the robot base).
    """

    def __init__(self, speed_ratio: float = 1.0, hand_to_robot=None, follow_orientation: bool = True):
        speed_ratio = _checked_ratio(speed_ratio)
        rotation = np.eye(3) if hand_to_robot is None else np.asarray(hand_to_robot, dtype=float)
        if rotation.shape != (3, 3) or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6):
            raise MotionCommanderError("hand_to_robot must be a 3x3 rotation matrix")
        self.speed_ratio = float(speed_ratio)
        # Rotation matrices, not scipy Rotation objects: this runs on every frame and
        # matrix products cost a microsecond where Rotation objects cost tens.
        self.hand_to_robot = rotation
        # The common case (device axes = base axes) skips three matrix products per frame.
        self._aligned = bool(np.array_equal(rotation, np.eye(3)))
        self.follow_orientation = follow_orientation
        self._hand_ref = None
        self._tool_ref = None
        self._last_hand = None  # hand position of the last target(): the anchor of a live ratio change

    @property
    def engaged(self) -> bool:
        """True between engage() and disengage()."""
        return self._hand_ref is not None

    def engage(self, hand_position, hand_orientation, tool_position, tool_orientation) -> None:
        """Take the current hand and tool poses as the reference of relative motion."""
        self._hand_ref = (np.array(hand_position, dtype=float), quat_to_matrix(hand_orientation))
        self._tool_ref = (np.array(tool_position, dtype=float), quat_to_matrix(tool_orientation))
        self._last_hand = self._hand_ref[0]
        self._prepare_frame_terms()

    def _prepare_frame_terms(self) -> None:
        """The per-frame constants of target_transform() as plain floats: the references'
        positions, and the rotation the hand's rotation is multiplied with. The tool target
        is H R h0^T H^T t0 (R the hand's rotation, h0 and t0 the references, H hand_to_robot),
        so everything right of R is fixed from engage on."""
        hand_p0, hand_r0 = self._hand_ref
        tool_p0, tool_r0 = self._tool_ref
        self._hand_p0 = hand_p0.tolist()
        self._tool_p0 = tool_p0.tolist()
        self._rotation_after = hand_r0.T @ self.hand_to_robot.T @ tool_r0

    def disengage(self) -> None:
        """Drop the reference; target() is unavailable until the next engage()."""
        self._hand_ref = None
        self._tool_ref = None
        self._last_hand = None

    def set_speed_ratio(self, speed_ratio: float) -> None:
        """Change the ratio live (e.g. from the dashboard) without moving the tool.

        While engaged, the references are re-anchored at the last hand position seen: the
        tool reference moves to the target of that hand position under the old ratio, so the
        target there is unchanged and only motion from now on is scaled by the new ratio.
        Orientation does not depend on the ratio, so its references stay.
        """
        speed_ratio = _checked_ratio(speed_ratio)
        if self.engaged:
            hand_p0, hand_r0 = self._hand_ref
            tool_p0, tool_r0 = self._tool_ref
            anchor = np.array(self._last_hand, dtype=float)
            self._tool_ref = (tool_p0 + self.speed_ratio * (self.hand_to_robot @ (anchor - hand_p0)), tool_r0)
            self._hand_ref = (anchor, hand_r0)
            self._prepare_frame_terms()
        self.speed_ratio = float(speed_ratio)

    def target(self, hand_position, hand_orientation):
        """Tool target (position, quaternion x, y, z, w) for the given hand pose."""
        position, rotation = self.target_transform(hand_position, hand_orientation)
        return position, matrix_to_quat(rotation)

    def target_transform(self, hand_position, hand_orientation):
        """Tool target (position, 3x3 rotation matrix) for the given hand pose: what the IK
        takes, without a round trip through a quaternion on every frame."""
        if not self.engaged:
            raise MotionCommanderError("teleop is not engaged; call engage() first")
        # Every frame, on its latency: the position in plain floats (a numpy call on a
        # 3-vector costs ~6 us after the idle between frames, several times the arithmetic;
        # bench/e2e_latency --breakdown), one array built at the end.
        hand = float_list(hand_position)
        self._last_hand = hand
        displacement = [h - h0 for h, h0 in zip(hand, self._hand_p0)]
        if not self._aligned:
            displacement = (self.hand_to_robot @ displacement).tolist()
        ratio = self.speed_ratio
        position = np.array([t0 + ratio * d for t0, d in zip(self._tool_p0, displacement)])
        if not self.follow_orientation:
            return position, self._tool_ref[1]
        # The hand's rotation since engage, re-expressed in the robot base frame, is applied
        # to the tool in the base frame, so turning the hand turns the tool the same way.
        rotation = quat_to_matrix(hand_orientation) @ self._rotation_after
        if not self._aligned:
            rotation = self.hand_to_robot @ rotation
        return position, rotation


class AutoClutch:
    """Engages once a hand has been tracked steadily, disengages when it is lost.

    Steady means ``steady_frames`` consecutive frames with no gap above ``lost_after_s``.
    """

    def __init__(self, steady_frames: int = 10, lost_after_s: float = 0.2):
        if steady_frames < 1 or not lost_after_s > 0:
            raise MotionCommanderError("a clutch needs steady_frames >= 1 and lost_after_s > 0")
        self.steady_frames = steady_frames
        self.lost_after_s = lost_after_s
        self._count = 0
        self._last_stamp: float | None = None

    def reset(self) -> None:
        """Require a fresh run of steady frames before engaging again."""
        self._count = 0

    def _count_frame(self, stamp: float) -> None:
        if self._last_stamp is not None and stamp - self._last_stamp > self.lost_after_s:
            self._count = 0
        self._last_stamp = stamp
        self._count += 1

    def on_frame(self, stamp: float, hands_num: int = 1) -> bool:
        """Record a tracked frame; return whether the clutch is now engaged."""
        self._count_frame(stamp)
        return self._count >= self.steady_frames

    def hand_lost(self, now: float) -> bool:
        """True when no frame came within ``lost_after_s`` before ``now``; resets the count."""
        if self._last_stamp is None or now - self._last_stamp > self.lost_after_s:
            self._count = 0
            return True
        return False


class GestureClutch(AutoClutch):
    """Engaged while the operator shows a second hand (a dead-man gesture).

    The primary hand steers; raising the other hand into view for ``steady_frames`` frames
    engages, taking it away disengages at once, like letting go of a dead-man switch.
    """

    def on_frame(self, stamp: float, hands_num: int = 1) -> bool:
        if hands_num < 2:
            self._last_stamp = stamp
            self._count = 0
            return False
        self._count_frame(stamp)
        return self._count >= self.steady_frames


class ButtonClutch(AutoClutch):
    """Engaged while a button (/motion_commander/engage) is held and a hand is tracked."""

    def __init__(self, steady_frames: int = 1, lost_after_s: float = 0.2):
        super().__init__(steady_frames, lost_after_s)
        self.pressed = False

    def set_pressed(self, pressed: bool) -> None:
        """Button state: True while held."""
        self.pressed = bool(pressed)
        if not pressed:
            self._count = 0

    def on_frame(self, stamp: float, hands_num: int = 1) -> bool:
        self._count_frame(stamp)
        return self.pressed and self._count >= self.steady_frames


CLUTCHES = {"auto": AutoClutch, "gesture": GestureClutch, "button": ButtonClutch}


def make_clutch(mode: str, steady_frames: int = 10, lost_after_s: float = 0.2):
    """Clutch for engage mode ``auto``, ``gesture`` or ``button``."""
    try:
        cls = CLUTCHES[mode]
    except KeyError:
        raise MotionCommanderError(f"unknown engage mode {mode!r}; choose auto, gesture or button") from None
    return cls(steady_frames if mode != "button" else 1, lost_after_s)
