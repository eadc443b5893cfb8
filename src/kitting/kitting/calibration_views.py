"""Choosing ChArUco calibration views from a live stream (a camera, or a video played like one).

A stream shows the same pose of the board for many frames; calibrating on twenty copies of
one view gives a confident wrong answer. ``ViewCollector.offer(image, t)`` takes a frame
only when

- at least ``interval`` s (stream time) passed since the last view taken,
- the board shows at least ``min_corners`` ChArUco corners (``calibration.detect_board``),
- the board moved: the corners seen in both views moved ``min_motion_px`` on average, or
  fewer than half of them are common to both (a new part of the board),

and returns (taken, reason) so the tool can print progress. Detection runs on a grey copy.
"""

import cv2
import numpy as np

from .calibration import BoardSpec, detect_board


def _grey(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image


class ViewCollector:
    def __init__(
        self,
        spec: BoardSpec = BoardSpec(),
        count: int = 20,
        min_corners: int = 8,
        interval: float = 1.0,
        min_motion_px: float = 20.0,
    ):
        if count < 1 or min_corners < 4 or interval < 0 or min_motion_px < 0:
            raise ValueError("need count >= 1, min_corners >= 4, interval >= 0 s, min_motion_px >= 0")
        self.spec, self.count, self.min_corners = spec, count, min_corners
        self.interval, self.min_motion_px = interval, min_motion_px
        self.views: list[np.ndarray] = []  # the frames taken, as given
        self.last_time: float | None = None
        self.last_points: dict | None = None  # board corner (x, y) in m -> pixel

    @property
    def done(self) -> bool:
        return len(self.views) >= self.count

    def offer(self, image, t: float) -> tuple[bool, str]:
        """Take ``image`` (seen at stream time ``t``, s) as a view if it qualifies."""
        if self.done:
            return False, f"already {self.count} views"
        if self.last_time is not None and t - self.last_time < self.interval:
            return False, "too soon after the last view"
        found, why = detect_board(_grey(image), self.spec, self.min_corners)
        if found is None:
            return False, why
        objects, pixels = found
        points = {(round(float(o[0]), 4), round(float(o[1]), 4)): p for o, p in zip(objects, pixels)}
        if self.last_points is not None:
            common = set(points) & set(self.last_points)
            if len(common) >= len(points) / 2:
                shift = float(np.mean([np.linalg.norm(points[k] - self.last_points[k]) for k in common]))
                if shift < self.min_motion_px:
                    return (
                        False,
                        f"board moved {shift:.0f} px since the last view (move it at least "
                        f"{self.min_motion_px:.0f} px, or tilt it)",
                    )
        self.views.append(np.asarray(image).copy())
        self.last_time, self.last_points = t, points
        return True, f"{len(points)} corners"
