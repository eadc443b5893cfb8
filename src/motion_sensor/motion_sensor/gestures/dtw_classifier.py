"""Dynamic-gesture classification: DTW nearest neighbours over normalised trajectory
templates, in dtaidistance's compiled core.

Each template and each query becomes a fixed-size feature array (``gesture_features``:
arc-length resampling, centring, RMS scaling, direction channels). The query is compared
with the templates by multi-dimensional DTW (``dtaidistance.dtw_ndim.distance_fast``,
squared-Euclidean inner distance, Sakoe-Chiba ``window``) in a cascade:

1. LB_Keogh of the query against every template's precomputed window envelope, for all
   templates at once in numpy (a valid lower bound of the windowed DTW distance);
2. templates visited in increasing lower-bound order; DTW is run with ``max_dist`` set to
   the current k-th best distance (early abandoning inside the C core), and the visit
   stops as soon as a lower bound exceeds it. The result equals a full scan.

Distances are reported per point (``dtw / sqrt(length)``). Closed-set mode (the default)
always answers the nearest class (distance-weighted k-NN vote when ``k`` > 1: the nearest
template counts 1, the i-th d_1/d_i; ties to the nearest). Open
set (``reject_distance`` set, or ``calibrate_rejection``) answers ``None`` when the
nearest template is farther than the threshold, so non-gesture motion is not forced into
a class.
"""

import bisect
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from dtaidistance import dtw_ndim
from dtaidistance.dtw import DTWSettings

try:  # the compiled core itself: dtw_ndim.distance_fast adds ~8 us of checks per call
    from dtaidistance import dtw_cc as _DTW_CC
except ImportError:  # pragma: no cover - dtaidistance without its C extension
    _DTW_CC = None

from motion_common.params import Param, ParamSchema
from motion_sensor.gestures.gesture_features import FEATURE_PARAMS, FeatureConfig, features

CLASSIFIER_PARAMS = ParamSchema(
    [
        Param("window", 0.25, "fraction of length", "Sakoe-Chiba band half-width", low=0.0, high=1.0),
        Param("k", 1, "templates", "nearest neighbours voting (1 = 1-NN)", low=1, high=15),
        Param(
            "reject_distance",
            None,
            "per-point DTW distance",
            "open-set threshold; None = closed set",
            kind=float,
            low=0.0,
            nullable=True,
        ),
    ]
).merged(FEATURE_PARAMS)


@dataclass
class Classification:
    """Outcome of one query: ``label`` (None when rejected), per-point ``distance`` to the
    nearest template of that label, ``confidence`` in [0, 1] (relative margin to the
    nearest other class), the best ``candidate`` even when rejected, the number of DTW
    computations run (``dtw_calls``)."""

    label: str | None
    distance: float
    confidence: float
    candidate: str
    runner_up: str | None
    runner_up_distance: float
    rejected: bool
    dtw_calls: int


class DTWClassifier:
    """k-NN DTW classifier over labelled trajectory templates (see the module docstring)."""

    def __init__(
        self,
        config: FeatureConfig = FeatureConfig(),
        window: float = 0.25,
        k: int = 1,
        reject_distance: float | None = None,
    ):
        self.config = config
        self.window_fraction = window
        self.k = int(k)
        self.reject_distance = reject_distance
        self.labels: list[str] = []
        self._data = np.zeros((0, config.length, config.channels))
        self._upper = self._data
        self._lower = self._data

    @classmethod
    def from_params(cls, values: dict | None = None, source: str = "dtw_classifier") -> "DTWClassifier":
        """Classifier from a parameter dict validated by CLASSIFIER_PARAMS."""
        checked = CLASSIFIER_PARAMS.validate(values or {}, source)
        feature_keys = set(FEATURE_PARAMS.params)
        config = FeatureConfig.from_params({k: v for k, v in checked.items() if k in feature_keys}, source)
        return cls(config, checked["window"], checked["k"], checked["reject_distance"])

    @property
    def window(self) -> int | None:
        """Sakoe-Chiba width in samples for dtaidistance (None = unconstrained)."""
        if self.window_fraction >= 1.0:
            return None
        return max(1, int(round(self.window_fraction * self.config.length)))

    @property
    def classes(self) -> list[str]:
        """Sorted distinct labels."""
        return sorted(set(self.labels))

    def __len__(self):
        return len(self.labels)

    def features(self, points, times=None) -> np.ndarray:
        """Feature array of one path with this classifier's settings."""
        return features(points, times, self.config)

    def add(self, label: str, points, times=None) -> None:
        """Add one template (a path n x 3, optional times)."""
        self.add_features([label], [self.features(points, times)])

    def fit(self, samples: Iterable[tuple[str, np.ndarray, np.ndarray | None]]) -> "DTWClassifier":
        """Add every (label, points, times) template; returns self."""
        labels, feats = [], []
        for label, points, times in samples:
            labels.append(label)
            feats.append(self.features(points, times))
        self.add_features(labels, feats)
        return self

    def add_features(self, labels: Sequence[str], feats: Sequence[np.ndarray]) -> None:
        """Add templates already turned into feature arrays."""
        if not len(labels):
            return
        block = np.stack([np.asarray(f, dtype=np.float64) for f in feats])
        upper, lower = self._envelopes(block)
        self.labels.extend(str(label) for label in labels)
        self._data = np.concatenate([self._data, block])
        self._upper = np.concatenate([self._upper, upper])
        self._lower = np.concatenate([self._lower, lower])

    def _envelopes(self, block: np.ndarray):
        """Running max / min over +-window samples of each template (LB_Keogh envelope)."""
        radius = self.config.length if self.window is None else self.window
        upper, lower = block.copy(), block.copy()
        for shift in range(1, radius + 1):
            upper[:, shift:] = np.maximum(upper[:, shift:], block[:, :-shift])
            upper[:, :-shift] = np.maximum(upper[:, :-shift], block[:, shift:])
            lower[:, shift:] = np.minimum(lower[:, shift:], block[:, :-shift])
            lower[:, :-shift] = np.minimum(lower[:, :-shift], block[:, shift:])
        return upper, lower

    def lower_bounds(self, query: np.ndarray) -> np.ndarray:
        """LB_Keogh of a feature array against every template (same scale as DTW)."""
        above = np.maximum(query[None] - self._upper, 0.0)
        below = np.maximum(self._lower - query[None], 0.0)
        return np.sqrt(np.einsum("nij,nij->n", above, above) + np.einsum("nij,nij->n", below, below))

    def _dtw_kwargs(self, max_dist: float) -> dict:
        """Keyword arguments of the compiled core for this window and an abandon bound."""
        kwargs = dict(self._c_kwargs)
        kwargs["max_dist"] = 0.0 if not np.isfinite(max_dist) else float(max_dist)
        return kwargs

    def dtw(self, a: np.ndarray, b: np.ndarray, max_dist: float = np.inf) -> float:
        """Windowed multi-dimensional DTW (dtaidistance C core); inf once above max_dist."""
        if _DTW_CC is None:
            return dtw_ndim.distance_fast(
                a, b, window=self.window, max_dist=None if not np.isfinite(max_dist) else max_dist
            )
        return _DTW_CC.distance_ndim(a, b, **self._dtw_kwargs(max_dist))

    @property
    def _c_kwargs(self) -> dict:
        return DTWSettings(window=self.window, use_ndim=True).c_kwargs()

    def scan(self, query: np.ndarray, count: int):
        """The ``count`` nearest templates ([(raw DTW distance, index)], nearest first), the
        nearest raw distance of every class met ({label: distance}, exact for the two
        nearest classes) and the number of DTW computations. Exact: a template is skipped
        only when its lower bound shows it can change neither."""
        if not self.labels:
            raise ValueError("the classifier has no templates")
        count = min(max(1, count), len(self.labels))
        bounds = self.lower_bounds(query)
        order = np.argsort(bounds, kind="stable")
        best: list[tuple[float, int]] = []
        per_class: dict[str, float] = {}
        threshold = np.inf
        calls = 0
        base = self._c_kwargs
        data, labels = self._data, self.labels
        for index in order:
            if bounds[index] > threshold:
                break
            if _DTW_CC is None:
                dist = self.dtw(query, data[index], threshold)
            else:
                base["max_dist"] = 0.0 if threshold == np.inf else float(threshold)
                dist = _DTW_CC.distance_ndim(query, data[index], **base)
            calls += 1
            if not np.isfinite(dist):
                continue
            if len(best) < count or dist < best[-1][0]:
                bisect.insort(best, (dist, int(index)))
                del best[count:]
            label = labels[index]
            if dist < per_class.get(label, np.inf):
                per_class[label] = dist
            kth = best[-1][0] if len(best) == count else np.inf
            two = sorted(per_class.values())[:2]
            threshold = max(kth, two[1] if len(two) == 2 else np.inf)
        return best, per_class, calls

    def classify(self, points, times=None, open_set: bool | None = None) -> Classification:
        """Classify one path. ``open_set`` defaults to "a rejection threshold is set"."""
        return self.classify_features(self.features(points, times), open_set)

    def classify_features(self, query: np.ndarray, open_set: bool | None = None) -> Classification:
        """Classify a feature array (see ``classify``)."""
        scale = np.sqrt(self.config.length)
        best, per_class, calls = self.scan(query, self.k)
        if self.k > 1:  # distance-weighted vote: the nearest counts 1, the others d_1 / d_i
            votes: dict[str, float] = {}
            nearest = max(best[0][0], 1e-12)
            for dist, index in best:
                label = self.labels[index]
                votes[label] = votes.get(label, 0.0) + nearest / max(dist, 1e-12)
            winner = max(votes, key=lambda label: (votes[label], -per_class[label]))
        else:
            winner = self.labels[best[0][1]]
        d_best = per_class[winner] / scale
        others = sorted((d, label) for label, d in per_class.items() if label != winner)
        runner_up, d_other = (others[0][1], others[0][0] / scale) if others else (None, np.inf)
        confidence = 1.0 if not np.isfinite(d_other) else max(0.0, (d_other - d_best) / max(d_other, 1e-12))
        open_set = self.reject_distance is not None if open_set is None else open_set
        rejected = bool(open_set and self.reject_distance is not None and d_best > self.reject_distance)
        return Classification(
            None if rejected else winner,
            float(d_best),
            float(confidence),
            winner,
            runner_up,
            float(d_other),
            rejected,
            calls,
        )

    def calibrate_rejection(self, percentile: float = 99.0, margin: float = 1.3) -> float:
        """Set ``reject_distance`` from the templates themselves: the ``percentile`` of each
        template's leave-one-out distance to its nearest same-class template, times
        ``margin``. Needs at least two templates of a class; returns the threshold."""
        scale = np.sqrt(self.config.length)
        within = []
        for i, label in enumerate(self.labels):
            same = [j for j, other in enumerate(self.labels) if other == label and j != i]
            if not same:
                continue
            within.append(min(self.dtw(self._data[i], self._data[j]) for j in same) / scale)
        if not within:
            raise ValueError("rejection calibration needs two templates of at least one class")
        self.reject_distance = float(np.percentile(within, percentile) * margin)
        return self.reject_distance
