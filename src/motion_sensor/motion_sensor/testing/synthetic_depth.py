"""Synthetic depth images of a hand with its forearm, ray-cast in numpy (tests, the
benchmark and demos without a camera).

The hand model, in its own frame (x along the fingers, z out of the back of the hand, as
hand.msg): an ellipsoid palm, four finger capsules and a thumb that curl into the palm as
``grab`` goes from 0 (open) to 1 (fist), a wrist and a forearm capsule running back and
away from the camera, and optionally a torso behind. Every pixel's ray is intersected
exactly with each primitive (only inside the primitive's projected bounding box) and the
nearest hit kept, so depths are exact to float precision before the optional sensor noise
(``noise_per_m2``: sigma = that times z^2, Kinect-like) and millimetre quantisation.
Coordinates are optical (x right, y down, z forward); ``HAND_UPRIGHT`` is the operator's
open hand facing the camera with the fingers up.
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from motion_sensor.devices.camera_intrinsics import Intrinsics

#: Fingers up (-y optical), back of the hand away from the camera (+z): columns x, y, z.
HAND_UPRIGHT = np.column_stack(([0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]))

DEFAULT_INTRINSICS = Intrinsics(fx=570.0, fy=570.0, cx=319.5, cy=239.5, width=640, height=480)

PALM_SEMI_AXES = (0.045, 0.042, 0.018)  # m: along the fingers, across, thickness
FOREARM_RADIUS = 0.026
FOREARM_LENGTH = 0.26
FOREARM_TILT = np.radians(30.0)  # away from the camera (towards the back of the hand)


@dataclass(frozen=True)
class HandPose:
    """Palm centre (m, optical), hand rotation (columns: hand x, y, z in optical) and grab 0-1."""

    position: np.ndarray
    rotation: np.ndarray
    grab: float = 0.0


def _capsules(pose: HandPose, forearm: bool) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(start, end, radius) of the finger, thumb, wrist and forearm capsules (optical)."""
    R, p, g = pose.rotation, np.asarray(pose.position, float), float(pose.grab)
    out = []
    curl = g * np.radians(110.0)
    for y, length, spread in (
        (-0.031, 0.068, -0.12),
        (-0.011, 0.078, -0.04),
        (0.011, 0.082, 0.04),
        (0.031, 0.074, 0.12),
    ):
        base = p + R @ np.array([0.040, y, 0.0])
        direction = np.array([np.cos(curl) * np.cos(spread), np.sin(spread) * (1 - g), -np.sin(curl)])
        out.append((base, base + R @ (direction / np.linalg.norm(direction)) * length * (1 - 0.35 * g), 0.0085))
    thumb_base = p + R @ np.array([-0.010, 0.036, -0.006])
    thumb_dir = np.array([0.55, 0.8 - 0.5 * g, -0.15 - 0.6 * g])
    out.append((thumb_base, thumb_base + R @ (thumb_dir / np.linalg.norm(thumb_dir)) * 0.055, 0.0105))
    if forearm:
        wrist = p + R @ np.array([-0.065, 0.0, 0.0])
        out.append((p + R @ np.array([-0.030, 0.0, 0.0]), wrist, 0.021))
        back = np.array([-np.cos(FOREARM_TILT), 0.0, np.sin(FOREARM_TILT)])
        out.append((wrist, wrist + R @ back * FOREARM_LENGTH, FOREARM_RADIUS))
    return out


def _box(centre, radius, intr: Intrinsics):
    """Pixel bounds (u0, u1, v0, v1) containing a sphere's image, or None if off-image."""
    z = centre[2] - radius
    if z <= 1e-3:
        return 0, intr.width, 0, intr.height
    ru, rv = radius * intr.fx / z, radius * intr.fy / z
    u, v = intr.cx + intr.fx * centre[0] / centre[2], intr.cy + intr.fy * centre[1] / centre[2]
    u0, u1 = max(int(u - ru * 1.5) - 1, 0), min(int(u + ru * 1.5) + 2, intr.width)
    v0, v1 = max(int(v - rv * 1.5) - 1, 0), min(int(v + rv * 1.5) + 2, intr.height)
    return (u0, u1, v0, v1) if u0 < u1 and v0 < v1 else None


def _rays(box, intr: Intrinsics):
    """Unit ray directions (h, w, 3) and their z components for the pixels of a box."""
    u0, u1, v0, v1 = box
    x = (np.arange(u0, u1) - intr.cx) / intr.fx
    y = (np.arange(v0, v1) - intr.cy) / intr.fy
    d = np.stack(np.broadcast_arrays(x[None, :], y[:, None], np.ones((1, 1))), axis=-1)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    return d


def _hit_capsule(d, a, b, r):
    """Ray distance to a capsule for unit rays ``d`` from the origin (inf on a miss)."""
    ba, oa = b - a, -a
    baba, baoa, oaoa = ba @ ba, ba @ oa, oa @ oa
    bard, rdoa = d @ ba, d @ oa
    qa = baba - bard * bard
    qb = baba * rdoa - baoa * bard
    qc = baba * oaoa - baoa * baoa - r * r * baba
    h = qb * qb - qa * qc
    t = np.full(d.shape[:-1], np.inf)
    with np.errstate(invalid="ignore", divide="ignore"):
        tc = (-qb - np.sqrt(h)) / qa
        y = baoa + tc * bard
        side = (h >= 0) & (y > 0) & (y < baba)
        t[side] = tc[side]
        for centre, which in ((a, y <= 0), (b, y >= baba)):
            oc = -centre
            sb = d @ oc
            sh = sb * sb - (oc @ oc - r * r)
            cap = (h >= 0) & which & (sh >= 0)
            t[cap] = np.minimum(t[cap], (-sb - np.sqrt(sh))[cap])
    t[~(t > 0)] = np.inf
    return t


def _hit_ellipsoid(d, centre, rotation, semi_axes):
    """Ray distance to an ellipsoid for unit rays ``d`` from the origin (inf on a miss)."""
    scale = np.asarray(semi_axes, float)
    o = (rotation.T @ -np.asarray(centre, float)) / scale
    dl = (d @ rotation) / scale
    qa = np.einsum("...i,...i->...", dl, dl)
    qb = 2.0 * (dl @ o)
    qc = o @ o - 1.0
    h = qb * qb - 4 * qa * qc
    t = np.full(d.shape[:-1], np.inf)
    hit = h >= 0
    t[hit] = (-qb[hit] - np.sqrt(h[hit])) / (2 * qa[hit])
    t[~(t > 0)] = np.inf
    return t


def render_hand(
    pose: HandPose,
    intr: Intrinsics = DEFAULT_INTRINSICS,
    forearm: bool = True,
    torso: bool = True,
    background_m: float = 2.5,
    extra: Sequence[HandPose] = (),
    noise_per_m2: float = 0.0,
    rng: np.random.Generator = None,
    quantise_mm: bool = True,
) -> np.ndarray:
    """Depth image (m, float32, 0 where nothing is hit) of the hand (and ``extra`` hands)."""
    depth = np.full((intr.height, intr.width), np.inf)
    shapes = []
    for hand in (pose, *extra):
        shapes.append(("ellipsoid", hand.position, hand.rotation, PALM_SEMI_AXES))
        shapes += [("capsule", a, b, r) for a, b, r in _capsules(hand, forearm)]
    if torso:
        chest = np.asarray(pose.position, float) + np.array([0.05, 0.28, 0.48])
        shapes.append(("ellipsoid", chest, np.eye(3), (0.19, 0.30, 0.11)))
    for kind, first, second, third in shapes:
        if kind == "capsule":
            centre, radius = (first + second) / 2, np.linalg.norm(second - first) / 2 + third
        else:
            centre, radius = np.asarray(first, float), max(third)
        box = _box(centre, radius, intr)
        if box is None:
            continue
        d = _rays(box, intr)
        t = _hit_capsule(d, first, second, third) if kind == "capsule" else _hit_ellipsoid(d, first, second, third)
        u0, u1, v0, v1 = box
        z = t * d[..., 2]
        view = depth[v0:v1, u0:u1]
        np.minimum(view, z, out=view)
    if background_m > 0:
        depth[np.isinf(depth)] = background_m
    depth[np.isinf(depth)] = 0.0
    if noise_per_m2 > 0:
        rng = rng or np.random.default_rng(0)
        depth = np.where(depth > 0, depth + rng.normal(0.0, 1.0, depth.shape) * noise_per_m2 * depth**2, 0.0)
    if quantise_mm:
        depth = np.round(depth * 1000.0) / 1000.0
    return depth.astype(np.float32)


def hand_path(frames: int, seed: int = 0) -> list[HandPose]:
    """A smooth 3-D path through the working volume (x +-0.18, y +-0.12, z 0.55-1.05 m) with
    the hand turning up to about 25 degrees about each axis, grab 0."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * np.pi, 6)
    poses = []
    for s in np.linspace(0.0, 1.0, frames, endpoint=False):
        w = 2 * np.pi * s
        position = np.array(
            [0.18 * np.sin(w + phase[0]), 0.12 * np.sin(2 * w + phase[1]), 0.80 + 0.25 * np.sin(w + phase[2])]
        )
        turn = Rotation.from_euler(
            "xyz", [0.35 * np.sin(w + phase[3]), 0.35 * np.sin(2 * w + phase[4]), 0.45 * np.sin(w + phase[5])]
        )
        poses.append(HandPose(position, HAND_UPRIGHT @ turn.as_matrix()))
    return poses
