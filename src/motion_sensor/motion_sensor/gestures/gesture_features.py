"""Trajectory normalisation and feature channels for DTW gesture classification.

A performance is a path of 3-D points (any unit, any rate, any length). ``features``
turns it into a fixed-size ``length x channels`` array, invariant to where and how big the
gesture was made and how fast:

1. drop non-finite rows and repeated points, light moving-average smoothing;
2. resample to ``length`` points equally spaced along the arc length (``resample="arc"``,
   removes speed variation: right for strokes such as letters or swipes) or equally spaced
   in time (``"time"``, keeps it);
3. centre on the centroid; ``plane="align"`` turns the best-fit (PCA) plane of a flat
   path to face +z (letters written on a tilted plane); divide by the RMS radius
   (``scale="rms"``) or half the largest bounding-box side (``"bbox"``): a uniform scale,
   aspect ratio kept, so a "1" and an "O" stay apart; ``axis_weights`` can damp an axis
   (e.g. depth);
4. channels: the normalised position times ``position_weight`` and the unit direction of
   travel (central differences) times ``direction_weight``; ``curvature_weight`` adds the
   turning angle per step (signed about the path's mean normal would need a plane: the
   unsigned angle is used).

Defaults (length 48, depth weight 0.5, no plane alignment, RMS scale) were chosen by
leave-subjects-out inside the training halves of the hard synthetic letters and SHREC'17
(bench/gesture_explore.py, bench/results/gesture_explore.json).

Everything is numpy; the result is C-contiguous float64, ready for dtaidistance.
"""

from dataclasses import dataclass, field

import numpy as np

from motion_common.params import Param, ParamSchema

FEATURE_PARAMS = ParamSchema(
    [
        Param("length", 48, "points", "samples per normalised path", low=8, high=512),
        Param("resample", "arc", "", "resampling: equal arc length or equal time", choices=("arc", "time")),
        Param("smooth", 3, "samples", "moving-average width before resampling (1 = none)", low=1, high=31),
        Param("position_weight", 1.0, "", "weight of the normalised position channels", low=0.0),
        Param("direction_weight", 0.6, "", "weight of the unit direction-of-travel channels", low=0.0),
        Param("curvature_weight", 0.0, "", "weight of the turning-angle channel (rad per step)", low=0.0),
        Param(
            "axis_weights", [1.0, 1.0, 0.5], "", "per-axis weight after normalisation (damp depth)", length=3, low=0.0
        ),
        Param(
            "plane",
            "none",
            "",
            "'align': turn the best-fit (PCA) plane of a flat path to face +z",
            choices=("none", "align"),
        ),
        Param(
            "scale", "rms", "", "size normalisation: RMS radius or largest bounding-box side", choices=("rms", "bbox")
        ),
    ]
)


@dataclass(frozen=True)
class FeatureConfig:
    """Normalisation settings (see the module docstring and FEATURE_PARAMS)."""

    length: int = 48
    resample: str = "arc"
    smooth: int = 3
    position_weight: float = 1.0
    direction_weight: float = 0.6
    curvature_weight: float = 0.0
    axis_weights: tuple[float, float, float] = field(default=(1.0, 1.0, 0.5))
    plane: str = "none"
    scale: str = "rms"

    @classmethod
    def from_params(cls, values: dict | None = None, source: str = "features") -> "FeatureConfig":
        """Validated config from a parameter dict (FEATURE_PARAMS)."""
        checked = FEATURE_PARAMS.validate(values or {}, source)
        checked["axis_weights"] = tuple(checked["axis_weights"])
        return cls(**checked)

    @property
    def channels(self) -> int:
        """Number of feature channels."""
        return 3 + (3 if self.direction_weight > 0 else 0) + (1 if self.curvature_weight > 0 else 0)


def clean(points, times=None):
    """(points n x 3, times n or None) without non-finite rows."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    keep = np.all(np.isfinite(points), axis=1)
    if times is not None:
        times = np.asarray(times, dtype=float).reshape(-1)
        keep &= np.isfinite(times)
        times = times[keep]
    return points[keep], times


def smooth_path(points: np.ndarray, width: int) -> np.ndarray:
    """Centred moving average (edges padded), width 1 = unchanged."""
    if width <= 1 or len(points) < width:
        return points
    kernel = np.ones(width) / width
    padded = np.pad(points, ((width // 2, width - 1 - width // 2), (0, 0)), mode="edge")
    return np.column_stack([np.convolve(padded[:, i], kernel, mode="valid") for i in range(points.shape[1])])


def resample(points: np.ndarray, length: int, mode: str = "arc", times=None) -> np.ndarray:
    """``length`` points along the path, equally spaced in arc length or in time."""
    if len(points) == 1:
        return np.repeat(points, length, axis=0)
    if mode == "time" and times is not None and times[-1] > times[0]:
        axis = times - times[0]
    else:
        axis = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    if axis[-1] <= 0:
        return np.repeat(points[:1], length, axis=0)
    axis, unique = np.unique(axis, return_index=True)  # drop repeated points (zero steps)
    points = points[unique]
    if len(axis) == 1:
        return np.repeat(points[:1], length, axis=0)
    target = np.linspace(0.0, axis[-1], length)
    return np.column_stack([np.interp(target, axis, points[:, i]) for i in range(3)])


def align_plane(
    path: np.ndarray, min_flatness: float = 0.15, max_thickness: float = 0.3, max_tilt: float = np.radians(50.0)
) -> np.ndarray:
    """A centred path turned by the smallest rotation that brings the normal of its best-fit
    (PCA) plane onto +z (the normal's sign chosen toward +z), so a letter written on a
    tilted plane faces the device again; in-plane orientation is kept. Paths that are not
    clearly flat and 2-D (second principal variance < ``min_flatness`` x the first: lines,
    swipes; or third > ``max_thickness`` x the second: 3-D paths) or whose plane is tilted
    more than ``max_tilt`` from facing +z are returned unchanged: their plane is not a
    writing plane."""
    cov = path.T @ path / max(len(path), 1)
    values, vectors = np.linalg.eigh(cov)  # ascending
    if values[2] <= 0 or values[1] < min_flatness * values[2] or values[0] > max_thickness * values[1]:
        return path
    normal = vectors[:, 0] * (1.0 if vectors[2, 0] >= 0 else -1.0)
    z = np.array([0.0, 0.0, 1.0])
    axis = np.cross(normal, z)
    sin, cos = np.linalg.norm(axis), float(normal @ z)
    if sin < 1e-9 or np.arccos(np.clip(cos, -1.0, 1.0)) > max_tilt:
        return path
    axis /= sin
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = np.eye(3) + sin * k + (1 - cos) * (k @ k)  # Rodrigues
    return path @ rot.T


def normalise(points, times=None, config: FeatureConfig = FeatureConfig()) -> np.ndarray:
    """The path resampled, centred and scaled to unit RMS radius (length x 3)."""
    points, times = clean(points, times)
    if len(points) == 0:
        raise ValueError("a gesture path needs at least one finite point")
    path = resample(smooth_path(points, config.smooth), config.length, config.resample, times)
    path = path - path.mean(axis=0)
    if config.plane == "align":
        path = align_plane(path)
    if config.scale == "bbox":
        radius = 0.5 * float(np.max(path.max(axis=0) - path.min(axis=0)))
    else:
        radius = np.sqrt(np.mean(np.sum(path**2, axis=1)))
    if radius > 0:
        path = path / radius
    return path * np.asarray(config.axis_weights)


def features(points, times=None, config: FeatureConfig = FeatureConfig()) -> np.ndarray:
    """Feature array (config.length x config.channels), C-contiguous float64."""
    path = normalise(points, times, config)
    channels = [path * config.position_weight]
    if config.direction_weight > 0 or config.curvature_weight > 0:
        step = np.gradient(path, axis=0)
        norm = np.linalg.norm(step, axis=1, keepdims=True)
        direction = np.divide(step, norm, out=np.zeros_like(step), where=norm > 1e-9)
        if config.direction_weight > 0:
            channels.append(direction * config.direction_weight)
        if config.curvature_weight > 0:
            cosine = np.clip(np.sum(direction[1:] * direction[:-1], axis=1), -1.0, 1.0)
            turn = np.concatenate([[0.0], np.arccos(cosine)])
            channels.append(turn[:, None] * config.curvature_weight)
    return np.ascontiguousarray(np.hstack(channels), dtype=np.float64)
