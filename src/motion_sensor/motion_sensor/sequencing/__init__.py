"""The stream between devices and the core: filters and the sequencer.

Its modules:

- ``filters``: the pose filters (mean, One Euro, Kalman IMM) and their parameters;
- ``sequencer``: validation, device binding, timing, trims, jump rejection, filtering;
- ``skeleton_gate``: a skeleton passes exactly when the sequencer passed its palm frame.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "FILTERS": "filters",
    "make_filter": "filters",
    "MeanFilter": "filters",
    "OneEuroFilter": "filters",
    "KalmanFilter": "filters",
    "Sequencer": "sequencer",
    "SequencerConfig": "sequencer",
    "SequencedPose": "sequencer",
    "sequencer_setup": "sequencer",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
