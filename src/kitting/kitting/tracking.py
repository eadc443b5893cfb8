"""Constant-velocity tracking of parts on the belt plane (filterpy's KalmanFilter).

State [x, vx, y, vy] (m, m/s) per track; measurements (x, y). Each ``update(t, obs)``
predicts every track to time t (F and Q built for that track's own dt), associates
observations by nearest neighbour (greedy, closest pairs first, within ``gate`` metres of
the prediction), corrects the matched tracks, starts a track for each unmatched
observation and stops tracks missed ``max_misses`` times in a row or gone past the belt's
end. A track is confirmed after ``min_hits`` hits; its class is the majority of its
observations' classes.
"""

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter
from scipy.linalg import block_diag

from motion_common.params import Param, ParamSchema

TRACKER_SCHEMA = ParamSchema(
    [
        Param("gate", 0.02, "m", "association distance", low=0.0, high=1.0, low_open=True),
        Param("measurement_std", 0.001, "m", "position measurement noise", low=0.0, high=0.1, low_open=True),
        Param("accel_std", 0.005, "m/s²", "process noise (white acceleration)", low=0.0, high=10.0, low_open=True),
        Param("initial_speed", 0.05, "m/s", "prior belt speed along +x for a new track", low=-1.0, high=1.0),
        Param("initial_speed_std", 0.05, "m/s", "prior speed uncertainty", low=0.0, high=1.0, low_open=True),
        Param("min_hits", 2, "", "hits to confirm a track", low=1, high=100),
        Param("max_misses", 3, "", "consecutive misses that stop a track", low=1, high=100),
        Param("x_end", 0.80, "m", "tracks past this x are stopped (belt end)", low=-5.0, high=5.0),
    ]
)


@dataclass
class Observation:
    class_name: str
    x: float
    y: float
    confidence: float = 1.0


@dataclass
class Track:
    track_id: int
    kf: KalmanFilter
    t: float  # s, time of the state
    last_seen: float = -math.inf  # s, stamp of the newest observation in the track
    hits: int = 1
    misses: int = 0
    classes: Counter = field(default_factory=Counter)
    confirmed: bool = False

    @property
    def class_name(self) -> str:
        return self.classes.most_common(1)[0][0]

    @property
    def position(self) -> np.ndarray:
        return np.array([self.kf.x[0, 0], self.kf.x[2, 0]])

    @property
    def velocity(self) -> np.ndarray:
        return np.array([self.kf.x[1, 0], self.kf.x[3, 0]])

    def predict_position(self, t: float) -> np.ndarray:
        """(x, y) at time t under constant velocity (no filter change)."""
        return self.position + self.velocity * (t - self.t)

    @property
    def position_std(self) -> float:
        return float(np.sqrt(max(self.kf.P[0, 0], self.kf.P[2, 2])))


class BeltTracker:
    def __init__(self, params: dict | None = None):
        self.params = TRACKER_SCHEMA.validate(params or {}, "tracker")
        self.tracks: dict[int, Track] = {}
        self.stopped: list[Track] = []
        self._next_id = 1

    def _new_filter(self, observation: Observation) -> KalmanFilter:
        P = self.params
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x = np.array([[observation.x], [P["initial_speed"]], [observation.y], [0.0]])
        kf.H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
        kf.R = np.eye(2) * P["measurement_std"] ** 2
        kf.P = np.diag(
            [
                P["measurement_std"] ** 2,
                P["initial_speed_std"] ** 2,
                P["measurement_std"] ** 2,
                P["initial_speed_std"] ** 2,
            ]
        )
        return kf

    def _predict(self, track: Track, t: float):
        dt = t - track.t
        if dt <= 0:
            return
        f = np.array([[1.0, dt], [0.0, 1.0]])
        track.kf.F = block_diag(f, f)
        q = Q_discrete_white_noise(dim=2, dt=dt, var=self.params["accel_std"] ** 2)
        track.kf.Q = block_diag(q, q)
        track.kf.predict()
        track.t = t

    def update(self, t: float, observations: Sequence[Observation]) -> list[Track]:
        """Advance to time t (s) with this frame's observations; returns the live tracks."""
        P = self.params
        for track in self.tracks.values():
            self._predict(track, t)
        pairs = []
        for track_id, track in self.tracks.items():
            for index, obs in enumerate(observations):
                distance = float(np.hypot(*(track.position - (obs.x, obs.y))))
                if distance <= P["gate"]:
                    pairs.append((distance, track_id, index))
        matched_tracks, matched_obs = set(), set()
        for _distance, track_id, index in sorted(pairs):
            if track_id in matched_tracks or index in matched_obs:
                continue
            matched_tracks.add(track_id)
            matched_obs.add(index)
            track, obs = self.tracks[track_id], observations[index]
            track.kf.update(np.array([[obs.x], [obs.y]]))
            track.hits += 1
            track.last_seen = t
            track.misses = 0
            track.classes[obs.class_name] += 1
            track.confirmed = track.confirmed or track.hits >= P["min_hits"]
        for track_id, track in list(self.tracks.items()):
            if track_id not in matched_tracks:
                track.misses += 1
            if track.misses >= P["max_misses"] or track.position[0] > P["x_end"]:
                self.stopped.append(self.tracks.pop(track_id))
        for index, obs in enumerate(observations):
            if index not in matched_obs:
                track = Track(self._next_id, self._new_filter(obs), t, t, classes=Counter({obs.class_name: 1}))
                track.confirmed = P["min_hits"] <= 1
                self.tracks[track.track_id] = track
                self._next_id += 1
        return list(self.tracks.values())

    def confirmed(self) -> list[Track]:
        return [track for track in self.tracks.values() if track.confirmed]
