"""How far one path trails another: the delay L that best explains the follower as an affine
map of the source delayed by L (least squares; an affine map absorbs a speed ratio and a change
of frame, so only the delay is left). Used by the session report (the hand-to-tool figure of
every session) and by bench/hand_to_tool (each stage of the chain). Pure numpy.
"""

import numpy as np

__all__ = ["LAGS_S", "MIN_SPAN_M", "best_lag", "trailing_lag"]

LAGS_S = np.arange(0.0, 0.3001, 0.002)  # s: the delays searched, 0-300 ms in 2 ms steps
MIN_SPAN_M = 0.02  # m: a source that moves less (on every axis) fits any delay


def best_lag(source, follower, lags=LAGS_S):
    """(lag s, residual rms) of the affine map follower(t) ~ A source(t - lag) + b.

    ``source`` and ``follower`` are arrays of rows (t, values...); the follower's samples
    count only where the delayed source is defined. None when too few samples overlap."""
    source, follower = np.asarray(source, dtype=float), np.asarray(follower, dtype=float)
    if len(source) < 2 or len(follower) < 20:
        return None
    best = None
    for lag in lags:
        t = follower[:, 0] - lag
        inside = (t >= source[0, 0]) & (t <= source[-1, 0])
        if inside.sum() < 20:
            continue
        x = np.column_stack([np.interp(t[inside], source[:, 0], source[:, k]) for k in range(1, source.shape[1])])
        y = follower[inside, 1:]
        design = np.column_stack([x, np.ones(len(x))])
        coef, *_ = np.linalg.lstsq(design, y, rcond=None)
        rms = float(np.sqrt(np.mean((design @ coef - y) ** 2)))
        if best is None or rms < best[1]:
            best = (float(lag), rms)
    return best


def trailing_lag(source, follower, min_span=MIN_SPAN_M, lags=LAGS_S):
    """Lag (ms) of ``follower`` behind ``source``, or None where it cannot be told: a source
    that moves less than ``min_span`` on every axis (a still hand fits any lag), too few
    samples, or a best fit at the end of the search (the follower does not follow within it,
    e.g. an arm held at a joint limit)."""
    source = np.asarray(source, dtype=float)
    if len(source) < 2 or float(np.ptp(source[:, 1:], axis=0).max()) < min_span:
        return None
    fit = best_lag(source, follower, lags)
    if fit is None or fit[0] >= lags[-1] - 1e-9:
        return None
    return round(1000.0 * fit[0], 1)
