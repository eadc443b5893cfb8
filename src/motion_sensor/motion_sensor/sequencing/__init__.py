"""The stream between devices and the core: filters and the sequencer.

Its modules:

- ``filters``: the pose filters (mean, One Euro, Kalman IMM) and their parameters;
- ``sequencer``: validation, device binding, timing, trims, jump rejection, filtering.
"""

from importlib import import_module as _import_module

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


def __getattr__(name):
    """Imports the submodule that defines ``name`` on first use (PEP 562)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import_module(f"{__name__}.{module}"), name)
    globals()[name] = value  # the next look-up finds it without this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
