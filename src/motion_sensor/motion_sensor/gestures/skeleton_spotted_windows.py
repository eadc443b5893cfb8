"""Training windows cut from continuous streams the way the online spotter cuts them.

The network is trained on clean, whole sequences, but the spotter (``skeleton_spotter``)
classifies windows of a live stream: motion between two rests, from fractions of the
segment to its end, so a window holds the way in and sometimes only part of a gesture
(its end cut at a slow phase, its start in the way in). A part of one gesture can then
look like another whole one (the end of a swipe down like a tap).

``spotted_windows(dataset, rng)`` plays each subject's sequences as one continuous stream
(``skeleton_stream.build_stream``: rests with tremor and a move between gestures), runs
the spotter's own segmentation on it with a stand-in classifier that keeps the windows
it is given, and labels every window with the gesture it covers most: the true class
when it holds at least ``min_cover`` of that gesture, else no gesture (label -1, a
window to reject). The training then learns a partial swipe down as a swipe down, not
as whatever whole gesture it resembles.
"""

import numpy as np

from motion_sensor.gestures.skeleton_classifier import SkeletonResult
from motion_sensor.gestures.skeleton_spotter import SkeletonSpotter
from motion_sensor.gestures.skeleton_stream import build_stream

__all__ = ["SpottedWindows", "spotted_windows"]


class _Recorder:
    """A classifier stand-in: keeps the windows it is given, each with the index of the
    stream frame being taken then (``now``), and answers uniformly, so the spotter reports
    nothing and no refractory period hides the next segment."""

    def __init__(self):
        self.windows = []
        self.now = 0

    def classify_batch(self, sequences):
        self.windows.extend((window, self.now) for window in sequences)
        return [SkeletonResult(np.full(14, 1.0 / 14), np.full(28, 1.0 / 28)) for _ in sequences]


class SpottedWindows:
    """Windows (each (n, 22, 3)) with their labels (-1: no gesture) and coverage."""

    def __init__(self, windows, label14, label28, cover):
        self.windows = list(windows)
        self.label14 = np.asarray(label14, dtype=np.int64)
        self.label28 = np.asarray(label28, dtype=np.int64)
        self.cover = np.asarray(cover, dtype=float)

    def __len__(self):
        return len(self.windows)


def _end_index(joints, now, last_frame):
    """Index of ``last_frame`` in the stream, searching back from ``now``."""
    for k in range(now, -1, -1):
        if np.array_equal(joints[k], last_frame):
            return k
    raise ValueError("a spotted window's last frame is not in its stream")


def spotted_windows(dataset, rng, orders=1, min_cover=0.5, params=None, rate=30.0):
    """``SpottedWindows`` of ``dataset`` (a ``SkeletonDataset``): per order and subject, one
    stream of that subject's sequences in a random order, segmented by a ``SkeletonSpotter``
    with ``params`` (its defaults: the windows it classifies)."""
    windows, label14, label28, cover = [], [], [], []
    for _ in range(orders):
        for subject in sorted(set(dataset.subject.tolist())):
            ids = np.flatnonzero(dataset.subject == subject)
            stamps, joints, truth = build_stream([dataset.sequences[i] for i in ids], list(ids), rng, rate=rate)
            recorder = _Recorder()
            spotter = SkeletonSpotter(recorder, params)
            for now, (stamp, frame) in enumerate(zip(stamps, joints, strict=True)):
                recorder.now = now
                spotter.update(stamp, frame)
            spotter.finish()
            for window, now in recorder.windows:
                end = _end_index(joints, now, window[-1])
                start = stamps[end - len(window) + 1]
                _label(window, start, stamps[end], truth, dataset, min_cover, out=(windows, label14, label28, cover))
    return SpottedWindows(windows, label14, label28, cover)


def _label(window, start, end, truth, dataset, min_cover, out):
    """Append ``window`` with the labels of the gesture it covers most."""
    best, best_cover = None, 0.0
    for index, g_start, g_end in truth:
        overlap = min(end, g_end) - max(start, g_start)
        share = overlap / max(g_end - g_start, 1e-9)
        if share > best_cover:
            best, best_cover = index, share
    positive = best is not None and best_cover >= min_cover
    windows, label14, label28, cover = out
    windows.append(np.array(window, dtype=np.float64))
    label14.append(int(dataset.label14[best]) if positive else -1)
    label28.append(int(dataset.label28[best]) if positive else -1)
    cover.append(round(best_cover, 4))
