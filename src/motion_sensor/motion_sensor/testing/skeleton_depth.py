"""Depth images of a real hand from its tracked skeleton (22 joints in SHREC'17 / DHG
order), with a hand model built from the skeleton itself: independent of
``synthetic_depth``'s parametric hand, so that the depth tracker can be measured on motion
and hand shapes it was not built around.

The hand model (``HandModel``; every size in metres):

- **fingers**: a capsule per phalanx between successive joints (base -> first -> second ->
  tip), radii tapering from ``finger_radii`` (proximal, middle, distal; the ring and little
  fingers are thinner by ``ring_thinner`` and ``pinky_thinner``); the thumb the same from its
  base with ``thumb_radii``;
- **palm**: a thick slab, the polygon through the wrist's two sides (``wrist_half_width``
  either side of the wrist joint, across the hand) and the four finger bases, swept by a
  sphere of ``palm_half_thickness`` (a flat prism per fan triangle around the palm centre,
  capsules along its rim);
- **thenar**: a capsule from the wrist's thumb side to the thumb base;
- **forearm**: two capsules continuing the palm centre -> wrist axis back from the wrist,
  the wrist (``wrist_radius`` over ``wrist_length``) then the forearm (``forearm_radius``
  over ``forearm_length``). The operator faces the camera, so the elbow is never nearer to
  it than the wrist: where that axis would point less than ``forearm_min_away_deg`` away
  from the camera, the forearm bends at the wrist (keeping its direction across the image)
  to point that far away; SHREC's hands tilted with the fingers away from the camera need
  up to about 25 degrees of wrist extension for this, well within a wrist's range.

Rendering is exact ray casting (each pixel's ray against each primitive, inside the
primitive's projected bounding box, nearest hit kept), then the sensor (``SensorNoise``):
Gaussian depth noise of sigma ``sigma_per_m2`` times z^2, quantisation in disparity
(``disparity_step_px`` of a structured-light camera with ``baseline_m``) then to whole
millimetres (16UC1), and dropout at silhouettes (pixels within one pixel of a depth jump
larger than ``edge_jump_m`` lost with probability ``edge_dropout``) and at random
(``random_dropout``). Coordinates are the camera's optical frame (x right, y down, z
forward, metres), which is also SHREC'17's.

Ground truth: the palm centre joint (``PALM``, SHREC's joint 1), which lies on the slab's
mid-plane; a tracker that reports the seen palm surface is a palm half thickness in front
of it.
"""

from dataclasses import dataclass

import numpy as np

from motion_sensor.devices.camera_intrinsics import Intrinsics

__all__ = [
    "WRIST",
    "PALM",
    "THUMB",
    "FINGERS",
    "HandModel",
    "SensorNoise",
    "hand_primitives",
    "render_skeleton",
    "place_in_view",
]

WRIST, PALM = 0, 1
THUMB = (2, 3, 4, 5)  # base, first joint, second joint, tip
FINGERS = ((6, 7, 8, 9), (10, 11, 12, 13), (14, 15, 16, 17), (18, 19, 20, 21))  # index .. little


@dataclass(frozen=True)
class HandModel:
    """Sizes of the hand built around a skeleton (m), adult averages."""

    finger_radii: tuple[float, float, float] = (0.0092, 0.0082, 0.0072)
    ring_thinner: float = 0.0004
    pinky_thinner: float = 0.0012
    thumb_radii: tuple[float, float, float] = (0.0115, 0.0095, 0.0085)
    palm_half_thickness: float = 0.0125
    wrist_half_width: float = 0.018
    thenar_radius: float = 0.0135
    wrist_radius: float = 0.024
    wrist_length: float = 0.06
    forearm_radius: float = 0.031
    forearm_length: float = 0.22
    forearm_min_away_deg: float = 10.0


@dataclass(frozen=True)
class SensorNoise:
    """A structured-light depth camera's errors (Kinect-like defaults); all zero: exact."""

    sigma_per_m2: float = 0.0015
    baseline_m: float = 0.075
    disparity_step_px: float = 0.125
    edge_jump_m: float = 0.03
    edge_dropout: float = 0.5
    random_dropout: float = 0.002


def _unit(v):
    n = np.linalg.norm(v)
    if n < 1e-9:
        raise ValueError("skeleton: two joints coincide where a direction is needed")
    return v / n


def hand_primitives(joints: np.ndarray, model: HandModel = HandModel()):
    """(capsules, prisms) of the hand around ``joints`` ((22, 3), optical, m): capsules as
    (a, b, radius), prisms as (p0, p1, p2, half_thickness), flat triangles swept either
    side of their plane (their rims are capsules of the list)."""
    j = np.asarray(joints, dtype=float)
    if j.shape != (22, 3) or not np.all(np.isfinite(j)):
        raise ValueError(f"skeleton: expected 22 finite 3-D joints, got shape {j.shape}")
    capsules = []
    for finger, shrink in zip(FINGERS, (0.0, 0.0, model.ring_thinner, model.pinky_thinner)):
        for k, r in enumerate(model.finger_radii):
            capsules.append((j[finger[k]], j[finger[k + 1]], r - shrink))
    for k, r in enumerate(model.thumb_radii):
        capsules.append((j[THUMB[k]], j[THUMB[k + 1]], r))
    # The palm: the wrist's two sides across the hand (index side first) and the finger bases.
    across = _unit(j[FINGERS[0][0]] - j[FINGERS[3][0]])
    wrist_index = j[WRIST] + across * model.wrist_half_width
    wrist_little = j[WRIST] - across * model.wrist_half_width
    rim = [wrist_index] + [j[f[0]] for f in FINGERS] + [wrist_little]
    h = model.palm_half_thickness
    prisms = []
    for a, b in zip(rim, rim[1:] + rim[:1]):
        capsules.append((a, b, h))
        prisms.append((j[PALM], a, b, h))
    capsules.append((wrist_index, j[THUMB[0]], model.thenar_radius))
    back = _forearm_direction(_unit(j[WRIST] - j[PALM]), np.radians(model.forearm_min_away_deg))
    elbow_side = j[WRIST] + back * model.wrist_length
    capsules.append((j[WRIST], elbow_side, model.wrist_radius))
    capsules.append((elbow_side, elbow_side + back * model.forearm_length, model.forearm_radius))
    return capsules, prisms


def place_in_view(joints: np.ndarray, depth_m: float) -> np.ndarray:
    """A skeleton sequence ((n, 22, 3), optical) moved rigidly, a translation only, so that
    its mean palm centre lies on the optical axis; its depth moves by ``depth_m``."""
    joints = np.asarray(joints, dtype=float)
    palm = joints[:, PALM].mean(axis=0)
    return joints + np.array([-palm[0], -palm[1], depth_m])


def _forearm_direction(back, min_away):
    """``back`` (unit, optical), turned about the wrist to point at least ``min_away``
    (rad) away from the camera (+z), keeping its direction across the image."""
    if back[2] >= np.sin(min_away):
        return back
    across = back[:2]
    norm = np.linalg.norm(across)
    across = across / norm if norm > 1e-9 else np.array([0.0, 1.0])
    return np.array([across[0] * np.cos(min_away), across[1] * np.cos(min_away), np.sin(min_away)])


def _pixel_box(points, radius, intr: Intrinsics):
    """(u0, u1, v0, v1) bounding the image of the points' convex hull grown by ``radius``,
    or None when it misses the image or lies behind the camera."""
    pts = np.asarray(points, float)
    if np.any(pts[:, 2] - radius <= 1e-3):
        return None
    z = pts[:, 2] - radius
    pad_u, pad_v = radius * intr.fx / z, radius * intr.fy / z
    u = intr.cx + intr.fx * pts[:, 0] / pts[:, 2]
    v = intr.cy + intr.fy * pts[:, 1] / pts[:, 2]
    u0, u1 = int(np.floor((u - 1.2 * pad_u).min())) - 1, int(np.ceil((u + 1.2 * pad_u).max())) + 2
    v0, v1 = int(np.floor((v - 1.2 * pad_v).min())) - 1, int(np.ceil((v + 1.2 * pad_v).max())) + 2
    u0, v0, u1, v1 = max(u0, 0), max(v0, 0), min(u1, intr.width), min(v1, intr.height)
    return (u0, u1, v0, v1) if u0 < u1 and v0 < v1 else None


def _pixel_rays(box, intr: Intrinsics):
    """Rays (h, w, 3) through the box's pixels scaled to z = 1: a hit at ray * t has depth t."""
    u0, u1, v0, v1 = box
    x = (np.arange(u0, u1, dtype=float) - intr.cx) / intr.fx
    y = (np.arange(v0, v1, dtype=float) - intr.cy) / intr.fy
    rays = np.empty((v1 - v0, u1 - u0, 3))
    rays[..., 0] = x[None, :]
    rays[..., 1] = y[:, None]
    rays[..., 2] = 1.0
    return rays


def _sphere_depth(rays, centre, r):
    """Depth of the nearest hit of each ray with a sphere (inf where it misses)."""
    a = np.einsum("...i,...i->...", rays, rays)
    b = rays @ centre
    disc = b * b - a * (centre @ centre - r * r)
    with np.errstate(invalid="ignore"):
        t = (b - np.sqrt(disc)) / a
    return np.where((disc >= 0) & (t > 0), t, np.inf)


def _capsule_depth(rays, a, b, r):
    """Depth of the nearest hit of each ray with the capsule a-b of radius r (inf on a miss):
    the side of the cylinder between the end planes, else the end spheres."""
    axis = b - a
    length = float(np.linalg.norm(axis))
    best = np.minimum(_sphere_depth(rays, a, r), _sphere_depth(rays, b, r))
    if length < 1e-9:
        return best
    e = axis / length
    # Components across the axis: the ray t * d is at distance r from the axis line when
    # |t d_perp - a_perp| = r.
    d_along = rays @ e
    d_perp = rays - d_along[..., None] * e
    a_perp = a - (a @ e) * e
    qa = np.einsum("...i,...i->...", d_perp, d_perp)
    qb = d_perp @ a_perp
    disc = qb * qb - qa * (a_perp @ a_perp - r * r)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (qb - np.sqrt(disc)) / qa
    s = t * d_along - a @ e  # position of the hit along the axis from a
    side = (disc >= 0) & (t > 0) & (s >= 0) & (s <= length)
    return np.where(side, np.minimum(t, best), best)


def _prism_depth(rays, p0, p1, p2, h):
    """Depth of the nearest hit of each ray with the triangle p0 p1 p2 moved h either way
    along its normal (its two faces; the rim is left to capsules)."""
    n = np.cross(p1 - p0, p2 - p0)
    norm = np.linalg.norm(n)
    out = np.full(rays.shape[:-1], np.inf)
    if norm < 1e-12:
        return out
    n = n / norm
    dn = rays @ n
    edges = ((p0, p1), (p1, p2), (p2, p0))
    for side in (h, -h):
        offset = n * side
        with np.errstate(invalid="ignore", divide="ignore"):
            t = ((p0 + offset) @ n) / dn
        hit = rays * t[..., None] - offset  # back on the triangle's plane
        inside = np.isfinite(t) & (t > 0)
        for q0, q1 in edges:
            inside &= (np.cross(q1 - q0, hit - q0) @ n) >= 0
        out = np.where(inside, np.minimum(out, t), out)
    return out


def render_skeleton(
    joints: np.ndarray,
    intr: Intrinsics,
    model: HandModel = HandModel(),
    noise: SensorNoise | None = SensorNoise(),
    rng: np.random.Generator | None = None,
    background_m: float = 0.0,
) -> np.ndarray:
    """Depth image (m, float32, 0 = no reading) of the hand around ``joints`` ((22, 3),
    optical, m). ``background_m`` > 0 puts a wall at that depth; ``noise`` None renders the
    exact surface (no quantisation either)."""
    capsules, prisms = hand_primitives(joints, model)
    depth = np.full((intr.height, intr.width), np.inf)
    for a, b, r in capsules:
        box = _pixel_box((a, b), r, intr)
        if box is not None:
            u0, u1, v0, v1 = box
            view = depth[v0:v1, u0:u1]
            np.minimum(view, _capsule_depth(_pixel_rays(box, intr), a, b, r), out=view)
    for p0, p1, p2, h in prisms:
        box = _pixel_box((p0, p1, p2), h, intr)
        if box is not None:
            u0, u1, v0, v1 = box
            view = depth[v0:v1, u0:u1]
            np.minimum(view, _prism_depth(_pixel_rays(box, intr), p0, p1, p2, h), out=view)
    if background_m > 0:
        depth[np.isinf(depth)] = background_m
    depth[np.isinf(depth)] = 0.0
    if noise is not None:
        depth = _sensor(depth, intr, noise, rng if rng is not None else np.random.default_rng(0))
    return depth.astype(np.float32)


def _sensor(depth, intr: Intrinsics, noise: SensorNoise, rng):
    """The exact depth as the sensor reports it (see the module)."""
    valid = depth > 0
    z = depth.copy()
    if noise.sigma_per_m2 > 0:
        z[valid] += rng.normal(0.0, 1.0, int(valid.sum())) * noise.sigma_per_m2 * z[valid] ** 2
    if noise.disparity_step_px > 0:
        fb = intr.fx * noise.baseline_m
        disparity = np.round(fb / z[valid] / noise.disparity_step_px) * noise.disparity_step_px
        z[valid] = fb / disparity
    z = np.where(valid, np.round(z * 1000.0) / 1000.0, 0.0)
    drop = np.zeros(z.shape, bool)
    if noise.edge_dropout > 0:
        # A depth jump to a neighbour (no reading counts as far) marks both sides' pixels.
        far = np.where(valid, depth, 1e3)
        jump = np.zeros(z.shape, bool)
        dv = np.abs(np.diff(far, axis=0)) > noise.edge_jump_m
        du = np.abs(np.diff(far, axis=1)) > noise.edge_jump_m
        jump[1:] |= dv
        jump[:-1] |= dv
        jump[:, 1:] |= du
        jump[:, :-1] |= du
        drop |= jump & (rng.random(z.shape) < noise.edge_dropout)
    if noise.random_dropout > 0:
        drop |= rng.random(z.shape) < noise.random_dropout
    z[drop] = 0.0
    return z
