"""Continuous skeleton streams built from segmented gestures, as the SHREC'19/'22 online
tracks build theirs: the sequences one after another, each followed by an idle gap in
which the hand rests (holds its last pose with a small tremor) and then moves to the next
sequence's first pose. The SHREC'17 stream device plays them; the spotting benchmark
scores the spotter on them against the known gesture spans.
"""

import numpy as np

__all__ = ["build_stream"]


def build_stream(sequences, labels, rng, rate=30.0, hold_s=(1.0, 3.0), move_s=0.5, tremor_m=0.001, order=None):
    """(stamps (n,), joints (n, 22, 3), [(label, start s, end s)]) of one continuous stream.

    ``sequences``: canonical skeleton sequences sampled at ``rate``; ``labels``: one per
    sequence; ``rng``: a seeded numpy Generator (hold lengths, tremor, and the order when
    ``order`` is None; pass ``range(len(sequences))`` to keep the given order). The stream
    starts and ends with a rest of ``hold_s[1]``.
    """
    if not len(sequences):
        raise ValueError("a stream needs at least one sequence")
    order = rng.permutation(len(sequences)) if order is None else list(order)
    first = np.asarray(sequences[order[0]], dtype=float)
    frames, truth = _rest(first[0], hold_s[1], rate, tremor_m, rng), []
    previous = None
    for i in order:
        seq = np.asarray(sequences[i], dtype=float)
        if previous is not None:
            frames.extend(_rest(previous[-1], rng.uniform(*hold_s), rate, tremor_m, rng))
            steps = max(1, int(round(move_s * rate)))
            frames.extend(previous[-1] + (seq[0] - previous[-1]) * k / steps for k in range(1, steps + 1))
        start = len(frames) / rate
        frames.extend(seq)
        truth.append((labels[i], start, (len(frames) - 1) / rate))
        previous = seq
    frames.extend(_rest(previous[-1], hold_s[1], rate, tremor_m, rng))
    return np.arange(len(frames)) / rate, np.array(frames), truth


def _rest(pose, seconds, rate, tremor_m, rng):
    count = int(round(seconds * rate))
    return [pose + rng.normal(0.0, tremor_m, pose.shape) for _ in range(count)]
