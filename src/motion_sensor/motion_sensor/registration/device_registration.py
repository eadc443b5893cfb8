"""Registration between hand space {O} and robot space {W} without a measuring instrument
(the paper's Fig. 5): the operator moves the hand along a path while the robot's tool
follows (or has followed) the same shape; the two recordings, made at different speeds,
are aligned with dynamic time warping and the rotation, translation and scale between them
estimated from the aligned pairs (Umeyama's method).

DTW runs in dtaidistance's compiled core. The first estimate pairs points at equal
fractions of each path's (smoothed) arc length, which does not depend on the unknown
transform nor on the speeds; DTW passes then align the positions themselves, once the
current estimate has mapped the hand path into robot space, and refine the fit.
"""

from dataclasses import dataclass

import numpy as np
import yaml
from dtaidistance import dtw_ndim

from motion_sensor.errors import MotionSensorError


@dataclass
class Registration:
    """p_robot = scale * rotation @ p_hand + translation; ``speed_reduction`` k plays hand
    motion k times slower on the robot when imitating it (the paper's ratio)."""

    rotation: np.ndarray
    translation: np.ndarray
    scale: float = 1.0
    speed_reduction: float = 1.0
    rms_error: float = 0.0

    def apply(self, points) -> np.ndarray:
        """Map hand-space points (n x 3 or 3) into robot space."""
        points = np.asarray(points, dtype=float)
        return self.scale * points @ self.rotation.T + self.translation

    def imitate(self, times, points):
        """(robot times, robot points) replaying a hand motion at the speed reduction."""
        times = np.asarray(times, dtype=float)
        return times[0] + (times - times[0]) * self.speed_reduction, self.apply(points)

    def to_dict(self) -> dict:
        """YAML-ready dict (units: m, unitless scale and ratio, rotation as a matrix)."""
        return {
            "rotation": self.rotation.round(12).tolist(),
            "translation_m": self.translation.round(12).tolist(),
            "scale": float(self.scale),
            "speed_reduction": float(self.speed_reduction),
            "rms_error_m": float(self.rms_error),
        }

    def save(self, path: str) -> None:
        """Write the registration as YAML."""
        with open(path, "w", encoding="utf-8") as fh:
            fh.write("# Hand space {O} -> robot space {W}: p_W = scale * rotation @ p_O + translation_m\n")
            yaml.safe_dump(self.to_dict(), fh, sort_keys=False)

    @classmethod
    def load(cls, path: str) -> "Registration":
        """Read and check a registration YAML; errors name the file and the field."""
        try:
            with open(path, encoding="utf-8") as fh:
                data = yaml.safe_load(fh)
        except (OSError, yaml.YAMLError) as exc:
            raise MotionSensorError(f"cannot read registration {path}: {exc}") from None
        try:
            rotation = np.array(data["rotation"], dtype=float)
            translation = np.array(data["translation_m"], dtype=float)
            scale = float(data.get("scale", 1.0))
            speed = float(data.get("speed_reduction", 1.0))
        except (TypeError, KeyError, ValueError) as exc:
            raise MotionSensorError(
                f"{path}: registration needs rotation (3x3), translation_m (3), scale, speed_reduction: {exc}"
            ) from None
        if (
            rotation.shape != (3, 3)
            or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6)
            or np.linalg.det(rotation) < 0
        ):
            raise MotionSensorError(f"{path}: 'rotation' is not a proper 3x3 rotation matrix")
        if translation.shape != (3,) or not scale > 0 or not speed > 0:
            raise MotionSensorError(f"{path}: translation_m needs 3 values, scale and speed_reduction > 0")
        return cls(rotation, translation, scale, speed, float(data.get("rms_error_m", 0.0)))


def umeyama(source: np.ndarray, target: np.ndarray, with_scale: bool = True):
    """(rotation, translation, scale) minimising |target - (s R source + t)|^2 (Umeyama 1991)."""
    source, target = np.asarray(source, float), np.asarray(target, float)
    mu_s, mu_t = source.mean(axis=0), target.mean(axis=0)
    xs, xt = source - mu_s, target - mu_t
    covariance = xt.T @ xs / len(source)
    u, singular, vt = np.linalg.svd(covariance)
    sign = np.eye(3)
    if np.linalg.det(u) * np.linalg.det(vt) < 0:
        sign[2, 2] = -1.0  # a reflection is not a rotation
    rotation = u @ sign @ vt
    variance = np.mean(np.sum(xs**2, axis=1))
    scale = float(np.trace(np.diag(singular) @ sign) / variance) if with_scale else 1.0
    return rotation, mu_t - scale * rotation @ mu_s, scale


def _arc_fraction(points: np.ndarray, smooth: int = 9) -> np.ndarray:
    """Fraction of the path's arc length reached at each point, after a short moving
    average so hand tremor does not inflate the length unevenly."""
    if len(points) > smooth:
        kernel = np.ones(smooth) / smooth
        padded = np.pad(points, ((smooth // 2, smooth // 2), (0, 0)), mode="edge")
        points = np.column_stack([np.convolve(padded[:, i], kernel, mode="valid") for i in range(3)])
    length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    return length / length[-1]


def _arc_pairs(hand: np.ndarray, robot: np.ndarray, count: int = 200):
    """Index pairs of hand and robot points at equal arc-length fractions."""
    fractions = np.linspace(0.0, 1.0, count)
    hand_index = np.searchsorted(_arc_fraction(hand), fractions).clip(0, len(hand) - 1)
    robot_index = np.searchsorted(_arc_fraction(robot), fractions).clip(0, len(robot) - 1)
    return list(zip(hand_index, robot_index))


def register(
    hand_points, robot_points, hand_times=None, robot_times=None, with_scale: bool = True, iterations: int = 3
) -> Registration:
    """Register a hand path to a robot tool path of the same motion (any speeds).

    ``*_times`` (s) give the speed-reduction ratio (robot duration / hand duration);
    without them it is 1.
    """
    hand = np.asarray(hand_points, dtype=float)
    robot = np.asarray(robot_points, dtype=float)
    if hand.ndim != 2 or robot.ndim != 2 or hand.shape[1] != 3 or robot.shape[1] != 3:
        raise MotionSensorError("register needs two n x 3 point arrays")
    if len(hand) < 10 or len(robot) < 10:
        raise MotionSensorError("register needs at least 10 points per path")
    if not (np.all(np.isfinite(hand)) and np.all(np.isfinite(robot))):
        raise MotionSensorError("register got non-finite points")
    if np.ptp(hand, axis=0).max() < 1e-3 or np.ptp(robot, axis=0).max() < 1e-3:
        raise MotionSensorError("a path barely moves: trace a shape of a few centimetres or more")
    path = _arc_pairs(hand, robot)
    rotation, translation, scale = _fit(hand, robot, path, with_scale)
    for _ in range(iterations):
        mapped = scale * hand @ rotation.T + translation
        path = dtw_ndim.warping_path(mapped, robot, use_c=True)
        rotation, translation, scale = _fit(hand, robot, path, with_scale)
    index_h, index_r = np.array(path).T
    residual = scale * hand[index_h] @ rotation.T + translation - robot[index_r]
    speed = 1.0
    if hand_times is not None and robot_times is not None:
        speed = float((robot_times[-1] - robot_times[0]) / (hand_times[-1] - hand_times[0]))
    return Registration(rotation, translation, scale, speed, float(np.sqrt(np.mean(np.sum(residual**2, axis=1)))))


def _fit(hand, robot, path, with_scale):
    index_h, index_r = np.array(path).T
    return umeyama(hand[index_h], robot[index_r], with_scale)
