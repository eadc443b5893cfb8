"""Varied hands for the skeleton renderer (``skeleton_depth``): the same tracked motion on
hands of other sizes and shapes, held at other angles and distances, so that a network
trained on a few subjects' renders sees more than their hands and their way of holding them.

A varied sequence (``vary_sequence``) keeps the skeleton's motion and changes, once for the
whole sequence, drawn from ``HandVariation``'s ranges with the caller's generator:

- **bone lengths** (``scale_bones``): every joint's offset from the wrist scaled by one
  overall factor, then each finger's (and the thumb's) phalanges by a factor of their own;
- **the hand model** (``varied_model``): the capsule radii scaled with the hand's size and a
  factor of their own, the palm slab's thickness and wrist width, the thenar, the wrist and
  the forearm each by their own factor;
- **the pose** (``tilting_rotation``, ``turn_sequence``): the whole sequence turned about its
  mean palm centre so that its mean palm normal is tilted a drawn angle from the line of
  sight (the same face towards the camera), then rolled about the line of sight;
- **the distance**: its mean palm centre put on the optical axis at a drawn depth
  (``skeleton_depth.place_in_view``).

Nothing here changes ``skeleton_depth``'s defaults: a sequence not passed through it renders
as before.
"""

from dataclasses import dataclass, replace

import numpy as np

from motion_sensor.testing.skeleton_depth import FINGERS, PALM, THUMB, WRIST, HandModel, place_in_view

__all__ = [
    "HandVariation",
    "scale_bones",
    "varied_model",
    "palm_normal",
    "tilting_rotation",
    "turn_sequence",
    "vary_sequence",
]

# SHREC's joints the palm's normal is taken from (as the depth bench does): wrist, index
# base, little finger base.
_INDEX_BASE, _LITTLE_BASE = FINGERS[0][0], FINGERS[3][0]


@dataclass(frozen=True)
class HandVariation:
    """Ranges (low, high) the varied hands are drawn from, uniformly."""

    overall_scale: tuple[float, float] = (0.8, 1.2)
    finger_scale: tuple[float, float] = (0.85, 1.15)
    radius_scale: tuple[float, float] = (0.85, 1.2)
    palm_thickness_scale: tuple[float, float] = (0.8, 1.25)
    wrist_width_scale: tuple[float, float] = (0.8, 1.3)
    thenar_scale: tuple[float, float] = (0.8, 1.25)
    forearm_scale: tuple[float, float] = (0.8, 1.3)
    tilt_deg: tuple[float, float] = (0.0, 90.0)
    roll_deg: tuple[float, float] = (-90.0, 90.0)
    palm_depth_m: tuple[float, float] = (0.6, 1.0)


def scale_bones(joints: np.ndarray, overall: float, per_finger=(1.0,) * 5) -> np.ndarray:
    """``joints`` ((..., 22, 3)) with every offset from the wrist scaled by ``overall`` and
    the phalanges of the thumb, index .. little finger (in that order) by ``per_finger``."""
    j = np.asarray(joints, dtype=float)
    if j.shape[-2:] != (22, 3):
        raise ValueError(f"skeleton: expected (..., 22, 3) joints, got shape {j.shape}")
    if len(per_finger) != 5:
        raise ValueError(f"per_finger: expected 5 factors (thumb, index .. little), got {len(per_finger)}")
    wrist = j[..., WRIST : WRIST + 1, :]
    out = wrist + (j - wrist) * overall
    for chain, factor in zip((THUMB,) + FINGERS, per_finger):
        # Each phalanx keeps its direction and is scaled; the joints after it follow it.
        for k in range(1, len(chain)):
            bone = (j[..., chain[k], :] - j[..., chain[k - 1], :]) * overall * factor
            out[..., chain[k], :] = out[..., chain[k - 1], :] + bone
    return out


def varied_model(rng: np.random.Generator, size: float = 1.0, variation: HandVariation = HandVariation()):
    """A ``HandModel`` drawn around the defaults for a hand ``size`` times the average."""
    base = HandModel()

    def draw(bounds):
        return float(rng.uniform(*bounds))

    radii = size * draw(variation.radius_scale)
    forearm = draw(variation.forearm_scale)
    return replace(
        base,
        finger_radii=tuple(r * radii for r in base.finger_radii),
        ring_thinner=base.ring_thinner * radii,
        pinky_thinner=base.pinky_thinner * radii,
        thumb_radii=tuple(r * radii for r in base.thumb_radii),
        palm_half_thickness=base.palm_half_thickness * size * draw(variation.palm_thickness_scale),
        wrist_half_width=base.wrist_half_width * size * draw(variation.wrist_width_scale),
        thenar_radius=base.thenar_radius * size * draw(variation.thenar_scale),
        wrist_radius=base.wrist_radius * forearm,
        forearm_radius=base.forearm_radius * forearm,
    )


def palm_normal(joints: np.ndarray) -> np.ndarray:
    """Unit palm normals ((..., 3)) of ``joints`` ((..., 22, 3)): index base minus wrist
    crossed with little finger base minus wrist."""
    j = np.asarray(joints, dtype=float)
    normal = np.cross(j[..., _INDEX_BASE, :] - j[..., WRIST, :], j[..., _LITTLE_BASE, :] - j[..., WRIST, :])
    return normal / np.linalg.norm(normal, axis=-1, keepdims=True)


def _about(axis, angle):
    """Rotation matrix of ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def tilting_rotation(normal: np.ndarray, tilt_deg: float, azimuth_deg: float, roll_deg: float) -> np.ndarray:
    """Rotation taking the unit palm ``normal`` to one tilted ``tilt_deg`` from the line of
    sight (z) towards ``azimuth_deg`` in the image, the same face towards the camera, then
    rolling everything ``roll_deg`` about the line of sight."""
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    tilt, azimuth = np.radians(tilt_deg), np.radians(azimuth_deg)
    face = 1.0 if n[2] >= 0 else -1.0
    target = np.array([np.sin(tilt) * np.cos(azimuth), np.sin(tilt) * np.sin(azimuth), face * np.cos(tilt)])
    axis = np.cross(n, target)
    sin, cos = np.linalg.norm(axis), float(n @ target)
    align = np.eye(3) if sin < 1e-12 else _about(axis / sin, np.arctan2(sin, cos))
    return _about(np.array([0.0, 0.0, 1.0]), np.radians(roll_deg)) @ align


def turn_sequence(joints: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """``joints`` ((n, 22, 3)) turned by ``rotation`` about their mean palm centre."""
    j = np.asarray(joints, dtype=float)
    centre = j[:, PALM].mean(axis=0)
    return (j - centre) @ np.asarray(rotation, dtype=float).T + centre


def vary_sequence(joints: np.ndarray, rng: np.random.Generator, variation: HandVariation = HandVariation()):
    """(joints, model): the sequence ``joints`` ((n, 22, 3), optical, m) on a varied hand,
    turned and placed, and the ``HandModel`` to render it with (see the module)."""
    j = np.asarray(joints, dtype=float)
    if j.ndim != 3 or j.shape[1:] != (22, 3) or not np.all(np.isfinite(j)):
        raise ValueError(f"skeleton sequence: expected finite (n, 22, 3) joints, got shape {j.shape}")
    size = float(rng.uniform(*variation.overall_scale))
    fingers = rng.uniform(*variation.finger_scale, size=5)
    model = varied_model(rng, size, variation)
    j = scale_bones(j, size, fingers)
    mean_normal = palm_normal(j).mean(axis=0)
    if np.linalg.norm(mean_normal) < 1e-6:  # a hand turned over and back: no mean face
        mean_normal = np.array([0.0, 0.0, -1.0])
    rotation = tilting_rotation(
        mean_normal,
        rng.uniform(*variation.tilt_deg),
        rng.uniform(0.0, 360.0),
        rng.uniform(*variation.roll_deg),
    )
    j = turn_sequence(j, rotation)
    j = place_in_view(j, rng.uniform(*variation.palm_depth_m) - j[:, PALM, 2].mean())
    return j, model
