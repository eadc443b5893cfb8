"""Hand tracking in a depth image, without ROS: nearest blob, palm centre, orientation.

``DepthHandTracker.track(depth_m, intrinsics)`` finds the hand as the depth camera sees
an operator reaching towards it (the paper's Kinect set-up):

1. **Blob.** Pixels inside the working volume (``min_depth_m``..``max_depth_m`` along the
   optical axis, ``max_lateral_m`` either side) and no more than ``band_depth_m`` behind
   the nearest of them are split into connected components. A component whose physical
   area (pixels times their footprint at its depth) lies in ``min_blob_area_m2``..
   ``max_blob_area_m2`` is a hand (with its forearm); the nearest is the primary hand, the
   next one a second hand (``hands_num`` 2, used by the gesture clutch). The body, a wall
   or a table merged with the hand is too large and means "no hand".
2. **Palm centre.** The maximum of the blob's distance transform (cv2.distanceTransform),
   single lost pixels (speckle, dropout) closed first: the palm is the widest part of hand
   plus forearm, and the search is kept within ``palm_search_depth_m`` of the blob's front
   so a forearm tilted away cannot win. After the first frame the search stays within
   ``track_radius_m`` of the previous palm as long as the blob there is at least 30 % as
   wide as its widest part (a palm turning edge-on narrows, and must not hand over to the
   forearm); further away, the hand moved more than that and the whole blob is searched.
   A palm tilted or edge-on can still be narrower than the forearm: the blob's 3-D points
   are profiled along their main axis in 1 cm sections of metric width, the forearm is the
   end of even width and the wrist the first section, from there, clearly narrower than
   it; a maximum found on the forearm's side of the wrist is searched again on the hand's
   side (``_forearm_cut``). The centroid of the transform's ridge (within ``ridge_px`` of the maximum) gives a
   sub-pixel centre; the median depth in a disc around it back-projects it with the
   intrinsics to a point of the seen palm *surface*. Fingers held together are a plate as
   wide as the palm, and the maximum slides onto it: where the profile found the wrist,
   the surface point is instead the 3-D centroid of the palm's core (``_palm_core``: the
   pixels at least ``palm_core_width_m`` inside the outline, ``palm_core_wrist_margin_m``
   beyond the wrist, within ``palm_core_radius_m`` of the maximum), and ``CoreBlend``
   spreads a switch between the two over frames. The palm centre is reported
   ``palm_half_thickness_m`` behind the surface point along the normal (step 3), met by
   the pixel's ray at h / cos(tilt), the tilt capped at 60 degrees. With ``palm_model``
   a small network (``depth_palm_model``) looks at a depth crop of the whole hand around
   that estimate and moves it ``palm_model_weight`` of the way to where it puts the palm
   centre, which holds where the widest part does not (a palm tilted well away); an
   implausible output (further than ``palm_model_max_offset_m``) or no usable crop leaves
   the estimate as it is.
3. **Orientation** from principal axes: the palm normal is the least-variance axis of the
   3-D points of the palm disc, the hand axis the main axis of the points within
   ``hand_radius_m`` of the centre (made orthogonal to the normal), pointing away from the
   forearm (the blob's points beyond 1.4 times that radius, past the fingertips) or, when no forearm is seen, as in the
   previous frame. ``palm_faces_camera`` says which way the back of the hand is.
4. **Fields**: ``hand_type`` by configuration or by position (``by_position``: a hand on the
   camera's left, +y, is the operator's right hand facing the camera); ``grab_strength``
   from how far the blob reaches beyond the palm along the hand axis (fingers curled in a
   fist reach less); ``hand_id`` changes when the hand is lost or jumps.

Positions and orientations come out in the camera's REP 103 body frame (x forward along
the optical axis, y left, z up), as hand.msg wants; the hand frame is hand.msg's (x along
the fingers, z out of the back of the hand).
"""

from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial.transform import Rotation

from motion_common.params import Param, ParamSchema
from motion_sensor.devices.camera_intrinsics import OPTICAL_TO_REP103, Intrinsics
from motion_sensor.devices.depth_palm_model import MAX_OFFSET_M, PalmModel
from motion_sensor.errors import MotionSensorError

TRACKER_PARAMS = ParamSchema(
    [
        Param("min_depth_m", 0.35, unit="m", low=0.05, doc="working volume: nearest depth along the optical axis"),
        Param("max_depth_m", 1.3, unit="m", low=0.1, doc="working volume: farthest depth along the optical axis"),
        Param(
            "max_lateral_m", 0.6, unit="m", low=0.05, doc="working volume: half width and half height around the axis"
        ),
        Param("band_depth_m", 0.25, unit="m", low=0.02, doc="blob pixels lie at most this far behind the nearest one"),
        Param("min_blob_area_m2", 0.003, unit="m^2", low=0, doc="a smaller blob is noise, not a hand"),
        Param(
            "max_blob_area_m2",
            0.06,
            unit="m^2",
            low=0,
            low_open=True,
            doc="a larger blob is the body or furniture, not a hand with its forearm",
        ),
        Param(
            "palm_search_depth_m",
            0.12,
            unit="m",
            low=0.01,
            doc="palm centre searched this deep behind the blob's front",
        ),
        Param("ridge_px", 1.0, unit="px", low=0, doc="distance-transform ridge width averaged into the palm centre"),
        Param(
            "track_radius_m",
            0.05,
            unit="m",
            low=0,
            doc="palm searched this close to the previous frame's palm (0: anywhere in the blob)",
        ),
        Param(
            "palm_half_thickness_m",
            0.014,
            unit="m",
            low=0,
            doc="the palm centre reported lies this far behind the seen palm surface (0: the surface)",
        ),
        Param(
            "palm_core_width_m",
            0.014,
            unit="m",
            low=0,
            doc="the palm's core: blob points at least this far inside its outline, more than a finger's "
            "half width (0: the palm centre is the distance transform's maximum)",
        ),
        Param(
            "palm_core_radius_m",
            0.13,
            unit="m",
            low=0.02,
            doc="the palm's core lies within this distance of the distance transform's maximum",
        ),
        Param(
            "palm_core_wrist_margin_m",
            0.035,
            unit="m",
            low=0,
            doc="the palm's core starts this far beyond the wrist the width profile found",
        ),
        Param(
            "palm_model",
            True,
            doc="correct the palm centre with the shipped network (depth_palm_model); false: the estimate above",
        ),
        Param(
            "palm_model_max_offset_m",
            MAX_OFFSET_M,
            unit="m",
            low=0,
            low_open=True,
            high=0.15,
            doc="a network's palm further than this from the estimate (0.12: the crop's half side) is "
            "implausible: the estimate stands",
        ),
        Param(
            "palm_model_weight",
            0.8,
            low=0,
            high=1,
            doc="the palm moves this fraction of the way from the estimate to the network's palm centre",
        ),
        Param("hand_radius_m", 0.1, unit="m", low=0.03, doc="points this close to the palm centre are the hand"),
        Param("palm_faces_camera", True, doc="the palm faces the camera (z, out of the back of the hand, points away)"),
        Param(
            "hand_type",
            "right",
            choices=("right", "left", "by_position"),
            doc="hand_type of the primary hand: fixed, or by its side of the camera (+y: right)",
        ),
        Param("max_hands", 2, low=1, high=2, doc="hands reported; 2 lets the gesture clutch see a second hand"),
        Param(
            "open_extent_m",
            0.115,
            unit="m",
            low=0,
            low_open=True,
            doc="fingertip reach beyond the palm centre, open hand",
        ),
        Param("fist_extent_m", 0.065, unit="m", low=0, low_open=True, doc="the same reach with a fist"),
        Param(
            "jump_m", 0.15, unit="m", low=0, low_open=True, doc="a palm moving further between frames is a new hand id"
        ),
    ]
)

OPTICAL_TO_BODY = OPTICAL_TO_REP103  # the name the depth tests and bench use

_CLOSE_KERNEL = np.ones((3, 3), np.uint8)
# Near the previous palm, a part of the blob this fraction as wide as its widest still
# counts as the palm; a narrower one means the hand moved further than track_radius_m.
_TRACK_MIN_WIDTH = 0.3
# Forearm and wrist (see _forearm_cut): the blob's width is profiled along its main axis in
# sections this long (m); the forearm is the end whose 10 sections next to it vary in width
# by less than _EVEN_RATIO times the other end's (an even cylinder against fingers and
# palm); the wrist is the first section, walking from the forearm's end, narrower than
# _WRIST_NARROWING times the forearm's width; the palm is searched from _WRIST_CUT_M
# beyond it toward the fingers.
_SECTION_M = 0.01
_EVEN_RATIO = 0.6
_WRIST_NARROWING = 0.85
_WRIST_CUT_M = 0.04
_FLIP_FRAMES = 3
_FOREARM_SIDE_M = 0.015
# A palm core of fewer sampled pixels (every second row and column, so about four times as
# many in the image) is no palm (a palm seen edge-on): the maximum stands.
_CORE_MIN_PIXELS = 8
# Switching between the core's centroid and the maximum moves the palm by at most this much
# a frame beyond the motion of the estimate it goes to (m). On real-motion renders of the
# tuning subjects 4 mm cost 1.2 mm RMS (the core back after a gap is reached too late),
# 15 mm 0.1 mm against switching outright; a hand moves up to 50 mm a frame there (p99).
_CORE_BLEND_STEP_M = 0.015

__all__ = ["TRACKER_PARAMS", "OPTICAL_TO_BODY", "DepthHand", "DepthHandTracker", "CoreBlend"]


class CoreBlend:
    """The correction from the distance transform's maximum to the palm core's centroid,
    carried from frame to frame.

    While the core is seen frame after frame the palm is the core's centroid itself. A
    frame without a core (a palm seen edge-on) goes back toward the maximum, and a core
    seen again after a gap, or at first after the maximum, is reached, by at most
    ``step_m`` of the correction a frame: the two estimates differ by several millimetres
    to a few centimetres, and switching outright would step the palm by that much. A new
    hand (``reset``) takes the estimate it has outright."""

    def __init__(self, step_m: float = _CORE_BLEND_STEP_M):
        self.step_m = float(step_m)
        self.reset()

    def reset(self) -> None:
        self._correction = None  # applied in the previous frame (m); None: no previous palm
        self._locked = False  # the correction is the core's own: follow it outright

    def update(self, centre: np.ndarray, core: np.ndarray | None) -> np.ndarray:
        """The palm surface point of this frame from the maximum's ``centre`` and the core's
        centroid (None: no core this frame)."""
        target = core - centre if core is not None else np.zeros(3)
        if self._correction is None or (core is not None and self._locked):
            correction = target
        else:
            delta = target - self._correction
            size = float(np.linalg.norm(delta))
            correction = target if size <= self.step_m else self._correction + delta * (self.step_m / size)
        self._locked = core is not None and bool(np.array_equal(correction, target))
        self._correction = correction
        return centre + correction


@dataclass
class DepthHand:
    """One tracking result: the primary hand (REP 103 camera frame) and what else was seen."""

    position: np.ndarray  # palm centre (m): palm_half_thickness_m behind the seen surface
    orientation: np.ndarray  # unit quaternion (x, y, z, w)
    hand_types: tuple[str, ...]  # one per hand seen, primary first
    hand_id: int
    grab_strength: float

    @property
    def hands_num(self) -> int:
        """Number of hands seen."""
        return len(self.hand_types)


class DepthHandTracker:
    """Stateful tracker (hand id, axis sign) over successive depth images; see the module."""

    def __init__(self, config: dict):
        self.config = dict(TRACKER_PARAMS.defaults(), **{k: v for k, v in config.items() if k in TRACKER_PARAMS.params})
        c = self.config
        if (
            c["min_depth_m"] >= c["max_depth_m"]
            or c["min_blob_area_m2"] >= c["max_blob_area_m2"]
            or c["fist_extent_m"] >= c["open_extent_m"]
        ):
            raise MotionSensorError(
                "depth hand: need min_depth_m < max_depth_m, min_blob_area_m2 < "
                "max_blob_area_m2 and fist_extent_m < open_extent_m"
            )
        self._ray_cache = None
        self._last_axis = None  # fingers direction (optical) of the previous frame
        self._last_arm = None  # the blob's main axis toward the fingers, previous frame
        self._flip_votes = 0  # successive frames whose width profile turned that axis over
        self._last_position = None
        self._last_surface = None  # seen palm surface of the previous frame (optical)
        self._core_blend = CoreBlend()  # the maximum -> the palm core's centroid (see _palm_core)
        # The learned correction of the palm centre (depth_palm_model), loaded once.
        self.palm_model = (
            PalmModel(max_offset_m=c["palm_model_max_offset_m"], weight=c["palm_model_weight"])
            if c["palm_model"]
            else None
        )
        self._hand_id = 0
        self.last_reason = ""

    def reset(self) -> None:
        """Forget the previous hand (a new stream)."""
        self._last_axis = None
        self._last_arm = None
        self._last_position = None
        self._last_surface = None
        self._core_blend.reset()

    def _rays(self, intr: Intrinsics):
        key = (intr.fx, intr.fy, intr.cx, intr.cy, intr.width, intr.height)
        if self._ray_cache is None or self._ray_cache[0] != key:
            xs = (np.arange(intr.width, dtype=np.float32) - intr.cx) / intr.fx
            ys = (np.arange(intr.height, dtype=np.float32) - intr.cy) / intr.fy
            self._ray_cache = (key, xs, ys)
        return self._ray_cache[1], self._ray_cache[2]

    def track(self, depth: np.ndarray, intr: Intrinsics) -> DepthHand | None:
        """The hand in ``depth`` (m, 0 = none, shape (height, width) of ``intr``), or None
        when there is none (``last_reason`` says why)."""
        c = self.config
        xs, ys = self._rays(intr)
        found = self._blobs(depth, intr, xs, ys)
        if not found:
            self._lost()
            return None
        labels, stats, candidates = found
        primary = candidates[0]
        hand = self._measure(depth, labels, stats, primary[0], intr, xs, ys)
        if hand is None:
            self._lost()
            return None
        types = [self._hand_type(hand[0])]
        if c["max_hands"] > 1 and len(candidates) > 1:
            other = candidates[1]
            types.append("left" if types[0] == "right" else "right")
            if c["hand_type"] == "by_position":
                types[1] = "right" if -other[2] > 0 else "left"
        position_opt, rotation_opt, grab = hand
        if self._last_position is None or np.linalg.norm(position_opt - self._last_position) > c["jump_m"]:
            self._hand_id += 1
        self._last_position = position_opt
        position = OPTICAL_TO_BODY @ position_opt
        rotation = OPTICAL_TO_BODY @ rotation_opt
        quaternion = Rotation.from_matrix(rotation).as_quat()
        self.last_reason = ""
        return DepthHand(
            position=position,
            orientation=quaternion,
            hand_types=tuple(types),
            hand_id=self._hand_id,
            grab_strength=grab,
        )

    def _lost(self):
        self._last_arm = None
        self._last_position = None
        self._last_surface = None
        self._core_blend.reset()

    def _hand_type(self, position_opt) -> str:
        mode = self.config["hand_type"]
        if mode != "by_position":
            return mode
        return "right" if position_opt[0] < 0 else "left"  # optical x < 0 is the camera's left (+y)

    def _blobs(self, depth, intr, xs, ys):
        """(labels, stats, [(label, mean depth, mean optical x)] nearest first) or None."""
        c = self.config
        lateral = c["max_lateral_m"]
        inside = (depth > c["min_depth_m"]) & (depth < c["max_depth_m"])
        # Lateral limits at the far end of the volume bound the columns and rows searched.
        u0 = max(0, int(np.floor(intr.cx - lateral * intr.fx / c["min_depth_m"])))
        u1 = min(intr.width, int(np.ceil(intr.cx + lateral * intr.fx / c["min_depth_m"])) + 1)
        sample = depth[::4, ::4][inside[::4, ::4]]
        if sample.size < 4:
            self.last_reason = "nothing in the working volume"
            return None
        near = float(np.partition(sample, 3)[3])  # the 4th nearest: one flying pixel is not the front
        mask = inside & (depth < near + c["band_depth_m"])
        mask[:, :u0] = False
        mask[:, u1:] = False
        count, labels, stats, _ = cv2.connectedComponentsWithStats(mask.view(np.uint8), connectivity=8)
        if count <= 1:
            self.last_reason = "nothing in the working volume"
            return None
        pixels = stats[1:, cv2.CC_STAT_AREA].astype(float)
        # Cheap prefilter: a hand at the volume's far end covers at least this many pixels.
        smallest = c["min_blob_area_m2"] * intr.fx * intr.fy / c["max_depth_m"] ** 2
        keep = np.nonzero(pixels >= smallest)[0] + 1
        if keep.size == 0:
            self.last_reason = "only blobs smaller than a hand"
            return None
        candidates, too_big = [], 0
        for label in keep:
            # Per-blob sums inside its bounding box: a few blobs, not the whole image.
            left, top = stats[label, cv2.CC_STAT_LEFT], stats[label, cv2.CC_STAT_TOP]
            box = (
                slice(top, top + stats[label, cv2.CC_STAT_HEIGHT]),
                slice(left, left + stats[label, cv2.CC_STAT_WIDTH]),
            )
            rows, cols = np.nonzero(labels[box] == label)
            z = depth[box][rows, cols]
            area = float(z @ z) / (intr.fx * intr.fy)  # each pixel covers (z/fx)(z/fy) m^2
            mean_z = float(z.mean())
            x = float(xs[cols + left] @ z) / z.size
            y = float(ys[rows + top] @ z) / z.size
            if abs(x) > lateral or abs(y) > lateral:
                continue
            if area > c["max_blob_area_m2"]:
                too_big += 1
            elif area >= c["min_blob_area_m2"]:
                candidates.append((int(label), mean_z, x))
        if not candidates:
            self.last_reason = (
                "the nearest blob is larger than a hand (the body or furniture?)"
                if too_big
                else "only blobs smaller than a hand"
            )
            return None
        candidates.sort(key=lambda item: item[1])
        return labels, stats, candidates

    def _forearm_cut(self, pts):
        """(main axis toward the fingers or None, whether the width profile oriented it,
        the wrist as (a point, its position along that axis from the point) or None).

        A palm turned edge-on is narrower than the forearm, so the widest part of the blob
        is no palm then: the blob's 3-D points (``pts``, optical, m) are profiled along their
        main axis in sections of metric width (across the axis and the line of sight), the
        forearm is the end whose width stays even, and the wrist where the width first drops
        below the forearm's walking from there (see the constants)."""
        if len(pts) < 20:
            return None, False, None
        mean = pts.mean(axis=0)
        arm = np.linalg.eigh(np.cov((pts - mean).T))[1][:, 2]
        if self._last_arm is not None and float(arm @ self._last_arm) < 0:
            arm = -arm
        s_pts = (pts - mean) @ arm
        s_lo, s_hi = np.percentile(s_pts, (0.5, 99.5))
        count = int((s_hi - s_lo) / _SECTION_M) + 1
        if count <= 20:
            return arm, False, None
        across = np.cross(arm, mean / np.linalg.norm(mean))
        across /= np.linalg.norm(across)
        section = np.clip(((s_pts - s_lo) / _SECTION_M).astype(int), 0, count - 1)
        q = pts @ across
        high, low = np.full(count, -np.inf), np.full(count, np.inf)
        np.maximum.at(high, section, q)
        np.minimum.at(low, section, q)
        width = np.where(np.isfinite(high), high - low, 0.0)
        ends = width[2:12], width[count - 12 : count - 2]
        spread = [float(np.std(e)) / max(float(np.mean(e)), 1e-3) for e in ends]
        flip = None  # what the profile says: the forearm at the far end, fingers the other way
        if spread[1] < _EVEN_RATIO * spread[0]:
            flip = True
        elif spread[0] < _EVEN_RATIO * spread[1]:
            flip = False
        profiled = flip is not None
        if self._last_arm is not None:
            # The axis cannot turn over between two frames: the profile overrules the
            # previous frame's direction only when it has said so for _FLIP_FRAMES frames.
            self._flip_votes = self._flip_votes + 1 if flip else 0
            if self._flip_votes < _FLIP_FRAMES:
                flip = False
            else:
                self._flip_votes = 0
        elif flip is None:
            return arm, False, None
        if flip:
            arm, s_pts, width, s_lo = -arm, -s_pts, width[::-1], -s_hi
        forearm = float(np.median(width[2:12]))
        # The wrist lies before the first section wider than the forearm (a palm facing the
        # camera) and short of the fingertips' last sections, which taper.
        wide = np.nonzero(width[4:] > forearm / _WRIST_NARROWING)[0]
        end = 4 + int(wide[0]) if wide.size else count - 3
        narrow = np.nonzero(width[4:end] < _WRIST_NARROWING * forearm)[0]
        if narrow.size == 0:
            return arm, profiled, None
        wrist = s_lo + (narrow[0] + 4) * _SECTION_M
        return arm, profiled, (mean, wrist)

    def _palm_core(self, centre, z, dist, front, wrist, arm, xs, ys, intr):
        """The seen palm surface's centre as the centroid of the palm's core, or None when
        the core is too small (a palm seen edge-on).

        The maximum of the distance transform is the middle of the widest disc that fits in
        the silhouette: it slides toward the fingers when they are held together (a plate as
        wide as the palm) and across the palm as it tilts. The core is every blob pixel at
        least ``palm_core_width_m`` inside the outline (no single finger is that wide), on the
        hand's side of the wrist and within ``palm_core_radius_m`` of the maximum; its 3-D
        centroid follows the whole palm instead of its widest point. Without a wrist the
        forearm's thick end would join the core, so the caller asks only when the width
        profile found one."""
        c = self.config
        deepest = front + c["palm_search_depth_m"]
        # Only pixels that can be wide enough at the deepest depth searched (the palm's
        # middle), and every second row and column of them: the centroid of a core a few
        # hundred pixels across needs no more, and it is a quarter of the work.
        rows, cols = np.nonzero(dist[::2, ::2] >= c["palm_core_width_m"] * intr.fx / deepest)
        rows, cols = rows * 2, cols * 2
        depth = z[rows, cols]
        keep = (depth > 0) & (depth < deepest)  # inside the closed blob already: the transform is 0 outside
        rows, cols, depth = rows[keep], cols[keep], depth[keep]
        keep = dist[rows, cols] * depth / intr.fx >= c["palm_core_width_m"]  # pixels to metres at their depth
        pts = np.column_stack((xs[cols[keep]] * depth[keep], ys[rows[keep]] * depth[keep], depth[keep]))
        offsets = pts - centre
        mean, s_wrist = wrist
        core = (np.einsum("ij,ij->i", offsets, offsets) <= c["palm_core_radius_m"] ** 2) & (
            (pts - mean) @ arm >= s_wrist + c["palm_core_wrist_margin_m"]
        )
        if int(np.count_nonzero(core)) < _CORE_MIN_PIXELS:
            return None
        return pts[core].mean(axis=0)

    def _measure(self, depth, labels, stats, label, intr, xs, ys):
        """(palm centre, optical rotation, grab) of one blob, or None."""
        c = self.config
        left, top = stats[label, cv2.CC_STAT_LEFT], stats[label, cv2.CC_STAT_TOP]
        width, height = stats[label, cv2.CC_STAT_WIDTH], stats[label, cv2.CC_STAT_HEIGHT]
        # One pixel of border so the distance transform sees the blob's edge at the crop's edge.
        t0, l0 = max(top - 1, 0), max(left - 1, 0)
        t1, l1 = min(top + height + 1, intr.height), min(left + width + 1, intr.width)
        blob = labels[t0:t1, l0:l1] == label
        z = np.where(blob, depth[t0:t1, l0:l1], 0.0)
        front = float(z[blob].min())
        # Single lost pixels inside the hand (speckle, dropout) would each put a zero in the
        # distance transform: closed before it.
        filled = cv2.morphologyEx(blob.view(np.uint8), cv2.MORPH_CLOSE, _CLOSE_KERNEL)
        # 3-D points of the blob (every second pixel is plenty for the axes).
        sub = blob[::2, ::2]
        zz = z[::2, ::2][sub]
        rows, cols = np.nonzero(sub)
        pts = np.column_stack((xs[l0:l1:2][cols] * zz, ys[t0:t1:2][rows] * zz, zz))
        arm, profiled, wrist = self._forearm_cut(pts)
        dist = cv2.distanceTransform(filled, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        search = np.where(filled.view(bool) & (z < front + c["palm_search_depth_m"]), dist, 0.0)
        if self._last_surface is not None and c["track_radius_m"] > 0:
            # Near the previous palm when it is still a palm-wide part of the blob there: a
            # palm turning edge-on stays the palm instead of jumping to the forearm.
            last = self._last_surface
            px, py = xs[l0:l1][None, :] * z, ys[t0:t1][:, None] * z
            close = (px - last[0]) ** 2 + (py - last[1]) ** 2 + (z - last[2]) ** 2 <= c["track_radius_m"] ** 2
            local = np.where(close, search, 0.0)
            if float(local.max()) >= max(1.0, _TRACK_MIN_WIDTH * float(search.max())):
                search = local
        if wrist is not None:
            # A palm found on the forearm's side of the wrist is the forearm: searched again
            # on the hand's side only.
            mean, s_wrist = wrist
            at_v, at_u = np.unravel_index(int(np.argmax(search)), search.shape)
            z_at = z[at_v, at_u]
            found = np.array([xs[l0 + at_u] * z_at, ys[t0 + at_v] * z_at, z_at])
            if float((found - mean) @ arm) < s_wrist + _FOREARM_SIDE_M:
                along = (
                    (xs[l0:l1][None, :] * z - mean[0]) * arm[0]
                    + (ys[t0:t1][:, None] * z - mean[1]) * arm[1]
                    + (z - mean[2]) * arm[2]
                )
                hand = np.where(along >= s_wrist + _WRIST_CUT_M, search, 0.0)
                if float(hand.max()) >= 1.0:
                    search = hand
        peak = float(search.max())
        if peak < 1.0:
            self.last_reason = "blob too thin for a palm"
            return None
        ridge_v, ridge_u = np.nonzero(search >= peak - c["ridge_px"])
        u = float(ridge_u.mean()) + l0
        v = float(ridge_v.mean()) + t0
        # Depth of the palm surface: median over a disc of half the inscribed radius.
        r = max(1, int(peak * 0.5))
        vi, ui = int(round(v)) - t0, int(round(u)) - l0
        patch = z[max(vi - r, 0) : vi + r + 1, max(ui - r, 0) : ui + r + 1]
        patch = patch[patch > 0]
        if patch.size == 0:
            self.last_reason = "no depth at the palm centre"
            return None
        zc = float(np.median(patch))
        centre = np.array([(u - intr.cx) / intr.fx * zc, (v - intr.cy) / intr.fy * zc, zc])
        core = None
        if c["palm_core_width_m"] > 0 and wrist is not None and arm is not None:
            core = self._palm_core(centre, z, dist, front, wrist, arm, xs[l0:l1], ys[t0:t1], intr)
        if arm is not None:
            # Without a clear forearm in the first frame, the palm found says which end
            # holds the fingers.
            if not profiled and self._last_arm is None and float((centre - pts.mean(axis=0)) @ arm) < 0:
                arm = -arm
            self._last_arm = arm
        offsets = pts - centre
        dist3 = np.einsum("ij,ij->i", offsets, offsets)
        palm_r = peak * zc / intr.fx
        # The palm's middle, clear of the thicker wrist; 2 cm at least, for a palm seen edge-on.
        palm = offsets[dist3 <= max(0.6 * palm_r, 0.02) ** 2]
        near = offsets[dist3 <= c["hand_radius_m"] ** 2]
        if len(palm) < 6 or len(near) < 10:
            self.last_reason = "too few points for the hand axes"
            return None
        normal = np.linalg.eigh(np.cov(palm.T))[1][:, 0]
        if (normal[2] < 0) == c["palm_faces_camera"]:
            normal = -normal  # z out of the back of the hand: away from the camera when the palm faces it
        axis = np.linalg.eigh(np.cov(near.T))[1][:, 2]
        axis = axis - normal * float(axis @ normal)
        axis /= np.linalg.norm(axis)
        far = offsets[dist3 > (1.4 * c["hand_radius_m"]) ** 2]  # beyond the fingertips: the forearm
        if len(far) >= 10:
            if float(far.mean(axis=0) @ axis) > 0:  # the forearm is behind the fingers
                axis = -axis
        elif self._last_axis is not None:
            if float(axis @ self._last_axis) < 0:
                axis = -axis
        elif axis[1] > 0:  # no forearm, no history: fingers up in the image
            axis = -axis
        self._last_axis = axis
        rotation = np.column_stack((axis, np.cross(normal, axis), normal))
        reach = float((offsets @ axis).max())
        grab = float(np.clip((c["open_extent_m"] - reach) / (c["open_extent_m"] - c["fist_extent_m"]), 0.0, 1.0))
        # The palm centre lies half a palm thickness behind the seen surface, along the
        # normal: the ray through the surface point meets it h / cos(tilt) further on (the
        # tilt capped at 60 degrees, where the normal is least sure).
        if self._last_surface is not None and float(np.linalg.norm(centre - self._last_surface)) > c["jump_m"]:
            self._core_blend.reset()  # another hand (a new hand_id): nothing to blend from
        self._last_surface = centre
        surface = self._core_blend.update(centre, core)
        ray = surface / np.linalg.norm(surface)
        palm_centre = surface + ray * c["palm_half_thickness_m"] / max(abs(float(ray @ normal)), 0.5)
        if self.palm_model is not None:
            corrected = self.palm_model.correct(z, t0, l0, palm_centre, intr)
            if corrected is not None:
                palm_centre = corrected
        return palm_centre, rotation, grab
