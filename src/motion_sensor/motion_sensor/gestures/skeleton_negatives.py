"""Hand motion that is not a gesture, for teaching the skeleton network to reject it.

The spotter classifies windows of motion between two rests; some of them hold no gesture
(ordinary teleop motion, the hand's way from one rest to the next) and the network must
then answer with no confident class. The training (``skeleton_training``) draws such
windows each epoch and pulls the network's answer on them towards the uniform
distribution (outlier exposure), so the output layout stays the same.

Two sources, both real hands:

- ``leap_motion(paths)``: real Leap recordings (v6 .jsonl.gz), each run of frames with a
  whole skeleton resampled to ``RATE`` (the SHREC'17 rate), canonical joints;
- ``transition``: the end of one training gesture, a rest with tremor, the move to the
  next gesture's first pose and at most its first ``head`` fraction, as the spotter sees
  between two gestures of the same person.

``NegativeSource.draw(rng, count)`` returns ``count`` windows of 0.5-4 s.
"""

import numpy as np

from motion_sensor.errors import MotionSensorError

__all__ = ["RATE", "leap_motion", "transition", "NegativeSource"]

RATE = 30.0
MIN_FRAMES = 15  # 0.5 s


def leap_motion(paths, rate=RATE, max_gap_s=0.3):
    """Canonical skeleton runs (each (n, 22, 3), at ``rate``) of the first hand of every
    frame that has a whole skeleton; a gap over ``max_gap_s`` starts a new run."""
    from motion_sensor.devices.leap_v6 import read_recording

    runs = []
    for path in paths:
        try:
            recording = read_recording(path)
        except (OSError, MotionSensorError) as exc:
            raise MotionSensorError(f"negative recording {path}: {exc}") from exc
        stamps, joints = [], []
        for frame in recording.frames:
            hands = [h for h in frame.hands if h.skeleton is not None]
            if not hands:
                continue
            if stamps and (frame.timestamp - stamps[-1] > max_gap_s or frame.timestamp <= stamps[-1]):
                runs.extend(_resampled(stamps, joints, rate))
                stamps, joints = [], []
            stamps.append(frame.timestamp)
            joints.append(hands[0].skeleton)
        runs.extend(_resampled(stamps, joints, rate))
    return runs


def _resampled(stamps, joints, rate):
    if len(stamps) < 2 or stamps[-1] - stamps[0] < MIN_FRAMES / rate:
        return []
    stamps, joints = np.asarray(stamps), np.asarray(joints, dtype=np.float64)
    grid = np.arange(stamps[0], stamps[-1], 1.0 / rate)
    flat = joints.reshape(len(joints), -1)
    out = np.stack([np.interp(grid, stamps, flat[:, k]) for k in range(flat.shape[1])], axis=1)
    return [out.reshape(len(grid), *joints.shape[1:])]


def transition(before, after, rng, rate=RATE, head=0.3, tremor_m=0.001):
    """The end of ``before``, a rest, the move to ``after``'s first pose and at most its
    first ``head`` fraction (canonical sequences)."""
    before, after = np.asarray(before, dtype=np.float64), np.asarray(after, dtype=np.float64)
    tail = before[int(len(before) * rng.uniform(1.0 - head, 1.0)) :]
    rest = before[-1] + rng.normal(0.0, tremor_m, (int(rng.uniform(0.3, 1.5) * rate),) + before.shape[1:])
    steps = max(2, int(rng.uniform(0.3, 0.7) * rate))
    ease = 0.5 - 0.5 * np.cos(np.pi * np.arange(1, steps + 1) / steps)
    move = before[-1] + (after[0] - before[-1]) * ease[:, None, None]
    start = after[: int(len(after) * rng.uniform(0.0, head))]
    return np.concatenate([part for part in (tail, rest, move, start) if len(part)])


class NegativeSource:
    """Windows of no gesture: from ``runs`` (``leap_motion``) and from transitions between
    the ``sequences`` of the same ``subjects`` (a training set), half each when both exist."""

    def __init__(self, runs=(), sequences=(), subjects=()):
        self.runs = [r for r in runs if len(r) >= MIN_FRAMES]
        self.sequences = list(sequences)
        self.by_subject = {}
        for i, subject in enumerate(subjects):
            self.by_subject.setdefault(int(subject), []).append(i)
        self.by_subject = {s: v for s, v in self.by_subject.items() if len(v) >= 2}

    def __bool__(self):
        return bool(self.runs or self.by_subject)

    def draw(self, rng, count, rate=RATE):
        """``count`` windows (each (n, 22, 3), n >= 15)."""
        out = []
        subjects = sorted(self.by_subject)
        for k in range(count):
            use_runs = self.runs and (not subjects or k % 2 == 0)
            if use_runs:
                run = self.runs[int(rng.integers(len(self.runs)))]
                length = min(len(run), int(rng.uniform(0.5, 4.0) * rate))
                first = int(rng.integers(len(run) - length + 1))
                out.append(run[first : first + length])
            else:
                ids = self.by_subject[subjects[int(rng.integers(len(subjects)))]]
                a, b = rng.choice(len(ids), 2, replace=False)
                window = transition(self.sequences[ids[a]], self.sequences[ids[b]], rng, rate)
                out.append(window[-int(4.0 * rate) :])
        return out
